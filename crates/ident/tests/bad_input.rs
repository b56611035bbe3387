//! Bad input is rejected with a message naming the file, the line and data row,
//! and the column. Line numbers are physical lines (header = line 1); data rows
//! count data records from 1.

use fistage_ident::{
    FrfOptions, StribeckOptions, UnitOverrides, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
    parse_frf_csv, parse_stribeck_csv, read_stribeck_csv, units::Quantity,
};

const GOOD_ROWS: &str = "-20,-6.1\n-5,-6.0\n-1,-6.4\n1,6.4\n5,6.0\n20,6.1\n";

fn stribeck_error(text: &str) -> String {
    match parse_stribeck_csv("lab.csv", text, &UnitOverrides::default()) {
        Ok(data) => fit_stribeck(&data, &StribeckOptions::default())
            .map(|_| ())
            .expect_err("the data should be rejected")
            .to_string(),
        Err(e) => e.to_string(),
    }
}

fn frf_error(text: &str) -> String {
    match parse_frf_csv("frf.csv", text, &UnitOverrides::default()) {
        Ok(data) => fit_frf(&data, &FrfOptions::with_mass(1.5))
            .map(|_| ())
            .expect_err("the data should be rejected")
            .to_string(),
        Err(e) => e.to_string(),
    }
}

fn assert_mentions(message: &str, parts: &[&str]) {
    for part in parts {
        assert!(
            message.contains(part),
            "'{message}' does not mention '{part}'"
        );
    }
}

#[test]
fn missing_column() {
    let message = stribeck_error(&format!("velocity_mm_per_s,current_A\n{GOOD_ROWS}"));
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "header (line 1)",
            "no force column",
            "force_N",
            "current_A",
        ],
    );
    let message = frf_error("freq_Hz,coherence\n10,0.9\n");
    assert_mentions(
        &message,
        &["frf.csv", "line 1", "no FRF response column", "coherence"],
    );
    let message = frf_error("freq_Hz,re_G_m_per_N\n10,1e-6\n");
    assert_mentions(
        &message,
        &[
            "frf.csv",
            "column 're_G_m_per_N'",
            "no imaginary part column",
        ],
    );
}

#[test]
fn non_numeric_and_empty_cells() {
    let text = format!("velocity_mm_per_s,force_N\n{GOOD_ROWS}7.5,abc\n");
    let message = stribeck_error(&text);
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "line 8 (data row 7)",
            "column 'force_N'",
            "'abc' is not a number",
        ],
    );
    let text = format!("# exported 2024-05-01\nvelocity_mm_per_s,force_N\n{GOOD_ROWS}  ,6.2\n");
    let message = stribeck_error(&text);
    assert_mentions(
        &message,
        &[
            "line 9 (data row 7)",
            "column 'velocity_mm_per_s'",
            "empty cell",
        ],
    );
    let message = stribeck_error("velocity_mm_per_s,force_N\n1,inf\n");
    assert_mentions(
        &message,
        &[
            "line 2 (data row 1)",
            "column 'force_N'",
            "not a finite number",
        ],
    );
}

#[test]
fn ragged_rows() {
    let message = stribeck_error("velocity_mm_per_s,force_N\n1,6.4\n2,6.3,7\n");
    assert_mentions(&message, &["lab.csv", "line 3", "malformed CSV"]);
}

#[test]
fn fewer_points_than_parameters() {
    let message = stribeck_error("velocity_mm_per_s,force_N\n-5,-6\n-1,-6.4\n1,6.4\n5,6\n");
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "column 'velocity_mm_per_s'",
            "4 data rows (lines 2-5)",
            "4 parameters",
            "at least 5",
        ],
    );
    let message = frf_error("freq_Hz,mag_um_per_N\n100,0.5\n200,2.0\n");
    assert_mentions(
        &message,
        &[
            "frf.csv",
            "column 'freq_Hz'",
            "2 data rows (lines 2-3)",
            "at least 3",
        ],
    );
}

#[test]
fn one_velocity_sign_for_a_two_sided_fit() {
    let text = "velocity_mm_per_s,force_N\n1,6.4\n2,6.2\n5,6.0\n10,6.0\n20,6.1\n";
    let message = stribeck_error(text);
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "column 'velocity_mm_per_s'",
            "all 5 velocities are positive",
            "lines 2-6",
            "--one-sided",
        ],
    );
    let data = parse_stribeck_csv("lab.csv", text, &UnitOverrides::default()).unwrap();
    let message = fit_stribeck_asymmetric(&data, &StribeckOptions::default())
        .unwrap_err()
        .to_string();
    assert_mentions(&message, &["all 5 velocities are positive"]);
    // A one-sided fit of the same data is allowed.
    let options = StribeckOptions {
        two_sided: false,
        ..StribeckOptions::default()
    };
    fit_stribeck(&data, &options).unwrap();
}

#[test]
fn zero_velocity() {
    let message = stribeck_error(&format!("velocity_mm_per_s,force_N\n{GOOD_ROWS}0,0.3\n"));
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "line 8 (data row 7)",
            "column 'velocity_mm_per_s'",
            "velocity 0",
        ],
    );
}

#[test]
fn zero_or_negative_frequencies() {
    let rows = "10,1e-6,-1e-8\n20,1.2e-6,-2e-8\n30,1.5e-6,-4e-8\n";
    for (bad, shown) in [("0", "got 0 Hz"), ("-50", "got -50 Hz")] {
        let text = format!("freq_Hz,re_G_m_per_N,im_G_m_per_N\n{rows}{bad},1e-6,-1e-8\n");
        let message = frf_error(&text);
        assert_mentions(
            &message,
            &[
                "frf.csv",
                "line 5 (data row 4)",
                "column 'freq_Hz'",
                "must be > 0",
                shown,
            ],
        );
    }
}

#[test]
fn zero_magnitude() {
    let message = frf_error("freq_Hz,mag_m_per_N\n10,1e-6\n20,0\n30,1e-6\n40,1e-6\n");
    assert_mentions(
        &message,
        &[
            "frf.csv",
            "line 3 (data row 2)",
            "column 'mag_m_per_N'",
            "magnitude must be > 0",
        ],
    );
}

#[test]
fn units_unknown_missing_or_contradicted() {
    let message = stribeck_error(&format!("velocity_in_per_s,force_N\n{GOOD_ROWS}"));
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "column 'velocity_in_per_s'",
            "unknown velocity unit 'in_per_s'",
            "mm/s",
        ],
    );
    let message = stribeck_error(&format!("velocity,force_N\n{GOOD_ROWS}"));
    assert_mentions(
        &message,
        &["column 'velocity'", "no unit", "--velocity-unit"],
    );
    // The flag supplies the unit of an unsuffixed column ...
    let units = UnitOverrides {
        velocity: fistage_ident::Unit::parse(Quantity::Velocity, "mm/s"),
        ..UnitOverrides::default()
    };
    let data =
        parse_stribeck_csv("lab.csv", &format!("velocity,force_N\n{GOOD_ROWS}"), &units).unwrap();
    assert_eq!(data.velocity[0], -0.02);
    // ... but may not contradict a suffix.
    let message = parse_stribeck_csv(
        "lab.csv",
        &format!("velocity_m_per_s,force_N\n{GOOD_ROWS}"),
        &units,
    )
    .unwrap_err()
    .to_string();
    assert_mentions(
        &message,
        &[
            "column 'velocity_m_per_s'",
            "says m/s but --velocity-unit says mm/s",
        ],
    );
}

#[test]
fn ambiguous_columns() {
    let message = stribeck_error(&format!(
        "velocity_mm_per_s,force_N,v_m_per_s\n{}",
        "1,2,3\n"
    ));
    assert_mentions(
        &message,
        &[
            "lab.csv",
            "column 'v_m_per_s'",
            "ambiguous",
            "velocity_mm_per_s",
        ],
    );
}

#[test]
fn unreadable_file() {
    let message = read_stribeck_csv("no/such/file.csv", &UnitOverrides::default())
        .unwrap_err()
        .to_string();
    assert_mentions(&message, &["no/such/file.csv", "cannot read"]);
}

#[test]
fn bad_options() {
    let data = parse_stribeck_csv(
        "lab.csv",
        &format!("velocity_mm_per_s,force_N\n{GOOD_ROWS}"),
        &UnitOverrides::default(),
    )
    .unwrap();
    let options = StribeckOptions {
        v_s_start: Some(-1.0),
        ..StribeckOptions::default()
    };
    let message = fit_stribeck(&data, &options).unwrap_err().to_string();
    assert_mentions(&message, &["v_s_start must be a positive number, got -1"]);
    let frf = parse_frf_csv(
        "frf.csv",
        "freq_Hz,mag_m_per_N\n10,1e-6\n20,2e-6\n30,1e-6\n40,1e-7\n",
        &UnitOverrides::default(),
    )
    .unwrap();
    let message = fit_frf(&frf, &FrfOptions::with_mass(0.0))
        .unwrap_err()
        .to_string();
    assert_mentions(&message, &["mass must be a positive number, got 0"]);
}

#[test]
fn leading_phase_is_rejected_as_a_sign_convention_problem() {
    let p = fistage_model::LugreParams::paper_table1();
    let mut data = fistage_ident::synth::FrfSynth::clean(&p, 1.5).generate();
    for g in &mut data.response {
        *g = g.conj();
    }
    let message = fit_frf(&data, &FrfOptions::with_mass(1.5))
        .unwrap_err()
        .to_string();
    assert_mentions(
        &message,
        &[
            "synthetic",
            "column 'response'",
            "opposite sign convention",
            "--magnitude-only",
        ],
    );
    // The magnitude alone is still usable.
    let options = FrfOptions {
        use_phase: false,
        ..FrfOptions::with_mass(1.5)
    };
    let fit = fit_frf(&data, &options).unwrap();
    assert!((fit.sigma0.value / p.sigma0 - 1.0).abs() < 1e-6);
}

//! Record identification on simulated lab records: clean recovery of all six
//! LuGre parameters and the mass, the same answer from starts 50% off,
//! convergence under a tighter plant tolerance, and bad input named by
//! file, column and row.

use fistage_ident::UnitOverrides;
use fistage_ident::csv_input::parse_record_csv;
use fistage_ident::record::{
    RecordOptions, RecordParam, RecordSynth, Theta, fit_record, parse_record_mat,
};
use fistage_ident::synth::small_stage;
use fistage_model::LugreParams;

fn worst_relative(fit: &Theta, truth: &Theta) -> (f64, &'static str) {
    RecordParam::ALL
        .iter()
        .map(|p| ((fit.get(*p) / truth.get(*p) - 1.0).abs(), p.name()))
        .fold((0.0, ""), |a, b| if b.0 > a.0 { b } else { a })
}

/// Table 1 (mass fitted) and a small stage far from it (mass known): every
/// parameter to 1e-4 from a 1 nm encoder, each inside its interval.
#[test]
fn clean_records_give_every_parameter() {
    for (truth, mass, known) in [
        (LugreParams::paper_table1(), 1.5, false),
        (small_stage(), 0.25, true),
    ] {
        let (record, _) = RecordSynth::new(truth, mass).generate().unwrap();
        let options = RecordOptions {
            mass: if known {
                fistage_ident::record::MassChoice::Known(mass)
            } else {
                fistage_ident::record::MassChoice::Fit
            },
            ..RecordOptions::default()
        };
        let fit = fit_record(&record, &options, &mut |_| true).unwrap();
        let exact = Theta::new(&truth, mass);
        let (worst, name) = worst_relative(&fit.theta, &exact);
        assert!(worst < 1e-4, "{name} off by {worst:e}");
        assert!(fit.residuals.rms < 1e-9, "rms {}", fit.residuals.rms);
        for p in &fit.free {
            let e = fit.estimate(*p);
            assert!(e.std_error.is_some_and(|s| s > 0.0), "{}", p.name());
        }
    }
}

/// Starts 50% off in every parameter, alternately up and down, come back to
/// the fit from the record's own start.
#[test]
fn starts_fifty_percent_off_give_the_same_answer() {
    let truth = LugreParams::paper_table1();
    let (record, _) = RecordSynth::new(truth, 1.5).generate().unwrap();
    let reference = fit_record(&record, &RecordOptions::default(), &mut |_| true).unwrap();
    let exact = Theta::new(&truth, 1.5);
    for pattern in [
        [1.5, 0.5, 1.5, 0.5, 1.5, 0.5, 1.5],
        [0.5, 1.5, 0.5, 1.5, 0.5, 1.5, 0.5],
    ] {
        let mut start = exact;
        for (v, f) in start.0.iter_mut().zip(pattern) {
            *v *= f;
        }
        let options = RecordOptions {
            start: Some(start),
            ..RecordOptions::default()
        };
        let fit = fit_record(&record, &options, &mut |_| true).unwrap();
        let (worst, name) = worst_relative(&fit.theta, &reference.theta);
        assert!(worst < 1e-4, "{pattern:?}: {name} off by {worst:e}");
    }
}

/// The fit does not depend on the time origin: the same record on a lab's
/// clock that stood at 1e4 s (where the smallest step relative to the time
/// once refused the steps of a breakaway) gives the fit of the record from 0.
#[test]
fn a_lab_clock_far_from_zero_gives_the_same_fit() {
    let (record, _) = RecordSynth::new(LugreParams::paper_table1(), 1.5)
        .generate()
        .unwrap();
    let reference = fit_record(&record, &RecordOptions::default(), &mut |_| true).unwrap();
    for origin in [1e4, 1e6] {
        let mut shifted = record.clone();
        for t in &mut shifted.time {
            *t += origin;
        }
        let fit = fit_record(&shifted, &RecordOptions::default(), &mut |_| true)
            .unwrap_or_else(|e| panic!("clock at {origin:e} s: {e}"));
        let (worst, name) = worst_relative(&fit.theta, &reference.theta);
        // The shifted times carry the round-off of the addition (1e-16 of
        // the origin), a sub-nanosecond jitter of the samples.
        assert!(
            worst < 1e-4,
            "clock at {origin:e} s: {name} off by {worst:e}"
        );
    }
}

/// The fit does not depend on the plant tolerance: 1e-8 and 1e-10 agree to
/// well inside the 0.2% asked of a clean record.
#[test]
fn a_tighter_plant_tolerance_changes_nothing() {
    let (record, _) = RecordSynth::new(small_stage(), 0.25).generate().unwrap();
    let fits: Vec<Theta> = [1e-8, 1e-10]
        .iter()
        .map(|&rtol| {
            let options = RecordOptions {
                rtol,
                ..RecordOptions::default()
            };
            fit_record(&record, &options, &mut |_| true).unwrap().theta
        })
        .collect();
    let (worst, name) = worst_relative(&fits[0], &fits[1]);
    assert!(worst < 1e-4, "{name}: {worst:e}");
}

#[test]
fn bad_records_are_named_by_file_column_and_row() {
    let units = UnitOverrides::default();
    let mut text = String::from("t_s,f_servo_N,x_nm\n");
    for k in 0..30 {
        let t = if k == 12 { 0.0011 } else { k as f64 * 1e-4 };
        text += &format!("{t},0.0,0\n");
    }
    let e = parse_record_csv("lab.csv", &text, &units)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("lab.csv") && e.contains("line 14") && e.contains("'t_s'"),
        "{e}"
    );
    let e = parse_record_csv("lab.csv", "t_s,force_N,y_nm\n0,0,0\n", &units)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no position column") && e.contains("x_nm"),
        "{e}"
    );
    let e = parse_record_csv("lab.csv", "t_s,force_N,x_furlong\n0,0,0\n", &units)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("'x_furlong'") && e.contains("unknown position unit"),
        "{e}"
    );
    let e = parse_record_mat("lab.mat", b"not a mat file", &units)
        .unwrap_err()
        .to_string();
    assert!(e.contains("lab.mat") && e.contains("not a MAT-file"), "{e}");
}

/// A record written as a MAT-file by the program's own writer reads back
/// with the same values.
#[test]
fn mat_records_read_back() {
    let (record, _) = RecordSynth::new(small_stage(), 0.25).generate().unwrap();
    let mut bytes = Vec::new();
    fistage_model::mat::write_columns(
        &mut bytes,
        &[
            ("t_s", &record.time),
            ("f_servo_N", &record.force),
            (
                "x_nm",
                &record.position.iter().map(|x| x * 1e9).collect::<Vec<_>>(),
            ),
        ],
    )
    .unwrap();
    let back = parse_record_mat("r.mat", &bytes, &UnitOverrides::default()).unwrap();
    assert_eq!(back.time, record.time);
    assert_eq!(back.force, record.force);
    for (a, b) in back.position.iter().zip(&record.position) {
        assert!((a - b).abs() <= 1e-15 * b.abs(), "{a} {b}");
    }
}

/// Monte Carlo coverage on records with an unmeasured force (0.01 N RMS,
/// 50 ms): the block-jackknife 95% intervals hold the truth in nearly all of
/// six seeded records (95% asked; the test allows 36 of 42 parameter
/// intervals and 4 of 6 for each parameter; measured 40, f_s the weakest
/// at 4), where Jacobian-only intervals,
/// blind to the correlation of the residuals, hold it in almost none. (The
/// bench measures 20 records: `fistage bench --record`.)
#[test]
fn intervals_hold_on_disturbed_records() {
    let truth = LugreParams::paper_table1();
    let exact = Theta::new(&truth, 1.5);
    // The six fits are independent: two at a time, so that this test is not
    // the suite's longest by itself.
    let fits: Vec<_> = std::thread::scope(|scope| {
        let workers: Vec<_> = [1..=3u64, 4..=6u64]
            .into_iter()
            .map(|seeds| {
                scope.spawn(move || {
                    seeds
                        .map(|seed| {
                            let synth = RecordSynth {
                                errors: fistage_ident::record::LabErrors {
                                    disturbance_rms: 0.01,
                                    seed,
                                    ..fistage_ident::record::LabErrors::encoder()
                                },
                                ..RecordSynth::new(truth, 1.5)
                            };
                            let (record, _) = synth.generate().unwrap();
                            fit_record(&record, &RecordOptions::default(), &mut |_| true).unwrap()
                        })
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        workers
            .into_iter()
            .flat_map(|worker| worker.join().expect("a fit thread"))
            .collect()
    });
    assert_eq!(fits.len(), 6);
    let mut covered = [0usize; 7];
    let mut covered_iid = 0;
    for fit in &fits {
        for (j, p) in RecordParam::ALL.iter().enumerate() {
            let t = exact.get(*p);
            let e = fit.estimate(*p);
            covered[j] += usize::from(e.covers(t));
            let iid = fit.iid_std_errors[j].expect("a Jacobian-only error");
            covered_iid += usize::from((e.value - t).abs() <= 1.96 * iid);
        }
    }
    let total: usize = covered.iter().sum();
    assert!(
        total >= 36,
        "jackknife intervals covered {total} of 42: {covered:?}"
    );
    assert!(
        covered.iter().all(|&c| c >= 4),
        "per parameter: {covered:?}"
    );
    assert!(
        covered_iid <= 12,
        "Jacobian-only intervals covered {covered_iid} of 42"
    );
}

/// A fit stopped by its iteration limit is no answer: the report names every
/// fitted parameter, so the program refuses it.
#[test]
fn an_unconverged_fit_is_named() {
    let (record, _) = RecordSynth::new(small_stage(), 0.25).generate().unwrap();
    let options = RecordOptions {
        max_iterations: 1,
        ..RecordOptions::default()
    };
    let fit = fit_record(&record, &options, &mut |_| true).unwrap();
    assert!(!fit.converged);
    let report = fistage_ident::record::RecordReport::new(&record, &fit);
    assert_eq!(
        report.not_identifiable.len(),
        7,
        "{:?}",
        report.not_identifiable
    );
    assert!(
        report
            .not_identifiable
            .iter()
            .any(|n| n.reason.contains("did not converge")),
        "{:?}",
        report.not_identifiable
    );
}

/// `fit.json` carries the fit's joint uncertainty, and it agrees with the
/// fit's other outputs: the covariance's diagonal is the square of each
/// standard error, the SI matrix is the logarithmic one scaled by the
/// values, and the replicates' spread is the jackknife covariance (the
/// identity `(G-1)/G sum_b d_b d_b^T` it was formed from, recomputed here
/// from the written replicates). The paths name the chosen element.
#[test]
fn the_report_carries_the_joint_covariance_and_the_replicates() {
    let (record, _) = RecordSynth::new(small_stage(), 0.25).generate().unwrap();
    let fit = fit_record(&record, &RecordOptions::default(), &mut |_| true).unwrap();
    let report = fistage_ident::record::RecordReport::new(&record, &fit).for_element("rail_1");
    let text = serde_json::to_string(&report).unwrap();
    let read: fistage_ident::record::RecordReport = serde_json::from_str(&text).unwrap();
    let covariance = read.covariance.clone().expect("a covariance");
    covariance.check().unwrap();
    let p = covariance.len();
    assert_eq!(p, fit.free.len());
    for (k, name) in covariance.parameters.iter().enumerate() {
        let param = read
            .params()
            .into_iter()
            .find(|(n, _)| n == name)
            .unwrap()
            .1;
        let se = param.std_error.expect("a standard error");
        let diagonal = covariance.matrix[k][k].sqrt();
        assert!(
            (diagonal / se - 1.0).abs() < 1e-9,
            "{name}: sqrt(diag) {diagonal:e} against std_error {se:e}"
        );
        assert_eq!(covariance.values[k], param.value);
        let expected = (name != "mass").then(|| format!("overrides.rail_1.{name}"));
        assert_eq!(covariance.paths[k], expected);
        for j in 0..p {
            let scaled = covariance.values[k] * covariance.log_matrix[k][j] * covariance.values[j];
            assert!((covariance.matrix[k][j] - scaled).abs() <= 1e-12 * scaled.abs().max(1e-300));
        }
    }
    let g = read.replicates.len();
    assert_eq!(g, fit.blocks, "one replicate per block");
    for i in 0..p {
        for j in 0..p {
            let sum: f64 = read
                .replicates
                .iter()
                .map(|r| (r[i] / covariance.values[i]).ln() * (r[j] / covariance.values[j]).ln())
                .sum();
            let from_replicates = sum * (g as f64 - 1.0) / g as f64;
            let written = covariance.log_matrix[i][j];
            assert!(
                (from_replicates - written).abs()
                    <= 1e-9 * (covariance.log_matrix[i][i] * covariance.log_matrix[j][j]).sqrt(),
                "[{i}][{j}]: {from_replicates:e} from the replicates, {written:e} written"
            );
        }
    }
}

//! The JSON report names every parameter with its SI value and 95% interval;
//! the override is valid TOML that a scenario can include; the plotting CSVs
//! hold the data and the fit.

use fistage_ident::report::{
    frf_curve_csv, frf_data_vs_fit_csv, stribeck_curve_csv, stribeck_data_vs_fit_csv,
};
use fistage_ident::synth::{FrfSynth, StribeckSynth, TABLE1_MASS};
use fistage_ident::{
    FrfOptions, FrfReport, Sigma2Input, StribeckOptions, StribeckReport, fit_frf, fit_stribeck,
    fit_stribeck_asymmetric, frf_override, stribeck_override,
};
use fistage_model::LugreParams;
use serde_json::Value;

fn check_param(json: &Value, name: &str) -> (f64, [f64; 2]) {
    let p = &json[name];
    let value = p["value"]
        .as_f64()
        .unwrap_or_else(|| panic!("{name}.value missing in {json}"));
    let ci = p["ci95"]
        .as_array()
        .unwrap_or_else(|| panic!("{name}.ci95 missing"));
    assert_eq!(ci.len(), 2);
    let (lo, hi) = (ci[0].as_f64().unwrap(), ci[1].as_f64().unwrap());
    assert!(
        lo <= value && value <= hi,
        "{name}: {value} not in [{lo}, {hi}]"
    );
    (value, [lo, hi])
}

#[test]
fn stribeck_json_and_override() {
    let p = LugreParams::paper_table1();
    let data = StribeckSynth::noisy(p, 2).generate();
    let asym = fit_stribeck_asymmetric(&data, &StribeckOptions::default()).unwrap();
    let report = StribeckReport::new("fss.csv", &asym.symmetric, Some(&asym));
    let json: Value = serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
    assert_eq!(json["kind"], "stribeck");
    assert_eq!(json["loss"], "l2");
    let (v_s, _) = check_param(&json, "v_s");
    assert!((v_s / p.v_s - 1.0).abs() < 0.05, "v_s in SI (m/s): {v_s}");
    for name in ["f_c", "f_s", "sigma2"] {
        check_param(&json, name);
    }
    assert_eq!(json["residuals"]["n"], 80);
    assert!(json["residuals"]["rms"].as_f64().unwrap() > 0.0);
    let asymmetry = &json["asymmetry"];
    assert_eq!(asymmetry["test"], "F");
    assert!(asymmetry["p_value"].as_f64().unwrap() > 0.05);
    assert_eq!(asymmetry["significant"], false);
    check_param(&asymmetry["negative"], "f_c");

    let text = stribeck_override("bearing_rl", &report);
    let parsed: toml::Table = toml::from_str(&text).unwrap();
    let element = &parsed["overrides"]["bearing_rl"];
    for name in ["f_c", "f_s", "v_s", "sigma2"] {
        assert_eq!(
            element[name].as_float().unwrap(),
            json[name]["value"].as_f64().unwrap(),
            "{text}"
        );
    }
    assert!(element.get("sigma0").is_none());
    // Element names that are not bare keys are quoted.
    let parsed: toml::Table = toml::from_str(&stribeck_override("rear left", &report)).unwrap();
    assert!(parsed["overrides"]["rear left"]["f_c"].is_float());

    let table = report.table();
    for word in [
        "f_c",
        "f_s",
        "v_s",
        "sigma2",
        "95% interval",
        "Asymmetry: F test",
        "not significant",
    ] {
        assert!(table.contains(word), "{table}");
    }
}

#[test]
fn frf_json_and_override() {
    let p = LugreParams::paper_table1();
    let data = FrfSynth::noisy(&p, TABLE1_MASS, 2).generate();
    let options = FrfOptions {
        sigma2: Some(Sigma2Input {
            value: 14.2,
            ci95: Some([13.9, 14.5]),
        }),
        ..FrfOptions::default()
    };
    let fit = fit_frf(&data, &options).unwrap();
    let report = FrfReport::new("frf.csv", &fit);
    let json: Value = serde_json::from_str(&serde_json::to_string(&report).unwrap()).unwrap();
    assert_eq!(json["kind"], "frf");
    let (sigma0, _) = check_param(&json, "sigma0");
    assert!((sigma0 / p.sigma0 - 1.0).abs() < 0.02);
    let (sigma1, [lo, hi]) = check_param(&json, "sigma1");
    let (damping, [dlo, dhi]) = check_param(&json, "sigma1_plus_sigma2");
    assert!((sigma1 - (damping - 14.2)).abs() < 1e-12);
    // sigma1's interval includes sigma2's uncertainty.
    assert!(hi - lo > dhi - dlo);
    assert_eq!(check_param(&json, "sigma2"), (14.2, [13.9, 14.5]));
    check_param(&json, "mass");
    assert_eq!(json["mass_fitted"], true);

    let text = frf_override("bearing_friction", &report, None);
    let parsed: toml::Table = toml::from_str(&text).unwrap();
    let element = &parsed["overrides"]["bearing_friction"];
    assert_eq!(element["sigma0"].as_float().unwrap(), sigma0);
    assert_eq!(element["sigma1"].as_float().unwrap(), sigma1);
    assert!(
        element.get("sigma2").is_none(),
        "sigma2 belongs to the Stribeck override"
    );

    // With the Stribeck report the override holds all six LuGre parameters.
    let stribeck_data = StribeckSynth::noisy(p, 2).generate();
    let stribeck_fit = fit_stribeck(&stribeck_data, &StribeckOptions::default()).unwrap();
    let stribeck = StribeckReport::new("fss.csv", &stribeck_fit, None);
    let text = frf_override("bearing_friction", &report, Some(&stribeck));
    let parsed: toml::Table = toml::from_str(&text).unwrap();
    let element = parsed["overrides"]["bearing_friction"].as_table().unwrap();
    let mut keys: Vec<&str> = element.keys().map(String::as_str).collect();
    keys.sort_unstable();
    assert_eq!(keys, ["f_c", "f_s", "sigma0", "sigma1", "sigma2", "v_s"]);
    assert_eq!(element["sigma2"].as_float().unwrap(), stribeck.sigma2.value);

    // Without sigma2 the override holds sigma0 only and says why.
    let fit = fit_frf(&data, &FrfOptions::with_mass(TABLE1_MASS)).unwrap();
    let report = FrfReport::new("frf.csv", &fit);
    let json: Value = serde_json::to_value(&report).unwrap();
    assert!(json.get("sigma1").is_none());
    assert_eq!(
        json["mass"]["ci95"],
        serde_json::json!([TABLE1_MASS, TABLE1_MASS])
    );
    let text = frf_override("bearing_friction", &report, None);
    let parsed: toml::Table = toml::from_str(&text).unwrap();
    assert!(
        parsed["overrides"]["bearing_friction"]
            .get("sigma1")
            .is_none()
    );
    assert!(text.contains("sigma1 needs sigma2"));
    assert!(report.table().contains("warning: sigma1 is not separated"));
}

#[test]
fn plotting_csvs_hold_data_and_fit() {
    let p = LugreParams::paper_table1();
    let data = StribeckSynth::noisy(p, 2).generate();
    let fit = fit_stribeck(&data, &StribeckOptions::default()).unwrap();
    let text = stribeck_data_vs_fit_csv(&data, &fit);
    assert_eq!(text.lines().count(), data.len() + 1);
    assert!(text.starts_with("line,velocity_m_per_s,force_N,fit_force_N,residual_N\n2,"));
    let curve = stribeck_curve_csv(&data, &fit, 400);
    assert_eq!(curve.lines().count(), 401);

    let data = FrfSynth::noisy(&p, TABLE1_MASS, 2).generate();
    let fit = fit_frf(&data, &FrfOptions::with_mass(TABLE1_MASS)).unwrap();
    let text = frf_data_vs_fit_csv(&data, &fit);
    assert_eq!(text.lines().count(), data.len() + 1);
    // Measured phases sit next to the model's (no 360 degree jumps).
    for line in text.lines().skip(1) {
        let cells: Vec<f64> = line.split(',').map(|c| c.parse().unwrap()).collect();
        assert!((cells[3] - cells[5]).abs() < 5.0, "{line}");
    }
    assert_eq!(frf_curve_csv(&data, &fit, 200).lines().count(), 201);
}

/// Data that cannot determine the parameters name them as not identifiable,
/// and the override leaves them out; good data name none.
#[test]
fn undetermined_parameters_are_named_and_not_written() {
    let p = LugreParams::paper_table1();
    let good = StribeckSynth::noisy(p, 2).generate();
    let fit = fit_stribeck(&good, &StribeckOptions::default()).unwrap();
    let report = StribeckReport::new("fss.csv", &fit, None);
    assert!(
        report.not_identifiable.is_empty(),
        "{:?}",
        report.not_identifiable
    );
    let mut zero = good.clone();
    zero.force.iter_mut().for_each(|f| *f = 0.0);
    let mut huge = good.clone();
    huge.force.iter_mut().for_each(|f| *f *= 1e300);
    for (case, data) in [("all-zero forces", zero), ("forces x 1e300", huge)] {
        let Ok(fit) = fit_stribeck(&data, &StribeckOptions::default()) else {
            continue; // refusing to fit at all is a clear answer too
        };
        let report = StribeckReport::new("bad.csv", &fit, None);
        assert!(
            !report.not_identifiable.is_empty(),
            "{case}: every parameter passed"
        );
        let toml_text = stribeck_override("bearing_friction", &report);
        let table: toml::Table = toml_text.parse().expect("valid TOML");
        let written = table["overrides"]["bearing_friction"]
            .as_table()
            .expect("table");
        for item in &report.not_identifiable {
            assert!(
                !written.contains_key(&item.parameter),
                "{case}: {} written although not identifiable",
                item.parameter
            );
            assert!(toml_text.contains("not identifiable"), "{case}");
        }
    }
}

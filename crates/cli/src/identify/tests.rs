//! `fistage identify` parsed and run end to end: flags, files written,
//! refusals.

use super::*;
use clap::Parser;
use std::path::{Path, PathBuf};

use fistage_ident::{Quantity, StribeckOptions, UnitOverrides, fit_stribeck, read_stribeck_csv};

use fistage_ident::synth::{FrfCsvLayout, FrfSynth, StribeckSynth, frf_csv, stribeck_csv, unit};
use fistage_model::LugreParams;
use fistage_plot::figures::curve::stribeck_plot;

#[derive(Parser)]
struct TestCli {
    #[command(subcommand)]
    command: TestCommand,
}

#[derive(Subcommand)]
enum TestCommand {
    Identify(IdentifyArgs),
}

fn parse(line: &str) -> std::result::Result<IdentifyArgs, clap::Error> {
    let words = std::iter::once("fistage").chain(line.split_whitespace());
    TestCli::try_parse_from(words).map(|cli| match cli.command {
        TestCommand::Identify(args) => args,
    })
}

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fistage-identify-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn flags_parse_and_conflict() {
    assert!(parse("identify stribeck d.csv --robust --asymmetric --json --element rl").is_ok());
    assert!(parse("identify frf d.csv --mass 1.5 --sigma2 14.2 --json").is_ok());
    assert!(parse("identify frf d.csv --fit-mass").is_ok());
    assert!(parse("identify frf d.csv --mass 1.5 --fit-mass").is_err());
    assert!(parse("identify stribeck d.csv --robust --loss l1").is_err());
    assert!(parse("identify stribeck d.csv --asymmetric --one-sided").is_err());
    assert!(parse("identify frf d.csv --sigma2-ci95 1,2").is_err());
}

#[test]
fn stribeck_then_frf_write_their_files() {
    let dir = scratch("chain");
    let p = LugreParams::paper_table1();
    let fss = dir.join("fss.csv");
    let data = StribeckSynth::noisy(p, 5).generate();
    let text = stribeck_csv(
        &data,
        unit(Quantity::Velocity, "mm/s"),
        unit(Quantity::Force, "N"),
    );
    std::fs::write(&fss, text).unwrap();
    let out_s = dir.join("stribeck");
    let line = format!(
        "identify stribeck {} --asymmetric --out {}",
        fss.display(),
        out_s.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_s.join("fit.json")).unwrap()).unwrap();
    let f_c = json["f_c"]["value"].as_f64().unwrap();
    assert!((f_c / p.f_c - 1.0).abs() < 0.02, "{json}");
    assert_eq!(json["asymmetry"]["significant"], false);
    for name in [
        "override.toml",
        "data_vs_fit.csv",
        "fit_curve.csv",
        "fit.svg",
        "fit.png",
    ] {
        assert!(out_s.join(name).is_file(), "{name}");
    }
    let svg = std::fs::read_to_string(out_s.join("fit.svg")).unwrap();
    for text in [
        "sliding velocity v [mm/s]",
        "steady-state friction force f_ss [N]",
        "measured",
        "fit (l2)",
        "fit of v &gt; 0 alone",
        "fit of v &lt; 0 alone",
    ] {
        assert!(svg.contains(text), "fit.svg lacks {text}");
    }
    assert_png(&out_s.join("fit.png"));

    let frf = dir.join("frf.csv");
    let data = FrfSynth::noisy(&p, 1.5, 5).generate();
    let layout = FrfCsvLayout::MagnitudePhase(
        unit(Quantity::Magnitude, "dB"),
        unit(Quantity::Phase, "deg"),
    );
    std::fs::write(
        &frf,
        frf_csv(&data, unit(Quantity::Frequency, "Hz"), layout),
    )
    .unwrap();
    let out_f = dir.join("frf");
    let line = format!(
        "identify frf {} --mass 1.5 --sigma2-from {} --element bearing_rl --out {}",
        frf.display(),
        out_s.join("fit.json").display(),
        out_f.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_f.join("fit.json")).unwrap()).unwrap();
    let sigma1 = json["sigma1"]["value"].as_f64().unwrap();
    assert!((sigma1 / p.sigma1 - 1.0).abs() < 0.05, "{json}");
    let svg = std::fs::read_to_string(out_f.join("fit.svg")).unwrap();
    for text in [
        "frequency [Hz]",
        "magnitude [dB]",
        "phase [",
        "measured",
        "fit: sigma0",
    ] {
        assert!(svg.contains(text), "fit.svg lacks {text}");
    }
    assert_png(&out_f.join("fit.png"));
    let toml = std::fs::read_to_string(out_f.join("override.toml")).unwrap();
    assert!(toml.contains("[overrides.bearing_rl]"), "{toml}");
    for key in [
        "sigma0 =", "sigma1 =", "f_c =", "f_s =", "v_s =", "sigma2 =",
    ] {
        assert!(toml.contains(key), "{toml}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A PNG file of some substance.
fn assert_png(path: &Path) {
    let bytes = std::fs::read(path).unwrap();
    assert!(bytes.starts_with(b"\x89PNG"), "{}", path.display());
    assert!(
        bytes.len() > 10_000,
        "{}: {} bytes",
        path.display(),
        bytes.len()
    );
}

#[test]
fn plots_flag_outliers_and_skip_a_missing_phase() {
    let dir = scratch("plots");
    let p = LugreParams::paper_table1();
    let (data, outliers) = StribeckSynth::noisy(p, 2)
        .with_outliers(3, p.f_c)
        .generate_with_outliers();
    let fss = dir.join("fss.csv");
    let text = stribeck_csv(
        &data,
        unit(Quantity::Velocity, "um/s"),
        unit(Quantity::Force, "N"),
    );
    std::fs::write(&fss, text).unwrap();
    let out = dir.join("robust");
    let line = format!(
        "identify stribeck {} --robust --out {}",
        fss.display(),
        out.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let svg = std::fs::read_to_string(out.join("fit.svg")).unwrap();
    assert!(svg.contains("suspected outliers (huber fit)"), "{svg}");
    assert!(svg.contains("fit (huber)"));
    assert!(!svg.contains("alone"));
    // The plot's outlier series holds exactly the injected points.
    let read = read_stribeck_csv(&fss, &UnitOverrides::default()).unwrap();
    let fit = fit_stribeck(&read, &StribeckOptions::robust()).unwrap();
    let plot = stribeck_plot(&read, &fit, None);
    let flagged = &plot.series[1];
    assert_eq!(flagged.x.len(), outliers.len());
    for &i in &outliers {
        assert!(
            flagged
                .x
                .iter()
                .any(|&v| (v - read.velocity[i] * 1e3).abs() < 1e-9),
            "point {i}"
        );
    }
    assert_eq!(
        plot.series[0].x.len() + flagged.x.len(),
        read.len(),
        "every point is drawn once"
    );

    let frf = dir.join("frf.csv");
    let data = FrfSynth::noisy(&p, 1.5, 3).generate();
    let layout = FrfCsvLayout::Magnitude(unit(Quantity::Magnitude, "um/N"));
    std::fs::write(
        &frf,
        frf_csv(&data, unit(Quantity::Frequency, "Hz"), layout),
    )
    .unwrap();
    let out = dir.join("frf");
    let line = format!(
        "identify frf {} --mass 1.5 --out {}",
        frf.display(),
        out.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let svg = std::fs::read_to_string(out.join("fit.svg")).unwrap();
    assert!(svg.contains("magnitude [dB]"));
    assert!(
        !svg.contains("phase ["),
        "no phase panel without phase data"
    );
    assert_png(&out.join("fit.png"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The stage's own simulation as the lab: measure, then identify from the
/// written files; Table 1 comes back within a few percent.
#[test]
fn simulated_measurements_identify_table1() {
    let dir = scratch("simulated");
    let robot = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/stage_1dof_rigid.urdf");
    let fss = dir.join("fss.csv");
    let line = format!(
        "identify simulate-stribeck {} --out {} --points 12 --seed 3",
        robot.display(),
        fss.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let header = std::fs::read_to_string(&fss).unwrap();
    assert!(
        header.starts_with("velocity_mm_per_s,force_N\n"),
        "{header}"
    );
    assert_eq!(header.lines().count(), 25);
    let out_s = dir.join("stribeck");
    let line = format!(
        "identify stribeck {} --out {}",
        fss.display(),
        out_s.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_s.join("fit.json")).unwrap()).unwrap();
    let p = LugreParams::paper_table1();
    for (key, truth, tolerance) in [
        ("f_c", p.f_c, 0.01),
        ("f_s", p.f_s, 0.01),
        ("v_s", p.v_s, 0.05),
        ("sigma2", p.sigma2, 0.03),
    ] {
        let value = json[key]["value"].as_f64().unwrap();
        assert!((value / truth - 1.0).abs() < tolerance, "{key}: {json}");
    }

    let frf = dir.join("frf.csv");
    let line = format!(
        "identify simulate-frf {} --out {} --points 20",
        robot.display(),
        frf.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let out_f = dir.join("frf");
    let line = format!(
        "identify frf {} --mass 1.5 --sigma2-from {} --out {}",
        frf.display(),
        out_s.join("fit.json").display(),
        out_f.display()
    );
    run(&parse(&line).unwrap()).unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_f.join("fit.json")).unwrap()).unwrap();
    let sigma0 = json["sigma0"]["value"].as_f64().unwrap();
    let sigma1 = json["sigma1"]["value"].as_f64().unwrap();
    assert!((sigma0 / p.sigma0 - 1.0).abs() < 0.01, "{json}");
    assert!((sigma1 / p.sigma1 - 1.0).abs() < 0.06, "{json}");
    assert!(out_f.join("fit.svg").is_file());

    // Bad ranges are refused before anything runs or is written.
    let bad = dir.join("bad.csv");
    let line = format!(
        "identify simulate-frf {} --out {} --f-min 100 --f-max 10",
        robot.display(),
        bad.display()
    );
    let message = run(&parse(&line).unwrap()).unwrap_err().to_string();
    assert!(message.contains("--f-min"), "{message}");
    assert!(!bad.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_failed_fit_writes_nothing() {
    let dir = scratch("fail");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "velocity_mm_per_s,force_N\n1,6.4\n2,x\n").unwrap();
    let out = dir.join("out");
    let line = format!(
        "identify stribeck {} --out {}",
        bad.display(),
        out.display()
    );
    let message = run(&parse(&line).unwrap()).unwrap_err().to_string();
    assert!(
        message.contains("bad.csv: line 3 (data row 2), column 'force_N'"),
        "{message}"
    );
    assert!(!out.exists());
    let line = format!(
        "identify stribeck {} --velocity-unit furlong/s",
        bad.display()
    );
    let message = run(&parse(&line).unwrap()).unwrap_err().to_string();
    assert!(
        message.contains("--velocity-unit: 'furlong/s' is not a velocity unit"),
        "{message}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A stage fit's records and paths are checked against the stage before
/// anything is fitted: a path that names nothing, a column no sensor reads,
/// several records without --stage, all refused by name; and the flags parse.
#[test]
fn stage_fits_refuse_what_does_not_fit_the_stage() {
    let dir = scratch("stage-refusals");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let scenario = root.join("scenarios/paper/fig05b_fi.toml");
    let record = dir.join("record.csv");
    let mut text = String::from("t_s,f_servo_N,x_nm,bearing_nm\n");
    for k in 0..100 {
        text += &format!("{},0,0,0\n", k as f64 * 1e-4);
    }
    std::fs::write(&record, text).unwrap();
    let line = |extra: &str| {
        format!(
            "identify record {} --stage {} {extra}",
            record.display(),
            scenario.display()
        )
    };
    assert!(parse(&line("")).is_err(), "--stage needs --fit");
    assert!(
        parse(&format!(
            "identify record {} --fit overrides.isolator.k_x",
            record.display()
        ))
        .is_err()
    );
    let run_line = |extra: &str| -> String {
        let IdentifyCommand::Record(args) = parse(&line(extra)).expect("parses").fit else {
            panic!("a record fit");
        };
        format!("{:#}", run_record(&args).expect_err("refused"))
    };
    let message = run_line("--fit overrides.nothing.k_x");
    assert!(message.contains("nothing"), "{message}");
    // The one-mass fit's flags are refused by name, not ignored.
    for flag in [
        "--mass 1.5",
        "--fit-mass",
        "--segments s.csv",
        "--start-velocity 0.1",
        "--start-bristle 1e-6",
        "--element rail",
        "--closed-loop other.toml",
    ] {
        let message = run_line(&format!("--fit overrides.isolator.k_x {flag}"));
        let name = flag.split_whitespace().next().unwrap_or(flag);
        assert!(
            message.contains(name) && message.contains("one-mass fit's"),
            "{flag}: {message}"
        );
    }
    let message = run_line("--fit overrides.isolator.k_x --horizon 0");
    assert!(message.contains("--horizon"), "{message}");
    // An earlier result in --out is refused, and kept.
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("fit.json"), "earlier").unwrap();
    let message = run_line(&format!(
        "--fit overrides.isolator.k_x --out {}",
        out.display()
    ));
    assert!(message.contains("earlier result"), "{message}");
    assert_eq!(
        std::fs::read_to_string(out.join("fit.json")).unwrap(),
        "earlier"
    );
    let message = run_line("--fit overrides.isolator.k_x,overrides.bearing_friction.f_c");
    assert!(
        message.contains("bearing_nm") && message.contains("no sensor 'bearing'"),
        "{message}"
    );
    let IdentifyCommand::Record(args) = parse(&format!(
        "identify record {} {}",
        record.display(),
        record.display()
    ))
    .expect("parses")
    .fit
    else {
        panic!("a record fit");
    };
    let message = format!("{:#}", run_record(&args).expect_err("refused"));
    assert!(message.contains("takes one record"), "{message}");
}

/// A stage fit end to end: a record of the FI stage made by
/// `simulate-record`, fitted for the isolator's stiffness from 20% off,
/// writes fit.json, override.toml and data_vs_fit.csv, whose residual
/// column is the simulated minus the measured reading on every row and
/// whose RMS is the one fit.json reports.
#[test]
fn a_stage_fit_writes_its_data_against_the_fit() {
    let dir = scratch("stage-files");
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let robot = root.join("robots/stage_1dof_fi.urdf");
    let truth = dir.join("truth.toml");
    let start = dir.join("start.toml");
    let robot_line = format!(
        "robot = {:?}\nduration = 1.0\n",
        robot.display().to_string()
    );
    std::fs::write(&truth, &robot_line).unwrap();
    std::fs::write(
        &start,
        format!("{robot_line}[overrides.isolator]\nk_x = 4.8e4\n"),
    )
    .unwrap();
    let record = dir.join("record.csv");
    run(&parse(&format!(
        "identify simulate-record {} --rate 2000 --seed 4 --out {}",
        truth.display(),
        record.display()
    ))
    .unwrap())
    .unwrap();
    let out = dir.join("fit");
    run(&parse(&format!(
        "identify record {} --stage {} --fit overrides.isolator.k_x --out {}",
        record.display(),
        start.display(),
        out.display()
    ))
    .unwrap())
    .unwrap();
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("fit.json")).unwrap()).unwrap();
    let k_x = json["parameters"][0]["value"].as_f64().unwrap();
    assert!((k_x / 4e4 - 1.0).abs() < 1e-4, "{k_x}");
    assert!(
        std::fs::read_to_string(out.join("override.toml"))
            .unwrap()
            .contains("k_x")
    );
    let mut reader = csv::Reader::from_path(out.join("data_vs_fit.csv")).unwrap();
    let header = reader.headers().unwrap().clone();
    assert_eq!(
        header.iter().collect::<Vec<_>>(),
        [
            "record",
            "t_s",
            "force_N",
            "sensor",
            "measured_m",
            "simulated_m",
            "residual_m"
        ]
    );
    let (mut rows, mut squares) = (0usize, 0.0);
    for row in reader.records() {
        let row = row.unwrap();
        let number = |i: usize| row[i].parse::<f64>().unwrap();
        let (measured, simulated, residual) = (number(4), number(5), number(6));
        assert_eq!(residual, simulated - measured);
        assert_eq!(&row[3], "encoder");
        squares += residual * residual;
        rows += 1;
    }
    assert_eq!(rows, 14_000, "7 s at 2 kHz, one sensor");
    let rms = (squares / rows as f64).sqrt();
    let reported = json["records"][0]["sensors"][0]["rms"].as_f64().unwrap();
    assert!(
        (rms / reported - 1.0).abs() < 1e-9,
        "{rms} against {reported}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

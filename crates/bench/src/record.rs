//! `fistage bench --record`: the record fit of `fistage identify record` on
//! 7 s lab-style records at 10 kHz (1 nm encoder), one core: Table 1's
//! stage with the mass fitted, a small stage far from it with the mass
//! known, Table 1 with a 0.01 N unmeasured force, and a closed-loop run of
//! `scenarios/identify/closed_loop_sine.toml` (the plant inside the
//! scenario's servo). Wall and CPU time of the whole fit (first estimates,
//! continuation, output error, intervals), its iterations and plant
//! evaluations, and the worst parameter error.

use std::time::Instant;

use fistage_analysis::record_lab::RecordLab;
use fistage_ident::record::{
    LabErrors, MassChoice, Record, RecordOptions, RecordParam, RecordSynth, ServoLoop, Theta,
    fit_record,
};
use fistage_ident::synth::small_stage;
use fistage_model::LugreParams;

/// Prints the Markdown table; `repeat` fits per case (median).
pub fn record_table(repeat: usize) -> anyhow::Result<()> {
    let repeat = repeat.clamp(1, 5);
    let disturbed = LabErrors {
        disturbance_rms: 0.01,
        seed: 7,
        ..LabErrors::encoder()
    };
    let cases = [
        (
            "Table 1, mass fitted",
            LugreParams::paper_table1(),
            1.5,
            false,
            LabErrors::encoder(),
        ),
        (
            "small stage, mass known",
            small_stage(),
            0.25,
            true,
            LabErrors::encoder(),
        ),
        (
            "Table 1, 0.01 N disturbance",
            LugreParams::paper_table1(),
            1.5,
            false,
            disturbed,
        ),
    ];
    println!(
        "Record fit (`fistage identify record`), 7 s at 10 kHz, 1 nm encoder, one core, median of {repeat} fits, release build\n"
    );
    println!("| record | wall s | CPU s | iterations | plant RHS evals | worst parameter error |");
    println!("|---|---:|---:|---:|---:|---:|");
    for (label, lugre, mass, known, errors) in cases {
        let synth = RecordSynth {
            errors,
            ..RecordSynth::new(lugre, mass)
        };
        let (record, _) = synth.generate()?;
        let options = RecordOptions {
            mass: if known {
                MassChoice::Known(mass)
            } else {
                MassChoice::Fit
            },
            ..RecordOptions::default()
        };
        time_fit(label, &record, &options, &Theta::new(&lugre, mass), repeat)?;
    }
    let scenario = std::path::Path::new("scenarios/identify/closed_loop_sine.toml");
    let record = RecordLab::new(3).measure_closed_loop(scenario, Some(7.0))?;
    let servo = ServoLoop::from_scenario(scenario)?;
    let truth = Theta::new(&servo.scenario_friction, servo.scenario_mass);
    let options = RecordOptions {
        mass: MassChoice::Known(servo.scenario_mass),
        closed_loop: Some(servo),
        horizon: None,
        ..RecordOptions::default()
    };
    time_fit(
        "closed loop, sine tracking, mass known, pure OE",
        &record,
        &options,
        &truth,
        repeat,
    )?;
    stage_table()
}

/// The nine FI-stage paths a stage fit estimates.
const FI_PATHS: [&str; 9] = fistage_ident::stage::PAPER_FI_PATHS;

/// The stage fit (`identify record --stage --fit`) of the paper's FI stage
/// (two masses, the isolator, LuGre on the bearing): the nine parameters
/// from a start 50% off in each, on a clean 7 s, 10 kHz record and on one
/// with a 0.02 N unmeasured force (from 20% off), one fit each.
fn stage_table() -> anyhow::Result<()> {
    use fistage_analysis::lab::LabStage;
    use fistage_ident::stage::{Loop, StageOptions, StagePlant, fit_stage};
    let dir = std::env::temp_dir().join(format!("fistage-bench-stage-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let robot = std::fs::canonicalize("robots/stage_1dof_fi.urdf")?;
    let write = |name: &str, overrides: &str| -> anyhow::Result<std::path::PathBuf> {
        let path = dir.join(name);
        let text = format!(
            "robot = \"{}\"\nduration = 1.0\n{overrides}",
            robot.display().to_string().replace('\\', "/")
        );
        std::fs::write(&path, text)?;
        Ok(path)
    };
    let truth = write("truth.toml", "")?;
    let far = write(
        "far.toml",
        "[overrides.isolator]\nk_x = 6e4\nc_x = 1.0\n[overrides.bearing]\nmass = 0.75\n\
         [overrides.bearing_friction]\nf_c = 2.55\nf_s = 9.75\nv_s = 0.025\nsigma0 = 1.1e6\n\
         sigma1 = 355\nsigma2 = 7.1\n",
    )?;
    let near = write(
        "near.toml",
        "[overrides.isolator]\nk_x = 4.8e4\nc_x = 1.6\n[overrides.bearing]\nmass = 0.6\n\
         [overrides.bearing_friction]\nf_c = 4.1\nf_s = 7.8\nv_s = 0.02\nsigma0 = 1.8e6\n\
         sigma1 = 280\nsigma2 = 11.4\n",
    )?;
    let stage = LabStage::load(&truth)?;
    let paths: Vec<String> = FI_PATHS.iter().map(|p| p.to_string()).collect();
    let values = |path: &std::path::Path| -> anyhow::Result<(StagePlant, Vec<f64>)> {
        let scenario = fistage_model::Scenario::from_file(path)?;
        let robot = fistage_model::RobotSpec::from_file(&scenario.robot)?;
        let plant = StagePlant::new(&scenario, &robot, &paths, Loop::Open)?;
        let nominal = plant.nominal().to_vec();
        Ok((plant, nominal))
    };
    let (_, truth_values) = values(&truth)?;
    println!(
        "\nStage fit (`fistage identify record --stage --fit`), FI stage, nine parameters, 7 s at 10 kHz, 1 nm encoder, one core, release build\n"
    );
    println!(
        "| record | start | wall s | CPU s | iterations | RHS evals | worst error | undetermined |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---|");
    let cases = [
        ("clean", 0.0, &far, "50% off"),
        ("0.02 N disturbance", 0.02, &near, "20% off"),
    ];
    for (label, disturbance, start, offset) in cases {
        let lab = RecordLab {
            errors: disturbed(disturbance, 3),
            ..RecordLab::new(3)
        };
        let (record, _) = lab.measure(&stage)?;
        let (plant, _) = values(start)?;
        let (wall, cpu) = (Instant::now(), crate::timing::thread_cpu_time());
        let fit = fit_stage(&plant, &[record], &StageOptions::default(), &mut |_| true)?;
        let (wall, cpu) = (
            wall.elapsed().as_secs_f64(),
            crate::timing::thread_cpu_time() - cpu,
        );
        let (worst, name) = (0..FI_PATHS.len())
            .filter(|&j| fit.fitted[j])
            .map(|j| ((fit.values[j] / truth_values[j] - 1.0).abs(), j))
            .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
        let short = |path: &str| fistage_ident::stage::identifiability::short(path);
        let undetermined: Vec<String> = fit.undetermined().iter().map(|p| short(p)).collect();
        println!(
            "| {label} | {offset} | {wall:.1} | {cpu:.1} | {} | {} | {worst:.1e} ({}) | {} |",
            fit.iterations,
            fit.rhs_evaluations,
            short(FI_PATHS[name]),
            if undetermined.is_empty() {
                "none".to_string()
            } else {
                undetermined.join(", ")
            }
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    four_bearing_table()
}

/// The stage fit of the one-axis stage on four bearings with FI
/// (`robots/stage_axis_4fi.urdf`, isolators 4% apart): each bearing's f_c,
/// f_s and sigma0 set 10% and 3.3% below and above the first bearing's,
/// fitted from four identical bearings (the first's values), clean 7 s
/// record at 10 kHz.
fn four_bearing_table() -> anyhow::Result<()> {
    use fistage_analysis::lab::LabStage;
    use fistage_ident::stage::{Continuation, Loop, StageOptions, StagePlant, fit_stage};
    let dir = std::env::temp_dir().join(format!("fistage-bench-four-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let robot = std::fs::canonicalize("robots/stage_axis_4fi.urdf")?;
    let bearings = ["a", "b", "c", "d"];
    let factors = [0.9, 29.0 / 30.0, 31.0 / 30.0, 1.1];
    let (f_c, f_s, sigma0) = (1.275, 1.625, 5.5e5);
    let write = |name: &str, factors: &[f64]| -> anyhow::Result<std::path::PathBuf> {
        let mut text = format!(
            "robot = \"{}\"\nduration = 1.0\n",
            robot.display().to_string().replace('\\', "/")
        );
        for (bearing, factor) in bearings.iter().zip(factors) {
            text += &format!(
                "[overrides.friction_{bearing}]\nf_c = {}\nf_s = {}\nsigma0 = {}\n",
                f_c * factor,
                f_s * factor,
                sigma0 * factor
            );
        }
        let path = dir.join(name);
        std::fs::write(&path, text)?;
        Ok(path)
    };
    let truth = write("truth.toml", &factors)?;
    let start = write("start.toml", &[1.0; 4])?;
    let lab = RecordLab {
        errors: disturbed(0.0, 3),
        ..RecordLab::new(3)
    };
    let (record, _) = lab.measure(&LabStage::load(&truth)?)?;
    let paths: Vec<String> = ["f_c", "f_s", "sigma0"]
        .iter()
        .map(|key| format!("overrides.friction_*.{key}"))
        .collect();
    let plant_of = |path: &std::path::Path| -> anyhow::Result<StagePlant> {
        let scenario = fistage_model::Scenario::from_file(path)?;
        let robot = fistage_model::RobotSpec::from_file(&scenario.robot)?;
        Ok(StagePlant::new(&scenario, &robot, &paths, Loop::Open)?)
    };
    let truth_values = plant_of(&truth)?.nominal().to_vec();
    let plant = plant_of(&start)?;
    let (wall, cpu) = (Instant::now(), crate::timing::thread_cpu_time());
    let fit = fit_stage(&plant, &[record], &StageOptions::default(), &mut |_| true)?;
    let (wall, cpu) = (
        wall.elapsed().as_secs_f64(),
        crate::timing::thread_cpu_time() - cpu,
    );
    let worst = (fit.values.iter().zip(&truth_values))
        .map(|(v, t)| (v / t - 1.0).abs())
        .fold(0.0, f64::max);
    println!(
        "\nStage fit, one-axis stage on four bearings with FI, f_c, f_s and sigma0 of each (12), from four identical bearings, clean 7 s at 10 kHz, one core\n"
    );
    println!("| wall s | CPU s | iterations | continuation | worst error | RMS residual |");
    println!("|---:|---:|---:|---|---:|---:|");
    println!(
        "| {wall:.1} | {cpu:.1} | {} | {} | {worst:.1e} | {:.2} nm |",
        fit.iterations,
        match fit.continuation {
            Continuation::Anchored => "anchored",
            Continuation::GrowingHorizons => "anchored, then growing horizons",
        },
        fit.records[0].sensors[0].rms * 1e9
    );
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// The Monte Carlo coverage of the stage fit's 95% intervals: the FI stage
/// (nine parameters), 20 records each with its own 0.02 N (RMS, 50 ms)
/// unmeasured force, each fitted from the truth (the intervals, not the
/// convergence, are measured). Per parameter: the RMS relative error of
/// the fits that determined it, the median relative standard error, how
/// many intervals hold the truth, and how often it was undetermined.
pub fn stage_coverage_table() -> anyhow::Result<()> {
    use fistage_analysis::lab::LabStage;
    use fistage_ident::stage::{Loop, StageOptions, StagePlant, fit_stage};
    let robot = std::fs::canonicalize("robots/stage_1dof_fi.urdf")?;
    let dir = std::env::temp_dir().join(format!("fistage-bench-cover-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let truth = dir.join("truth.toml");
    std::fs::write(
        &truth,
        format!(
            "robot = \"{}\"\nduration = 1.0\n",
            robot.display().to_string().replace('\\', "/")
        ),
    )?;
    let stage = LabStage::load(&truth)?;
    let scenario = fistage_model::Scenario::from_file(&truth)?;
    let robot_spec = fistage_model::RobotSpec::from_file(&scenario.robot)?;
    let paths: Vec<String> = FI_PATHS.iter().map(|p| p.to_string()).collect();
    let plant = StagePlant::new(&scenario, &robot_spec, &paths, Loop::Open)?;
    let truth_values = plant.nominal().to_vec();
    let p = paths.len();
    let (mut errors, mut se) = (vec![Vec::new(); p], vec![Vec::new(); p]);
    let (mut covered, mut undetermined) = (vec![0usize; p], vec![0usize; p]);
    let cpu = crate::timing::thread_cpu_time();
    for seed in 1..=COVERAGE_SEEDS {
        let lab = RecordLab {
            errors: disturbed(0.02, seed),
            ..RecordLab::new(seed)
        };
        let (record, _) = lab.measure(&stage)?;
        let fit = fit_stage(&plant, &[record], &StageOptions::default(), &mut |_| true)?;
        for j in 0..p {
            let t = truth_values[j];
            if !fit.fitted[j] {
                undetermined[j] += 1;
                continue;
            }
            let e = &fit.estimates[j];
            errors[j].push(e.value / t - 1.0);
            se[j].push(e.std_error.unwrap_or(f64::NAN) / t);
            covered[j] += usize::from(e.covers(t));
        }
    }
    let cpu = crate::timing::thread_cpu_time() - cpu;
    println!(
        "Coverage of the stage fit's 95% intervals: FI stage, nine parameters, 7 s at 10 kHz, 1 nm encoder, 0.02 N RMS unmeasured force (50 ms), {COVERAGE_SEEDS} seeds, each fitted from the truth ({cpu:.0} CPU s in all)\n"
    );
    println!(
        "| parameter | RMS error (determined) | median s.e. | covered (of determined) | undetermined |"
    );
    println!("|---|---:|---:|---:|---:|");
    for j in 0..p {
        let n = errors[j].len();
        let rms = (errors[j].iter().map(|e| e * e).sum::<f64>() / n.max(1) as f64).sqrt();
        se[j].sort_by(f64::total_cmp);
        let median = se[j].get(n / 2).copied().unwrap_or(f64::NAN);
        println!(
            "| {} | {rms:.2e} | {median:.2e} | {}/{n} | {}/{COVERAGE_SEEDS} |",
            fistage_ident::stage::identifiability::short(FI_PATHS[j]),
            covered[j],
            undetermined[j]
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(())
}

/// A 1 nm encoder with an unmeasured force of `rms` N (50 ms), drawn from `seed`.
fn disturbed(rms: f64, seed: u64) -> LabErrors {
    LabErrors {
        disturbance_rms: rms,
        seed,
        ..LabErrors::encoder()
    }
}

/// Times `repeat` fits of `record` and prints their row.
fn time_fit(
    label: &str,
    record: &Record,
    options: &RecordOptions,
    truth: &Theta,
    repeat: usize,
) -> anyhow::Result<()> {
    let (mut walls, mut cpus) = (Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..repeat {
        let (wall, cpu) = (Instant::now(), crate::timing::thread_cpu_time());
        let fit = fit_record(record, options, &mut |_| true)?;
        walls.push(wall.elapsed().as_secs_f64());
        cpus.push(crate::timing::thread_cpu_time() - cpu);
        last = Some(fit);
    }
    let fit = last.ok_or_else(|| anyhow::anyhow!("no fit"))?;
    let (worst, name) = RecordParam::ALL
        .iter()
        .map(|p| ((fit.theta.get(*p) / truth.get(*p) - 1.0).abs(), p.name()))
        .fold((0.0, ""), |a, b| if b.0 > a.0 { b } else { a });
    walls.sort_by(f64::total_cmp);
    cpus.sort_by(f64::total_cmp);
    println!(
        "| {label} | {:.2} | {:.2} | {} | {} | {worst:.1e} ({name}) |",
        walls[walls.len() / 2],
        cpus[cpus.len() / 2],
        fit.iterations,
        fit.rhs_evaluations
    );
    Ok(())
}

/// Seeds of the coverage table.
const COVERAGE_SEEDS: u64 = 20;

/// The Monte Carlo coverage of the record fit's 95% intervals: Table 1's
/// stage, 20 records each with its own 0.01 N (RMS, 50 ms) unmeasured force,
/// fitted with the default 10 ms horizon and as a pure output error. Per
/// parameter: the RMS relative error, the median relative standard error
/// (block jackknife and Jacobian-only), and how many of the 20 intervals hold the
/// truth.
pub fn coverage_table() -> anyhow::Result<()> {
    let truth_lugre = LugreParams::paper_table1();
    let truth = Theta::new(&truth_lugre, 1.5);
    println!(
        "Coverage of the record fit's 95% intervals: Table 1, 7 s at 10 kHz, 1 nm encoder, 0.01 N RMS unmeasured force (50 ms), {COVERAGE_SEEDS} seeds\n"
    );
    println!(
        "| horizon | parameter | RMS error | median s.e. (jackknife) | median s.e. (Jacobian only) | covered (jackknife) | covered (Jacobian only) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for (label, horizon) in [("10 ms", Some(10e-3)), ("whole (pure OE)", None)] {
        let mut errors = vec![Vec::new(); 7];
        let mut se = vec![Vec::new(); 7];
        let mut se_iid = vec![Vec::new(); 7];
        let mut covered = [0usize; 7];
        let mut covered_iid = [0usize; 7];
        for seed in 1..=COVERAGE_SEEDS {
            let synth = RecordSynth {
                errors: disturbed(0.01, seed),
                ..RecordSynth::new(truth_lugre, 1.5)
            };
            let (record, _) = synth.generate()?;
            let options = RecordOptions {
                horizon,
                ..RecordOptions::default()
            };
            let fit = fit_record(&record, &options, &mut |_| true)?;
            for (j, p) in RecordParam::ALL.iter().enumerate() {
                let t = truth.get(*p);
                let e = fit.estimate(*p);
                errors[j].push(e.value / t - 1.0);
                se[j].push(e.std_error.unwrap_or(f64::NAN) / t);
                let iid = fit.iid_std_errors.get(j).copied().flatten();
                se_iid[j].push(iid.unwrap_or(f64::NAN) / t);
                covered[j] += usize::from(e.covers(t));
                covered_iid[j] += usize::from(iid.is_some_and(|s| (e.value - t).abs() <= 1.96 * s));
            }
        }
        for (j, p) in RecordParam::ALL.iter().enumerate() {
            let rms =
                (errors[j].iter().map(|e| e * e).sum::<f64>() / errors[j].len() as f64).sqrt();
            let median = |v: &mut Vec<f64>| {
                v.sort_by(f64::total_cmp);
                v[v.len() / 2]
            };
            println!(
                "| {label} | {} | {rms:.2e} | {:.2e} | {:.2e} | {}/{COVERAGE_SEEDS} | {}/{COVERAGE_SEEDS} |",
                p.name(),
                median(&mut se[j]),
                median(&mut se_iid[j]),
                covered[j],
                covered_iid[j]
            );
        }
    }
    Ok(())
}

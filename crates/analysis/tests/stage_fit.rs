//! Grey-box fits of whole stages (`fistage_ident::stage`) to records made
//! by fistage's own engine on the full assembled model: the FI stage's nine
//! parameters from a start 50% off, what a pre-motion record cannot
//! determine, two records (one with a bearing encoder) in one fit, a
//! closed-loop record through the scenario's servo, and a fit's covariance
//! drawn as a population.

use std::path::{Path, PathBuf};

use fistage_analysis::lab::LabStage;
use fistage_analysis::record_lab::RecordLab;
use fistage_ident::record::{LabErrors, Record};
use fistage_ident::stage::{Loop, StageFit, StageOptions, StagePlant, fit_stage};
use fistage_model::{RobotSpec, Scenario};

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fistage-stage-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("creates a scratch folder");
    dir
}

/// An open-loop scenario of `robot` (a path) with `overrides` (TOML) appended.
fn scenario(dir: &Path, name: &str, robot: &Path, overrides: &str) -> PathBuf {
    let path = dir.join(name);
    let text = format!(
        "robot = \"{}\"\nduration = 1.0\n{overrides}\n",
        robot.display().to_string().replace('\\', "/")
    );
    std::fs::write(&path, text).expect("writes the scenario");
    path
}

/// The paper's FI stage with a second encoder on the bearing.
fn fi_robot_with_bearing_encoder(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(repository().join("robots/stage_1dof_fi.urdf"))
        .expect("reads the robot");
    let sensor = "  <fistage:sensor name=\"bearing_encoder\" link=\"bearing\">\n    \
                  <origin xyz=\"0 0 0\"/>\n    <axis xyz=\"1 0 0\"/>\n  </fistage:sensor>\n</robot>";
    let path = dir.join("stage_1dof_fi_two_encoders.urdf");
    std::fs::write(&path, text.replace("</robot>", sensor)).expect("writes the robot");
    path
}

const FI_PATHS: [&str; 9] = fistage_ident::stage::PAPER_FI_PATHS;

/// 50% off in every parameter (f_s kept above f_c).
const FI_FAR: &str = "[overrides.isolator]\nk_x = 6e4\nc_x = 1.0\n\
[overrides.bearing]\nmass = 0.75\n\
[overrides.bearing_friction]\nf_c = 2.55\nf_s = 9.75\nv_s = 0.025\nsigma0 = 1.1e6\nsigma1 = 355\nsigma2 = 7.1\n";

/// A record of the lab program at `rate` Hz on the stage of `truth`, a 1 nm encoder.
fn record_at(rate: f64, truth: &Path, seed: u64, further: &[&str]) -> Record {
    let lab = RecordLab {
        dt: 1.0 / rate,
        errors: LabErrors {
            seed,
            ..LabErrors::encoder()
        },
        further_sensors: further.iter().map(|s| s.to_string()).collect(),
        ..RecordLab::new(seed)
    };
    let stage = LabStage::load(truth).expect("stage");
    lab.measure(&stage).expect("record").0
}

/// A 5 kHz record.
fn record(truth: &Path, seed: u64, further: &[&str]) -> Record {
    record_at(5e3, truth, seed, further)
}

/// Fits `paths` of the stage of `start` to open-loop `records`.
fn fit_paths(start: &Path, records: &[Record], paths: &[&str]) -> (StagePlant, StageFit) {
    fit_driven(start, records, paths, Loop::Open)
}

/// Fits `paths` of the stage of `start` to `records` driven by `drive`.
fn fit_driven(
    start: &Path,
    records: &[Record],
    paths: &[&str],
    drive: Loop,
) -> (StagePlant, StageFit) {
    let scenario = Scenario::from_file(start).expect("scenario");
    let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    let paths: Vec<String> = paths.iter().map(|p| p.to_string()).collect();
    let plant = StagePlant::new(&scenario, &robot, &paths, drive).expect("plant");
    // rtol 1e-6 against the default 1e-8: the parameters still come back to
    // 1e-4, at a third of the cost.
    let options = StageOptions {
        rtol: 1e-6,
        ..StageOptions::default()
    };
    let fit = fit_stage(&plant, records, &options, &mut |_| true).expect("fits");
    (plant, fit)
}

/// Fits the nine FI paths.
fn fit(start: &Path, records: &[Record]) -> (StagePlant, StageFit) {
    fit_paths(start, records, &FI_PATHS)
}

/// The paper's values of the FI paths (the robot file's).
fn truth_values(truth: &Path) -> Vec<f64> {
    let scenario = Scenario::from_file(truth).expect("scenario");
    let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
    let paths: Vec<String> = FI_PATHS.iter().map(|p| p.to_string()).collect();
    StagePlant::new(&scenario, &robot, &paths, Loop::Open)
        .expect("plant")
        .nominal()
        .to_vec()
}

/// From 50% off in all nine (isolator stiffness and damping, bearing mass,
/// six LuGre parameters), a clean 5 kHz record brings every one back to
/// within 1e-4; the first analysis finds all nine determined.
#[test]
fn the_fi_stage_comes_back_from_fifty_percent_off() {
    let dir = scratch("far");
    let robot = repository().join("robots/stage_1dof_fi.urdf");
    let truth = scenario(&dir, "truth.toml", &robot, "");
    let far = scenario(&dir, "far.toml", &robot, FI_FAR);
    let (_, fit) = fit(&far, &[record(&truth, 3, &[])]);
    assert!(fit.undetermined().is_empty(), "{:?}", fit.undetermined());
    for (j, value) in truth_values(&truth).iter().enumerate() {
        let error = fit.values[j] / value - 1.0;
        assert!(error.abs() < 1e-4, "{}: {error:e}", FI_PATHS[j]);
    }
    assert!(fit.converged);
    let rms = fit.records[0].sensors[0].rms;
    assert!(rms < 2e-9, "rms residual {rms:e} m against a 1 nm encoder");
}

/// The pre-motion part of the program alone (rest, the small chirp, rest:
/// no sliding) cannot see the Coulomb level or the Stribeck velocity: the
/// first analysis names both, and they stay at the scenario's values.
#[test]
fn a_pre_motion_record_names_f_c_and_v_s_undetermined() {
    let dir = scratch("premotion");
    let robot = repository().join("robots/stage_1dof_fi.urdf");
    let truth = scenario(&dir, "truth.toml", &robot, "");
    let full = record(&truth, 5, &[]);
    // The rest and the chirp's first 0.3 s (to 17 Hz, below the isolator
    // mode: further on, the lightly damped mode swings the bearing loose).
    let keep = full.time.partition_point(|&t| t < 0.5);
    let premotion = Record::from_arrays(
        "premotion",
        full.time[..keep].to_vec(),
        full.force[..keep].to_vec(),
        full.position[..keep].to_vec(),
    )
    .expect("record");
    let (plant, fit) = fit(&truth, &[premotion]);
    let undetermined = fit.before.undetermined();
    for path in [
        "overrides.bearing_friction.f_c",
        "overrides.bearing_friction.v_s",
    ] {
        assert!(undetermined.iter().any(|p| p == path), "{undetermined:?}");
        let j = FI_PATHS.iter().position(|p| *p == path).expect("a path");
        assert!(!fit.fitted[j]);
        assert_eq!(fit.values[j], plant.nominal()[j]);
    }
    // The presliding stiffness is seen.
    let sigma0 = FI_PATHS
        .iter()
        .position(|p| p.ends_with("sigma0"))
        .expect("sigma0");
    assert!(fit.before.parameters[sigma0].determined);
}

/// Two records in one fit, the second with an encoder on the bearing: both
/// readings of both records are fitted (per-record residuals at the
/// encoders' level), and five parameters come back from 20% off.
#[test]
fn two_records_one_with_a_bearing_encoder_fit_jointly() {
    let dir = scratch("two");
    let robot = fi_robot_with_bearing_encoder(&dir);
    let truth = scenario(&dir, "truth.toml", &robot, "");
    let near = scenario(
        &dir,
        "near.toml",
        &robot,
        "[overrides.isolator]\nk_x = 4.8e4\nc_x = 1.6\n[overrides.bearing]\nmass = 0.6\n\
         [overrides.bearing_friction]\nf_c = 4.1\nsigma0 = 1.8e6\n",
    );
    let records = [
        record_at(2e3, &truth, 7, &[]),
        record_at(2e3, &truth, 8, &["bearing_encoder"]),
    ];
    assert_eq!(records[1].sensors[0].column, "bearing_encoder_m");
    let paths = [
        FI_PATHS[0],
        FI_PATHS[1],
        FI_PATHS[2],
        FI_PATHS[3],
        FI_PATHS[6],
    ];
    let (_, fit) = fit_paths(&near, &records, &paths);
    assert_eq!(fit.records.len(), 2);
    assert_eq!(fit.records[0].sensors.len(), 1);
    assert_eq!(fit.records[1].sensors.len(), 2);
    assert_eq!(fit.records[1].sensors[1].sensor, "bearing_encoder");
    for record in &fit.records {
        for sensor in &record.sensors {
            assert!(sensor.rms < 3e-9, "{}: {:e} m", sensor.column, sensor.rms);
        }
    }
    let all = truth_values(&truth);
    for (j, path) in paths.iter().enumerate() {
        let value = all[FI_PATHS.iter().position(|p| p == path).expect("a path")];
        let error = fit.values[j] / value - 1.0;
        assert!(error.abs() < 1e-4, "{path}: {error:e}");
    }
}

/// A closed-loop record: the FI stage in its own PID servo tracking a
/// 5 mm, 1 Hz sine (2 s at 2 kHz, 1 nm encoder, the servo reading the
/// quantised position), fitted through the same servo law: the isolator's
/// stiffness and damping and the bearing's f_c, f_s and sigma0 come back
/// from 20% off to within 1%, each inside its 95% interval (measured: the
/// damping, which a 1 Hz sine barely moves, 2e-3 off with a standard
/// error of 5e-3; the rest within 2e-4).
#[test]
fn a_closed_loop_record_fits_through_the_scenarios_servo() {
    let dir = scratch("closed");
    let robot = repository().join("robots/stage_1dof_fi.urdf");
    let servo = "[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\n\
                 c = 100.0\nk_i = 1e5\n\n[reference]\nkind = \"sine\"\namplitude = 5e-3\n\
                 frequency = 1.0\n";
    let truth = scenario(&dir, "truth.toml", &robot, servo);
    let start = scenario(
        &dir,
        "start.toml",
        &robot,
        &format!(
            "{servo}\n[overrides.isolator]\nk_x = 4.8e4\nc_x = 2.4\n\
             [overrides.bearing_friction]\nf_c = 4.08\nf_s = 7.8\nsigma0 = 1.76e6\n"
        ),
    );
    let lab = RecordLab {
        dt: 1.0 / 2e3,
        errors: LabErrors {
            seed: 7,
            ..LabErrors::encoder()
        },
        ..RecordLab::new(7)
    };
    let record = lab
        .measure_closed_loop(&truth, Some(2.0))
        .expect("a closed-loop record");
    let paths = [
        FI_PATHS[0],
        FI_PATHS[1],
        FI_PATHS[3],
        FI_PATHS[4],
        FI_PATHS[6],
    ];
    let (_, fit) = fit_driven(&start, &[record], &paths, Loop::Closed);
    assert_eq!(fit.drive, Loop::Closed);
    assert!(fit.undetermined().is_empty(), "{:?}", fit.undetermined());
    let truth = truth_values(&truth);
    for (j, path) in paths.iter().enumerate() {
        let k = FI_PATHS.iter().position(|p| p == path).expect("an FI path");
        let error = fit.values[j] / truth[k] - 1.0;
        assert!(error.abs() < 1e-2, "{path}: {error:e}");
        assert!(
            fit.estimates[j].covers(truth[k]),
            "{path}: {:?}",
            fit.estimates[j]
        );
    }
}

/// A stage fit's uncertainty carried into its population: the fit.json of
/// a disturbed FI record (the isolator's k_j and c_j, the bearing's
/// sigma0), read by `[robust] from_fit`, draws stages whose `ln theta` has
/// the fit's mean and covariance (sample moments inside four standard
/// errors), and each drawn stage is built and judged with those values.
#[test]
fn a_stage_fit_carries_its_covariance_into_a_population() {
    use fistage_analysis::robust::RobustSpec;
    use fistage_ident::stage::StageReport;
    let dir = scratch("from-fit");
    let robot = repository().join("robots/stage_1dof_fi.urdf");
    let truth = scenario(&dir, "truth.toml", &robot, "");
    let start = scenario(
        &dir,
        "start.toml",
        &robot,
        "[overrides.isolator]\nk_x = 4.4e4\nc_x = 2.2\n\
         [overrides.bearing_friction]\nsigma0 = 2.0e6\n",
    );
    let lab = RecordLab {
        dt: 1.0 / 2e3,
        errors: LabErrors {
            disturbance_rms: 0.02,
            seed: 11,
            ..LabErrors::encoder()
        },
        ..RecordLab::new(11)
    };
    let record = lab
        .measure(&LabStage::load(&truth).expect("stage"))
        .expect("record")
        .0;
    let paths = [FI_PATHS[0], FI_PATHS[1], FI_PATHS[6]];
    let (_, fit) = fit_paths(&start, &[record], &paths);
    assert!(fit.undetermined().is_empty(), "{:?}", fit.undetermined());
    let report = StageReport::new(&start.display().to_string(), &fit);
    std::fs::write(
        dir.join("fit.json"),
        serde_json::to_string_pretty(&report).expect("json"),
    )
    .expect("writes fit.json");
    let study_text = format!(
        "robot = {:?}\nduration = 1.0\n[platform]\nvelocity = 0.02\n\
         [controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\nc = 100\n\
         [robust]\nsamples = 3000\nseed = 5\nsampling = \"random\"\nfrom_fit = \"fit.json\"\n",
        robot.display().to_string()
    );
    let study = Scenario::from_str(&study_text, &dir.join("study.toml")).expect("study");
    let robot_file = RobotSpec::from_file(&study.robot).expect("robot");
    let spec = RobustSpec::from_scenario(&study, &robot_file, None, None).expect("from_fit");
    let columns: Vec<&str> = spec.columns().iter().map(|t| t.path.as_str()).collect();
    assert_eq!(columns, paths);
    let n = spec.samples;
    let logs: Vec<Vec<f64>> = (0..n)
        .map(|i| spec.values(i).iter().map(|v| v.ln()).collect())
        .collect();
    let cov = fit.log_covariance.as_ref().expect("a covariance");
    let mean: Vec<f64> = (0..3)
        .map(|j| logs.iter().map(|d| d[j]).sum::<f64>() / n as f64)
        .collect();
    for j in 0..3 {
        let tolerance = 4.0 * (cov[(j, j)] / n as f64).sqrt();
        let centre = fit.values[j].ln();
        assert!(
            (mean[j] - centre).abs() < tolerance,
            "{}: mean of ln {} against {centre} (+- {tolerance})",
            paths[j],
            mean[j]
        );
        let variance = logs.iter().map(|d| (d[j] - mean[j]).powi(2)).sum::<f64>() / (n - 1) as f64;
        let tolerance = 4.0 * cov[(j, j)] * (2.0 / n as f64).sqrt();
        assert!(
            (variance - cov[(j, j)]).abs() < tolerance,
            "{}: variance of ln {variance:e} against {:e}",
            paths[j],
            cov[(j, j)]
        );
    }
    let (loaded_robot, model) = fistage_model::assemble(robot_file.clone(), &study).expect("model");
    let base = fistage_model::Loaded {
        scenario: study.clone(),
        robot: loaded_robot,
        model,
    };
    for index in 0..4 {
        let result = spec.evaluate(&base, &robot_file, index);
        assert_eq!(result.values, spec.values(index));
        assert!(result.refused.is_none(), "{:?}", result.refused);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

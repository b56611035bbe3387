//! Closed-loop record fits: a scenario's servo drives the full assembled
//! stage along its reference, the record holds its encoder and force
//! command, and the fit simulates the one-mass plant inside the same servo
//! law. Two independent simulations agree; the fit recovers the stage's
//! friction from a clean record, its intervals hold on disturbed ones, and
//! stages that are not one mass are refused by name.

use std::path::{Path, PathBuf};

use fistage_analysis::record_lab::RecordLab;
use fistage_ident::record::plant::{Anchors, Drive, PlantTolerance, simulate};
use fistage_ident::record::{
    LabErrors, MassChoice, RecordOptions, RecordParam, ServoLoop, Theta, fit_record,
};

fn repository() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A scratch folder for this test process.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("fistage-closed-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("creates a scratch folder");
    dir
}

/// A scenario of `robot` with a PID servo tracking a 5 mm, 1 Hz sine, with
/// `extra` TOML appended.
fn scenario(dir: &Path, robot: &str, extra: &str) -> PathBuf {
    let robot = repository().join("robots").join(robot);
    let text = format!(
        "title = \"closed-loop record\"\nrobot = {robot:?}\nduration = 3.0\n\n\
         [controller]\nsensor = \"encoder\"\nactuator = \"drive\"\nk = 6e4\nc = 100.0\n\
         k_i = 1e5\n\n\
         [reference]\nkind = \"sine\"\namplitude = 5e-3\nfrequency = 1.0\n\n{extra}"
    );
    let path = dir.join("closed_loop.toml");
    std::fs::write(&path, text).expect("writes the scenario");
    path
}

/// The servo with every kind of state (integral, LuGre feedforward,
/// observer) simulated around the one-mass plant follows the full assembled
/// model's run of the same scenario to integration accuracy.
#[test]
fn the_one_mass_loop_follows_the_assembled_stage() {
    let dir = scratch("agree");
    let extra = "[compensation]\nkind = \"lugre\"\nelement = \"bearing_friction\"\n\
                 error = { sigma0 = 0.2 }\n\n[dob]\nbandwidth = 50.0\nnominal_mass = 1.4\n";
    let path = scenario(&dir, "stage_1dof_rigid.urdf", extra);
    let mut lab = RecordLab::new(1);
    lab.errors = LabErrors::exact();
    let record = lab.measure_closed_loop(&path, Some(1.5)).expect("records");
    let servo = ServoLoop::from_scenario(&path).expect("a one-mass servo loop");
    assert_eq!(
        servo.n_states(),
        3,
        "integral, compensator bristle, observer"
    );
    let theta = Theta::new(&servo.scenario_friction, servo.scenario_mass);
    let run = |rtol: f64| {
        let tolerance = PlantTolerance::for_theta(&theta, rtol);
        let anchors = Anchors::default();
        simulate(
            &record,
            Drive::Servo(&servo),
            &theta,
            &[],
            false,
            &anchors,
            tolerance,
        )
        .expect("simulates")
    };
    let amplitude = record.position.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for rtol in [1e-8, 1e-10] {
        let simulated = run(rtol);
        let worst = (simulated.position.iter().zip(&record.position))
            .map(|(s, m)| (s - m).abs())
            .fold(0.0f64, f64::max);
        let bound = 20.0 * rtol * amplitude;
        eprintln!("rtol {rtol:e}: loops differ by {worst:e} m");
        assert!(
            worst < bound,
            "rtol {rtol:e}: the loops differ by {worst:e} m (bound {bound:e})"
        );
    }
    // The open-loop plant replaying the logged force drifts away from the
    // closed loop: the servo is what holds the stage.
    let tolerance = PlantTolerance::for_theta(&theta, 1e-10);
    let replay = simulate(
        &record,
        Drive::Recorded,
        &theta,
        &[],
        false,
        &Anchors::default(),
        tolerance,
    )
    .expect("simulates");
    let drift = (replay.position.iter().zip(&record.position))
        .map(|(s, m)| (s - m).abs())
        .fold(0.0f64, f64::max);
    eprintln!("held-force replay drifts {drift:e} m");
    assert!(
        drift > 1e-7,
        "the held-force replay stays within {drift:e} m"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A clean closed-loop record with a 1 nm encoder gives all six LuGre
/// parameters and the mass to 1e-4, without a guess, at 3 s and at 7 s (at
/// 7 s the record's own first estimates find no Stribeck drop and no
/// sigma2, since a servo's sine has no steady sliding, and the start comes
/// from the grid of Stribeck curves instead).
#[test]
fn a_clean_closed_loop_record_gives_every_parameter() {
    for duration in [3.0, 7.0] {
        clean_closed_loop_fit(duration);
    }
}

fn clean_closed_loop_fit(duration: f64) {
    let dir = scratch(&format!("clean-{duration}"));
    let path = scenario(&dir, "stage_1dof_rigid.urdf", "");
    let record = RecordLab::new(3)
        .measure_closed_loop(&path, Some(duration))
        .expect("records");
    let servo = ServoLoop::from_scenario(&path).expect("servo");
    let truth = Theta::new(&servo.scenario_friction, servo.scenario_mass);
    let options = RecordOptions {
        closed_loop: Some(servo),
        horizon: None,
        ..RecordOptions::default()
    };
    let fit = fit_record(&record, &options, &mut |_| true).expect("fits");
    assert!(fit.converged);
    for p in RecordParam::ALL {
        let error = fit.theta.get(p) / truth.get(p) - 1.0;
        assert!(
            error.abs() < 1e-4,
            "{duration} s: {} off by {error:e}",
            p.name()
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Stick-slip on a counter-surface moving at 20 mm/s (paper Fig. 5a
/// without FI), held by the PD servo: a limit cycle, fitted with the
/// default 10 ms horizon, gives all six parameters to 1e-3 although the
/// record has neither steady sliding nor presliding for first estimates.
#[test]
fn a_stick_slip_limit_cycle_gives_every_parameter() {
    let path = repository().join("scenarios/paper/fig05a_rigid.toml");
    let record = RecordLab::new(5)
        .measure_closed_loop(&path, Some(3.0))
        .expect("records");
    let servo = ServoLoop::from_scenario(&path).expect("servo");
    assert_eq!(servo.platform_velocity, 0.02);
    let truth = Theta::new(&servo.scenario_friction, servo.scenario_mass);
    let options = RecordOptions {
        mass: MassChoice::Known(servo.scenario_mass),
        closed_loop: Some(servo),
        ..RecordOptions::default()
    };
    let fit = fit_record(&record, &options, &mut |_| true).expect("fits");
    assert!(fit.converged);
    for p in RecordParam::ALL {
        let error = fit.theta.get(p) / truth.get(p) - 1.0;
        assert!(error.abs() < 1e-3, "{} off by {error:e}", p.name());
    }
}

/// On closed-loop records with an unlogged 0.01 N disturbance the
/// jackknife intervals (mass known) cover the truth in most of 8 records
/// per parameter, where the Jacobian-only ones mostly miss.
#[test]
fn closed_loop_intervals_hold_on_disturbed_records() {
    let dir = scratch("coverage");
    let path = scenario(&dir, "stage_1dof_rigid.urdf", "");
    let servo = ServoLoop::from_scenario(&path).expect("servo");
    let truth = Theta::new(&servo.scenario_friction, servo.scenario_mass);
    let options = RecordOptions {
        mass: MassChoice::Known(servo.scenario_mass),
        closed_loop: Some(servo),
        horizon: None,
        ..RecordOptions::default()
    };
    let lugre = &RecordParam::ALL[..6];
    let records = 8;
    // The eight records are independent: fitted two at a time, so that this
    // test is not its binary's longest by itself.
    let fits: Vec<_> = std::thread::scope(|scope| {
        let workers: Vec<_> = [1..=records / 2, records / 2 + 1..=records]
            .into_iter()
            .map(|seeds| {
                let (path, options) = (&path, &options);
                scope.spawn(move || {
                    seeds
                        .map(|seed| {
                            let mut lab = RecordLab::new(seed);
                            lab.errors.disturbance_rms = 0.01;
                            let record = lab.measure_closed_loop(path, Some(2.0)).expect("records");
                            fit_record(&record, options, &mut |_| true).expect("fits")
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
    assert_eq!(fits.len(), records as usize);
    let mut covered = [0usize; 6];
    let mut covered_iid = 0;
    for fit in &fits {
        for (j, p) in lugre.iter().enumerate() {
            let e = fit.estimate(*p);
            covered[j] += usize::from(e.covers(truth.get(*p)));
            let iid = fit.iid_std_errors[j].expect("a Jacobian-only error");
            covered_iid += usize::from((e.value - truth.get(*p)).abs() <= 1.96 * iid);
        }
    }
    let total: usize = covered.iter().sum();
    eprintln!("jackknife covered {covered:?}, Jacobian-only {covered_iid} of 48");
    assert!(total >= 40, "covered {total} of 48: {covered:?}");
    assert!(
        covered.iter().all(|&c| c >= 5),
        "per parameter: {covered:?}"
    );
    assert!(
        covered_iid <= 16,
        "Jacobian-only covered {covered_iid} of 48"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// A stage with FI (two masses) and a scenario without a servo are refused
/// with the scenario named and the reason.
#[test]
fn stages_that_are_not_one_mass_are_refused() {
    let dir = scratch("refuse");
    let fi = scenario(&dir, "stage_1dof_fi.urdf", "");
    let message = ServoLoop::from_scenario(&fi).unwrap_err().to_string();
    assert!(message.contains("closed_loop.toml"), "{message}");
    assert!(message.contains("isolator"), "{message}");
    let robot = repository().join("robots/stage_1dof_rigid.urdf");
    let open = dir.join("open.toml");
    std::fs::write(
        &open,
        format!("title = \"no servo\"\nrobot = {robot:?}\nduration = 1.0\n"),
    )
    .expect("writes");
    let message = ServoLoop::from_scenario(&open).unwrap_err().to_string();
    assert!(message.contains("open.toml"), "{message}");
    assert!(message.contains("[controller]"), "{message}");
    std::fs::remove_dir_all(&dir).ok();
}

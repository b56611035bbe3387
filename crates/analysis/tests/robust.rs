//! Tolerance analysis against answers known without it:
//!
//! * a closed-form probability: the rigid PD stage with only its damping gain
//!   toleranced (uniform) is unstable exactly below the Routh-Hurwitz
//!   boundary c*, found from the paper's analytic conditions (not from the
//!   eigenvalues the study uses), so P(unstable) = (c* - low) / (high - low);
//!   plain Monte Carlo lands inside its own Wilson interval, and scrambled
//!   Sobol converges as 1/n (one sample per stratum in one dimension);
//! * samples are functions of (seed, index): the same seed gives the same
//!   rows, any split into shards recombines into the single run;
//! * patterns draw every match independently, or once for all with
//!   `shared = true`; nonsense tables are errors naming the key.

use std::path::{Path, PathBuf};

use fistage_analysis::robust::{RobustSpec, Summary};
use fistage_analysis::routh::{RigidStage, rigid_slipping};
use fistage_model::{Loaded, RobotSpec, Scenario, assemble};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A study of `robot` with the rigid stage's servo at k = 1e5 over a
/// platform at 20 mm/s, and this `[robust]` table.
fn study(robot: &str, robust: &str) -> (Loaded, RobotSpec, Scenario) {
    study_with_servo(robot, "k = 1e5\nc = 250", robust)
}

/// The same with other servo gains (`gains`: the `[controller]` lines).
fn study_with_servo(robot: &str, gains: &str, robust: &str) -> (Loaded, RobotSpec, Scenario) {
    let text = scenario_text(robot, gains, robust);
    let scenario = Scenario::from_str(&text, Path::new("robust.toml")).expect("scenario");
    let robot_file = RobotSpec::from_file(&scenario.robot).expect("robot");
    let (robot, model) = assemble(robot_file.clone(), &scenario).expect("model");
    let loaded = Loaded {
        scenario: scenario.clone(),
        robot,
        model,
    };
    (loaded, robot_file, scenario)
}

/// The scenario file of such a study.
fn scenario_text(robot: &str, gains: &str, robust: &str) -> String {
    format!(
        "robot = {:?}\nduration = 1.0\n[platform]\nvelocity = 0.02\n[controller]\nsensor = \"encoder\"\nactuator = \"drive\"\n{gains}\n{robust}",
        root().join(robot).display().to_string()
    )
}

/// The damping gain where the rigid stage's slipping equilibrium changes
/// stability, by bisection of the analytic Routh-Hurwitz conditions.
pub(crate) fn routh_boundary(loaded: &Loaded) -> f64 {
    let model = &loaded.model;
    let stage = |c: f64| RigidStage {
        mass: model.bodies()[0].mass,
        k: 1e5,
        c,
        lugre: model.frictions()[0].lugre,
        platform_velocity: 0.02,
    };
    let stable = |c: f64| rigid_slipping(&stage(c)).stable;
    let (mut lo, mut hi) = (1.0, 2000.0);
    assert!(!stable(lo) && stable(hi), "one boundary in the bracket");
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) { hi = mid } else { lo = mid }
    }
    0.5 * (lo + hi)
}

fn damping_table(samples: usize, sampling: &str, low: f64, high: f64) -> String {
    format!(
        "[robust]\nsamples = {samples}\nseed = 3\nsampling = \"{sampling}\"\n[[robust.parameter]]\nparameter = \"controller.c\"\ndistribution = \"uniform\"\nrelative = false\nlow = {low:?}\nhigh = {high:?}\n"
    )
}

fn p_unstable(robust: &str) -> (f64, [f64; 2]) {
    let (loaded, robot_file, scenario) = study("robots/stage_1dof_rigid.urdf", robust);
    let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
    let indices: Vec<usize> = (0..spec.samples).collect();
    let results = spec.run(&loaded, &robot_file, &indices, 2, &|_, _| {});
    let summary = Summary::of(&spec, &results);
    assert_eq!(summary.undetermined_linear + summary.refused, 0);
    let p = summary.p_unstable_linear.expect("linear analysis");
    assert_eq!(p.n, spec.samples);
    (p.estimate, p.ci95)
}

#[test]
fn one_toleranced_gain_gives_the_closed_form_probability() {
    let (loaded, _, _) = study("robots/stage_1dof_rigid.urdf", "");
    let c_star = routh_boundary(&loaded);
    // A non-dyadic probability (0.4 / 1.7), so that no design hits it by its
    // structure alone.
    let (low, high) = (0.6 * c_star, 2.3 * c_star);
    let exact = (c_star - low) / (high - low);
    println!("c* = {c_star:.4} N s/m, P(unstable) = {exact:.6}");
    // Plain Monte Carlo: inside its own 95% interval.
    let (p, ci) = p_unstable(&damping_table(2000, "random", low, high));
    assert!(
        ci[0] <= exact && exact <= ci[1],
        "random: {p} {ci:?} vs {exact}"
    );
    // Latin hypercube: stratified, error below one stratum.
    let (p, _) = p_unstable(&damping_table(500, "lhs", low, high));
    assert!(
        (p - exact).abs() <= 1.0 / 500.0 + 1e-12,
        "lhs: {p} vs {exact}"
    );
    // Scrambled Sobol: the error shrinks as 1/n.
    for n in [64, 256, 1024] {
        let (p, ci) = p_unstable(&damping_table(n, "sobol", low, high));
        let error = (p - exact).abs();
        println!("sobol n = {n}: {p:.6} (error {error:.2e}), ci {ci:?}");
        assert!(
            error <= 1.0 / n as f64 + 1e-12,
            "sobol n = {n}: {p} vs {exact}"
        );
        assert!(ci[0] <= exact && exact <= ci[1]);
    }
}

#[test]
fn samples_are_reproducible_and_shards_recombine() {
    let table = "[robust]\nsamples = 48\nseed = 11\nsampling = \"random\"\n\
                 [[robust.parameter]]\nparameter = \"controller.c\"\ndistribution = \"lognormal\"\nrelative = false\nmedian = 36.0\nsd = 0.3\n\
                 [[robust.parameter]]\nparameter = \"overrides.bearing_friction.f_s\"\ndistribution = \"normal\"\nsd = 0.05\n";
    let (loaded, robot_file, scenario) = study("robots/stage_1dof_rigid.urdf", table);
    let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
    let all: Vec<usize> = (0..48).collect();
    let whole = spec.run(&loaded, &robot_file, &all, 2, &|_, _| {});
    let again = spec.run(&loaded, &robot_file, &all, 1, &|_, _| {});
    assert_eq!(whole, again, "the same seed gives the same samples");
    let mut shards = Vec::new();
    for i in 0..3 {
        let mine: Vec<usize> = all.iter().copied().filter(|k| k % 3 == i).collect();
        shards.extend(spec.run(&loaded, &robot_file, &mine, 1, &|_, _| {}));
    }
    shards.sort_by_key(|r| r.index);
    assert_eq!(shards, whole, "shards recombine into the single run");
    let other = RobustSpec::from_scenario(&scenario, &robot_file, None, Some(12)).expect("spec");
    assert_ne!(
        other.values(0),
        spec.values(0),
        "another seed, other samples"
    );
    // Both verdicts appear, so the comparison is not between empty rows.
    let unstable = whole
        .iter()
        .filter(|r| r.outcome.stable_linear == Some(false))
        .count();
    assert!(unstable > 0 && unstable < 48, "{unstable} of 48 unstable");
}

#[test]
fn patterns_draw_each_match_or_one_shared_draw() {
    let pattern = |shared: bool| {
        format!(
            "[robust]\nsamples = 8\n[[robust.parameter]]\nparameter = \"overrides.friction_*.f_s\"\ndistribution = \"uniform\"\nhalf_width = 0.1\nshared = {shared}\n"
        )
    };
    let spec = |table: &str| {
        let (_, robot_file, scenario) = study("robots/stage_4fi.urdf", table);
        RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec")
    };
    let independent = spec(&pattern(false));
    assert_eq!(independent.dimensions.len(), 4);
    let values = independent.values(5);
    assert!(values.windows(2).any(|w| w[0] != w[1]), "independent draws");
    let shared = spec(&pattern(true));
    assert_eq!(shared.dimensions.len(), 1);
    assert_eq!(shared.columns().len(), 4);
    let values = shared.values(5);
    // Same nominal, same quantile: the same value for all four bearings.
    assert!(values.windows(2).all(|w| w[0] == w[1]), "{values:?}");
}

#[test]
fn nonsense_tables_are_named() {
    let error = |robust: &str| {
        // Refused where the scenario loads (keys and kinds of values, as
        // every table) or where the study reads the table (its meaning).
        let text = scenario_text("robots/stage_1dof_rigid.urdf", "k = 1e5\nc = 250", robust);
        if let Err(refusal) = Scenario::from_str(&text, Path::new("robust.toml")) {
            return refusal.to_string();
        }
        let (_, robot_file, scenario) = study("robots/stage_1dof_rigid.urdf", robust);
        RobustSpec::from_scenario(&scenario, &robot_file, None, None)
            .expect_err("refused")
            .to_string()
    };
    let entry = |body: &str| format!("[robust]\n[[robust.parameter]]\n{body}\n");
    let cases = [
        ("[robust]\nsamples = 10\n".to_string(), "nothing is toleranced"),
        (
            entry("parameter = \"controller.c\"\ndistribution = \"normal\"\nsd = 0.3"),
            "truncnormal",
        ),
        (
            entry("parameter = \"overrides.nope.f_s\"\ndistribution = \"uniform\"\nhalf_width = 0.1"),
            "nope",
        ),
        (
            entry("parameter = \"overrides.*.q\"\ndistribution = \"uniform\"\nhalf_width = 0.1"),
            "matches no parameter",
        ),
        (
            entry("parameter = \"controller.c\"\ndistribution = \"uniform\""),
            "robust.parameter[0].half_width",
        ),
        (
            entry("parameter = \"controller.k_i\"\ndistribution = \"uniform\"\nhalf_width = 0.1"),
            "robust.parameter[0].relative",
        ),
        (
            entry("parameter = \"controller.c\"\ndistribution = \"uniform\"\nrelative = false\nlow = 5\nhigh = 1"),
            "robust.parameter[0].high",
        ),
        (
            entry("parameter = \"controller.c\"\ndistribution = \"gamma\"\nsd = 1"),
            "robust",
        ),
        (
            format!(
                "{}[[robust.parameter]]\nparameter = \"controller.c\"\ndistribution = \"uniform\"\nhalf_width = 0.2\n",
                entry("parameter = \"controller.c\"\ndistribution = \"uniform\"\nhalf_width = 0.1")
            ),
            "toleranced twice",
        ),
        (
            "[robust]\nsamples = 70000\n[[robust.parameter]]\nparameter = \"controller.c\"\ndistribution = \"uniform\"\nhalf_width = 0.1\n".to_string(),
            "use random or lhs",
        ),
        (
            "[robust]\nsamples = 0\n[[robust.parameter]]\nparameter = \"controller.c\"\ndistribution = \"uniform\"\nhalf_width = 0.1\n".to_string(),
            "robust.samples",
        ),
    ];
    for (table, needle) in cases {
        let message = error(&table);
        assert!(message.contains(needle), "{needle:?} not in {message:?}");
    }
}

mod tuning {
    use super::*;
    use fistage_analysis::robust::tune::{Criterion, Population, TuneSettings, tune};

    fn fi_population() -> (Loaded, RobotSpec, RobustSpec) {
        let table = "[robust]\nsamples = 32\nseed = 2\n\
                     [[robust.parameter]]\nparameter = \"overrides.bearing_friction.f_s\"\ndistribution = \"normal\"\nsd = 0.05\n\
                     [[robust.parameter]]\nparameter = \"overrides.isolator.k_x\"\ndistribution = \"uniform\"\nhalf_width = 0.2\n";
        let (loaded, robot_file, scenario) = study("robots/stage_1dof_fi.urdf", table);
        let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
        (loaded, robot_file, spec)
    }

    /// The gains found keep every stage stable with the margin asked for,
    /// and 2% more stiffness (more bandwidth) fails at every damping of a
    /// grid twice as fine as the search's, checked by a separate run of the
    /// population through `RobustSpec::run`.
    #[test]
    fn tuned_gains_are_safe_and_a_little_more_bandwidth_is_not() {
        let (loaded, robot_file, spec) = fi_population();
        let population = Population::draw(&spec, &loaded, &robot_file, 32);
        assert_eq!(population.len(), 32);
        let settings = TuneSettings {
            k_range: [1e3, 1e6],
            c_range: [10.0, 1e3],
            points: 12,
            criterion: Criterion::Margin(0.5),
        };
        let tuning = tune(&population, &loaded, &robot_file, &settings, &|_| {});
        let [k, c] = tuning
            .gains
            .expect("admissible gains exist for the FI stage");
        println!("k = {k:.4e}, c = {c:.4e}, {:?}", tuning.standing);
        let worst_at = |k: f64, c: f64| {
            let mut base = loaded.clone();
            let controller = base.scenario.controller.as_mut().expect("controller");
            controller.k = k;
            controller.c = c;
            let all: Vec<usize> = (0..32).collect();
            spec.run(&base, &robot_file, &all, 2, &|_, _| {})
                .iter()
                .map(|r| r.outcome.max_real_eig.expect("linear verdict"))
                .fold(f64::NEG_INFINITY, f64::max)
        };
        // The table's draws do not touch the gains, so the run sees the tuned ones.
        let worst = worst_at(k, c);
        assert!(worst <= -0.5, "worst largest real part {worst}");
        let fine: Vec<f64> = (0..24)
            .map(|i| 10.0 * 100f64.powf(i as f64 / 23.0))
            .collect();
        for &cv in &fine {
            let worst = worst_at(1.02 * k, cv);
            assert!(
                worst > -0.5,
                "k x 1.02 with c = {cv} still keeps the margin: {worst}"
            );
        }
    }

    /// The four-bearing stage's anti-phase bearing modes are out of the
    /// servo's reach: no gains suffice, and more isolator damping is named
    /// as the remedy, by a factor that works.
    #[test]
    fn the_four_bearing_stage_needs_isolator_damping_not_gains() {
        let table = "[robust]\nsamples = 16\nseed = 1\n\
                     [[robust.parameter]]\nparameter = \"overrides.friction_*.f_s\"\ndistribution = \"truncnormal\"\nsd = 0.1\nlow = -0.15\nhigh = 0.25\n";
        let (loaded, robot_file, scenario) = study("robots/stage_4fi.urdf", table);
        let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
        let population = Population::draw(&spec, &loaded, &robot_file, 16);
        let settings = TuneSettings {
            k_range: [1e3, 1e6],
            c_range: [1.0, 1e3],
            points: 8,
            criterion: Criterion::Margin(0.0),
        };
        let tuning = tune(&population, &loaded, &robot_file, &settings, &|_| {});
        assert!(tuning.gains.is_none(), "{:?}", tuning.gains);
        let damping = &tuning.remedies[0];
        assert!(damping.what.contains("isolator damping"));
        let (factor, gains) = (
            damping.factor.expect("a factor"),
            damping.gains.expect("gains"),
        );
        println!("isolator damping x {factor:.2} at {gains:?}");
        assert!(factor > 1.0);
        let with = population.standing(Some(gains), &damping.parameters, factor);
        assert_eq!((with.unstable, with.undetermined), (0, 0), "{with:?}");
        let without = population.standing(Some(gains), &damping.parameters, 1.0);
        assert!(without.unstable > 0, "{without:?}");
    }
}

/// Simulated samples carry the tracking and yaw amplitudes: a four-bearing
/// stage whose bearings' friction differs yaws (the mismatch turns the
/// table), the 1-DOF stage has no yaw.
#[test]
fn simulated_samples_carry_the_yaw_of_a_floating_table() {
    let table = "[robust]\nsamples = 3\nanalysis = \"simulation\"\nduration = 0.3\nsampling = \"random\"\n\
                 [[robust.parameter]]\nparameter = \"overrides.friction_*.f_c\"\ndistribution = \"uniform\"\nhalf_width = 0.2\n";
    let (loaded, robot_file, scenario) = study("robots/stage_4fi.urdf", table);
    let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
    let results = spec.run(&loaded, &robot_file, &[0, 1, 2], 2, &|_, _| {});
    for r in &results {
        let yaw = r.outcome.yaw_amplitude.expect("a floating table yaws");
        assert!(yaw > 0.0 && yaw.is_finite(), "{yaw}");
        assert!(r.outcome.amplitude.is_some_and(f64::is_finite));
        assert!(r.outcome.stable_linear.is_none(), "simulation only");
    }
    let one = "[robust]\nsamples = 1\nanalysis = \"both\"\nduration = 0.3\n\
               [[robust.parameter]]\nparameter = \"controller.c\"\ndistribution = \"uniform\"\nhalf_width = 0.2\n";
    let (loaded, robot_file, scenario) = study("robots/stage_1dof_fi.urdf", one);
    let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
    let result = &spec.run(&loaded, &robot_file, &[0], 1, &|_, _| {})[0];
    assert!(result.outcome.yaw_amplitude.is_none());
    assert!(result.outcome.amplitude.is_some() && result.outcome.stable_linear.is_some());
}

mod integral {
    use super::*;
    use fistage_analysis::robust::tune::{Criterion, Population, TuneSettings, tune};

    /// With an integral gain in the servo, tune raises k_i as far as every
    /// stage allows at the chosen (k, c): 5% more makes a stage unstable.
    /// (The integral mode sits near -k_i / k, so no margin beyond it can
    /// be asked; the criterion here is plain stability.)
    #[test]
    fn the_integral_gain_is_raised_to_its_limit() {
        let table = "[robust]\nsamples = 16\nseed = 2\n\
                     [[robust.parameter]]\nparameter = \"overrides.bearing_friction.f_s\"\ndistribution = \"normal\"\nsd = 0.05\n";
        let (loaded, robot_file, scenario) = study_with_servo(
            "robots/stage_1dof_fi.urdf",
            "k = 6e4\nc = 100\nk_i = 100",
            table,
        );
        let spec = RobustSpec::from_scenario(&scenario, &robot_file, None, None).expect("spec");
        let population = Population::draw(&spec, &loaded, &robot_file, 16);
        let criterion = Criterion::Margin(0.0);
        let settings = TuneSettings {
            k_range: [1e3, 1e6],
            c_range: [10.0, 1e3],
            points: 10,
            criterion,
        };
        let tuning = tune(&population, &loaded, &robot_file, &settings, &|_| {});
        let gains = tuning.gains.expect("gains");
        let k_i = tuning.k_i.expect("an integral gain");
        println!("gains {gains:?}, k_i {k_i:.4e}");
        assert!(k_i >= 100.0);
        let path = ["controller.k_i".to_string()];
        let at = |factor: f64| population.standing(Some(gains), &path, factor * k_i / 100.0);
        assert!(at(1.0).admits(criterion), "{:?}", at(1.0));
        assert!(k_i < 1e8, "the limit lies inside the searched range");
        assert!(!at(1.05).admits(criterion), "{:?}", at(1.05));
    }
}

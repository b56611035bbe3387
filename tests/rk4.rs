//! The classical fourth-order engine: it agrees with Dormand-Prince on the
//! four-bearing traverse and converges at fourth order under a tighter
//! tolerance; the default engine takes it at loose tolerances on that stage
//! (where lightly damped bushing modes set the step) and Dormand-Prince at
//! tight ones, and there it takes fewer evaluations than Dormand-Prince.

use fistage_sim::MethodKind as Method;
use fistage_sim::{AutoEngine, initial_state};
use fistage_tests::{deviation, load, run_with};

#[test]
fn agrees_with_dormand_prince_and_converges_on_the_traverse() {
    let mut loaded = load("scenarios/coupling/friction20_traverse.toml");
    loaded.scenario.duration = 0.3;
    loaded.scenario.window = [0.15, 0.3];
    let reference = run_with(&loaded, "native", 1e-12);
    let runs: Vec<_> = [1e-5, 1e-7, 1e-9]
        .iter()
        .map(|&rtol| {
            let run = run_with(&loaded, "rk4", rtol);
            let d = deviation(&run, &reference, "encoder.position");
            println!(
                "rk4 rtol {rtol:e}: {:?}, deviation {d:.2e} of the range",
                run.trajectory.stats.counts
            );
            (d, run.trajectory.stats.counts)
        })
        .collect();
    let d: Vec<f64> = runs.iter().map(|(d, _)| *d).collect();
    assert!(d[0] < 1e-4, "{d:?}");
    assert!(d[1] < d[0] / 10.0 && d[2] < d[1] / 10.0, "{d:?}");
    // Fourth order: 100x tighter costs about 100^(1/4) = 3.2x the steps
    // where accuracy sets them (the tighter pair).
    let steps = |i: usize| runs[i].1.steps as f64;
    let ratio = steps(2) / steps(1);
    assert!((2.0..4.5).contains(&ratio), "step ratio {ratio}");
}

#[test]
fn auto_takes_it_at_loose_tolerances_where_the_bushings_set_the_step() {
    let mut loaded = load("scenarios/coupling/friction20_traverse.toml");
    loaded.scenario.duration = 0.3;
    loaded.scenario.window = [0.15, 0.3];
    let x0 = initial_state(&loaded.model, &loaded.scenario).expect("start");
    let auto = AutoEngine::for_scenario(&loaded.scenario);
    let loose = auto.choice(&loaded.model, &x0, 1e-6);
    println!("rtol 1e-6: {}", loose.reason);
    assert_eq!(loose.method, Method::Classical);
    assert_eq!(
        auto.choice(&loaded.model, &x0, 1e-8).method,
        Method::DormandPrince
    );
    let (classical, dormand_prince) = (
        run_with(&loaded, "auto", 1e-6),
        run_with(&loaded, "native", 1e-6),
    );
    assert_eq!(classical.trajectory.stats.engine, "rk4");
    let (a, b) = (
        classical.trajectory.stats.counts.rhs_evaluations,
        dormand_prince.trajectory.stats.counts.rhs_evaluations,
    );
    println!("evaluations at rtol 1e-6: rk4 {a}, native {b}");
    assert!((a as f64) < 0.8 * b as f64, "{a} against {b}");
    let d = deviation(&classical, &dormand_prince, "encoder.position");
    assert!(d < 1e-5, "{d:.2e} of the range");
    // A bristle-bound stage keeps the implicit-explicit method however loose.
    let slipping = load("scenarios/paper/fig06b_fi_vp50.toml");
    let x0 = initial_state(&slipping.model, &slipping.scenario).expect("start");
    let choice = AutoEngine::for_scenario(&slipping.scenario).choice(&slipping.model, &x0, 1e-5);
    assert_eq!(choice.method, Method::Imex);
}

//! Runs on the compiled right-hand side: a run switches to the machine code
//! after its first evaluations and its trajectory is, to the bit, the one
//! the generic evaluation gives; a run too short to pay for compiling does
//! not compile; every engine gives the same trajectory either way.

use fistage_codegen::Function;
use fistage_tests::{load, run};

#[test]
fn a_long_run_compiles_and_gives_the_generic_evaluations_trajectory() {
    for (scenario, duration, engine) in [
        ("scenarios/paper/fig05b_fi.toml", 0.5, "auto"),
        ("scenarios/paper/fig05b_fi.toml", 0.5, "native"),
        ("scenarios/paper/fig05b_fi.toml", 0.5, "dop853"),
        ("scenarios/coupling/friction20_traverse.toml", 0.4, "auto"),
        ("scenarios/coupling/friction20_traverse.toml", 0.4, "rk4"),
        ("scenarios/coupling/friction20_traverse.toml", 0.4, "imex"),
    ] {
        let mut fresh = load(scenario);
        fresh.scenario.duration = duration;
        fresh.scenario.window = [duration / 2.0, duration];
        fresh.scenario.solver.engine = engine.parse().expect("engine");
        let mut generic = fresh.clone();
        generic.model = fresh.model.interpreted();
        assert!(fresh.model.compiled(Function::Rhs).is_none());
        let (compiled_run, generic_run) = (run(&fresh), run(&generic));
        let counts = compiled_run.trajectory.stats.counts;
        println!("{scenario} {engine}: {counts:?}");
        assert!(counts.rhs_evaluations > 15_000, "{counts:?}");
        assert!(
            fresh.model.compiled(Function::Rhs).is_some(),
            "{scenario} {engine}: not compiled after {counts:?}"
        );
        assert_eq!(counts, generic_run.trajectory.stats.counts);
        assert_eq!(
            compiled_run.trajectory.states, generic_run.trajectory.states,
            "{scenario} {engine}"
        );
    }
}

#[test]
fn a_short_run_does_not_compile() {
    let mut loaded = load("scenarios/paper/fig05b_fi.toml");
    loaded.scenario.duration = 0.01;
    loaded.scenario.window = [0.0, 0.01];
    let output = run(&loaded);
    let evaluations = output.trajectory.stats.counts.rhs_evaluations;
    assert!(evaluations < 10_000, "{evaluations}");
    assert!(loaded.model.compiled(Function::Rhs).is_none());
    assert!(loaded.model.compiled(Function::ImplicitStage).is_none());
}

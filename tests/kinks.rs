//! Steps that end on the friction law's kinks (the sign changes of a
//! contact's slip velocity, where the bristle rate is not differentiable).
//! On the one-axis stage with four bearings, which sticks and slips on each
//! bearing at its own times (about 430 sign changes per bearing in 5 s),
//! stepping across the kinks had one attempt in five rejected and left the
//! encoder position 1.2e-6 of its range off at rtol 1e-8 (imex; 1.7e-6 with
//! Dormand-Prince). Landing the steps on the predicted crossings must keep
//! the rejections rare and the answer within the tolerance's reach, for the
//! explicit and the implicit-explicit engine alike.

use fistage_tests::{deviation, load, run_with as with};

#[test]
fn steps_land_on_the_kinks_of_a_stage_that_sticks_and_slips() {
    let loaded = load("scenarios/bench/axis_4fi_fig05b.toml");
    let reference = with(&loaded, "native", 1e-11);
    for engine in ["imex", "native"] {
        let run = with(&loaded, engine, 1e-8);
        let counts = run.trajectory.stats.counts;
        let rejected = counts.rejected as f64 / (counts.steps + counts.rejected) as f64;
        let d = deviation(&run, &reference, "encoder.position");
        println!(
            "{engine} rtol 1e-8: {} steps, {:.1}% of attempts rejected, deviation {d:.2e} of the range",
            counts.steps,
            100.0 * rejected
        );
        assert!(
            rejected < 0.05,
            "{engine}: {:.1}% rejected",
            100.0 * rejected
        );
        assert!(d < 5e-7, "{engine}: deviation {d:.2e} of the range");
    }
}

//! The eighth-order explicit engine (DOP853): it agrees with the fifth-order
//! engine and converges under a tighter tolerance on the paper's stick-slip
//! stage, and on the four-bearing stage through a point-to-point move, whose
//! start and end restart the integration (the continuous extension of the
//! step before each restart is formed from the inputs before it).

use fistage_tests::{deviation, load, run_with};

/// Deviation of `encoder.position` from a tight fifth-order reference at
/// each tolerance, with the step counts.
fn deviations(scenario: &str, rtols: &[f64]) -> Vec<(f64, u64)> {
    let loaded = load(scenario);
    let reference = run_with(&loaded, "native", 1e-12);
    rtols
        .iter()
        .map(|&rtol| {
            let run = run_with(&loaded, "dop853", rtol);
            let d = deviation(&run, &reference, "encoder.position");
            let counts = run.trajectory.stats.counts;
            println!(
                "{scenario} dop853 rtol {rtol:e}: {} steps, {} rejected, deviation {d:.2e} of the range",
                counts.steps, counts.rejected
            );
            (d, counts.steps)
        })
        .collect()
}

#[test]
fn agrees_with_the_fifth_order_engine_and_converges_on_stick_slip() {
    let found = deviations("scenarios/paper/fig05b_fi.toml", &[1e-6, 1e-8, 1e-10]);
    let d: Vec<f64> = found.iter().map(|(d, _)| *d).collect();
    assert!(d[1] < 1e-6, "{d:?}");
    assert!(d[1] < d[0] / 10.0 && d[2] < d[1] / 10.0, "{d:?}");
}

#[test]
fn agrees_through_the_restarts_of_a_point_to_point_move() {
    let found = deviations("scenarios/coupling/symmetric_p2p.toml", &[1e-7, 1e-10]);
    let d: Vec<f64> = found.iter().map(|(d, _)| *d).collect();
    assert!(d[1] < 1e-8, "{d:?}");
    assert!(d[1] < d[0], "{d:?}");
}

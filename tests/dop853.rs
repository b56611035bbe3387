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
    let reference = run_with(&loaded, "native", 1e-13);
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

/// Convergence is read where the tolerance sets the error. On this stage
/// DOP853's steps are held at its stability limit by the bristles up to
/// rtol 1e-8 (a fifth of the attempts rejected): there its error is the
/// same at 1e-7 and 1e-8 (3e-8) and moves by a factor of two when rtol moves
/// by one part in 10^7, so a convergence check that starts at rtol 1e-6
/// passes or fails with round-off. From 1e-8 on the error follows rtol.
#[test]
fn agrees_with_the_fifth_order_engine_and_converges_on_stick_slip() {
    let found = deviations(
        "scenarios/paper/fig05b_fi.toml",
        &[1e-8, 1e-9, 1e-10, 1e-11],
    );
    let d: Vec<f64> = found.iter().map(|(d, _)| *d).collect();
    assert!(d[0] < 1e-6, "{d:?}");
    assert!(d[2] < d[0] / 10.0 && d[3] < d[1] / 10.0, "{d:?}");
}

#[test]
fn agrees_through_the_restarts_of_a_point_to_point_move() {
    let found = deviations("scenarios/coupling/symmetric_p2p.toml", &[1e-7, 1e-10]);
    let d: Vec<f64> = found.iter().map(|(d, _)| *d).collect();
    assert!(d[1] < 1e-8, "{d:?}");
    assert!(d[1] < d[0], "{d:?}");
}

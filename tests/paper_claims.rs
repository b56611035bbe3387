//! The source paper's qualitative claims about the 1-DOF stages, measured.
//! The numbers fistage gets are quoted in the README; where fistage disagrees
//! with the paper (Fig. 10, rigid stage) the test states what fistage finds.

use fistage_sim::RunOutput;
use fistage_tests::{load, peak_to_peak, run, stats};

const TABLE: &str = "encoder.position";

fn run_paper(name: &str) -> (fistage_model::Loaded, RunOutput) {
    let loaded = load(&format!("scenarios/paper/{name}.toml"));
    let output = run(&loaded);
    (loaded, output)
}

/// Local maxima of a signal after `from`.
fn maxima(output: &RunOutput, signal: &str, from: f64) -> Vec<f64> {
    let t = &output.signals.times;
    let x = output.signals.column(signal).expect("signal");
    (1..x.len() - 1)
        .filter(|&k| t[k] >= from && x[k] > x[k - 1] && x[k] >= x[k + 1])
        .map(|k| x[k])
        .collect()
}

/// Spread of successive maxima relative to their mean: ~0 for a periodic limit
/// cycle, large for irregular motion.
fn maxima_spread(output: &RunOutput, from: f64) -> f64 {
    let m = maxima(output, TABLE, from);
    assert!(m.len() > 10, "too few oscillation maxima: {}", m.len());
    let mean = m.iter().sum::<f64>() / m.len() as f64;
    let sd = (m.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / m.len() as f64).sqrt();
    sd / mean.abs()
}

/// Fig. 5: at c = 10 both stages stick-slip and the FI amplitude is smaller; at
/// c = 100 the rigid stage settles while the FI stage keeps oscillating.
#[test]
fn fig05_friction_isolator_oscillations() {
    let p2p = |name: &str| peak_to_peak(&run_paper(name).1, TABLE);
    let (fi_a, rigid_a, fi_b, rigid_b) = (
        p2p("fig05a_fi"),
        p2p("fig05a_rigid"),
        p2p("fig05b_fi"),
        p2p("fig05b_rigid"),
    );
    assert!(
        fi_a > 1e-5 && rigid_a > 1e-5,
        "both oscillate at c = 10: {fi_a:e}, {rigid_a:e}"
    );
    assert!(
        fi_a < 0.8 * rigid_a,
        "FI amplitude smaller at c = 10: {fi_a:e} vs {rigid_a:e}"
    );
    assert!(
        rigid_b < 1e-9,
        "rigid stage settles at c = 100: {rigid_b:e}"
    );
    assert!(
        fi_b > 1e-5,
        "FI stage still oscillates at c = 100: {fi_b:e}"
    );
}

/// Fig. 10 (k = 6.5e5, c = 250): the FI stage converges to a limit cycle. The
/// paper also shows a limit cycle for the rigid stage, about ten times larger;
/// fistage finds the rigid stage's slipping equilibrium linearly stable and
/// reached from rest, so it settles instead.
#[test]
fn fig10_limit_cycle_with_fi() {
    let (loaded, fi) = run_paper("fig10_fi");
    let amplitude = peak_to_peak(&fi, TABLE);
    assert!(
        amplitude > 5e-6 && amplitude < 2e-5,
        "FI limit cycle {amplitude:e} m"
    );
    assert!(
        maxima_spread(&fi, loaded.scenario.window[0]) < 0.01,
        "FI motion is periodic"
    );
    let rigid = peak_to_peak(&run_paper("fig10_rigid").1, TABLE);
    println!("Fig. 10: table peak-to-peak FI {amplitude:.4e} m, rigid {rigid:.4e} m");
    assert!(rigid < 1e-9, "rigid stage settles: {rigid:e}");
}

/// Fig. 12 (FI, k = 2e4, c = 100): without integral action the table stays
/// about 0.3 mm off; k_i = 1e5 removes the offset; 1e6 oscillates periodically;
/// 5e6 oscillates irregularly.
#[test]
fn fig12_integral_action() {
    let (_, ki0) = run_paper("fig12_ki0");
    let offset = stats(&ki0, TABLE);
    assert!(
        (2.5e-4..3.5e-4).contains(&offset.mean),
        "offset {:e} m",
        offset.mean
    );
    assert!(offset.peak_to_peak < 1e-8);
    let (_, ki1e5) = run_paper("fig12_ki1e5");
    let removed = stats(&ki1e5, TABLE);
    assert!(
        removed.mean.abs() < 1e-7 && removed.peak_to_peak < 1e-7,
        "{removed:?}"
    );
    let (loaded, ki1e6) = run_paper("fig12_ki1e6");
    assert!(peak_to_peak(&ki1e6, TABLE) > 1e-4);
    let regular = maxima_spread(&ki1e6, loaded.scenario.window[0]);
    assert!(regular < 0.01, "k_i = 1e6 maxima spread {regular}");
    let (loaded, ki5e6) = run_paper("fig12_ki5e6");
    assert!(peak_to_peak(&ki5e6, TABLE) > 1e-4);
    let irregular = maxima_spread(&ki5e6, loaded.scenario.window[0]);
    println!(
        "Fig. 12: k_i = 0 offset {:.4e} m; k_i = 1e5 mean {:.3e} m, p2p {:.3e} m; \
         k_i = 1e6 p2p {:.4e} m, maxima spread {regular:.2e}; k_i = 5e6 p2p {:.4e} m, maxima spread {irregular:.2e}",
        offset.mean,
        removed.mean,
        removed.peak_to_peak,
        peak_to_peak(&ki1e6, TABLE),
        peak_to_peak(&ki5e6, TABLE)
    );
    assert!(irregular > 0.1, "k_i = 5e6 maxima spread {irregular}");
}

/// Time in the window during which the bearing is stuck to its counter-surface.
pub fn stuck_time(output: &RunOutput, from: f64, threshold: f64) -> f64 {
    let t = &output.signals.times;
    let slip = output
        .signals
        .column("bearing_friction.slip_velocity")
        .expect("slip");
    let dt = t[1] - t[0];
    t.iter()
        .zip(slip)
        .filter(|(time, v)| **time >= from && v.abs() < threshold)
        .count() as f64
        * dt
}

/// Fig. 13 (tracking 1 mm sin(0.2 pi t)): with the platform at rest the bearing
/// sticks at every reversal; with the platform at 1 mm/s it never sticks.
#[test]
fn fig13_stiction_at_reversals() {
    // 2% of the reference's peak velocity (0.63 mm/s).
    let threshold = 0.02 * 2.0 * std::f64::consts::PI * 0.1 * 1e-3;
    let (loaded, at_rest) = run_paper("fig13_vp0");
    let from = loaded.scenario.window[0];
    let stuck = stuck_time(&at_rest, from, threshold);
    println!("Fig. 13: bearing stuck {stuck:.3} s of the last 10 s with the platform at rest");
    // A sliding sinusoid spends only 2 * 0.02 / pi = 1.3% of the time that slow.
    assert!(
        stuck > 1.0,
        "bearing stuck {stuck} s of 10 s with the platform at rest"
    );
    let (_, moving) = run_paper("fig13_vp1");
    let stuck = stuck_time(&moving, from, threshold);
    println!("Fig. 13: bearing stuck {stuck:.3} s of the last 10 s with the platform at 1 mm/s");
    assert_eq!(
        stuck, 0.0,
        "bearing never sticks with the platform at 1 mm/s"
    );
}

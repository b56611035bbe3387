//! The implicit-explicit engine (ARK5(4)8L[2]SA, bristles implicit) and the
//! default engine's choice: imex agrees with the explicit engine and
//! converges under a tighter tolerance; where the bristle relaxation bounds
//! the explicit step it takes several times fewer steps; `auto` takes imex
//! there and the explicit method where the bushings bound the step, and its
//! run is the chosen engine's, to the bit.

use fistage_model::Loaded;
use fistage_sim::MethodKind as Method;
use fistage_sim::{AutoEngine, RunOutput, initial_state};
use fistage_tests::{deviation, load, run_with as with, stats};

fn steps(run: &RunOutput) -> u64 {
    run.trajectory.stats.counts.steps
}

#[test]
fn agrees_with_the_explicit_engine_and_converges() {
    let loaded = load("scenarios/paper/fig05b_fi.toml");
    let reference = with(&loaded, "native", 1e-11);
    let target = stats(&reference, "encoder.position");
    let mut deviations = Vec::new();
    for rtol in [1e-6, 1e-8, 1e-10] {
        let run = with(&loaded, "imex", rtol);
        let d = deviation(&run, &reference, "encoder.position");
        let s = stats(&run, "encoder.position");
        let p2p = (s.peak_to_peak - target.peak_to_peak).abs() / target.peak_to_peak;
        println!(
            "imex rtol {rtol:e}: {} steps, deviation {d:.2e} of the range, p2p {p2p:.2e}",
            steps(&run)
        );
        deviations.push(d);
    }
    assert!(deviations[1] < 1e-5, "{deviations:?}");
    assert!(deviations[2] < deviations[1] / 10.0, "{deviations:?}");
    assert!(deviations[1] < deviations[0], "{deviations:?}");
}

#[test]
fn bristle_bound_stages_take_imex_and_bushing_bound_ones_do_not() {
    // Fig. 6b at 50 mm/s: the FI stage slips throughout, the bristles bound
    // the explicit step.
    let slipping = load("scenarios/paper/fig06b_fi_vp50.toml");
    let choice = |loaded: &Loaded| {
        let x0 = initial_state(&loaded.model, &loaded.scenario).expect("start");
        AutoEngine::for_scenario(&loaded.scenario).choice(
            &loaded.model,
            &x0,
            loaded.scenario.solver.rtol,
        )
    };
    let picked = choice(&slipping);
    println!("fig06b_fi_vp50: {}", picked.reason);
    assert_eq!(picked.method, Method::Imex);
    let (explicit, imex) = (
        with(&slipping, "native", 1e-8),
        with(&slipping, "imex", 1e-8),
    );
    println!("steps: native {}, imex {}", steps(&explicit), steps(&imex));
    assert!(steps(&imex) * 4 < steps(&explicit));
    let d = deviation(&imex, &explicit, "encoder.position");
    assert!(d < 1e-5, "imex against native: {d:.2e} of the range");
    let auto = with(&slipping, "auto", 1e-8);
    assert_eq!(auto.trajectory.states, imex.trajectory.states);
    assert_eq!(auto.trajectory.stats.engine, "imex");

    // The four-bearing traverse: its stiff bushings, not the bristles,
    // bound the explicit step.
    let traverse = load("scenarios/coupling/friction20_traverse.toml");
    let picked = choice(&traverse);
    println!("friction20_traverse: {}", picked.reason);
    assert_eq!(picked.method, Method::DormandPrince);
}

/// The four-bearing stage under the Fig. 5b conditions: the full-state
/// Jacobian at its slipping equilibrium (quaternion rows and all) once sent
/// the unbalanced Schur iteration into an endless loop, so the default engine
/// never started. Its spectral radius must now come out, and agree with that
/// of the Jacobian in tangent coordinates (rotation vectors instead of the
/// quaternion: a different matrix with the same modes but the quaternion's
/// norm direction, which is neutral).
#[test]
fn the_choice_reads_the_four_bearing_stage_spectrum() {
    use fistage_model::EquilibriumKind;
    use fistage_model::eigen::spectral_radius;
    for path in [
        "scenarios/coupling/symmetric_fig05b.toml",
        "scenarios/coupling/symmetric_real_height_fig05b.toml",
    ] {
        let loaded = load(path);
        let x0 = initial_state(&loaded.model, &loaded.scenario).expect("start");
        let picked = AutoEngine::for_scenario(&loaded.scenario).choice(
            &loaded.model,
            &x0,
            loaded.scenario.solver.rtol,
        );
        println!("{path}: {}", picked.reason);
        let full = picked.full_radius.expect("the full spectrum");
        let slipping = loaded.scenario.slipping_inputs();
        let equilibrium = loaded
            .model
            .equilibrium(EquilibriumKind::Slipping, &slipping, &x0)
            .expect("slipping equilibrium");
        let (tangent, _) = loaded.model.tangent_jacobian(&equilibrium, &slipping);
        let reduced = spectral_radius(&tangent).expect("the tangent spectrum");
        assert!(
            (full - reduced).abs() < 1e-8 * reduced,
            "{path}: {full:e} against {reduced:e} in tangent coordinates"
        );
        // The bushings (kHz), not the bristles, bound the explicit step here.
        assert_eq!(picked.method, Method::DormandPrince, "{path}");
        assert!(
            full > 2.0 * std::f64::consts::PI * 1.4e3,
            "{path}: {full:e}"
        );
    }
}

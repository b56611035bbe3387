//! Converged results: tightening the tolerance 100x changes no reported
//! steady-state peak-to-peak by more than 0.5% on the Fig. 5 cases. Signals
//! that have settled (peak-to-peak below 1e-6 of their largest value over the
//! whole run) must stay settled.

use fistage_tests::{load, run};

#[test]
fn fig05_statistics_are_converged() {
    for name in ["fig05a_fi", "fig05a_rigid", "fig05b_fi", "fig05b_rigid"] {
        let mut loaded = load(&format!("scenarios/paper/{name}.toml"));
        loaded.scenario.solver.rtol = 1e-8;
        let coarse = run(&loaded);
        loaded.scenario.solver.rtol = 1e-10;
        let fine = run(&loaded);
        for (c, f) in coarse.summary.iter().zip(&fine.summary) {
            assert_eq!(c.name, f.name);
            let column = fine.signals.column(&f.name).expect("signal");
            let size = column.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
            let (p_coarse, p_fine) = (c.stats.peak_to_peak, f.stats.peak_to_peak);
            if p_fine > 1e-6 * size {
                let change = (p_coarse - p_fine).abs() / p_fine;
                assert!(
                    change <= 0.005,
                    "{name}: {} peak-to-peak {p_coarse:e} at rtol 1e-8 vs {p_fine:e} at 1e-10 ({:.3}%)",
                    c.name,
                    100.0 * change
                );
            } else {
                assert!(
                    p_coarse <= 1e-5 * size,
                    "{name}: {} settled at rtol 1e-10 (p2p {p_fine:e}) but not at 1e-8 ({p_coarse:e})",
                    c.name
                );
            }
        }
    }
}

//! Helpers shared by the integration tests.
#![allow(dead_code)]

use fistage_ident::{FrfFit, StribeckFit};
use fistage_model::LugreParams;

/// The two parameter sets of the tests: the paper's Table 1 and a small stage.
pub fn parameter_sets() -> [(&'static str, LugreParams, f64); 2] {
    [
        (
            "table1",
            LugreParams::paper_table1(),
            fistage_ident::synth::TABLE1_MASS,
        ),
        (
            "small stage",
            fistage_ident::synth::small_stage(),
            fistage_ident::synth::SMALL_STAGE_MASS,
        ),
    ]
}

pub fn rel(a: f64, b: f64) -> f64 {
    (a / b - 1.0).abs()
}

/// The true (f_c, f_s, v_s, sigma2).
pub fn stribeck_truth(p: &LugreParams) -> [f64; 4] {
    [p.f_c, p.f_s, p.v_s, p.sigma2]
}

/// Relative errors of (f_c, f_s, v_s, sigma2).
pub fn stribeck_errors(fit: &StribeckFit, p: &LugreParams) -> [f64; 4] {
    let e = fit.estimates();
    let t = stribeck_truth(p);
    [0, 1, 2, 3].map(|k| rel(e[k].value, t[k]))
}

/// Relative errors of (sigma0, sigma1 + sigma2, mass).
pub fn frf_errors(fit: &FrfFit, p: &LugreParams, mass: f64) -> [f64; 3] {
    [
        rel(fit.sigma0.value, p.sigma0),
        rel(fit.damping.value, p.sigma1 + p.sigma2),
        rel(fit.mass.value, mass),
    ]
}

pub fn max(values: &[f64]) -> f64 {
    values.iter().copied().fold(0.0, f64::max)
}

//! The paper's Routh-Hurwitz test for the rigid (no isolator) PD stage at its
//! slipping equilibrium (Eqs. 17-20), as printed and corrected.
//!
//! In the paper's dimensionless variables (omega_n = sqrt(k / M), zeta =
//! c / (2 M omega_n), kappa_2 = sigma0 / k, eta_2 = sigma2 / c, gamma_2 =
//! sigma1 / c, H = |v| / (omega_n g(v)), Gamma = v g'(v) / g(v) at v = x_p'),
//! the characteristic polynomial of J_{1,2} is `lambda^3 + a1 lambda^2 + a2
//! lambda + a3` with
//!
//! ```text
//! a1 = 2 zeta (1 + eta_2 + gamma_2 Gamma) + H
//! a2 = kappa_2 Gamma + 2 zeta H (1 + eta_2) + 1
//! a3 = H
//! ```
//!
//! and the equilibrium is stable iff `a1 > 0`, `a3 > 0` and `a1 a2 > a3`.
//! Two misprints in the paper: Eq. 20 gives the last term of a1 as
//! `2 gamma_2 Gamma` (the factor zeta is missing; J_{1,2}'s own entry
//! `-2 zeta A1` has it), and the Routh condition is printed as
//! `(a1 a2 - a0 a3) / a2 > 0`, where the Routh array's entry is
//! `(a1 a2 - a0 a3) / a1`. Here M = m_t + m_b, the mass of Eq. 3: Eq. 13
//! writes m_t, which is the isolator model's mass.

use fistage_model::LugreParams;

/// The rigid PD stage of paper Eq. 3 sliding over a platform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RigidStage {
    /// Moving mass m_t + m_b, kg.
    pub mass: f64,
    /// Proportional gain, N/m.
    pub k: f64,
    /// Derivative gain, N s/m.
    pub c: f64,
    /// Friction.
    pub lugre: LugreParams,
    /// Platform velocity, m/s (non-zero).
    pub platform_velocity: f64,
}

/// Coefficients and verdicts of the Routh-Hurwitz test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RouthHurwitz {
    /// a1, a2, a3 of the corrected characteristic polynomial (a0 = 1).
    pub coefficients: [f64; 3],
    /// Natural frequency used for the dimensionless time, rad/s.
    pub omega_n: f64,
    /// Verdict of the corrected conditions.
    pub stable: bool,
    /// Verdict of the conditions as printed in the paper (Eq. 20 and the text below it).
    pub stable_as_printed: bool,
}

/// Routh-Hurwitz at the slipping equilibrium of the rigid stage.
pub fn rigid_slipping(stage: &RigidStage) -> RouthHurwitz {
    let p = &stage.lugre;
    let omega_n = (stage.k / stage.mass).sqrt();
    let zeta = stage.c / (2.0 * stage.mass * omega_n);
    let (kappa2, eta2, gamma2) = (p.sigma0 / stage.k, p.sigma2 / stage.c, p.sigma1 / stage.c);
    let v = stage.platform_velocity;
    let g = p.g(v);
    let dg = -(p.f_s - p.f_c) * (-(v / p.v_s).powi(2)).exp() * 2.0 * v / (p.v_s * p.v_s) / p.sigma0;
    let h = v.abs() / (omega_n * g);
    let gamma = v * dg / g;
    let a1 = 2.0 * zeta * (1.0 + eta2 + gamma2 * gamma) + h;
    let a2 = kappa2 * gamma + 2.0 * zeta * h * (1.0 + eta2) + 1.0;
    let a3 = h;
    let printed_a1 = 2.0 * zeta + h + 2.0 * eta2 * zeta + 2.0 * gamma2 * gamma;
    RouthHurwitz {
        coefficients: [a1, a2, a3],
        omega_n,
        stable: a1 > 0.0 && a3 > 0.0 && a1 * a2 - a3 > 0.0,
        stable_as_printed: printed_a1 > 0.0 && (printed_a1 * a2 - a3) / a2 > 0.0,
    }
}

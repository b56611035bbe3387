//! Modal analysis at an equilibrium: linearise in tangent coordinates, take all
//! eigenpairs, and describe each mode by its frequency, damping ratio, shape in
//! named coordinates and kinetic-energy participation.

use fistage_model::{EquilibriumError, EquilibriumKind, Inputs, JointMotion, Model};
use nalgebra::{Complex, DMatrix};
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::eigen::eigen_decomposition;

/// Why a modal analysis failed.
#[derive(Debug, Error)]
pub enum AnalysisError {
    /// No equilibrium was found.
    #[error(transparent)]
    Equilibrium(#[from] EquilibriumError),
}

/// Kinetic-energy share of one coordinate in a mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Participation {
    /// Coordinate name: `table.x` .. `table.yaw`, or a body on a prismatic or revolute joint.
    pub coordinate: String,
    /// Share of the mode's kinetic energy (diagonal of the mass matrix), 0 to 1.
    pub share: f64,
    /// Shape entry: magnitude relative to the largest position entry.
    pub magnitude: f64,
    /// Shape entry: phase relative to the largest position entry, degrees.
    pub phase_deg: f64,
}

/// One eigenvalue (one of each complex-conjugate pair) and what moves in it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Mode {
    /// Real part of the eigenvalue, 1/s.
    pub real: f64,
    /// Imaginary part (>= 0), rad/s.
    pub imag: f64,
    /// Undamped natural frequency |lambda| / 2 pi, Hz.
    pub frequency_hz: f64,
    /// Damped frequency Im(lambda) / 2 pi, Hz (0 for a real eigenvalue).
    pub damped_frequency_hz: f64,
    /// Damping ratio -Re(lambda) / |lambda| (1 for a decaying real eigenvalue, < 0 unstable;
    /// meaningless for a neutral eigenvalue, whose sign is round-off).
    pub damping_ratio: f64,
    /// Whether the eigenvalue is zero to round-off (|lambda| below 1e-8 of the
    /// Jacobian's norm): a free coordinate, such as a stuck bearing's position.
    pub neutral: bool,
    /// Whether the eigenvalue is complex.
    pub oscillatory: bool,
    /// Kinetic-energy participation per position coordinate.
    pub participation: Vec<Participation>,
    /// Share of the eigenvector (scaled by nominal state sizes) in the bristle states.
    pub bristle_share: f64,
    /// Coordinate with the largest kinetic-energy share.
    pub dominant: String,
    /// Relative eigen-residual (accuracy check).
    pub residual: f64,
}

impl Mode {
    /// Kinetic-energy share of a named coordinate.
    pub fn share(&self, coordinate: &str) -> f64 {
        self.participation
            .iter()
            .find(|p| p.coordinate == coordinate)
            .map_or(0.0, |p| p.share)
    }
}

impl ModalAnalysis {
    /// The modes with mechanical content (oscillatory, less than half of the
    /// eigenvector in the bristle states), unstable ones first, then by
    /// natural frequency: the ones worth drawing.
    pub fn mechanical_modes(&self) -> Vec<usize> {
        let mut order: Vec<usize> = (0..self.modes.len())
            .filter(|&k| self.modes[k].oscillatory && self.modes[k].bristle_share < 0.5)
            .collect();
        order.sort_by(|&a, &b| {
            let (ma, mb) = (&self.modes[a], &self.modes[b]);
            (mb.real > 0.0)
                .cmp(&(ma.real > 0.0))
                .then(ma.frequency_hz.total_cmp(&mb.frequency_hz))
        });
        order
    }
}

/// What the eigenvalues can back about an equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every non-neutral eigenvalue lies in the open left half plane, by more
    /// than the numerical error.
    Stable,
    /// Some eigenvalue lies in the right half plane by more than the error.
    Unstable,
    /// The decomposition failed a check, or the largest real part is within
    /// its numerical error of zero.
    Undetermined,
}

/// An eigenvalue smaller than this times the Jacobian's norm is neutral
/// (zero within what the decomposition resolves).
const NEUTRAL: f64 = RESOLVED;

/// Below this times the Jacobian's norm an eigenvalue is zero to round-off;
/// between it and [`NEUTRAL`] a growing one cannot be told from zero.
const RESOLVED: f64 = 1e3 * f64::EPSILON;

/// Largest relative eigen-residual `|J v - lambda v| / (|J| + |lambda|)` a
/// pair may have and still be trusted.
const RESIDUAL_LIMIT: f64 = 1e-6;

/// The verdict the eigenvalues back, with the reason when none: the Jacobian
/// and eigenvalues are finite, every pair's residual is small, the
/// eigenvalues sum to the trace (an independent check of the whole set), and
/// the largest real part is farther from zero than the error the residuals
/// and the Jacobian's norm allow.
fn verdict(
    jacobian: &DMatrix<f64>,
    pairs: &[crate::eigen::EigenPair],
    modes: &[Mode],
    max_real_part: f64,
) -> (Verdict, Option<String>) {
    let any_active = modes.iter().any(|m| !m.neutral);
    let undetermined = |why: String| (Verdict::Undetermined, Some(why));
    if jacobian.iter().any(|v| !v.is_finite()) {
        return undetermined("the Jacobian has non-finite entries".into());
    }
    if pairs
        .iter()
        .any(|p| !(p.value.re.is_finite() && p.value.im.is_finite()))
    {
        return undetermined("the eigenvalue iteration did not converge".into());
    }
    let scale = jacobian.norm().max(f64::MIN_POSITIVE);
    let n = jacobian.nrows().max(1) as f64;
    let sum: f64 = pairs.iter().map(|p| p.value.re).sum();
    let trace = jacobian.trace();
    if (sum - trace).abs() > 1e-8 * n * scale {
        return undetermined(format!(
            "the eigenvalues sum to {sum:.6e}, the Jacobian's trace is {trace:.6e}"
        ));
    }
    let worst = pairs.iter().map(|p| p.residual).fold(0.0, f64::max);
    if worst.is_nan() || worst > RESIDUAL_LIMIT {
        return undetermined(format!(
            "an eigenpair's relative residual is {worst:.1e} (limit {RESIDUAL_LIMIT:.0e})"
        ));
    }
    if !any_active {
        return undetermined("every eigenvalue is neutral (zero within round-off)".into());
    }
    let error = RESOLVED.max(worst) * scale;
    if max_real_part > error {
        // A resolved growing mode: unstable whatever the unresolved ones do.
        return (Verdict::Unstable, None);
    }
    if let Some(hidden) = modes
        .iter()
        .find(|m| m.neutral && m.real > 0.0 && m.real.hypot(m.imag) > RESOLVED * scale)
    {
        return undetermined(format!(
            "a growing mode ({:.3e} {:+.3e}i 1/s) is too small to resolve against a Jacobian of norm {scale:.1e}",
            hidden.real, hidden.imag
        ));
    }
    if max_real_part.abs() <= error {
        return undetermined(format!(
            "the largest real part {max_real_part:.3e} 1/s is within the numerical error {error:.1e} 1/s of zero (Jacobian norm {scale:.1e})"
        ));
    }
    (Verdict::Stable, None)
}

/// The inputs at which a scenario's equilibria are studied: no reference
/// motion, and the counter-surface at the platform velocity less the
/// reference's traverse velocity (a traverse at V over a still surface is,
/// for the friction, the stage at rest over a surface sliding at -V).
pub fn equilibrium_inputs(scenario: &fistage_model::Scenario) -> Inputs {
    scenario.slipping_inputs()
}

/// Everything the linearisation at one equilibrium says.
#[derive(Debug, Clone, Serialize)]
pub struct ModalAnalysis {
    /// `sticking` or `slipping`.
    pub equilibrium: String,
    /// The equilibrium state (full coordinates, in the model's state order).
    pub state: Vec<f64>,
    /// Position coordinate names, in shape order.
    pub coordinates: Vec<String>,
    /// Modes sorted by natural frequency.
    pub modes: Vec<Mode>,
    /// Largest real part of the eigenvalues that are not neutral, 1/s.
    pub max_real_part: f64,
    /// Number of neutral (zero) eigenvalues: |lambda| below 1e-10 of the
    /// Jacobian's norm. A stuck contact has one each, since its bristle
    /// deflection and its position then move together.
    pub neutral: usize,
    /// Every eigenvalue that is not neutral lies in the open left half plane,
    /// and the eigen-decomposition passed its checks (see `verdict`).
    pub stable: bool,
    /// `stable`, `unstable`, or `undetermined` when the numerics cannot back
    /// either (see `undetermined_reason`).
    pub verdict: Verdict,
    /// Why the verdict is undetermined.
    pub undetermined_reason: Option<String>,
    /// The tangent-coordinate Jacobian.
    #[serde(skip)]
    pub jacobian: DMatrix<f64>,
    /// Names of the tangent coordinates (rows and columns of the Jacobian).
    pub jacobian_coordinates: Vec<String>,
    /// The Jacobian row by row, for the JSON output.
    pub jacobian_rows: Vec<Vec<f64>>,
}

/// Readable names of the position coordinates in tangent order: floating
/// joints as `<body>.x .y .z .roll .pitch .yaw`, others by body name.
pub fn coordinate_names(model: &Model) -> Vec<String> {
    let mut names = vec![String::new(); model.layout().nv];
    for body in model.bodies() {
        let v0 = body.joint.v_offset;
        match body.joint.motion {
            JointMotion::Floating => {
                for (k, axis) in ["x", "y", "z", "roll", "pitch", "yaw"].iter().enumerate() {
                    names[v0 + k] = format!("{}.{axis}", body.name);
                }
            }
            _ => names[v0] = body.name.clone(),
        }
    }
    names
}

/// Linearises at the equilibrium of the given kind and describes every mode.
pub fn modal_analysis(
    model: &Model,
    inputs: &Inputs,
    kind: EquilibriumKind,
    start: &[f64],
) -> Result<ModalAnalysis, AnalysisError> {
    let mut inputs = *inputs;
    if kind == EquilibriumKind::Sticking {
        inputs.platform_velocity = 0.0;
    }
    let state = model.equilibrium(kind, &inputs, start)?;
    let (jacobian, tangent) = model.tangent_jacobian(&state, &inputs);
    let np = tangent.n_positions;
    let mass = model.mass_matrix(&state);
    let coordinates = coordinate_names(model);
    let nominal: Vec<f64> = tangent
        .names
        .iter()
        .map(|n| {
            model
                .layout()
                .index(n)
                .map_or(1e-3, |i| model.layout().nominal[i])
        })
        .collect();
    let is_bristle: Vec<bool> = tangent
        .kinds
        .iter()
        .map(|k| *k == fistage_model::StateKind::Bristle)
        .collect();
    let mut modes = Vec::new();
    let pairs = eigen_decomposition(&jacobian);
    for mut pair in pairs.iter().cloned() {
        // Repeated real roots can come out of the Schur form as a pair with
        // imaginary parts at round-off level: they are two real eigenvalues.
        if pair.value.im.abs() <= 1e-9 * pair.value.norm().max(1.0) {
            pair.value.im = 0.0;
        }
        if pair.value.im < 0.0 {
            continue;
        }
        let velocity: Vec<Complex<f64>> = (0..np).map(|i| pair.vector[np + i]).collect();
        let energy: Vec<f64> = (0..np)
            .map(|i| mass[(i, i)] * velocity[i].norm_sqr())
            .collect();
        let total: f64 = energy.iter().sum::<f64>().max(f64::MIN_POSITIVE);
        let reference = (0..np)
            .max_by(|&a, &b| pair.vector[a].norm().total_cmp(&pair.vector[b].norm()))
            .map(|i| pair.vector[i])
            .unwrap_or(Complex::new(1.0, 0.0));
        let participation: Vec<Participation> = (0..np)
            .map(|i| {
                let relative = if reference.norm() > 0.0 {
                    pair.vector[i] / reference
                } else {
                    Complex::new(0.0, 0.0)
                };
                Participation {
                    coordinate: coordinates[i].clone(),
                    share: energy[i] / total,
                    magnitude: relative.norm(),
                    phase_deg: relative.arg().to_degrees(),
                }
            })
            .collect();
        let scaled_norm = |select: &dyn Fn(usize) -> bool| -> f64 {
            (0..pair.vector.len())
                .filter(|&i| select(i))
                .map(|i| (pair.vector[i].norm() / nominal[i]).powi(2))
                .sum::<f64>()
        };
        let all = scaled_norm(&|_| true).max(f64::MIN_POSITIVE);
        let bristle_share = scaled_norm(&|i| is_bristle[i]) / all;
        let dominant = participation
            .iter()
            .max_by(|a, b| a.share.total_cmp(&b.share))
            .map(|p| p.coordinate.clone())
            .unwrap_or_default();
        let magnitude = pair.value.norm();
        modes.push(Mode {
            real: pair.value.re,
            imag: pair.value.im,
            frequency_hz: magnitude / (2.0 * std::f64::consts::PI),
            damped_frequency_hz: pair.value.im / (2.0 * std::f64::consts::PI),
            damping_ratio: if magnitude > 0.0 {
                -pair.value.re / magnitude
            } else {
                0.0
            },
            oscillatory: pair.value.im > 1e-9 * magnitude.max(1.0),
            neutral: false,
            participation,
            bristle_share,
            dominant,
            residual: pair.residual,
        });
    }
    let scale = jacobian.norm().max(1.0);
    for mode in &mut modes {
        mode.neutral = (mode.real * mode.real + mode.imag * mode.imag).sqrt() < NEUTRAL * scale;
    }
    let neutral = modes.iter().filter(|m| m.neutral).count();
    let any_active = modes.iter().any(|m| !m.neutral);
    // Over every mode when all are neutral, so the number is never infinite.
    let max_real_part = modes
        .iter()
        .filter(|m| !m.neutral || !any_active)
        .map(|m| m.real)
        .filter(|r| r.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    let max_real_part = if max_real_part.is_finite() {
        max_real_part
    } else {
        0.0
    };
    let (verdict, undetermined_reason) = verdict(&jacobian, &pairs, &modes, max_real_part);
    Ok(ModalAnalysis {
        equilibrium: kind.name().into(),
        state,
        coordinates,
        modes,
        max_real_part,
        neutral,
        stable: verdict == Verdict::Stable,
        verdict,
        undetermined_reason,
        jacobian_coordinates: tangent.names.clone(),
        jacobian_rows: (0..jacobian.nrows())
            .map(|r| jacobian.row(r).iter().copied().collect())
            .collect(),
        jacobian,
    })
}

//! Equilibria of a model, found by Newton's method in tangent coordinates with
//! the exact Jacobian. All velocities are zero at both kinds:
//!
//! - **sticking** (pre-motion): every contact is stuck, `v = 0`, and holds the
//!   point where its bristles put it: `z = z_0 + s`, with `s` the contact's
//!   displacement since the start. The platform is taken at rest (the sticking
//!   Jacobian does not depend on its velocity).
//! - **slipping**: the stage stands still while the counter-surfaces slide at
//!   the platform velocity, so every bristle sits at `z = sgn(v) g(v)` (paper
//!   Eq. 7) and the servo, isolators and gravity balance the steady friction.
//!
//! With integral action the tracking error is zero at both.

use nalgebra::{DMatrix, DVector};
use thiserror::Error;

use crate::elements::Inputs;
use crate::model::Model;

/// Which equilibrium.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EquilibriumKind {
    /// Contacts stuck (pre-motion regime).
    Sticking,
    /// Contacts sliding at the platform velocity.
    Slipping,
}

impl EquilibriumKind {
    /// Its name in reports and JSON: `sticking` or `slipping`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Sticking => "sticking",
            Self::Slipping => "slipping",
        }
    }
}

/// Why no equilibrium was found.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EquilibriumError {
    /// Newton's method did not converge.
    #[error(
        "no {kind:?} equilibrium: Newton's method did not converge in {iterations} iterations (scaled step {step:.3e})"
    )]
    NoConvergence {
        /// Kind sought.
        kind: EquilibriumKind,
        /// Iterations done.
        iterations: usize,
        /// Last scaled step size.
        step: f64,
    },
    /// The linearised balance is singular (e.g. a free degree of freedom with no
    /// stiffness holding it).
    #[error(
        "no {kind:?} equilibrium: the force balance is singular (a degree of freedom is not held by any stiffness; the free direction is mostly \"{free}\")"
    )]
    Singular {
        /// Kind sought.
        kind: EquilibriumKind,
        /// The coordinate that moves most along the balance's null direction.
        free: String,
    },
}

const MAX_ITERATIONS: usize = 60;

impl Model {
    /// The equilibrium of the given kind nearest to `start` (whose velocities are
    /// ignored), for the given inputs.
    pub fn equilibrium(
        &self,
        kind: EquilibriumKind,
        inputs: &Inputs,
        start: &[f64],
    ) -> Result<Vec<f64>, EquilibriumError> {
        let mut inputs = *inputs;
        if kind == EquilibriumKind::Sticking {
            inputs.platform_velocity = 0.0;
        }
        let nq = self.structure.layout.nq;
        let nv = self.structure.layout.nv;
        let mut x = start.to_vec();
        x[nq..nq + nv].fill(0.0);
        let z_start: Vec<f64> = self
            .structure
            .frictions
            .iter()
            .map(|f| x[f.z_index])
            .collect();
        if kind == EquilibriumKind::Slipping {
            for friction in &self.structure.frictions {
                x[friction.z_index] = friction.lugre.steady_state_z(-inputs.platform_velocity);
            }
        }
        // The feedforward compensator's states are driven by the reference
        // alone: with the reference at rest and the counter-surface still
        // they rest where they start; otherwise they balance like the rest,
        // except a state whose rate depends on no unknown (a model driven by
        // a reference at rest), which rests too.
        let tangent = self.tangent(&x);
        let compensator: Vec<usize> = (self.feedforward_states())
            .filter_map(|i| tangent_index(&tangent, &self.structure.layout.names[i]))
            .collect();
        let mut ws = self.workspace();
        let mut f = vec![0.0; self.n_states()];
        let mut last_step = f64::INFINITY;
        for _ in 0..MAX_ITERATIONS {
            let (jacobian, tangent) = self.tangent_jacobian(&x, &inputs);
            self.rhs(&x, &inputs, &mut f, &mut ws);
            if kind == EquilibriumKind::Sticking {
                // The contact displacements are element values, which the
                // fast evaluations of `rhs` do not fill.
                self.evaluate(&x, &inputs, &mut ws);
            }
            let rate = &tangent.project * DVector::from_column_slice(&f);
            let np = tangent.n_positions;
            let n = tangent.names.len();
            // Unknowns: positions, bristles, integral (everything but velocities).
            let unknowns: Vec<usize> = (0..np).chain(np + nv..n).collect();
            // Equations: accelerations, bristle balance, integral rate.
            let mut system = DMatrix::zeros(unknowns.len(), unknowns.len());
            let mut residual = DVector::zeros(unknowns.len());
            for (row, equation) in (np..n).enumerate() {
                let held = compensator.contains(&equation)
                    && (kind == EquilibriumKind::Sticking
                        || row_is_zero(&jacobian, equation, &unknowns));
                if held {
                    // The compensator's state rests where it starts: x - x_0 = 0.
                    let state = self.structure.layout.index(&tangent.names[equation]);
                    residual[row] = state.map_or(0.0, |i| x[i] - start[i]);
                    for (col, &unknown) in unknowns.iter().enumerate() {
                        system[(row, col)] = if unknown == equation { 1.0 } else { 0.0 };
                    }
                    continue;
                }
                let sticking_contact = if kind == EquilibriumKind::Sticking {
                    self.structure.frictions.iter().position(|fr| {
                        tangent_index(&tangent, &self.structure.layout.names[fr.z_index])
                            == Some(equation)
                    })
                } else {
                    None
                };
                match sticking_contact {
                    Some(k) => {
                        // z - z_0 - s(q) = 0; ds/dq equals d(slip)/dv, which is dz'/dv here.
                        residual[row] = x[self.structure.frictions[k].z_index]
                            - z_start[k]
                            - ws.elements.contact_displacement[k];
                        for (col, &unknown) in unknowns.iter().enumerate() {
                            system[(row, col)] = if unknown < np {
                                -jacobian[(equation, np + unknown)]
                            } else if unknown == equation {
                                1.0
                            } else {
                                0.0
                            };
                        }
                    }
                    None => {
                        residual[row] = rate[equation];
                        for (col, &unknown) in unknowns.iter().enumerate() {
                            system[(row, col)] = jacobian[(equation, unknown)];
                        }
                    }
                }
            }
            let Some(solution) = system.clone().lu().solve(&(-residual)) else {
                return Err(EquilibriumError::Singular {
                    kind,
                    free: free_coordinate(&system, &unknowns, &tangent.names),
                });
            };
            let mut step = vec![0.0; n];
            for (value, &unknown) in solution.iter().zip(&unknowns) {
                step[unknown] = *value;
            }
            x = self.retract(&x, &step);
            last_step = unknowns
                .iter()
                .map(|&u| step[u].abs() / tangent_nominal(self, &tangent, u))
                .fold(0.0, f64::max);
            if last_step < 1e-9 {
                return Ok(x);
            }
        }
        Err(EquilibriumError::NoConvergence {
            kind,
            iterations: MAX_ITERATIONS,
            step: last_step,
        })
    }
}

impl Model {
    /// The states of the feedforward compensators, in servo order.
    fn feedforward_states(&self) -> impl Iterator<Item = usize> + '_ {
        (self.structure.controller.iter())
            .flat_map(|c| &c.feedforward)
            .flat_map(|f| f.state_index..f.state_index + f.n_states())
    }
}

/// Whether the rate of tangent coordinate `equation` depends on no unknown.
fn row_is_zero(jacobian: &DMatrix<f64>, equation: usize, unknowns: &[usize]) -> bool {
    unknowns.iter().all(|&u| jacobian[(equation, u)] == 0.0)
}

/// The name of the unknown that dominates the null direction of a singular
/// balance (the right singular vector of the smallest singular value).
fn free_coordinate(system: &DMatrix<f64>, unknowns: &[usize], names: &[String]) -> String {
    let Some(svd) = crate::eigen::svd(system.clone(), false, true) else {
        return "unknown".into();
    };
    let Some(v_t) = svd.v_t else {
        return "unknown".into();
    };
    if svd.singular_values.is_empty() {
        return "unknown".into();
    }
    let smallest = svd.singular_values.iamin();
    let row = v_t.row(smallest);
    let column = (0..row.len())
        .max_by(|&a, &b| row[a].abs().total_cmp(&row[b].abs()))
        .unwrap_or(0);
    unknowns
        .get(column)
        .and_then(|&u| names.get(u))
        .cloned()
        .unwrap_or_else(|| "unknown".into())
}

fn tangent_index(tangent: &crate::linearize::Tangent, name: &str) -> Option<usize> {
    tangent.names.iter().position(|n| n == name)
}

/// Typical size of a tangent coordinate, for the convergence test.
fn tangent_nominal(model: &Model, tangent: &crate::linearize::Tangent, index: usize) -> f64 {
    model
        .structure
        .layout
        .index(&tangent.names[index])
        .map_or(1e-3, |i| model.structure.layout.nominal[i])
}

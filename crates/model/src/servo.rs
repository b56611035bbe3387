//! The servo law, written once for every evaluation path: PID on a sensor
//! reading, model-based feedforward friction compensation driven by the
//! reference, and a disturbance observer (DOB).
//!
//! ```text
//! e    = x - x_r
//! u_c  = -(k e + c e' + k_i integral(e)) + f_ff        (PID + feedforward)
//! f    = u_c - d_hat                                    (the actuator force)
//! f_ff = friction model driven by x_r', with its own state w:
//!        LuGre: w = z_c,  (f_ff, z_c') = LuGre(x_r', z_c)
//!        Dahl:  w = f_ff, f_ff' = Dahl(x_r', f_ff)
//!      or, through an isolator simulated dynamically (a virtual bearing of
//!      mass m_b on the isolator k_j, c_j, sliding at v_b with friction f(v_b - x_p', w)):
//!        d = x_r - x_b,  d' = x_r' - v_b,  m_b v_b' = k_j d + c_j d' - f,
//!        f_ff = k_j d + c_j d'   (the isolator's pull on the table)
//! d_hat = Q(s) (m_n s x' - f),  Q(s) = omega / (s + omega),  omega = 2 pi bandwidth
//! ```
//!
//! The observer compares the force the nominal plant `1 / (m_n s^2)` needs
//! for the measured motion with the force applied; the difference, low-pass
//! filtered, is the disturbance estimate it subtracts. With the state
//! `eta = d_hat - omega m_n x'` it needs one state and no acceleration:
//! `eta' = -omega (f + d_hat) = -omega u_c`. A constant disturbance is
//! rejected exactly in steady state (`u_c` integrates to zero).

use crate::bristle::BristleStage;
use crate::dahl::DahlParams;
use crate::elements::{Controller, StateKind};
use crate::lugre::LugreParams;
use crate::scalar::Scalar;
use crate::values::InputValues;

/// A friction model a compensator simulates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionModel {
    /// LuGre; the state is the compensator's bristle deflection, m.
    Lugre(LugreParams),
    /// Dahl; the state is the friction force, N.
    Dahl(DahlParams),
}

impl FrictionModel {
    /// A model of `kind` with every parameter unset (NaN), to be filled.
    pub(crate) fn unset(kind: crate::compensation::CompensationKind) -> Self {
        use crate::compensation::CompensationKind;
        let nan = f64::NAN;
        match kind {
            CompensationKind::Lugre => Self::Lugre(LugreParams {
                sigma0: nan,
                sigma1: nan,
                sigma2: nan,
                f_c: nan,
                f_s: nan,
                v_s: nan,
            }),
            CompensationKind::Dahl => Self::Dahl(DahlParams {
                sigma: nan,
                f_c: nan,
                exponent: nan,
            }),
        }
    }

    /// A parameter by name (NaN for a name the model does not have).
    pub fn get(&self, name: &str) -> f64 {
        match self {
            Self::Lugre(p) => LugreParams::key(name).map_or(f64::NAN, |k| k.get(p)),
            Self::Dahl(p) => DahlParams::key(name).map_or(f64::NAN, |k| k.get(p)),
        }
    }

    /// Sets a parameter by name (a name the model does not have is ignored).
    pub fn set(&mut self, name: &str, value: f64) {
        match self {
            Self::Lugre(p) => {
                if let Some(k) = LugreParams::key(name) {
                    k.set(p, value);
                }
            }
            Self::Dahl(p) => {
                if let Some(k) = DahlParams::key(name) {
                    k.set(p, value);
                }
            }
        }
    }

    /// The first parameter that breaks a rule: (name, what it must be).
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        match self {
            Self::Lugre(p) => p.validate().map_err(|e| {
                let message = e.to_string();
                let tail = message.strip_prefix(e.name).unwrap_or(&message).trim();
                (e.name, tail.to_string())
            }),
            Self::Dahl(p) => p.validate(),
        }
    }

    /// The model as felt through an isolator of stiffness `k_j` and damping
    /// `c_j` along the contact axis, the bearing's mass neglected (paper
    /// Section 2.1). In pre-motion the contact is a spring and damper
    /// (`sigma0`, `sigma1`) in series with the isolator's (`k_j`, `c_j`); at
    /// low frequency the pair acts as the stiffness
    /// `k_c = sigma0 k_j / (sigma0 + k_j)` (Eq. 1) and the damping
    /// `(sigma1 k_j^2 + c_j sigma0^2) / (sigma0 + k_j)^2`. Sliding forces
    /// (`f_c`, `f_s`, `v_s`, `sigma2`) pass through the isolator unchanged.
    /// A Dahl model's stiffness combines the same way.
    pub fn felt_through(&self, k_j: f64, c_j: f64) -> Self {
        let series = |k: f64| k * k_j / (k + k_j);
        match *self {
            Self::Lugre(p) => {
                let total = p.sigma0 + k_j;
                Self::Lugre(LugreParams {
                    sigma0: series(p.sigma0),
                    sigma1: (p.sigma1 * k_j * k_j + c_j * p.sigma0 * p.sigma0) / (total * total),
                    ..p
                })
            }
            Self::Dahl(p) => Self::Dahl(DahlParams {
                sigma: series(p.sigma),
                ..p
            }),
        }
    }

    /// The friction force the model predicts at velocity `v` and internal
    /// state `w`, and the state's rate.
    #[inline(always)]
    pub(crate) fn force_and_rate<S: Scalar>(&self, v: S, w: S) -> (S, S) {
        match self {
            Self::Lugre(p) => p.force_and_z_rate_of(v, w),
            Self::Dahl(p) => (w, p.force_rate_of(v, w)),
        }
    }

    /// What its state is, its name suffix and its typical size.
    pub(crate) fn state(&self) -> (StateKind, &'static str, f64) {
        match self {
            Self::Lugre(p) => (StateKind::CompensatorBristle, "z", p.f_s / p.sigma0),
            Self::Dahl(p) => (StateKind::CompensatorForce, "f_d", p.f_c),
        }
    }
}

/// Feedforward friction compensation: a friction model driven by the
/// reference, simulated with its own state.
#[derive(Debug, Clone, PartialEq)]
pub struct Feedforward {
    /// The name of the friction element it models, when it models one.
    pub element: Option<String>,
    /// The friction model simulated (already felt through the isolator when
    /// the isolator is treated statically).
    pub model: FrictionModel,
    /// The bearing behind the isolator, when it is simulated dynamically.
    pub bearing: Option<VirtualBearing>,
    /// Index of the compensator's first state: the model's state, or with a
    /// virtual bearing the isolator deflection, then the bearing velocity,
    /// then the model's state.
    pub state_index: usize,
}

/// The bearing a compensator simulates behind an isolator: its mass and the
/// isolator's stiffness and damping along the contact axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VirtualBearing {
    /// Bearing mass m_b, kg.
    pub mass: f64,
    /// Isolator stiffness k_j along the contact axis, N/m.
    pub stiffness: f64,
    /// Isolator damping c_j along the contact axis, N s/m.
    pub damping: f64,
}

impl Feedforward {
    /// Number of states it has.
    pub fn n_states(&self) -> usize {
        if self.bearing.is_some() { 3 } else { 1 }
    }

    /// The index of its LuGre model's bristle state, which an
    /// implicit-explicit integrator may treat implicitly (none for Dahl).
    pub fn bristle_state(&self) -> Option<usize> {
        match self.model {
            FrictionModel::Lugre(_) => Some(self.state_index + self.n_states() - 1),
            FrictionModel::Dahl(_) => None,
        }
    }

    /// Its force and the rates of its states (unused entries zero).
    #[inline(always)]
    fn force_and_rates<S: Scalar>(
        &self,
        x: &[S],
        inputs: &InputValues<S>,
        bristles: &mut BristleStage<S>,
    ) -> (S, [S; 3]) {
        let i = self.state_index;
        let v_r = inputs.reference_velocity;
        match &self.bearing {
            None => {
                let (force, rate) = bristles.compensator_law(&self.model, v_r, x[i]);
                (force, [rate, S::zero(), S::zero()])
            }
            Some(bearing) => {
                let (deflection, velocity, w) = (x[i], x[i + 1], x[i + 2]);
                let deflection_rate = v_r - velocity;
                let slip = velocity - inputs.platform_velocity;
                let (friction, w_rate) = bristles.compensator_law(&self.model, slip, w);
                let pull = S::constant(bearing.stiffness) * deflection
                    + S::constant(bearing.damping) * deflection_rate;
                let acceleration = (pull - friction) * S::constant(1.0 / bearing.mass);
                (pull, [deflection_rate, acceleration, w_rate])
            }
        }
    }
}

/// A disturbance observer with a first-order Q-filter.
#[derive(Debug, Clone, PartialEq)]
pub struct Observer {
    /// Nominal mass m_n, kg.
    pub nominal_mass: f64,
    /// Q-filter cut-off omega, rad/s (2 pi times the bandwidth in Hz).
    pub cutoff: f64,
    /// Index of the observer state eta in the state vector.
    pub state_index: usize,
}

/// What the servo law gives besides its force: the tracking error, the
/// compensators' contributions, and the rates of the servo's own states in
/// the order integral, feedforward, observer.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ServoValues<S> {
    /// Tracking error x - x_r, m.
    pub error: S,
    /// Feedforward friction compensation force, N.
    pub feedforward: S,
    /// Disturbance estimate d_hat, N.
    pub estimate: S,
    /// Rates of the integral, the feedforward states and the observer state.
    rates: [S; 5],
}

impl<S: Scalar> ServoValues<S> {
    /// All zero.
    pub fn zero() -> Self {
        Self {
            error: S::zero(),
            feedforward: S::zero(),
            estimate: S::zero(),
            rates: [S::zero(); 5],
        }
    }
}

impl Controller {
    /// The servo's own states in the order of [`ServoValues`]'s rates.
    fn state_slots(&self) -> [Option<usize>; 5] {
        let feedforward = |k: usize| {
            (self.feedforward.as_ref())
                .filter(|f| k < f.n_states())
                .map(|f| f.state_index + k)
        };
        [
            self.integral_index,
            feedforward(0),
            feedforward(1),
            feedforward(2),
            self.observer.as_ref().map(|o| o.state_index),
        ]
    }

    /// The servo law at a sensor reading and rate: the actuator force and
    /// the values of [`ServoValues`]. `x` holds the servo's own states at
    /// the indices the controller names (the model's state vector, or any
    /// vector laid out by the same indices).
    #[inline(always)]
    pub fn law<S: Scalar>(
        &self,
        position: S,
        velocity: S,
        x: &[S],
        inputs: &InputValues<S>,
    ) -> (S, ServoValues<S>) {
        self.law_at_stage(
            position,
            velocity,
            x,
            inputs,
            &mut BristleStage::explicit(0),
        )
    }

    /// [`Controller::law`] with the compensator's model read through the
    /// evaluation's bristle treatment (see [`BristleStage::compensator_law`]).
    #[inline(always)]
    pub(crate) fn law_at_stage<S: Scalar>(
        &self,
        position: S,
        velocity: S,
        x: &[S],
        inputs: &InputValues<S>,
        bristles: &mut BristleStage<S>,
    ) -> (S, ServoValues<S>) {
        let error = position - inputs.reference_position;
        let error_rate = velocity - inputs.reference_velocity;
        let integral = self.integral_index.map_or(S::zero(), |i| x[i]);
        let mut values = ServoValues::zero();
        values.error = error;
        values.rates[0] = error;
        let mut command = -(S::constant(self.k) * error
            + S::constant(self.c) * error_rate
            + S::constant(self.k_i) * integral);
        if let Some(feedforward) = &self.feedforward {
            let (force, rates) = feedforward.force_and_rates(x, inputs, bristles);
            values.feedforward = force;
            values.rates[1..4].copy_from_slice(&rates);
            command += force;
        }
        let mut force = command;
        if let Some(observer) = &self.observer {
            let cutoff = S::constant(observer.cutoff);
            let estimate =
                x[observer.state_index] + cutoff * S::constant(observer.nominal_mass) * velocity;
            values.estimate = estimate;
            values.rates[4] = -cutoff * command;
            force = command - estimate;
        }
        (force, values)
    }

    /// Writes the rates of the servo's own states into `dx`.
    #[inline(always)]
    pub(crate) fn write_rates<S: Scalar>(&self, values: &ServoValues<S>, dx: &mut [S]) {
        // The slots of [`Self::state_slots`], read straight off the
        // controller: this runs in every evaluation.
        if let Some(index) = self.integral_index {
            dx[index] = values.rates[0];
        }
        if let Some(feedforward) = &self.feedforward {
            let (start, count) = (feedforward.state_index, feedforward.n_states());
            dx[start..start + count].copy_from_slice(&values.rates[1..1 + count]);
        }
        if let Some(observer) = &self.observer {
            dx[observer.state_index] = values.rates[4];
        }
    }

    /// The servo's own states and their rates: (state index, rate).
    pub fn state_rates<S: Scalar>(
        &self,
        values: &ServoValues<S>,
    ) -> impl Iterator<Item = (usize, S)> + '_ {
        let rates = values.rates;
        self.state_slots()
            .into_iter()
            .zip(rates)
            .filter_map(|(slot, rate)| slot.map(|i| (i, rate)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every layout of the servo's own states: an integral or none, no
    /// feedforward, a static one (one state) or one with a virtual bearing
    /// (three), an observer or none, at scattered indices.
    fn layouts() -> Vec<Controller> {
        let feedforwards = [
            None,
            Some((None, 4)),
            Some((
                Some(VirtualBearing {
                    mass: 0.1,
                    stiffness: 1e4,
                    damping: 1.0,
                }),
                6,
            )),
        ];
        let mut layouts = Vec::new();
        for integral_index in [None, Some(2)] {
            for feedforward in &feedforwards {
                for observer in [None, Some(11)] {
                    layouts.push(Controller {
                        sensor: 0,
                        actuator: 0,
                        k: 1.0,
                        c: 1.0,
                        k_i: if integral_index.is_some() { 1.0 } else { 0.0 },
                        integral_index,
                        feedforward: feedforward.map(|(bearing, state_index)| Feedforward {
                            element: None,
                            model: FrictionModel::Lugre(LugreParams::paper_table1()),
                            bearing,
                            state_index,
                        }),
                        observer: observer.map(|state_index| Observer {
                            nominal_mass: 1.0,
                            cutoff: 10.0,
                            state_index,
                        }),
                    });
                }
            }
        }
        layouts
    }

    #[test]
    fn write_rates_writes_exactly_the_listed_state_rates() {
        let mut values = ServoValues::<f64>::zero();
        values.rates = [1.0, 2.0, 3.0, 4.0, 5.0];
        for controller in layouts() {
            let mut dx = [f64::NAN; 12];
            controller.write_rates(&values, &mut dx);
            let listed: Vec<(usize, f64)> = controller.state_rates(&values).collect();
            for (index, rate) in &listed {
                assert_eq!(dx[*index], *rate, "{controller:?}");
            }
            let written = dx.iter().filter(|r| !r.is_nan()).count();
            assert_eq!(written, listed.len(), "{controller:?}: {dx:?}");
        }
    }
}

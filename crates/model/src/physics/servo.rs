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
use crate::elements::{Controller, Feedforward};
use crate::scalar::Scalar;
use crate::values::{InputValues, ServoValues};

impl Feedforward {
    /// Its force and the rates of its states (unused entries zero).
    #[inline(always)]
    fn force_and_rates<S: Scalar>(
        &self,
        k: usize,
        x: &[S],
        inputs: &InputValues<S>,
        bristles: &mut BristleStage<S>,
    ) -> (S, [S; 3]) {
        let i = self.state_index;
        let v_r = inputs.reference_velocity;
        match &self.bearing {
            None => {
                let (force, rate) = bristles.compensator_law(k, &self.model, v_r, x[i]);
                (force, [rate, S::zero(), S::zero()])
            }
            Some(bearing) => {
                let (deflection, velocity, w) = (x[i], x[i + 1], x[i + 2]);
                let deflection_rate = v_r - velocity;
                let slip = velocity - inputs.platform_velocity;
                let (friction, w_rate) = bristles.compensator_law(k, &self.model, slip, w);
                let pull = S::constant(bearing.stiffness) * deflection
                    + S::constant(bearing.damping) * deflection_rate;
                let acceleration = (pull - friction) * S::constant(1.0 / bearing.mass);
                (pull, [deflection_rate, acceleration, w_rate])
            }
        }
    }
}

impl Controller {
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
        let mut values = ServoValues::zero();
        let mut bristles = BristleStage::explicit(0, self.feedforward.len());
        let force = self.law_into(position, velocity, x, inputs, &mut bristles, &mut values);
        (force, values)
    }

    /// [`Controller::law`] with the compensators' models read through the
    /// evaluation's bristle treatment (see [`BristleStage::compensator_law`]),
    /// writing its values in place: every value the servo has is written (a
    /// compensator's entries beyond its own states, and those of
    /// compensators it does not have, are left as they are), so an
    /// evaluation neither clears nor copies the whole [`ServoValues`].
    /// Returns the actuator force.
    #[inline(always)]
    pub(crate) fn law_into<S: Scalar>(
        &self,
        position: S,
        velocity: S,
        x: &[S],
        inputs: &InputValues<S>,
        bristles: &mut BristleStage<S>,
        values: &mut ServoValues<S>,
    ) -> S {
        let error = position - inputs.reference_position;
        let error_rate = velocity - inputs.reference_velocity;
        let integral = self.integral_index.map_or(S::zero(), |i| x[i]);
        values.error = error;
        values.integral_rate = error;
        let mut command = -(S::constant(self.k) * error
            + S::constant(self.c) * error_rate
            + S::constant(self.k_i) * integral);
        values.feedforward = S::zero();
        for (k, feedforward) in self.feedforward.iter().enumerate() {
            let (force, rates) = feedforward.force_and_rates(k, x, inputs, bristles);
            values.compensator_forces[k] = force;
            values.compensator_rates[k] = rates;
            values.feedforward += force;
        }
        command += values.feedforward;
        let mut force = command;
        if let Some(observer) = &self.observer {
            let cutoff = S::constant(observer.cutoff);
            let estimate =
                x[observer.state_index] + cutoff * S::constant(observer.nominal_mass) * velocity;
            values.estimate = estimate;
            values.observer_rate = -cutoff * command;
            force = command - estimate;
        }
        force
    }

    /// Writes the rates of the servo's own states into `dx`.
    #[inline(always)]
    pub(crate) fn write_rates<S: Scalar>(&self, values: &ServoValues<S>, dx: &mut [S]) {
        if let Some(index) = self.integral_index {
            dx[index] = values.integral_rate;
        }
        for (feedforward, rates) in self.feedforward.iter().zip(&values.compensator_rates) {
            let (start, count) = (feedforward.state_index, feedforward.n_states());
            dx[start..start + count].copy_from_slice(&rates[..count]);
        }
        if let Some(observer) = &self.observer {
            dx[observer.state_index] = values.observer_rate;
        }
    }

    /// The servo's own states and their rates: (state index, rate), in the
    /// order integral, each compensator's states, observer.
    pub fn state_rates<S: Scalar>(
        &self,
        values: &ServoValues<S>,
    ) -> impl Iterator<Item = (usize, S)> + '_ {
        let integral = (self.integral_index).map(|i| (i, values.integral_rate));
        let compensators = (self.feedforward.iter().zip(values.compensator_rates)).flat_map(
            |(feedforward, rates)| {
                (0..feedforward.n_states()).map(move |j| (feedforward.state_index + j, rates[j]))
            },
        );
        let observer = (self.observer.as_ref()).map(|o| (o.state_index, values.observer_rate));
        integral.into_iter().chain(compensators).chain(observer)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elements::{FrictionModel, Observer, VirtualBearing};
    use crate::lugre::LugreParams;

    /// Every layout of the servo's own states: an integral or none, no
    /// feedforward, a static one (one state), one with a virtual bearing
    /// (three) or three compensators, an observer or none, at scattered
    /// indices.
    fn layouts() -> Vec<Controller> {
        let bearing = Some(VirtualBearing {
            mass: 0.1,
            stiffness: 1e4,
            damping: 1.0,
        });
        let feedforwards = [
            vec![],
            vec![(None, 4)],
            vec![(bearing, 6)],
            vec![(bearing, 3), (None, 7), (bearing, 8)],
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
                        feedforward: (feedforward.iter())
                            .map(|(bearing, state_index)| Feedforward {
                                element: None,
                                model: FrictionModel::Lugre(LugreParams::paper_table1()),
                                bearing: *bearing,
                                state_index: *state_index,
                            })
                            .collect(),
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
        values.integral_rate = 1.0;
        for (k, rates) in values.compensator_rates.iter_mut().enumerate() {
            *rates = [
                10.0 * k as f64 + 2.0,
                10.0 * k as f64 + 3.0,
                10.0 * k as f64 + 4.0,
            ];
        }
        values.observer_rate = 5.0;
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

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
    use crate::elements::{FrictionModel, Observer, VirtualBearing};
    use crate::lugre::LugreParams;

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

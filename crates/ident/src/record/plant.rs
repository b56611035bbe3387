//! The plant of a record fit (paper Eq. 31): one mass on one LuGre contact,
//! driven by the recorded force,
//!
//! ```text
//! M x'' = -(sigma0 z + sigma1 z' + sigma2 x') + f,   z' = x' - |x'| / g(x') z,
//! ```
//!
//! integrated by fistage's Dormand-Prince engine through the whole record,
//! restarted at every sample (the force is held over each interval). With
//! sensitivities, each free parameter adds the three states `d(x, v, z) / d
//! ln(theta)`, whose rates one dual-number evaluation of the same law gives
//! (state perturbed along the sensitivity, parameter along itself): exact
//! forward sensitivities of the simulated output, integrated with error
//! control like the states. The LuGre law is [`LugreOf`], the one the
//! stage models use.

use fistage_model::{DualSVec64, LugreOf, LugreParams, Scalar};
use fistage_ode::{AdaptiveMethod, DormandPrince, OdeSystem, Tolerances};
use nalgebra::SVector;
use num_dual::Derivative;

use super::data::Record;
use super::servo_loop::{MAX_SERVO_STATES, PLANT_STATES, ServoLoop};
use crate::error::{IdentError, Result};

/// A parameter a record fit can estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RecordParam {
    /// Coulomb level f_C, N.
    FC,
    /// Static level f_S, N.
    FS,
    /// Stribeck velocity v_s, m/s.
    VS,
    /// Bristle stiffness sigma0, N/m.
    Sigma0,
    /// Bristle damping sigma1, N s/m.
    Sigma1,
    /// Viscous friction sigma2, N s/m.
    Sigma2,
    /// Moving mass M, kg.
    Mass,
}

impl RecordParam {
    /// Every parameter, in the order of [`Theta`].
    pub const ALL: [RecordParam; 7] = [
        Self::FC,
        Self::FS,
        Self::VS,
        Self::Sigma0,
        Self::Sigma1,
        Self::Sigma2,
        Self::Mass,
    ];

    /// The name in reports and JSON (`f_c`, ..., `mass`).
    pub fn name(self) -> &'static str {
        match self {
            Self::FC => "f_c",
            Self::FS => "f_s",
            Self::VS => "v_s",
            Self::Sigma0 => "sigma0",
            Self::Sigma1 => "sigma1",
            Self::Sigma2 => "sigma2",
            Self::Mass => "mass",
        }
    }

    /// The SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Self::FC | Self::FS => "N",
            Self::VS => "m/s",
            Self::Sigma0 => "N/m",
            Self::Sigma1 | Self::Sigma2 => "N s/m",
            Self::Mass => "kg",
        }
    }

    /// Position in [`Theta`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// The seven plant parameters in the order of [`RecordParam::ALL`], SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Theta(pub [f64; 7]);

impl Theta {
    /// From LuGre parameters and a mass.
    pub fn new(lugre: &LugreParams, mass: f64) -> Self {
        Self([
            lugre.f_c,
            lugre.f_s,
            lugre.v_s,
            lugre.sigma0,
            lugre.sigma1,
            lugre.sigma2,
            mass,
        ])
    }

    /// The LuGre part.
    pub fn lugre(&self) -> LugreParams {
        let [f_c, f_s, v_s, sigma0, sigma1, sigma2, _] = self.0;
        LugreParams {
            sigma0,
            sigma1,
            sigma2,
            f_c,
            f_s,
            v_s,
        }
    }

    /// The mass, kg.
    pub fn mass(&self) -> f64 {
        self.0[6]
    }

    /// One parameter.
    pub fn get(&self, param: RecordParam) -> f64 {
        self.0[param.index()]
    }
}

/// The rates `(x', v', z')` of Eq. 31 for any scalar, the contact sliding
/// at `v - platform_velocity`.
#[inline]
fn rates<S: Scalar>(theta: &[S; 7], force: S, v: S, z: S, platform_velocity: f64) -> [S; 3] {
    let [f_c, f_s, v_s, sigma0, sigma1, sigma2, mass] = *theta;
    let law = LugreOf {
        sigma0,
        sigma1,
        sigma2,
        f_c,
        f_s,
        v_s,
    };
    let slip = if platform_velocity == 0.0 {
        v
    } else {
        v - S::constant(platform_velocity)
    };
    let (friction, z_dot) = law.force_and_z_rate(slip, z);
    [v, (force - friction) / mass, z_dot]
}

/// What drives the plant.
#[derive(Debug, Clone, Copy)]
pub enum Drive<'a> {
    /// The recorded force, held over each sample interval (open loop).
    Recorded,
    /// A scenario's servo on the simulated encoder (closed loop).
    Servo(&'a ServoLoop),
}

impl Drive<'_> {
    /// Number of states before sensitivities: the plant's and the servo's.
    fn base(&self) -> usize {
        PLANT_STATES + self.servo().map_or(0, ServoLoop::n_states)
    }

    fn servo(&self) -> Option<&ServoLoop> {
        match self {
            Drive::Recorded => None,
            Drive::Servo(s) => Some(s),
        }
    }
}

/// Eq. 31 (with its servo) and the sensitivities of `free` as an [`OdeSystem`].
struct SensitivitySystem<'a> {
    theta: [f64; 7],
    free: &'a [RecordParam],
    /// The held force of the current sample interval (open loop).
    force: f64,
    servo: Option<&'a ServoLoop>,
    /// States before sensitivities.
    base: usize,
    /// The record's first time, s: the integration runs on the time since
    /// it, so a fit does not depend on where a lab's clock stood (the
    /// smallest step is relative to the time, and a clock at 1e4 s would
    /// refuse the steps a breakaway needs).
    time_origin: f64,
}

impl SensitivitySystem<'_> {
    /// The rates of the plant and servo states `y` (`base` entries).
    #[inline]
    fn evaluate<S: Scalar>(&self, t: f64, theta: &[S; 7], y: &[S], dy: &mut [S]) {
        match self.servo {
            None => {
                let r = rates(theta, S::constant(self.force), y[1], y[2], 0.0);
                dy[..PLANT_STATES].copy_from_slice(&r);
            }
            Some(servo) => {
                let (force, values) = servo.force(self.time_origin + t, y);
                let r = rates(theta, force, y[1], y[2], servo.platform_velocity);
                dy[..PLANT_STATES].copy_from_slice(&r);
                servo.write_rates(&values, dy);
            }
        }
    }
}

/// The most states before sensitivities.
const MAX_BASE: usize = PLANT_STATES + MAX_SERVO_STATES;

impl OdeSystem for SensitivitySystem<'_> {
    fn dim(&self) -> usize {
        self.base * (1 + self.free.len())
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        let nb = self.base;
        self.evaluate(t, &self.theta, &y[..nb], &mut dy[..nb]);
        if self.free.is_empty() {
            return;
        }
        // One pass with a lane per free parameter: lane j carries
        // d / d ln(theta_j) (the parameter moves along itself, the state
        // along its sensitivity).
        let mut theta = self.theta.map(Lanes::from_re);
        for (j, param) in self.free.iter().enumerate() {
            let i = param.index();
            let mut eps = SVector::<f64, LANES>::zeros();
            eps[j] = self.theta[i];
            theta[i].eps = Derivative::some(eps);
        }
        let mut state = [Lanes::from_re(0.0); MAX_BASE];
        for (c, entry) in state.iter_mut().enumerate().take(nb) {
            let lanes = SVector::<f64, LANES>::from_fn(|j, _| {
                if j < self.free.len() {
                    y[nb * (1 + j) + c]
                } else {
                    0.0
                }
            });
            *entry = Lanes::new(y[c], Derivative::some(lanes));
        }
        let mut rate = [Lanes::from_re(0.0); MAX_BASE];
        self.evaluate(t, &theta, &state[..nb], &mut rate[..nb]);
        for (c, value) in rate.iter().enumerate().take(nb) {
            let eps = value.eps.0.unwrap_or_else(SVector::zeros);
            for j in 0..self.free.len() {
                dy[nb * (1 + j) + c] = eps[j];
            }
        }
    }
}

/// Lanes of the sensitivity pass: one per parameter of [`Theta`].
const LANES: usize = 7;

/// The dual number of the sensitivity pass.
type Lanes = DualSVec64<LANES>;

/// Integration accuracy of the plant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlantTolerance {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance of position and bristle deflection, m (also of
    /// their sensitivities, which are in m per unit log-parameter).
    pub atol_position: f64,
    /// Absolute tolerance of the velocity, m/s.
    pub atol_velocity: f64,
}

impl PlantTolerance {
    /// Tolerances for parameters `theta`: `rtol` times the presliding
    /// distance `f_c / sigma0` and the Stribeck velocity.
    pub fn for_theta(theta: &Theta, rtol: f64) -> Self {
        let lugre = theta.lugre();
        Self {
            rtol,
            atol_position: rtol * lugre.f_c / lugre.sigma0,
            atol_velocity: rtol * lugre.v_s,
        }
    }
}

/// Where a simulation is re-anchored to the measurement.
#[derive(Debug, Clone, Copy, Default)]
pub struct Anchors<'a> {
    /// Samples where the position is set to the encoder's, sorted.
    pub samples: &'a [usize],
    /// Measured velocity at every sample (NaN where unknown), to set there too.
    pub velocity: Option<&'a [f64]>,
}

/// A simulated record.
#[derive(Debug, Clone, PartialEq)]
pub struct Simulated {
    /// Position at every sample time, m.
    pub position: Vec<f64>,
    /// Velocity at every sample time, m/s.
    pub velocity: Vec<f64>,
    /// `d position[k] / d ln(theta_j)` for the free parameters, row-major
    /// (one row of `free.len()` per sample); empty without sensitivities.
    pub jacobian: Vec<f64>,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
}

/// Simulates the plant with parameters `theta` through `record`, driven by
/// its force (open loop) or by a servo (closed loop), from the record's
/// start state at its first position; with the sensitivities of `free` when
/// `sensitivities` is set. At each sample of `anchors.samples` the
/// simulated position is set to the measured one (a segment start; velocity
/// and bristle carry on), so drift does not accumulate from one segment into
/// the next; and the velocity too when `anchors.velocity` gives one.
pub fn simulate(
    record: &Record,
    drive: Drive<'_>,
    theta: &Theta,
    free: &[RecordParam],
    sensitivities: bool,
    anchors: &Anchors,
    tolerance: PlantTolerance,
) -> Result<Simulated> {
    let free_used: &[RecordParam] = if sensitivities { free } else { &[] };
    let nb = drive.base();
    let mut system = SensitivitySystem {
        theta: theta.0,
        free: free_used,
        force: record.force[0],
        servo: drive.servo(),
        base: nb,
        time_origin: record.time[0],
    };
    let dim = system.dim();
    let mut y0 = vec![0.0; dim];
    y0[0] = record.position[0];
    y0[1] = record.start.velocity;
    y0[2] = record.start.bristle;
    let mut atol_base = vec![
        tolerance.atol_position,
        tolerance.atol_velocity,
        tolerance.atol_position,
    ];
    if let Some(servo) = drive.servo() {
        y0[PLANT_STATES..nb].copy_from_slice(servo.initial());
        atol_base.extend(servo.nominal().iter().map(|n| tolerance.rtol * n));
    }
    let atol: Vec<f64> = atol_base.iter().copied().cycle().take(dim).collect();
    let dt = record.sample_interval();
    let tol = Tolerances {
        rtol: tolerance.rtol,
        atol,
        max_step: dt.max(f64::MIN_POSITIVE),
        min_step_relative: 1e-14,
    };
    let n = record.len();
    let p = free_used.len();
    let mut out = Simulated {
        position: Vec::with_capacity(n),
        velocity: Vec::with_capacity(n),
        jacobian: Vec::with_capacity(n * p),
        rhs_evaluations: 0,
    };
    let origin = record.time[0];
    let t_end = record.time[n - 1];
    let breakpoints: Vec<f64> = drive.servo().map_or_else(Vec::new, |s| {
        s.breakpoints(origin, t_end)
            .into_iter()
            .map(|b| b - origin)
            .collect()
    });
    let mut next_breakpoint = breakpoints.iter().copied().peekable();
    let mut integrator = DormandPrince::new(&mut system, 0.0, &y0, tol);
    let mut next_anchor = anchors.samples.iter().copied().peekable();
    for k in 0..n {
        if k > 0 {
            let t_stop = record.time[k] - origin;
            while integrator.t < t_stop {
                let target = next_breakpoint
                    .peek()
                    .copied()
                    .filter(|&b| b <= t_stop)
                    .unwrap_or(t_stop);
                integrator.step(&mut system, target).map_err(|failure| {
                    simulation_failed(record, theta, origin + integrator.t, failure)
                })?;
                if integrator.t >= target && next_breakpoint.peek() == Some(&target) {
                    next_breakpoint.next();
                    integrator.restart(&mut system);
                }
            }
        }
        while next_anchor.peek().is_some_and(|&a| a < k) {
            next_anchor.next();
        }
        let mut state_moved = false;
        if next_anchor.peek() == Some(&k) && k > 0 {
            integrator.x[0] = record.position[k];
            for j in 0..p {
                integrator.x[nb * (1 + j)] = 0.0;
            }
            // The servo reads the position; the open-loop rates do not.
            state_moved = system.servo.is_some();
            if let Some(v) = anchors
                .velocity
                .and_then(|v| v.get(k))
                .filter(|v| v.is_finite())
            {
                integrator.x[1] = *v;
                for j in 0..p {
                    integrator.x[nb * (1 + j) + 1] = 0.0;
                }
                state_moved = true;
            }
        }
        out.position.push(integrator.x[0]);
        out.velocity.push(integrator.x[1]);
        for j in 0..p {
            out.jacobian.push(integrator.x[nb * (1 + j)]);
        }
        // The last stage of the step is the first of the next unless the
        // force or the state changed here.
        let force_changed = system.servo.is_none() && record.force[k] != system.force;
        if k + 1 < n && (state_moved || force_changed) {
            system.force = record.force[k];
            integrator.restart(&mut system);
        }
    }
    out.rhs_evaluations = integrator.counts.rhs_evaluations;
    Ok(out)
}

/// The error of a failed plant simulation, with the parameters it ran with.
fn simulation_failed(
    record: &Record,
    theta: &Theta,
    t: f64,
    failure: impl std::fmt::Debug,
) -> IdentError {
    let names = RecordParam::ALL.iter().zip(theta.0);
    let values: Vec<String> = names
        .map(|(p, v)| format!("{} = {v:.4e}", p.name()))
        .collect();
    IdentError::Simulation {
        file: record.source.clone(),
        message: format!(
            "the plant simulation failed near t = {t:.6} s ({failure:?}) with {}",
            values.join(", ")
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record() -> Record {
        let n = 3000;
        let time: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
        let force = time
            .iter()
            .map(|t| 8.0 * (2.0 * std::f64::consts::PI * 7.0 * t).sin())
            .collect();
        Record::from_arrays("<test>", time, force, vec![0.0; n]).expect("valid")
    }

    /// The sensitivities agree with central differences of the simulated
    /// position (relative step 1e-4) for every parameter.
    #[test]
    fn sensitivities_match_finite_differences() {
        let rec = record();
        let theta = Theta::new(&LugreParams::paper_table1(), 1.5);
        let tol = PlantTolerance::for_theta(&theta, 1e-11);
        let sim = simulate(
            &rec,
            Drive::Recorded,
            &theta,
            &RecordParam::ALL,
            true,
            &Anchors::default(),
            tol,
        )
        .expect("runs");
        for (j, param) in RecordParam::ALL.iter().enumerate() {
            let shifted = |factor: f64| {
                let mut th = theta;
                th.0[param.index()] *= factor;
                simulate(
                    &rec,
                    Drive::Recorded,
                    &th,
                    &[],
                    false,
                    &Anchors::default(),
                    tol,
                )
                .expect("runs")
            };
            let h: f64 = 1e-4;
            let (up, down) = (shifted(h.exp()), shifted((-h).exp()));
            let mut worst: f64 = 0.0;
            let mut scale: f64 = 0.0;
            for k in 0..rec.len() {
                let fd = (up.position[k] - down.position[k]) / (2.0 * h);
                let exact = sim.jacobian[k * RecordParam::ALL.len() + j];
                worst = worst.max((fd - exact).abs());
                scale = scale.max(exact.abs());
            }
            assert!(
                worst <= 1e-4 * scale,
                "{}: worst {worst:e} against {scale:e}",
                param.name()
            );
        }
    }
}

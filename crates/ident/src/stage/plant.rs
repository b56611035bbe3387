//! The plant of a stage fit: a scenario's assembled model (any robot file)
//! with some of its parameter-table entries free, simulated through a record
//! with the forward sensitivities of its sensor readings.
//!
//! The sensitivities `S_j = dx / d ln(theta_j)` obey `S_j' = (df/dx) S_j +
//! df / d ln(theta_j)`. The first term is exact: one dual-number evaluation
//! of the model's own right-hand side with the state moving along every
//! `S_j` at once (a lane each). The second is a central difference of the
//! right-hand side between two models assembled with `theta_j` moved by
//! `exp(+-h)`, evaluated at the same state (so a friction kink sits at the
//! same place in both): its error is `O(h^2)`, about 1e-10 relative, far
//! below the integration's. The start state's sensitivity is the central
//! difference of the two models' start states. Sensitivities and states are
//! integrated together by fistage's Dormand-Prince method with error control
//! on both, restarted at every change of the held force.
//!
//! Where the build has a code generator, both terms run as one compiled
//! function ([`fistage_codegen::parametric_kernel`]): the right-hand side
//! differentiated forward along the `S_j`, with each constant that moves
//! between the shifted models carrying its own central difference (the same
//! `O(h^2)` difference, taken once per constant instead of per evaluation);
//! the readings likewise ([`fistage_codegen::sensitivity_kernel`]). For the
//! FI stage's nine parameters that is ten times fewer CPU seconds a fit.

use fistage_codegen::{Differentiated, SensitivityKernel, parametric_kernel, sensitivity_kernel};
use fistage_model::{
    DualSVec64, Excitation, Inputs, Model, Parameter, RobotSpec, Scenario, ScenarioExcitation,
    Workspace, assemble, initial_state,
};
use fistage_ode::{AdaptiveMethod, DormandPrince, OdeSystem, Tolerances};
use nalgebra::{DMatrix, DVector, SVector};
use num_dual::Derivative;

use crate::error::{IdentError, Result};
use crate::record::Record;

/// Log step of the central differences in the parameters.
const LOG_STEP: f64 = 3e-5;

/// The most free parameters of one fit.
pub const MAX_PARAMETERS: usize = 32;

/// How a record's stage was driven.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Loop {
    /// The recorded force on the actuators, held over each sample interval;
    /// the scenario's servo, compensation and platform motion are left out.
    Open,
    /// The scenario's own servo along its reference (the recorded force is
    /// the servo's, and is not an input).
    Closed,
}

/// A stage with free parameters.
#[derive(Debug, Clone)]
pub struct StagePlant {
    source: String,
    scenario: Scenario,
    robot: RobotSpec,
    parameters: Vec<Parameter>,
    nominal: Vec<f64>,
    drive: Loop,
    sensors: Vec<String>,
    main_sensor: String,
}

impl StagePlant {
    /// The stage of `scenario` (its robot file as written in `robot`) with
    /// the parameters `patterns` free: paths of the parameter table, `*`
    /// matching within a name (`overrides.friction_*.f_c`). Each must name
    /// something, none twice, and each must be positive in the scenario
    /// (the fit works on logarithms).
    pub fn new(
        scenario: &Scenario,
        robot: &RobotSpec,
        patterns: &[String],
        drive: Loop,
    ) -> Result<Self> {
        let source = scenario.file.display().to_string();
        let mut scenario = scenario.clone();
        if drive == Loop::Open {
            scenario.controller = None;
            scenario.compensation.clear();
            scenario.observer = None;
            scenario.platform_velocity = 0.0;
        } else if scenario.controller.is_none() {
            return Err(IdentError::InvalidOption(format!(
                "{source}: a closed-loop record needs a scenario with a [controller]"
            )));
        }
        let mut parameters: Vec<Parameter> = Vec::new();
        for pattern in patterns {
            let found = if pattern.contains('*') {
                let found = Parameter::matching(pattern, &scenario, robot);
                if found.is_empty() {
                    return Err(IdentError::InvalidOption(format!(
                        "--fit {pattern}: matches no parameter of {source}"
                    )));
                }
                found
            } else {
                vec![Parameter::resolve(pattern, &scenario, robot)?]
            };
            for parameter in found {
                if parameters.contains(&parameter) {
                    return Err(IdentError::InvalidOption(format!(
                        "--fit: {parameter} is named twice"
                    )));
                }
                parameters.push(parameter);
            }
        }
        if parameters.is_empty() {
            return Err(IdentError::InvalidOption(
                "--fit: name at least one parameter path".into(),
            ));
        }
        if parameters.len() > MAX_PARAMETERS {
            return Err(IdentError::InvalidOption(format!(
                "--fit names {} parameters; a fit takes at most {MAX_PARAMETERS}",
                parameters.len()
            )));
        }
        let (after, model) = assemble(robot.clone(), &scenario)?;
        let nominal: Vec<f64> = parameters
            .iter()
            .map(|p| p.read(&scenario, &after))
            .collect();
        for (parameter, value) in parameters.iter().zip(&nominal) {
            if !(value.is_finite() && *value > 0.0) {
                return Err(IdentError::InvalidOption(format!(
                    "{parameter} is {} in {source}; a fit works on logarithms and starts from \
                     the scenario's value: give it a positive one there",
                    fistage_model::rule::show(*value)
                )));
            }
        }
        let sensors: Vec<String> = model.sensors().iter().map(|s| s.name.clone()).collect();
        let main_sensor = scenario
            .controller
            .as_ref()
            .map(|c| c.sensor.clone())
            .or_else(|| sensors.first().cloned())
            .ok_or_else(|| {
                IdentError::InvalidOption(format!(
                    "{source}: the stage has no sensor (fistage:sensor) to compare a record with"
                ))
            })?;
        if model.actuators().is_empty() && drive == Loop::Open {
            return Err(IdentError::InvalidOption(format!(
                "{source}: the stage has no actuator (fistage:actuator) for the recorded force"
            )));
        }
        Ok(Self {
            source,
            scenario,
            robot: robot.clone(),
            parameters,
            nominal,
            drive,
            sensors,
            main_sensor,
        })
    }

    /// The scenario file.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The free parameters, in fit order.
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// The scenario's values of the free parameters, SI.
    pub fn nominal(&self) -> &[f64] {
        &self.nominal
    }

    /// How the records were driven.
    pub fn drive(&self) -> Loop {
        self.drive
    }

    /// The stage's sensors by name.
    pub fn sensors(&self) -> &[String] {
        &self.sensors
    }

    /// The sensor a record's position column reads: the servo's, else the first.
    pub fn main_sensor(&self) -> &str {
        &self.main_sensor
    }

    /// The model with the free parameters at `values` (SI).
    pub fn model_at(&self, values: &[f64]) -> Result<Model> {
        let (mut scenario, mut robot) = (self.scenario.clone(), self.robot.clone());
        for (parameter, &value) in self.parameters.iter().zip(values) {
            parameter.write(&mut scenario, &mut robot, value)?;
        }
        let (_, model) = assemble(robot, &scenario)?;
        Ok(model)
    }

    /// The models a simulation needs at `values`: the centre and each
    /// parameter of `sensitive` (indices) moved by `exp(+-h)`.
    pub(crate) fn models(&self, values: &[f64], sensitive: &[usize]) -> Result<Models> {
        let centre = compiled(self.model_at(values)?);
        let start = initial_state(&centre, &self.scenario)?;
        let signals_kernel = (!sensitive.is_empty())
            .then(|| sensitivity_kernel(&centre, Differentiated::Signals, sensitive.len()).ok())
            .flatten();
        let mut models = Models {
            centre,
            rhs_kernel: None,
            signals_kernel,
            start,
            plus: Vec::new(),
            minus: Vec::new(),
            start_sensitivity: Vec::new(),
        };
        {
            for &j in sensitive {
                let shifted = |factor: f64| {
                    let mut v = values.to_vec();
                    v[j] *= factor;
                    let model = self.model_at(&v)?;
                    let start = initial_state(&model, &self.scenario)?;
                    Ok::<_, IdentError>((model, start))
                };
                let (up, up_start) = shifted(LOG_STEP.exp())?;
                let (down, down_start) = shifted((-LOG_STEP).exp())?;
                models.start_sensitivity.push(
                    up_start
                        .iter()
                        .zip(&down_start)
                        .map(|(a, b)| (a - b) / (2.0 * LOG_STEP))
                        .collect(),
                );
                models.plus.push(up);
                models.minus.push(down);
            }
        }
        if !sensitive.is_empty() {
            let shifted: Vec<(&Model, &Model)> = models.plus.iter().zip(&models.minus).collect();
            models.rhs_kernel = parametric_kernel(&models.centre, &shifted, LOG_STEP).ok();
            // The shifted models run only for a parameter the kernel does
            // not carry: only those are worth compiling.
            for j in 0..sensitive.len() {
                let carried = (models.rhs_kernel.as_ref()).is_some_and(|k| k.includes_parameter(j));
                if !carried {
                    for model in [&models.plus[j], &models.minus[j]] {
                        let _ =
                            fistage_codegen::machine_code(model, fistage_codegen::Function::Rhs);
                    }
                }
            }
        }
        Ok(models)
    }

    /// The scenario's excitation (closed loop).
    fn excitation(&self) -> ScenarioExcitation {
        ScenarioExcitation::from_scenario(&self.scenario)
    }

    /// Simulates the first `samples` samples of `record`, reading the
    /// sensors `outputs` (indices of the model's signals), with the
    /// sensitivities when `models` has them; at each sample of `anchors`
    /// the stage is translated so the first output reads the measured
    /// `anchors.measured` displacement.
    pub(crate) fn simulate(
        &self,
        models: &Models,
        record: &Record,
        outputs: &[usize],
        samples: usize,
        rtol: f64,
        anchors: Option<Anchors<'_>>,
    ) -> Result<Simulated> {
        let p = models.plus.len();
        let run = Run {
            models,
            record,
            outputs,
            samples,
            rtol,
            anchors,
        };
        // Each lane count compiles the model's whole evaluation once more
        // in dual numbers, which runs only where no kernel is compiled (a
        // build without the code generator). One size: a second one for up
        // to 16 parameters made this crate's release build take 92 CPU-s
        // instead of 33 (the README's first command about 60 CPU-s more),
        // for lean fits of a few parameters 1.6x faster.
        debug_assert!(p <= MAX_PARAMETERS);
        self.simulate_lanes::<MAX_PARAMETERS>(run)
    }

    /// The direction of the state that translates the whole stage so the
    /// reading of `output` (a signal index) grows by 1 m with nothing else
    /// changing: the least-norm combination of the translation coordinates
    /// that leaves every force as it is at the start state. None when the
    /// stage has no such direction (a spring to the ground along the sensor).
    pub(crate) fn translation(&self, models: &Models, output: usize) -> Option<Translation> {
        let model = &models.centre;
        let layout = model.layout();
        let n = model.n_states();
        let coords: Vec<usize> = (0..layout.nq)
            .filter(|&i| layout.kinds[i] == fistage_model::StateKind::Translation)
            .collect();
        if coords.is_empty() {
            return None;
        }
        let inputs = Inputs::default();
        let mut ws = model.workspace();
        let x0 = &models.start;
        let h = 1e-6;
        let rows: Vec<usize> = (layout.nq..n).collect();
        let mut forces = DMatrix::<f64>::zeros(rows.len(), coords.len());
        let mut reading = DVector::<f64>::zeros(coords.len());
        let (mut up, mut down) = (vec![0.0; n], vec![0.0; n]);
        let signals = model.signals().len();
        let (mut out_up, mut out_down) = (vec![0.0; signals], vec![0.0; signals]);
        for (c, &i) in coords.iter().enumerate() {
            let mut x = x0.clone();
            x[i] += h;
            model.rhs(&x, &inputs, &mut up, &mut ws);
            model.outputs(&x, &inputs, &mut out_up, &mut ws);
            x[i] -= 2.0 * h;
            model.rhs(&x, &inputs, &mut down, &mut ws);
            model.outputs(&x, &inputs, &mut out_down, &mut ws);
            for (r, &row) in rows.iter().enumerate() {
                forces[(r, c)] = (up[row] - down[row]) / (2.0 * h);
            }
            reading[c] = (out_up[output] - out_down[output]) / (2.0 * h);
        }
        // The null space of the forces' dependence on the translations.
        let svd = forces.clone().svd(false, true);
        let v_t = svd.v_t?;
        let largest = svd.singular_values.iter().fold(0.0f64, |m, v| m.max(*v));
        let mut null: Vec<DVector<f64>> = Vec::new();
        for k in 0..coords.len() {
            let sigma = svd.singular_values.get(k).copied().unwrap_or(0.0);
            if sigma <= 1e-9 * largest.max(1e-300) {
                null.push(v_t.row(k).transpose());
            }
        }
        // Rows beyond the singular values (more coordinates than rows).
        for k in svd.singular_values.len()..coords.len() {
            null.push(v_t.row(k).transpose());
        }
        let projections: Vec<f64> = null.iter().map(|v| v.dot(&reading)).collect();
        let norm2: f64 = projections.iter().map(|a| a * a).sum();
        if norm2.is_nan() || norm2 <= 1e-12 {
            return None;
        }
        let mut direction = vec![0.0; n];
        for (v, a) in null.iter().zip(&projections) {
            for (c, &i) in coords.iter().enumerate() {
                direction[i] += v[c] * a / norm2;
            }
        }
        // The velocity that moves the stage along it: the least-norm `w`
        // with (d q' / d v) w = the position direction.
        let (nq, nv) = (layout.nq, layout.nv);
        let mut kinematics = DMatrix::<f64>::zeros(nq, nv);
        for c in 0..nv {
            let mut x = x0.clone();
            x[nq + c] += 1.0;
            model.rhs(&x, &inputs, &mut up, &mut ws);
            x[nq + c] -= 2.0;
            model.rhs(&x, &inputs, &mut down, &mut ws);
            for r in 0..nq {
                kinematics[(r, c)] = (up[r] - down[r]) / 2.0;
            }
        }
        let target = DVector::from_column_slice(&direction[..nq]);
        let solved = kinematics.svd(true, true).solve(&target, 1e-12).ok()?;
        let mut velocity = vec![0.0; n];
        velocity[nq..nq + nv].copy_from_slice(solved.as_slice());
        Some(Translation {
            position: direction,
            velocity,
        })
    }

    fn simulate_lanes<const N: usize>(&self, run: Run<'_>) -> Result<Simulated> {
        let Run {
            models,
            record,
            outputs,
            samples,
            rtol,
            anchors,
        } = run;
        let model = &models.centre;
        let (n, p) = (model.n_states(), models.plus.len());
        let excitation = (self.drive == Loop::Closed).then(|| self.excitation());
        let mut system = SensitivitySystem::<N> {
            models,
            n,
            p,
            excitation: excitation.as_ref(),
            held: record.force[0],
            ws: model.workspace(),
            ws_dual: model.workspace_of(),
            x_dual: vec![DualSVec64::<N>::from_re(0.0); n],
            dx_dual: vec![DualSVec64::<N>::from_re(0.0); n],
            up: vec![0.0; n],
            down: vec![0.0; n],
        };
        if excitation.is_some() {
            system.held = 0.0;
        }
        let mut y0 = vec![0.0; n * (1 + p)];
        y0[..n].copy_from_slice(&models.start);
        for (j, s) in models.start_sensitivity.iter().enumerate() {
            y0[n * (1 + j)..n * (2 + j)].copy_from_slice(s);
        }
        let nominal = &model.layout().nominal;
        let tol = Tolerances {
            rtol,
            atol: (0..y0.len()).map(|i| rtol * nominal[i % n]).collect(),
            max_step: record.sample_interval().max(f64::MIN_POSITIVE),
            min_step_relative: 1e-14,
        };
        let samples = samples.min(record.len());
        let origin = record.time[0];
        let breakpoints: Vec<f64> = excitation
            .as_ref()
            .map(|e| e.breakpoints())
            .unwrap_or_default();
        let mut next_breakpoint = breakpoints.iter().copied().filter(|&b| b > 0.0).peekable();
        let mut out = Simulated {
            readings: vec![Vec::with_capacity(samples); outputs.len()],
            jacobian: vec![Vec::with_capacity(samples * p); outputs.len()],
            rhs_evaluations: 0,
        };
        let mut reader = Reader::<N>::new(models, outputs);
        let mut integrator = DormandPrince::new(&mut system, 0.0, &y0, tol);
        let mut next_anchor = anchors
            .as_ref()
            .map(|a| a.samples.iter().copied().peekable());
        for k in 0..samples {
            if k > 0 {
                let t_stop = record.time[k] - origin;
                while integrator.t < t_stop {
                    let target = next_breakpoint
                        .peek()
                        .copied()
                        .filter(|&b| b <= t_stop)
                        .unwrap_or(t_stop);
                    integrator
                        .step(&mut system, target)
                        .map_err(|failure| self.failed(record, origin + integrator.t, failure))?;
                    if integrator.t >= target && next_breakpoint.peek() == Some(&target) {
                        next_breakpoint.next();
                        integrator.restart(&mut system);
                    }
                }
            }
            let inputs = system.inputs(integrator.t);
            let mut moved = false;
            if let (Some(anchors), Some(queue)) = (&anchors, next_anchor.as_mut()) {
                while queue.peek().is_some_and(|&a| a < k) {
                    queue.next();
                }
                if k > 0 && queue.peek() == Some(&k) {
                    reader.anchor(&mut integrator.x, &inputs, &out, anchors, k);
                    moved = true;
                }
            }
            reader.read(&integrator.x, &inputs, &mut out);
            let force_changed = excitation.is_none() && record.force[k] != system.held;
            if k + 1 < samples && (force_changed || moved) {
                if excitation.is_none() {
                    system.held = record.force[k];
                }
                integrator.restart(&mut system);
            }
        }
        out.rhs_evaluations = integrator.counts.rhs_evaluations;
        Ok(out)
    }

    fn failed(&self, record: &Record, t: f64, failure: impl std::fmt::Debug) -> IdentError {
        IdentError::Simulation {
            file: record.source.clone(),
            message: format!(
                "the simulation of {} failed near t = {t:.6} s ({failure:?})",
                self.source
            ),
        }
    }
}

/// `model` with its right-hand side compiled to machine code where the
/// build can (a simulation evaluates it hundreds of thousands of times);
/// the generic evaluation otherwise, with the same numbers.
fn compiled(model: Model) -> Model {
    let _ = fistage_codegen::machine_code(&model, fistage_codegen::Function::Rhs);
    model
}

/// A rigid translation of the whole stage in state space.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Translation {
    /// The state change that moves the reading by 1 m and no force.
    pub position: Vec<f64>,
    /// The state change that moves the stage along it at 1 m/s.
    pub velocity: Vec<f64>,
}

/// Where a simulation is re-anchored to the measurement.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Anchors<'a> {
    /// Samples where the stage is translated onto the measurement, sorted.
    pub samples: &'a [usize],
    /// The first output's measured readings.
    pub measured: &'a [f64],
    /// [`StagePlant::translation`] of the first output.
    pub direction: &'a Translation,
    /// The measured rate of the first output (NaN where unknown) and the
    /// signal of its simulated rate, to set the velocity too.
    pub velocity: Option<(&'a [f64], usize)>,
}

/// One simulation's inputs.
struct Run<'a> {
    models: &'a Models,
    record: &'a Record,
    outputs: &'a [usize],
    samples: usize,
    rtol: f64,
    anchors: Option<Anchors<'a>>,
}

/// The models of one simulation.
pub(crate) struct Models {
    centre: Model,
    /// The centre's `f` and `(df/dx) S_j` as machine code, where compiled.
    rhs_kernel: Option<SensitivityKernel>,
    /// The centre's signals and their derivatives along the `S_j`, likewise.
    signals_kernel: Option<SensitivityKernel>,
    start: Vec<f64>,
    plus: Vec<Model>,
    minus: Vec<Model>,
    start_sensitivity: Vec<Vec<f64>>,
}

/// A simulated record.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Simulated {
    /// Per output, the reading at every simulated sample, m.
    pub readings: Vec<Vec<f64>>,
    /// Per output, `d reading[k] / d ln(theta_j)`, one row of `p` per sample.
    pub jacobian: Vec<Vec<f64>>,
    /// Right-hand-side evaluations.
    pub rhs_evaluations: u64,
}

/// The model and its sensitivities as one ODE system.
struct SensitivitySystem<'a, const N: usize> {
    models: &'a Models,
    n: usize,
    p: usize,
    excitation: Option<&'a ScenarioExcitation>,
    /// The recorded force of the current sample interval (open loop).
    held: f64,
    ws: Workspace,
    ws_dual: Workspace<DualSVec64<N>>,
    x_dual: Vec<DualSVec64<N>>,
    dx_dual: Vec<DualSVec64<N>>,
    up: Vec<f64>,
    down: Vec<f64>,
}

impl<const N: usize> SensitivitySystem<'_, N> {
    /// The inputs at integration time `t` (from the record's first sample).
    fn inputs(&self, t: f64) -> Inputs {
        match self.excitation {
            Some(e) => e.inputs(t),
            None => Inputs {
                servo_force: self.held,
                ..Inputs::default()
            },
        }
    }
}

/// A dual number whose lanes are `values(j)` for the first `p` lanes.
fn lanes<const N: usize>(re: f64, p: usize, values: impl Fn(usize) -> f64) -> DualSVec64<N> {
    let eps = SVector::<f64, N>::from_fn(|j, _| if j < p { values(j) } else { 0.0 });
    DualSVec64::new(re, Derivative::some(eps))
}

impl<const N: usize> OdeSystem for SensitivitySystem<'_, N> {
    fn dim(&self) -> usize {
        self.n * (1 + self.p)
    }

    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) {
        let (n, p) = (self.n, self.p);
        let inputs = self.inputs(t);
        let models = self.models;
        let kernel = models
            .rhs_kernel
            .as_ref()
            .filter(|kernel| kernel.evaluate(y, &inputs.values(), dy).is_ok());
        if kernel.is_none() {
            self.state_part(y, &inputs, dy);
        }
        for j in 0..p {
            if kernel.is_some_and(|kernel| kernel.includes_parameter(j)) {
                continue;
            }
            models.plus[j].rhs(&y[..n], &inputs, &mut self.up, &mut self.ws);
            models.minus[j].rhs(&y[..n], &inputs, &mut self.down, &mut self.ws);
            for c in 0..n {
                dy[n * (1 + j) + c] += (self.up[c] - self.down[c]) / (2.0 * LOG_STEP);
            }
        }
    }
}

impl<const N: usize> SensitivitySystem<'_, N> {
    /// `f(x)` and `(df/dx) S_j` by the generic evaluation (one dual-number
    /// pass, a lane per parameter): where no kernel is compiled, or its
    /// recorded branches do not hold.
    fn state_part(&mut self, y: &[f64], inputs: &Inputs, dy: &mut [f64]) {
        let (n, p) = (self.n, self.p);
        let models = self.models;
        models
            .centre
            .rhs(&y[..n], inputs, &mut dy[..n], &mut self.ws);
        if p == 0 {
            return;
        }
        for c in 0..n {
            self.x_dual[c] = lanes(y[c], p, |j| y[n * (1 + j) + c]);
        }
        models.centre.rhs_of(
            &self.x_dual,
            &inputs.values(),
            &mut self.dx_dual,
            &mut self.ws_dual,
        );
        for j in 0..p {
            for c in 0..n {
                dy[n * (1 + j) + c] = self.dx_dual[c].eps.0.map_or(0.0, |e| e[j]);
            }
        }
    }
}

/// Reads the sensors and their sensitivities at a sample.
struct Reader<'a, const N: usize> {
    models: &'a Models,
    outputs: &'a [usize],
    values: Vec<f64>,
    up: Vec<f64>,
    down: Vec<f64>,
    /// Every signal, then per parameter every signal's derivative along
    /// the state's sensitivity (`m (1 + p)` entries).
    tangents: Vec<f64>,
    dual: Vec<DualSVec64<N>>,
    x_dual: Vec<DualSVec64<N>>,
    ws: Workspace,
    ws_dual: Workspace<DualSVec64<N>>,
    /// Per parameter, whether it moves a reading at a fixed state (a
    /// sensor's point); found at the first sample.
    direct: Option<Vec<bool>>,
}

impl<'a, const N: usize> Reader<'a, N> {
    fn new(models: &'a Models, outputs: &'a [usize]) -> Self {
        let model = &models.centre;
        let signals = model.signals().len();
        Self {
            models,
            outputs,
            values: vec![0.0; signals],
            up: vec![0.0; signals],
            down: vec![0.0; signals],
            tangents: vec![0.0; signals * (1 + models.plus.len())],
            dual: vec![DualSVec64::from_re(0.0); signals],
            x_dual: vec![DualSVec64::from_re(0.0); model.n_states()],
            ws: model.workspace(),
            ws_dual: model.workspace_of(),
            direct: None,
        }
    }

    /// Every signal with its derivatives along the state's sensitivities,
    /// into `self.tangents`: by the compiled kernel where there is one and
    /// its branches hold, else one dual-number evaluation.
    fn signal_tangents(&mut self, y: &[f64], inputs: &Inputs) {
        let models = self.models;
        let (n, p) = (models.centre.n_states(), models.plus.len());
        let compiled = models.signals_kernel.as_ref().is_some_and(|kernel| {
            kernel
                .evaluate(y, &inputs.values(), &mut self.tangents)
                .is_ok()
        });
        if compiled {
            return;
        }
        for c in 0..n {
            self.x_dual[c] = lanes(y[c], p, |j| y[n * (1 + j) + c]);
        }
        models.centre.outputs_of(
            &self.x_dual,
            &inputs.values(),
            &mut self.dual,
            &mut self.ws_dual,
        );
        let m = self.dual.len();
        for (s, dual) in self.dual.iter().enumerate() {
            self.tangents[s] = dual.re;
            for j in 0..p {
                self.tangents[m * (1 + j) + s] = dual.eps.0.map_or(0.0, |e| e[j]);
            }
        }
    }

    /// The derivative of `signal` along parameter `j`'s state sensitivity
    /// (after [`Reader::signal_tangents`]).
    fn along(&self, signal: usize, j: usize) -> f64 {
        self.tangents[self.values.len() * (1 + j) + signal]
    }

    /// Translates the stage (and its sensitivities) so the first output's
    /// displacement since sample 0 is the measured one, and its
    /// sensitivities are those of sample 0 (the reading no longer depends
    /// on the parameters).
    fn anchor(
        &mut self,
        y: &mut [f64],
        inputs: &Inputs,
        out: &Simulated,
        anchors: &Anchors,
        k: usize,
    ) {
        let models = self.models;
        let (n, p) = (models.centre.n_states(), models.plus.len());
        let signal = self.outputs[0];
        models
            .centre
            .outputs(&y[..n], inputs, &mut self.values, &mut self.ws);
        let simulated = self.values[signal] - out.readings[0][0];
        let measured = anchors.measured[k] - anchors.measured[0];
        let shift = measured - simulated;
        let translation = anchors.direction;
        for (c, d) in translation.position.iter().enumerate() {
            y[c] += shift * d;
        }
        let rate = anchors
            .velocity
            .and_then(|(v, signal)| v.get(k).filter(|v| v.is_finite()).map(|v| (*v, signal)));
        if let Some((measured_rate, rate_signal)) = rate {
            models
                .centre
                .outputs(&y[..n], inputs, &mut self.values, &mut self.ws);
            let change = measured_rate - self.values[rate_signal];
            for (c, d) in translation.velocity.iter().enumerate() {
                y[c] += change * d;
            }
        }
        if p == 0 {
            return;
        }
        self.signal_tangents(y, inputs);
        for j in 0..p {
            let now = self.along(signal, j);
            let first = out.jacobian[0][j];
            for (c, d) in translation.position.iter().enumerate() {
                y[n * (1 + j) + c] += (first - now) * d;
            }
            // The set rate no longer depends on the parameters.
            if let Some((_, rate_signal)) = rate {
                let now = self.along(rate_signal, j);
                for (c, d) in translation.velocity.iter().enumerate() {
                    y[n * (1 + j) + c] -= now * d;
                }
            }
        }
    }

    fn read(&mut self, y: &[f64], inputs: &Inputs, out: &mut Simulated) {
        let models = self.models;
        let (n, p) = (models.centre.n_states(), models.plus.len());
        let x = &y[..n];
        if p == 0 {
            models
                .centre
                .outputs(x, inputs, &mut self.values, &mut self.ws);
            for (o, &signal) in self.outputs.iter().enumerate() {
                out.readings[o].push(self.values[signal]);
            }
            return;
        }
        self.signal_tangents(y, inputs);
        for (o, &signal) in self.outputs.iter().enumerate() {
            out.readings[o].push(self.tangents[signal]);
        }
        let direct = self.direct.get_or_insert_with(|| vec![true; p]).clone();
        let mut moves = vec![false; p];
        let mut rows = vec![vec![0.0; p]; self.outputs.len()];
        for j in 0..p {
            if direct[j] {
                models.plus[j].outputs(x, inputs, &mut self.up, &mut self.ws);
                models.minus[j].outputs(x, inputs, &mut self.down, &mut self.ws);
            }
            for (o, &signal) in self.outputs.iter().enumerate() {
                let along = self.along(signal, j);
                let shift = if direct[j] {
                    (self.up[signal] - self.down[signal]) / (2.0 * LOG_STEP)
                } else {
                    0.0
                };
                moves[j] |= shift != 0.0;
                rows[o][j] = along + shift;
            }
        }
        if out.readings[0].len() == 1 {
            self.direct = Some(moves);
        }
        for (o, row) in rows.into_iter().enumerate() {
            out.jacobian[o].extend(row);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The FI stage of the paper with its nine physical parameters free, and
    /// a 0.3 s record of a force chirp that breaks the bearing loose.
    fn fi_stage() -> (StagePlant, Record) {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let scenario =
            Scenario::from_file(&root.join("scenarios/paper/fig05b_fi.toml")).expect("scenario");
        let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
        let paths: Vec<String> = super::super::PAPER_FI_PATHS.map(String::from).to_vec();
        let plant = StagePlant::new(&scenario, &robot, &paths, Loop::Open).expect("plant");
        let n = 3000;
        let time: Vec<f64> = (0..n).map(|k| k as f64 * 1e-4).collect();
        let force = (time.iter())
            .map(|t| 9.0 * t / 0.3 * (2.0 * std::f64::consts::PI * (5.0 + 40.0 * t) * t).sin())
            .collect();
        let record = Record::from_arrays("<chirp>", time, force, vec![0.0; n]).expect("record");
        (plant, record)
    }

    /// The compiled sensitivity kernels (the parameters' effects carried by
    /// the model's constants) give the generic evaluation's readings and
    /// Jacobian (dual numbers and differences of models) to rounding.
    #[test]
    fn compiled_and_generic_sensitivities_agree() {
        let (plant, record) = fi_stage();
        let nominal = plant.nominal().to_vec();
        let all: Vec<usize> = (0..nominal.len()).collect();
        let compiled = plant.models(&nominal, &all).expect("models");
        if compiled.rhs_kernel.is_none() || compiled.signals_kernel.is_none() {
            eprintln!("SKIPPED: this build has no code generator (fistage-codegen/cranelift)");
            return;
        }
        let kernel = compiled.rhs_kernel.as_ref().expect("compiled");
        let included: Vec<bool> = (0..all.len())
            .map(|j| kernel.includes_parameter(j))
            .collect();
        // Each of the nine is a plain number of the model: the kernel
        // carries all their effects, and no model is differenced.
        assert!(included.iter().all(|&i| i), "{included:?}");
        let mut generic = plant.models(&nominal, &all).expect("models");
        generic.rhs_kernel = None;
        generic.signals_kernel = None;
        let encoder = compiled
            .centre
            .signal_index("encoder.position")
            .expect("encoder");
        let run = |models: &Models| {
            plant
                .simulate(models, &record, &[encoder], record.len(), 1e-10, None)
                .expect("simulates")
        };
        let (fast, slow) = (run(&compiled), run(&generic));
        let largest = slow.jacobian[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let moved = slow.readings[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for (a, b) in fast.readings[0].iter().zip(&slow.readings[0]) {
            assert!((a - b).abs() <= 1e-9 * moved, "{a} against {b}");
        }
        let worst = (fast.jacobian[0].iter().zip(&slow.jacobian[0]))
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        // The two differ in rounding (another order of the same operations),
        // which the integration at rtol 1e-10 carries to about 1e-9 of the
        // largest entry; a wrong derivative would be off by its own size.
        assert!(worst <= 1e-8 * largest, "{worst:e} against {largest:e}");
    }

    /// Every sensitivity agrees with five-point differences of whole
    /// simulations (relative step 2e-4) to 1e-6 of the Jacobian's largest
    /// entry for free runs (1e-5 for runs re-anchored every 5 ms in
    /// position and velocity onto a stage at rest).
    #[test]
    fn sensitivities_match_finite_differences_of_whole_runs() {
        let (plant, record) = fi_stage();
        let nominal = plant.nominal().to_vec();
        let p = nominal.len();
        let model = plant.model_at(&nominal).expect("model");
        let encoder = model.signal_index("encoder.position").expect("encoder");
        let rate = model
            .signal_index("encoder.velocity")
            .expect("encoder rate");
        let all: Vec<usize> = (0..p).collect();
        let rtol = 1e-11;
        let models = plant.models(&nominal, &all).expect("models");
        let translation = plant.translation(&models, encoder).expect("a free axis");
        let samples: Vec<usize> = (50..record.len()).step_by(50).collect();
        let at_rest = vec![0.0; record.len()];
        let anchored = Anchors {
            samples: &samples,
            measured: &record.position,
            direction: &translation,
            velocity: Some((&at_rest, rate)),
        };
        for anchors in [None, Some(anchored)] {
            let simulate = |models: &Models| {
                plant
                    .simulate(models, &record, &[encoder], record.len(), rtol, anchors)
                    .expect("simulates")
            };
            let exact = simulate(&models);
            let moved = exact.readings[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            assert!(moved > 1e-7, "the chirp moves the table {moved:e} m");
            let h: f64 = 2e-4;
            let largest = exact.jacobian[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for j in 0..p {
                let run = |steps: f64| {
                    let mut v = nominal.clone();
                    v[j] *= (steps * h).exp();
                    simulate(&plant.models(&v, &[]).expect("models"))
                        .readings
                        .remove(0)
                };
                // The five-point stencil: truncation O(h^4), so the step can
                // be large against the runs' own integration noise.
                let (up2, up, down, down2) = (run(2.0), run(1.0), run(-1.0), run(-2.0));
                let mut worst: f64 = 0.0;
                let mut scale: f64 = 0.0;
                for k in 0..record.len() {
                    let fd = (-up2[k] + 8.0 * up[k] - 8.0 * down[k] + down2[k]) / (12.0 * h);
                    let sensitivity = exact.jacobian[0][k * p + j];
                    worst = worst.max((fd - sensitivity).abs());
                    scale = scale.max(sensitivity.abs());
                }
                // Within 1e-6 of the Jacobian's largest entry and 1e-4 of the
                // column's own (free runs); 1e-5 of the largest anchored,
                // where the runs move a thousandth as far and the
                // differences' own noise, about 1e-10 m, is near 1e-6.
                let within = match anchors {
                    None => worst <= 1e-6 * largest && worst <= 1e-4 * scale,
                    Some(_) => worst <= 1e-5 * largest,
                };
                assert!(
                    within,
                    "{} (anchored: {}): worst {worst:e} against {scale:e} (largest {largest:e})",
                    plant.parameters()[j],
                    anchors.is_some()
                );
            }
        }
    }
}

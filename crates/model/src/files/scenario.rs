//! Scenario files (TOML): which robot, per-element overrides, platform velocity,
//! controller, reference, run length, solver tolerances, outputs and the
//! steady-state window. Parsing is strict: an unknown key is an error naming it.
//!
//! ```toml
//! title = "Fig. 5b, stage with friction isolator"
//! robot = "../../robots/stage_1dof_fi.urdf"   # relative to this file
//! duration = 5.0                              # s
//!
//! [platform]
//! velocity = 0.02                             # m/s, counter-surface along each contact axis
//!
//! [controller]                                # PID on a sensor, through an actuator
//! sensor = "encoder"
//! actuator = "drive"
//! k = 6e4                                     # N/m
//! c = 100.0                                   # N s/m
//! k_i = 0.0                                   # N/(m s)
//!
//! [reference]
//! kind = "sine"                               # constant | step | ramp | sine | p2p | csv
//! amplitude = 1e-3
//! frequency = 0.1
//!
//! [overrides.bearing_friction]                # by element (or link) name
//! f_c = 6.1
//! ```

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::compensation::{
    CompensationSettings, ObserverSettings, read_compensations, read_observer,
};
use crate::error::LoadError;
use crate::reference::{MoveProfile, Reference};
use crate::rule::{Rule, readable_numbers};
use crate::studies::{RobustTable, SweepTable};

/// The scenario file as written, before checks.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct ScenarioFile {
    robot: PathBuf,
    #[serde(default)]
    title: String,
    duration: f64,
    #[serde(default = "default_gravity")]
    gravity: [f64; 3],
    #[serde(default)]
    platform: PlatformFile,
    controller: Option<ControllerSettings>,
    /// `[compensation]` or `[[compensation]]`, read key by key (see
    /// [`crate::compensation`]).
    compensation: Option<toml::Value>,
    /// Read key by key (see [`crate::compensation`]).
    dob: Option<toml::Table>,
    /// Read key by key (see `Checker::reference`), so that an error
    /// names the key rather than the table.
    #[serde(default)]
    reference: toml::Table,
    #[serde(default)]
    overrides: BTreeMap<String, BTreeMap<String, toml::Value>>,
    #[serde(default)]
    initial: BTreeMap<String, f64>,
    #[serde(default)]
    start: Start,
    #[serde(default)]
    solver: SolverSettings,
    /// Shorthand for `solver.engine`.
    engine: Option<EngineKind>,
    #[serde(default)]
    rapier: RapierSettings,
    #[serde(default)]
    output: OutputFile,
    #[serde(default)]
    statistics: StatisticsFile,
    /// A parameter sweep (its meaning is the analysis crate's).
    sweep: Option<SweepTable>,
    /// A tolerance analysis likewise.
    robust: Option<RobustTable>,
}

fn default_gravity() -> [f64; 3] {
    [0.0, 0.0, -9.81]
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct PlatformFile {
    #[serde(default)]
    velocity: f64,
}

/// PID servo: `f = -k (x - x_r) - c (x' - x_r') - k_i * integral(x - x_r) dt`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSettings {
    /// Sensor element whose reading is x.
    pub sensor: String,
    /// Actuator element that applies f.
    pub actuator: String,
    /// Proportional gain, N/m.
    pub k: f64,
    /// Derivative gain, N s/m.
    pub c: f64,
    /// Integral gain, N/(m s).
    #[serde(default)]
    pub k_i: f64,
}

/// A servo gain.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Gain {
    /// Proportional gain `k`, N/m.
    K,
    /// Derivative gain `c`, N s/m.
    C,
    /// Integral gain `k_i`, N/(m s).
    KI,
}

impl Gain {
    /// The three gains in path order.
    pub const ALL: [Gain; 3] = [Gain::K, Gain::C, Gain::KI];

    /// What the scenario reader and every writer require of a gain.
    pub const RULE: Rule = Rule::NonNegative;

    /// Key under `[controller]`.
    pub fn key(self) -> &'static str {
        match self {
            Gain::K => "k",
            Gain::C => "c",
            Gain::KI => "k_i",
        }
    }

    pub(crate) fn unit(self) -> &'static str {
        match self {
            Gain::K => "N/m",
            Gain::C => "N.s/m",
            Gain::KI => "N/(m.s)",
        }
    }

    pub(crate) fn description(self) -> &'static str {
        match self {
            Gain::K => "servo proportional gain",
            Gain::C => "servo derivative gain",
            Gain::KI => "servo integral gain",
        }
    }
}

impl ControllerSettings {
    /// One gain.
    pub fn gain(&self, gain: Gain) -> f64 {
        match gain {
            Gain::K => self.k,
            Gain::C => self.c,
            Gain::KI => self.k_i,
        }
    }

    /// One gain, to write (see [`crate::Parameter`] for the checked way).
    pub fn gain_mut(&mut self, gain: Gain) -> &mut f64 {
        match gain {
            Gain::K => &mut self.k,
            Gain::C => &mut self.c,
            Gain::KI => &mut self.k_i,
        }
    }
}

/// Which engine integrates a scenario (`solver.engine`, or `engine` at the top).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EngineKind {
    /// The cheapest sound adaptive method for the model, chosen before the
    /// run from its linearisation and tolerance: `native`, `imex` or `rk4`
    /// (what `fistage check` shows).
    #[default]
    Auto,
    /// Error-controlled explicit Dormand-Prince 5(4) (also `dopri5`).
    #[serde(alias = "dopri5")]
    Native,
    /// Linearly implicit Rosenbrock-W ROS34PW2 with the exact Jacobian (also `implicit`).
    #[serde(alias = "implicit")]
    Rosenbrock,
    /// Additive Runge-Kutta `ARK5(4)8L[2]SA`, the bristle states implicit (also `ark548`).
    #[serde(alias = "ark548")]
    Imex,
    /// Explicit eighth-order Dormand-Prince pair DOP853, for tight tolerances.
    Dop853,
    /// The classical fourth-order Runge-Kutta method with a free third-order
    /// estimate (also `classical`), for loose tolerances on stages held by
    /// lightly damped stiff modes.
    #[serde(alias = "classical")]
    Rk4,
    /// rapier3d-f64 with a fixed step, under the model's own force elements.
    Rapier,
}

impl EngineKind {
    /// Every engine, in the order help texts list them.
    pub const ALL: [EngineKind; 7] = [
        EngineKind::Auto,
        EngineKind::Native,
        EngineKind::Rosenbrock,
        EngineKind::Imex,
        EngineKind::Dop853,
        EngineKind::Rk4,
        EngineKind::Rapier,
    ];

    /// The name in scenario files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            EngineKind::Auto => "auto",
            EngineKind::Native => "native",
            EngineKind::Rosenbrock => "rosenbrock",
            EngineKind::Imex => "imex",
            EngineKind::Dop853 => "dop853",
            EngineKind::Rk4 => "rk4",
            EngineKind::Rapier => "rapier",
        }
    }

    /// Whether the engine controls its error (the rapier engine takes fixed steps).
    pub fn is_adaptive(self) -> bool {
        self != EngineKind::Rapier
    }
}

impl std::fmt::Display for EngineKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for EngineKind {
    type Err = String;

    /// Parses a name or alias as scenario files accept them.
    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "auto" => Ok(EngineKind::Auto),
            "native" | "dopri5" => Ok(EngineKind::Native),
            "rosenbrock" | "implicit" => Ok(EngineKind::Rosenbrock),
            "imex" | "ark548" => Ok(EngineKind::Imex),
            "dop853" => Ok(EngineKind::Dop853),
            "rk4" | "classical" => Ok(EngineKind::Rk4),
            "rapier" => Ok(EngineKind::Rapier),
            other => Err(format!(
                "unknown engine \"{other}\" (available: {})",
                EngineKind::ALL.map(EngineKind::name).join(", ")
            )),
        }
    }
}

/// Which engine integrates the model, and how tightly.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSettings {
    /// The engine.
    #[serde(default)]
    pub engine: EngineKind,
    /// Relative tolerance.
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// Multiplies the per-state absolute tolerances `rtol * nominal_scale`.
    #[serde(default = "one")]
    pub atol_scale: f64,
    /// Largest step, s (default: no limit beyond the output interval).
    pub max_step: Option<f64>,
    /// Largest number of steps before the run is abandoned.
    #[serde(default = "default_max_steps")]
    pub max_steps: u64,
}

fn default_rtol() -> f64 {
    1e-8
}
fn one() -> f64 {
    1.0
}
fn default_max_steps() -> u64 {
    20_000_000
}

impl SolverSettings {
    /// The relative tolerances every engine accepts: finite, `0 < rtol < 0.1`
    /// (the rule for `solver.rtol`, `--rtol` and an FMU importer's tolerance).
    pub fn check_rtol(rtol: f64) -> Result<(), String> {
        // Below 1e-14 no double-precision error estimate can meet the
        // tolerance: the step size would only collapse.
        if rtol.is_finite() && (MIN_RTOL..0.1).contains(&rtol) {
            Ok(())
        } else {
            Err(format!(
                "must be >= {MIN_RTOL:e} and < 0.1, got {}",
                crate::rule::show(rtol)
            ))
        }
    }
}

/// The settling band of staircase steps unless a scenario gives one, m.
pub const DEFAULT_SETTLE_WINDOW: f64 = 50e-9;

/// The tightest relative tolerance a double-precision run can honour.
pub const MIN_RTOL: f64 = 1e-14;

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            engine: EngineKind::default(),
            rtol: default_rtol(),
            atol_scale: 1.0,
            max_step: None,
            max_steps: default_max_steps(),
        }
    }
}

/// Settings of the rapier engine (`[rapier]`): the fixed step and optional colliders.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RapierSettings {
    /// Fixed step, s (default: from the model's fastest mode, see `step_fraction`).
    pub dt: Option<f64>,
    /// Step as a fraction of 2 / |lambda|max at the starting state (default 0.05).
    pub step_fraction: Option<f64>,
    /// End-of-travel stops on prismatic joints (`[[rapier.stop]]`).
    #[serde(default, rename = "stop")]
    pub stops: Vec<StopSettings>,
    /// A payload box resting on a link (`[rapier.payload]`).
    pub payload: Option<PayloadSettings>,
}

/// A hard stop at one or both ends of a prismatic joint's travel: a fixed
/// block the moving body's collider hits.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StopSettings {
    /// Prismatic joint whose travel is limited.
    pub joint: String,
    /// Joint coordinate where the body meets the lower stop, m.
    pub lower: Option<f64>,
    /// Joint coordinate where the body meets the upper stop, m.
    pub upper: Option<f64>,
    /// Coefficient of restitution of the impact (0 = dead stop, 1 = elastic).
    #[serde(default)]
    pub restitution: f64,
}

/// A box resting on a link, held by gravity and contact friction only.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PayloadSettings {
    /// Link it rests on (its top face is found from `position` and `size`).
    pub link: String,
    /// Box edge lengths, m.
    pub size: [f64; 3],
    /// Mass, kg (uniform density).
    pub mass: f64,
    /// Centre of the box at the start, m, in the frame of the body that
    /// carries the link (the link's own frame unless fixed joints merged it
    /// into another link's body).
    pub position: [f64; 3],
    /// Coulomb friction coefficient of the contact.
    #[serde(default = "default_payload_friction")]
    pub friction: f64,
}

fn default_payload_friction() -> f64 {
    0.5
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputFile {
    sample_rate: Option<f64>,
    signals: Option<Vec<String>>,
    #[serde(default)]
    format: OutputFormat,
}

/// Which trajectory files `fistage run` writes (`output.format`, or `--format`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputFormat {
    /// `trajectory.csv`.
    #[default]
    Csv,
    /// `trajectory.mat` (a version 7 MAT-file).
    Mat,
    /// Both.
    Both,
}

impl OutputFormat {
    /// Whether `trajectory.csv` is written.
    pub fn csv(self) -> bool {
        self != Self::Mat
    }

    /// Whether `trajectory.mat` is written.
    pub fn mat(self) -> bool {
        self != Self::Csv
    }
}

impl std::str::FromStr for OutputFormat {
    type Err = String;

    /// `csv`, `mat` or `both`, as scenario files write them.
    fn from_str(text: &str) -> Result<Self, String> {
        match text {
            "csv" => Ok(Self::Csv),
            "mat" => Ok(Self::Mat),
            "both" => Ok(Self::Both),
            other => Err(format!("unknown format \"{other}\" (csv, mat or both)")),
        }
    }
}

#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct StatisticsFile {
    window: Option<Vec<f64>>,
    /// Half-width of the band a staircase step settles into, m.
    settle_window: Option<f64>,
}

/// Where a run starts (before the `[initial]` entries are applied).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Start {
    /// The zero configuration, at rest, bristles relaxed.
    #[default]
    Zero,
    /// The static (sticking) equilibrium: gravity sag and preloads settled, at rest.
    Static,
    /// The slipping equilibrium at the platform velocity.
    Slipping,
}

/// A per-element parameter override: `[overrides.<target>] <key> = <value>`.
#[derive(Debug, Clone, PartialEq)]
pub struct Override {
    /// Element or link name.
    pub target: String,
    /// Parameter key.
    pub key: String,
    /// New value, SI units.
    pub value: f64,
}

/// A checked scenario with paths resolved against the scenario file.
#[derive(Debug, Clone)]
pub struct Scenario {
    /// The scenario file.
    pub file: PathBuf,
    /// Human-readable title.
    pub title: String,
    /// Robot file, resolved.
    pub robot: PathBuf,
    /// Simulated time, s.
    pub duration: f64,
    /// Gravity in world coordinates, m/s^2.
    pub gravity: [f64; 3],
    /// Counter-surface velocity along every friction contact axis, m/s.
    pub platform_velocity: f64,
    /// Servo controller, if any.
    pub controller: Option<ControllerSettings>,
    /// Feedforward friction compensators in the servo, in file order (one
    /// per friction element at most; empty: none).
    pub compensation: Vec<CompensationSettings>,
    /// Disturbance observer in the servo, if any (`[dob]`).
    pub observer: Option<ObserverSettings>,
    /// Reference for the controller.
    pub reference: Reference,
    /// Overrides in file order (sorted by target, then key).
    pub overrides: Vec<Override>,
    /// Initial state entries by state name, applied on top of `start`.
    pub initial: BTreeMap<String, f64>,
    /// Where the run starts.
    pub start: Start,
    /// Solver settings.
    pub solver: SolverSettings,
    /// Settings of the rapier engine.
    pub rapier: RapierSettings,
    /// Output sample rate, Hz.
    pub sample_rate: f64,
    /// Signals to write (all when `None`).
    pub signals: Option<Vec<String>>,
    /// Which trajectory files a run writes.
    pub output_format: OutputFormat,
    /// Steady-state window for statistics, s.
    pub window: [f64; 2],
    /// Half-width of the band around its target that a staircase step must
    /// enter and stay in to count as settled, m (default 50 nm).
    pub settle_window: f64,
    /// The `[sweep]` table, when present.
    pub sweep: Option<SweepTable>,
    /// The `[robust]` table (a tolerance analysis), when present.
    pub robust: Option<RobustTable>,
}

impl Scenario {
    /// The inputs of the slipping equilibrium: the stage at rest while the
    /// counter-surfaces slide at the platform velocity less the reference's
    /// traverse velocity (what `fistage modes` and the method choice read).
    pub fn slipping_inputs(&self) -> crate::Inputs {
        crate::Inputs {
            platform_velocity: self.platform_velocity - self.reference.traverse_velocity(),
            ..crate::Inputs::default()
        }
    }

    /// Reads and checks a scenario file (not the robot it names).
    pub fn from_file(path: &Path) -> Result<Self, LoadError> {
        let text = crate::input::read_text(path, crate::input::MAX_DESCRIPTION_BYTES).map_err(
            |reason| LoadError::Io {
                file: path.to_path_buf(),
                reason,
            },
        )?;
        Self::from_str(&text, path)
    }

    /// Reads and checks scenario TOML; relative paths resolve against `file`'s folder.
    pub fn from_str(text: &str, file: &Path) -> Result<Self, LoadError> {
        let raw: ScenarioFile = toml::from_str(text).map_err(|e| {
            let message = readable_numbers(e.to_string().trim_end()).replace('\n', "\n  ");
            let table = e.span().and_then(|span| table_at(text, span.start));
            LoadError::Syntax {
                file: file.to_path_buf(),
                message: match table {
                    Some(table) => format!("{table}: {message}"),
                    None => message,
                },
            }
        })?;
        let base = file.parent().unwrap_or(Path::new(""));
        let checker = Checker { file };
        if raw.robot.as_os_str().is_empty() {
            return Err(checker.error("robot", "is empty: name the robot file"));
        }
        checker.positive("duration", raw.duration)?;
        for (axis, g) in ["x", "y", "z"].iter().zip(raw.gravity) {
            checker.finite(&format!("gravity.{axis}"), g)?;
        }
        checker.finite("platform.velocity", raw.platform.velocity)?;
        if let Some(controller) = &raw.controller {
            for gain in Gain::ALL {
                Gain::RULE.check(controller.gain(gain)).map_err(|e| {
                    checker.error(&format!("controller.{}", gain.key()), e.to_string())
                })?;
            }
        }
        let compensation = match &raw.compensation {
            Some(value) => read_compensations(value).map_err(|(key, m)| checker.error(&key, m))?,
            None => Vec::new(),
        };
        let observer = match &raw.dob {
            Some(table) => Some(read_observer(table).map_err(|(key, m)| checker.error(&key, m))?),
            None => None,
        };
        if raw.controller.is_none() {
            let table = [
                ("compensation", !compensation.is_empty()),
                ("dob", observer.is_some()),
            ];
            if let Some((key, _)) = table.iter().find(|(_, present)| *present) {
                return Err(checker.error(
                    key,
                    "acts in the servo, and the scenario has no [controller]: add one",
                ));
            }
        }
        let reference = checker.reference(raw.reference, base)?;
        SolverSettings::check_rtol(raw.solver.rtol)
            .map_err(|message| checker.error("solver.rtol", message))?;
        checker.positive("solver.atol_scale", raw.solver.atol_scale)?;
        if let Some(h) = raw.solver.max_step {
            checker.positive("solver.max_step", h)?;
        }
        let mut solver = raw.solver;
        if let Some(engine) = raw.engine {
            if solver.engine != EngineKind::default() && solver.engine != engine {
                return Err(checker.error(
                    "engine",
                    format!(
                        "\"{engine}\" contradicts solver.engine = \"{}\"",
                        solver.engine
                    ),
                ));
            }
            solver.engine = engine;
        }
        checker.rapier(&raw.rapier)?;
        let sample_rate = raw
            .output
            .sample_rate
            .unwrap_or_else(|| default_sample_rate(raw.duration));
        checker.positive("output.sample_rate", sample_rate)?;
        let settle_window = raw
            .statistics
            .settle_window
            .unwrap_or(DEFAULT_SETTLE_WINDOW);
        checker.positive("statistics.settle_window", settle_window)?;
        let window = match raw.statistics.window.as_deref() {
            None => [raw.duration / 2.0, raw.duration],
            Some(&[from, to]) => [from, to],
            Some(other) => {
                return Err(checker.error(
                    "statistics.window",
                    format!(
                        "must be [from, to] (two times, s), got {} values",
                        other.len()
                    ),
                ));
            }
        };
        let window_ok = window[0] >= 0.0 && window[0] < window[1] && window[1] <= raw.duration;
        if !window_ok {
            return Err(checker.error(
                "statistics.window",
                format!(
                    "must satisfy 0 <= start < end <= duration ({}), got [{}, {}]",
                    raw.duration, window[0], window[1]
                ),
            ));
        }
        let interval = 1.0 / sample_rate;
        let samples = (raw.duration / interval).floor() + 1.0;
        if samples > MAX_SAMPLES {
            return Err(checker.error(
                "output.sample_rate",
                format!(
                    "{sample_rate} Hz over the duration of {} s is {samples:.3e} samples; at most {MAX_SAMPLES:e}",
                    raw.duration
                ),
            ));
        }
        // Samples sit at k / sample_rate: the window must hold at least one.
        let in_window =
            (window[1] / interval + 1e-9).floor() - (window[0] / interval - 1e-9).ceil() + 1.0;
        if in_window < 1.0 {
            return Err(checker.error(
                "statistics.window",
                format!(
                    "[{}, {}] s holds no output sample at {sample_rate} Hz; widen it or raise output.sample_rate",
                    window[0], window[1]
                ),
            ));
        }
        let overrides = checker.overrides(raw.overrides)?;
        for (name, value) in &raw.initial {
            checker.finite(&format!("initial.{name}"), *value)?;
        }
        Ok(Scenario {
            file: file.to_path_buf(),
            title: raw.title,
            robot: base.join(raw.robot),
            duration: raw.duration,
            gravity: raw.gravity,
            platform_velocity: raw.platform.velocity,
            controller: raw.controller,
            compensation,
            observer,
            reference,
            overrides,
            initial: raw.initial,
            start: raw.start,
            solver,
            rapier: raw.rapier,
            sample_rate,
            signals: raw.output.signals,
            output_format: raw.output.format,
            window,
            settle_window,
            sweep: raw.sweep,
            robust: raw.robust,
        })
    }

    /// An error about a key of this scenario.
    pub fn error(&self, key: impl Into<String>, message: impl Into<String>) -> LoadError {
        LoadError::scenario(&self.file, key, message)
    }
}

/// The most output samples a run may hold (each is a full state vector).
pub const MAX_SAMPLES: f64 = 2e7;

/// 1 kHz for short runs, fewer samples for long ones (at most about 200 000).
fn default_sample_rate(duration: f64) -> f64 {
    1000.0_f64.min(200_000.0 / duration)
}

struct Checker<'a> {
    file: &'a Path,
}

impl Checker<'_> {
    fn error(&self, key: &str, message: impl Into<String>) -> LoadError {
        LoadError::scenario(self.file, key, message)
    }

    /// Ranges of the `[rapier]` settings (names are checked against the model later).
    fn rapier(&self, rapier: &RapierSettings) -> Result<(), LoadError> {
        if let Some(dt) = rapier.dt {
            self.positive("rapier.dt", dt)?;
        }
        if let Some(fraction) = rapier.step_fraction {
            self.positive("rapier.step_fraction", fraction)?;
            if fraction > 1.0 {
                return Err(self.error("rapier.step_fraction", "must be at most 1"));
            }
        }
        for (i, stop) in rapier.stops.iter().enumerate() {
            let key = format!("rapier.stop[{i}]");
            if stop.lower.is_none() && stop.upper.is_none() {
                return Err(self.error(&key, "needs lower, upper or both"));
            }
            for (name, value) in [("lower", stop.lower), ("upper", stop.upper)] {
                if let Some(v) = value {
                    self.finite(&format!("{key}.{name}"), v)?;
                }
            }
            if let (Some(lower), Some(upper)) = (stop.lower, stop.upper)
                && lower >= upper
            {
                return Err(self.error(&key, format!("lower {lower} must be below upper {upper}")));
            }
            if !(0.0..=1.0).contains(&stop.restitution) {
                return Err(self.error(
                    &format!("{key}.restitution"),
                    format!(
                        "must be in [0, 1], got {}",
                        crate::rule::show(stop.restitution)
                    ),
                ));
            }
        }
        if let Some(payload) = &rapier.payload {
            self.positive("rapier.payload.mass", payload.mass)?;
            for (axis, size) in ["x", "y", "z"].iter().zip(payload.size) {
                self.positive(&format!("rapier.payload.size.{axis}"), size)?;
            }
            for (axis, p) in ["x", "y", "z"].iter().zip(payload.position) {
                self.finite(&format!("rapier.payload.position.{axis}"), p)?;
            }
            self.non_negative("rapier.payload.friction", payload.friction)?;
        }
        Ok(())
    }

    fn rule(&self, key: &str, value: f64, rule: Rule) -> Result<(), LoadError> {
        rule.check(value)
            .map_err(|e| self.error(key, e.to_string()))
    }

    fn finite(&self, key: &str, value: f64) -> Result<(), LoadError> {
        self.rule(key, value, Rule::Finite)
    }

    fn positive(&self, key: &str, value: f64) -> Result<(), LoadError> {
        self.rule(key, value, Rule::Positive)
    }

    fn non_negative(&self, key: &str, value: f64) -> Result<(), LoadError> {
        self.rule(key, value, Rule::NonNegative)
    }

    /// The `[reference]` table, key by key: `kind` (default `constant`), then
    /// the numbers (each checked by its rule) or, for `csv`, the strings
    /// that kind takes; every error names its key.
    fn reference(&self, table: toml::Table, base: &Path) -> Result<Reference, LoadError> {
        let kind = match table.get("kind") {
            None => "constant",
            Some(toml::Value::String(kind)) => kind.as_str(),
            Some(other) => {
                return Err(self.error(
                    "reference.kind",
                    format!("must be a string, got {}", other.type_str()),
                ));
            }
        };
        let keys: &[&str] = match kind {
            "constant" => &["value"],
            "step" => &["time", "initial", "value"],
            "ramp" => &["start", "initial", "velocity"],
            "sine" => &["amplitude", "frequency", "phase", "offset"],
            "p2p" | "point_to_point" => &["start", "duration", "initial", "distance"],
            "csv" => &["file", "time_column", "position_column"],
            "circle" => &["radius", "tangential_velocity"],
            "staircase" => &[
                "start",
                "initial",
                "step",
                "move_time",
                "dwell",
                "steps",
                "profile",
            ],
            other => {
                return Err(self.error(
                    "reference.kind",
                    format!(
                        "unknown kind \"{other}\" (constant, step, ramp, sine, p2p, circle, staircase or csv)"
                    ),
                ));
            }
        };
        if let Some(key) = table
            .keys()
            .find(|k| *k != "kind" && !keys.contains(&k.as_str()))
        {
            return Err(self.error(
                &format!("reference.{key}"),
                format!(
                    "unknown key for kind = \"{kind}\" (it takes {})",
                    keys.join(", ")
                ),
            ));
        }
        let number = |key: &str, default: Option<f64>| -> Result<f64, LoadError> {
            let rule = Reference::key_rule(key);
            let path = format!("reference.{key}");
            let value = match (table.get(key), default) {
                (Some(toml::Value::Float(v)), _) => *v,
                (Some(toml::Value::Integer(v)), _) => *v as f64,
                (Some(other), _) => {
                    return Err(
                        self.error(&path, format!("must be a number, got {}", other.type_str()))
                    );
                }
                (None, Some(default)) => default,
                (None, None) => {
                    return Err(self.error(&path, format!("missing: kind = \"{kind}\" needs it")));
                }
            };
            self.rule(&path, value, rule)?;
            Ok(value)
        };
        let text = |key: &str, default: Option<&str>| -> Result<String, LoadError> {
            match (table.get(key), default) {
                (Some(toml::Value::String(s)), _) => Ok(s.clone()),
                (Some(other), _) => Err(self.error(
                    &format!("reference.{key}"),
                    format!("must be a string, got {}", other.type_str()),
                )),
                (None, Some(default)) => Ok(default.to_string()),
                (None, None) => Err(self.error(
                    &format!("reference.{key}"),
                    format!("missing: kind = \"{kind}\" needs it"),
                )),
            }
        };
        Ok(match kind {
            "constant" => Reference::Constant {
                value: number("value", Some(0.0))?,
            },
            "step" => Reference::Step {
                time: number("time", None)?,
                initial: number("initial", Some(0.0))?,
                value: number("value", None)?,
            },
            "ramp" => Reference::Ramp {
                start: number("start", Some(0.0))?,
                initial: number("initial", Some(0.0))?,
                velocity: number("velocity", None)?,
            },
            "sine" => Reference::Sine {
                amplitude: number("amplitude", None)?,
                frequency_hz: number("frequency", None)?,
                phase: number("phase", Some(0.0))?,
                offset: number("offset", Some(0.0))?,
            },
            "circle" => Reference::Circle {
                radius: number("radius", None)?,
                tangential_velocity: number("tangential_velocity", None)?,
            },
            "staircase" => {
                let steps = number("steps", Some(1.0))?;
                if !(steps.fract() == 0.0 && steps <= 1e6) {
                    return Err(self.error(
                        "reference.steps",
                        format!("must be a whole number from 1 to 1000000, got {steps}"),
                    ));
                }
                let profile = match text("profile", Some("minimum_jerk"))?.as_str() {
                    "minimum_jerk" | "min_jerk" => MoveProfile::MinimumJerk,
                    "trapezoidal" => MoveProfile::Trapezoidal,
                    other => {
                        return Err(self.error(
                            "reference.profile",
                            format!("unknown profile \"{other}\" (minimum_jerk or trapezoidal)"),
                        ));
                    }
                };
                Reference::Staircase {
                    start: number("start", Some(0.0))?,
                    initial: number("initial", Some(0.0))?,
                    step: number("step", None)?,
                    move_time: number("move_time", None)?,
                    dwell: number("dwell", None)?,
                    steps: steps as usize,
                    profile,
                }
            }
            "csv" => Reference::from_csv(
                &base.join(text("file", None)?),
                &text("time_column", Some("time"))?,
                &text("position_column", Some("position"))?,
            )?,
            _ => Reference::PointToPoint {
                start: number("start", None)?,
                duration: number("duration", None)?,
                initial: number("initial", Some(0.0))?,
                distance: number("distance", None)?,
            },
        })
    }

    fn overrides(
        &self,
        raw: BTreeMap<String, BTreeMap<String, toml::Value>>,
    ) -> Result<Vec<Override>, LoadError> {
        let mut overrides = Vec::new();
        for (target, table) in raw {
            if table.is_empty() {
                return Err(self.error(
                    &format!("overrides.{target}"),
                    "an empty table overrides nothing: give keys, or remove it",
                ));
            }
            for (key, value) in table {
                let path = format!("overrides.{target}.{key}");
                let value = match value {
                    toml::Value::Float(v) => v,
                    toml::Value::Integer(v) => v as f64,
                    other => {
                        return Err(self
                            .error(&path, format!("must be a number, got {}", other.type_str())));
                    }
                };
                self.finite(&path, value)?;
                overrides.push(Override {
                    target: target.clone(),
                    key,
                    value,
                });
            }
        }
        Ok(overrides)
    }
}

/// The header of the table (`[sweep]`, `[[robust.parameter]]`) that holds
/// byte `offset` of a TOML text, if any does: parser messages show the line,
/// not the table it belongs to.
fn table_at(text: &str, offset: usize) -> Option<&str> {
    let before = text.get(..offset)?;
    before
        .lines()
        .map(str::trim)
        .rfind(|line| line.starts_with('['))
        .map(|line| line.split('#').next().unwrap_or(line).trim_end())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scenario, LoadError> {
        Scenario::from_str(text, Path::new("scenarios/test.toml"))
    }

    #[test]
    fn minimal_scenario_has_defaults() {
        let s = parse("robot = \"../robots/r.urdf\"\nduration = 2.0\n").unwrap();
        assert_eq!(s.robot, Path::new("scenarios/../robots/r.urdf"));
        assert_eq!(s.window, [1.0, 2.0]);
        assert_eq!(s.solver.rtol, 1e-8);
        assert_eq!(s.reference, Reference::Constant { value: 0.0 });
        assert_eq!(s.sample_rate, 1000.0);
    }

    #[test]
    fn unknown_keys_are_named() {
        let e = parse("robot = \"r.urdf\"\nduration = 2.0\n[controller]\nsensor=\"s\"\nactuator=\"a\"\nk=1\nc=1\nkp=3\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("scenarios/test.toml") && e.contains("kp"), "{e}");
        let e = parse("robot = \"r.urdf\"\nduration = 2.0\nspeed = 3\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("speed"), "{e}");
    }

    /// `[sweep]` and `[robust]` are read with the rest: a key they do not
    /// have is refused when the scenario loads, by every command, where it
    /// was once refused only by the command that ran the study.
    #[test]
    fn study_tables_refuse_unknown_keys_on_load() {
        let head = "robot = \"r.urdf\"\nduration = 1\n";
        let sweep = "[[sweep.axis]]\nparameter = \"alpha\"\nfrom = 1\nto = 2\npoints = 3\n";
        let s = parse(&format!("{head}{sweep}")).unwrap();
        let table = s.sweep.expect("a [sweep] table");
        assert_eq!(table.axes[0].points, Some(3));
        assert_eq!(table.oscillation_threshold, 1e-9);
        for (text, key) in [
            (format!("{head}{sweep}step = 2\n"), "step"),
            (format!("{head}[sweep]\naxes = []\n"), "axes"),
            (
                format!(
                    "{head}[robust]\nsamples = 8\n[[robust.parameter]]\nparameter = \"alpha\"\ndistribution = \"normal\"\nsigma = 0.1\n"
                ),
                "sigma",
            ),
            (format!("{head}[robust]\nsample = 8\n"), "sample"),
        ] {
            let e = parse(&text).unwrap_err().to_string();
            assert!(
                e.contains("scenarios/test.toml") && e.contains(key),
                "{key}: {e}"
            );
            assert!(
                e.contains("sweep") || e.contains("robust"),
                "names the table: {e}"
            );
        }
        let e = parse(&format!("{head}[robust]\nsampling = \"grid\"\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("grid") && e.contains("sobol"), "{e}");
    }

    #[test]
    fn bad_values_are_named() {
        let e = parse("robot = \"r.urdf\"\nduration = -1\n")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "scenarios/test.toml: duration: must be > 0, got -1");
        let e = parse("robot = \"r.urdf\"\nduration = 1\n[overrides.bearing]\nsigma0 = \"big\"\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("overrides.bearing.sigma0: must be a number"),
            "{e}"
        );
        let e = parse(
            "robot = \"r.urdf\"\nduration = 1\n[reference]\nkind = \"sine\"\namplitude = 1\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("frequency"), "{e}");
        let e = parse("robot = \"r.urdf\"\nduration = 1\n[statistics]\nwindow = [0.5, 2.0]\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("statistics.window"), "{e}");
    }
}

//! The parameter table: every tunable quantity of a study is one entry, with
//! its path, unit, validity rule, and how it is read from and written to the
//! study (a [`Scenario`] and its [`RobotSpec`] as read from file). Scenario
//! overrides, sweep axes, FMU parameters, tolerance-analysis draws and
//! identify's override writer all go through it, so a value is checked by the
//! same rule wherever it comes from.
//!
//! Paths:
//!
//! | path | unit | rule | what it sets |
//! |---|---|---|---|
//! | `controller.k`, `controller.c`, `controller.k_i` | N/m, N s/m, N/(m s) | >= 0 | servo gains |
//! | `platform.velocity` | m/s | finite | counter-surface velocity |
//! | `alpha` | 1 | > 0 | factor on every isolator's x stiffness and damping (paper Fig. 9) |
//! | `beta` | 1 | > 0 | factor on the mass and inertia of every link carrying friction |
//! | `spread.<lugre key>`, `spread.friction` | 1 | -1 < s < 1 | mismatch of the friction contacts |
//! | `overrides.<friction>.<lugre key>` | SI | [`LugreParams::KEYS`] | one contact's LuGre parameter |
//! | `overrides.<friction>.x` (`y`, `z`) | m | finite | contact point |
//! | `overrides.<isolator>.k_x` .. `c_rz` | SI | >= 0 | [`IsolatorSpec::KEYS`] |
//! | `overrides.<isolator>.x` (`y`, `z`) | m | finite | attach point |
//! | `overrides.<actuator or sensor>.x` (`y`, `z`) | m | finite | point |
//! | `overrides.<link>.mass` | kg | > 0 | link mass (inertia scales with it) |
//! | `compensation.<element>.<model key>` | SI | the model's | the model parameter of the compensator of `<element>` (`sigma0` .. `v_s`; Dahl: `sigma`, `f_c`, `exponent`); `compensation.<model key>` for a model without an element, or the only compensator |
//! | `compensation.<element>.error.<model key>` | 1 | > -1 | relative error on that parameter; `compensation.error.<model key>` likewise |
//! | `dob.bandwidth`, `dob.nominal_mass` | Hz, kg | > 0 | disturbance observer |
//! | `reference.<number key>` | SI | the key's | a number of `[reference]` (e.g. `tangential_velocity`, `step`) |
//!
//! `alpha`, `beta` and `spread.*` act on the robot file's values and read as
//! their neutral value (1, 1 and 0). `spread.<key>` gives contact i of n (file
//! order) its value times `1 + s w_i`, weights running evenly from +1 to -1;
//! `spread.friction` spreads `f_c`, `f_s` and `sigma0` together.
//!
//! ```
//! use fistage_model::{Parameter, RobotSpec, Scenario};
//! # let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper");
//! let mut scenario = Scenario::from_file(&dir.join("fig05b_fi.toml"))?;
//! let mut robot = RobotSpec::from_file(&scenario.robot)?;
//! let gain = Parameter::resolve("controller.k", &scenario, &robot)?;
//! assert_eq!(gain.unit(), "N/m");
//! gain.write(&mut scenario, &mut robot, 1e5)?;
//! assert_eq!(gain.read(&scenario, &robot), 1e5);
//! // The loader's rule holds here too: a negative gain is refused.
//! assert!(gain.write(&mut scenario, &mut robot, -1.0).is_err());
//! # Ok::<(), fistage_model::LoadError>(())
//! ```

use std::fmt;

use crate::compensation::{CompensationKind, ERROR_RULE, ModelKey, ObserverKey};
use crate::error::LoadError;
use crate::lugre::{InvalidLugreParameter, LugreKey, LugreParams};
use crate::model::Model;
use crate::reference::Reference;
use crate::robot::{IsolatorKey, IsolatorSpec, RobotSpec};
use crate::rule::Rule;
use crate::scenario::{Gain, Scenario};

/// A coordinate of a point (`x`, `y`, `z`).
const POINT_KEYS: [&str; 3] = ["x", "y", "z"];

/// The kinds of element a path `overrides.<name>.<key>` can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
enum Element {
    Friction(usize),
    Isolator(usize),
    Actuator(usize),
    Sensor(usize),
}

/// What a parameter acts on, resolved against one robot file.
#[derive(Debug, Clone, Copy)]
enum Target {
    Gain(Gain),
    PlatformVelocity,
    Alpha,
    Beta,
    /// `spread.<key>`: the LuGre keys it spreads.
    Spread(&'static [&'static str]),
    Lugre(usize, &'static LugreKey),
    Isolator(usize, &'static IsolatorKey),
    Point(Element, usize),
    LinkMass(usize),
    /// A parameter of a feedforward compensator's model (the compensator's
    /// index in the scenario).
    Compensation(usize, ModelKey),
    /// The relative error on one.
    CompensationError(usize, ModelKey),
    Observer(ObserverKey),
    /// A number key of `[reference]`.
    Reference(&'static str),
}

const SPREAD_FRICTION: [&str; 3] = ["f_c", "f_s", "sigma0"];

/// One entry of the parameter table, resolved against a study.
#[derive(Debug, Clone)]
pub struct Parameter {
    path: String,
    target: Target,
}

impl PartialEq for Parameter {
    fn eq(&self, other: &Self) -> bool {
        self.path == other.path
    }
}

impl Eq for Parameter {}

impl fmt::Display for Parameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.path)
    }
}

impl Parameter {
    /// Resolves `path` against a scenario and its robot file. The error names
    /// the path and says what exists instead.
    pub fn resolve(path: &str, scenario: &Scenario, robot: &RobotSpec) -> Result<Self, LoadError> {
        let target = resolve_target(path, scenario, robot)?;
        Ok(Self {
            path: path.to_string(),
            target,
        })
    }

    /// The parameters whose paths match `pattern`, where `*` stands for
    /// any run of characters other than `.` (`overrides.bearing_*.f_s`), in
    /// table order; empty when none does.
    pub fn matching(pattern: &str, scenario: &Scenario, robot: &RobotSpec) -> Vec<Self> {
        Self::all(scenario, robot)
            .into_iter()
            .filter(|p| Self::path_matches(pattern, p.path()))
            .collect()
    }

    /// Whether `path` matches `pattern`, where `*` stands for any run of
    /// characters other than `.`.
    pub fn path_matches(pattern: &str, path: &str) -> bool {
        let (p, s) = (pattern.as_bytes(), path.as_bytes());
        let (mut i, mut j) = (0, 0);
        let (mut star, mut resume) = (None, 0);
        while j < s.len() {
            if i < p.len() && p[i] == b'*' {
                star = Some(i);
                resume = j;
                i += 1;
            } else if i < p.len() && p[i] == s[j] {
                i += 1;
                j += 1;
            } else if let Some(k) = star
                && s[resume] != b'.'
            {
                i = k + 1;
                resume += 1;
                j = resume;
            } else {
                return false;
            }
        }
        p[i..].iter().all(|&c| c == b'*')
    }

    /// Every parameter of the study, in table order: gains, platform
    /// velocity, then element by element (frictions, isolators, actuators,
    /// sensors, link masses), then the scale and spread parameters.
    pub fn all(scenario: &Scenario, robot: &RobotSpec) -> Vec<Self> {
        let mut list = Vec::new();
        let mut push = |path: String, target| list.push(Self { path, target });
        if scenario.controller.is_some() {
            for gain in Gain::ALL {
                push(format!("controller.{}", gain.key()), Target::Gain(gain));
            }
        }
        // A compensator's parameters are named by the element it models,
        // `compensation.<element>.<key>` (several are told apart so); one
        // with explicit values and no element is `compensation.<key>`, and
        // that shorter path also reaches the only compensator of a study.
        for (i, compensation) in scenario.compensation.iter().enumerate() {
            let prefix = match &compensation.element {
                Some(element) => format!("compensation.{element}"),
                None => "compensation".to_string(),
            };
            for key in compensation.kind.keys() {
                push(
                    format!("{prefix}.{}", key.name),
                    Target::Compensation(i, key),
                );
            }
            for key in compensation.kind.keys() {
                let path = format!("{prefix}.error.{}", key.name);
                push(path, Target::CompensationError(i, key));
            }
        }
        if scenario.observer.is_some() {
            for key in ObserverKey::ALL {
                push(format!("dob.{}", key.name()), Target::Observer(key));
            }
        }
        push("platform.velocity".into(), Target::PlatformVelocity);
        for key in scenario.reference.number_keys() {
            push(format!("reference.{key}"), Target::Reference(key));
        }
        for (i, friction) in robot.frictions.iter().enumerate() {
            for key in &LugreParams::KEYS {
                let path = format!("overrides.{}.{}", friction.name, key.name);
                push(path, Target::Lugre(i, key));
            }
            for (axis, name) in POINT_KEYS.iter().enumerate() {
                let path = format!("overrides.{}.{name}", friction.name);
                push(path, Target::Point(Element::Friction(i), axis));
            }
        }
        for (i, isolator) in robot.isolators.iter().enumerate() {
            for key in &IsolatorSpec::KEYS {
                let path = format!("overrides.{}.{}", isolator.name, key.name);
                push(path, Target::Isolator(i, key));
            }
            for (axis, name) in POINT_KEYS.iter().enumerate() {
                let path = format!("overrides.{}.{name}", isolator.name);
                push(path, Target::Point(Element::Isolator(i), axis));
            }
        }
        let point_elements = (robot.actuators.iter().enumerate())
            .map(|(i, a)| (Element::Actuator(i), &a.name))
            .chain((robot.sensors.iter().enumerate()).map(|(i, s)| (Element::Sensor(i), &s.name)));
        for (element, name) in point_elements {
            for (axis, key) in POINT_KEYS.iter().enumerate() {
                push(
                    format!("overrides.{name}.{key}"),
                    Target::Point(element, axis),
                );
            }
        }
        for (i, link) in robot.links.iter().enumerate() {
            if link.mass > 0.0 {
                push(format!("overrides.{}.mass", link.name), Target::LinkMass(i));
            }
        }
        if !robot.isolators.is_empty() {
            push("alpha".into(), Target::Alpha);
        }
        if !robot.frictions.is_empty() {
            push("beta".into(), Target::Beta);
        }
        if robot.frictions.len() > 1 {
            for key in &LugreParams::KEYS {
                push(
                    format!("spread.{}", key.name),
                    Target::Spread(std::slice::from_ref(&key.name)),
                );
            }
            push("spread.friction".into(), Target::Spread(&SPREAD_FRICTION));
        }
        list
    }

    /// The path, e.g. `overrides.bearing_friction.sigma0`.
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The FMI variable name: the path without its `overrides.` prefix.
    pub fn short_name(&self) -> &str {
        self.path.strip_prefix("overrides.").unwrap_or(&self.path)
    }

    /// SI unit, as FMI unit names write it (`1` for factors).
    pub fn unit(&self) -> &'static str {
        match self.target {
            Target::Gain(gain) => gain.unit(),
            Target::PlatformVelocity => "m/s",
            Target::Alpha | Target::Beta | Target::Spread(_) => "1",
            Target::Lugre(_, key) => key.unit,
            Target::Isolator(_, key) => key.unit,
            Target::Point(..) => "m",
            Target::LinkMass(_) => "kg",
            Target::Compensation(_, key) => key.unit,
            Target::CompensationError(..) => "1",
            Target::Observer(key) => key.unit(),
            Target::Reference(key) => reference_unit(key),
        }
    }

    /// The rule every value must meet.
    pub fn rule(&self) -> Rule {
        match self.target {
            Target::Gain(_) => Gain::RULE,
            Target::PlatformVelocity | Target::Point(..) => Rule::Finite,
            Target::Alpha | Target::Beta | Target::LinkMass(_) => Rule::Positive,
            Target::Spread(_) => Rule::Spread,
            Target::Lugre(_, key) => key.rule,
            Target::Isolator(..) => IsolatorSpec::RULE,
            Target::Compensation(_, key) => key.rule,
            Target::CompensationError(..) => ERROR_RULE,
            Target::Observer(_) => ObserverKey::RULE,
            Target::Reference(key) => Reference::key_rule(key),
        }
    }

    /// Whether the value is relative to the robot file (`alpha`, `beta`,
    /// `spread.*`) rather than a value in its own right.
    pub fn is_relative(&self) -> bool {
        matches!(
            self.target,
            Target::Alpha | Target::Beta | Target::Spread(_)
        )
    }

    /// Whether an exported FMU offers this parameter as a variable (servo
    /// gains, LuGre parameters and isolator stiffness and damping).
    pub fn is_fmi_variable(&self) -> bool {
        matches!(
            self.target,
            Target::Gain(_)
                | Target::Lugre(..)
                | Target::Isolator(..)
                | Target::Compensation(..)
                | Target::CompensationError(..)
                | Target::Observer(_)
        )
    }

    /// A few words on what it is.
    pub fn description(&self, robot: &RobotSpec) -> String {
        match self.target {
            Target::Gain(gain) => gain.description().to_string(),
            Target::PlatformVelocity => "counter-surface velocity along every contact axis".into(),
            Target::Alpha => "factor on every isolator's x stiffness and damping".into(),
            Target::Beta => "factor on the mass of every link that carries friction".into(),
            Target::Spread(keys) => format!(
                "relative spread of {} over the friction contacts",
                keys.join(", ")
            ),
            Target::Lugre(i, key) => format!(
                "LuGre {} of {} ({})",
                key.name, robot.frictions[i].name, key.description
            ),
            Target::Isolator(i, key) => {
                format!("isolator {} {}", robot.isolators[i].name, key.name)
            }
            Target::Point(element, axis) => format!(
                "{} coordinate of the point of {}",
                POINT_KEYS[axis],
                element_name(robot, element)
            ),
            Target::LinkMass(i) => format!("mass of link {}", robot.links[i].name),
            Target::Compensation(_, key) => {
                format!(
                    "feedforward compensator{}'s {} ({})",
                    self.compensated_element(),
                    key.name,
                    key.description
                )
            }
            Target::CompensationError(_, key) => {
                format!(
                    "relative error on the feedforward compensator{}'s {}",
                    self.compensated_element(),
                    key.name
                )
            }
            Target::Observer(key) => key.description().into(),
            Target::Reference(key) => format!("reference {key}"),
        }
    }

    /// ` of <element>` when the path names the element a compensator
    /// models (`compensation.<element>.<key>`), else nothing.
    fn compensated_element(&self) -> String {
        let rest = self.path.strip_prefix("compensation.").unwrap_or_default();
        match rest.split_once('.') {
            Some((first, _)) if first != "error" => format!(" of {first}"),
            _ => String::new(),
        }
    }

    /// The value in the study (the neutral 1 or 0 for relative parameters).
    pub fn read(&self, scenario: &Scenario, robot: &RobotSpec) -> f64 {
        match self.target {
            Target::Gain(gain) => scenario.controller.as_ref().map_or(0.0, |c| c.gain(gain)),
            Target::PlatformVelocity => scenario.platform_velocity,
            Target::Compensation(i, key) => (scenario.compensation.get(i))
                .and_then(|c| c.stated_model(robot, &scenario.file).ok())
                .map_or(f64::NAN, |model| model.get(key.name)),
            Target::CompensationError(i, key) => (scenario.compensation.get(i))
                .and_then(|c| c.error.get(key.name).copied())
                .unwrap_or(0.0),
            Target::Observer(key) => scenario.observer.map_or(f64::NAN, |o| o.get(key)),
            Target::Reference(key) => scenario.reference.number(key).unwrap_or(f64::NAN),
            _ => self.read_robot(robot),
        }
    }

    /// A value held by the robot description (the neutral value for relative ones).
    fn read_robot(&self, robot: &RobotSpec) -> f64 {
        match self.target {
            Target::Gain(_)
            | Target::PlatformVelocity
            | Target::Compensation(..)
            | Target::CompensationError(..)
            | Target::Observer(_)
            | Target::Reference(_) => f64::NAN,
            Target::Alpha | Target::Beta => 1.0,
            Target::Spread(_) => 0.0,
            Target::Lugre(i, key) => key.get(&robot.frictions[i].lugre),
            Target::Isolator(i, key) => robot.isolators[i].get(key),
            Target::Point(element, axis) => match element {
                Element::Friction(i) => robot.frictions[i].point[axis],
                Element::Isolator(i) => robot.isolators[i].origin.translation.vector[axis],
                Element::Actuator(i) => robot.actuators[i].point[axis],
                Element::Sensor(i) => robot.sensors[i].point[axis],
            },
            Target::LinkMass(i) => robot.links[i].mass,
        }
    }

    /// The value in an assembled model, where the model holds it: servo gains,
    /// robot-file values (after overrides), the compensator's and observer's
    /// values. `None` for the platform velocity (an input, not part of a
    /// model), the reference and the factors and spreads.
    pub fn read_model(&self, model: &Model) -> Option<f64> {
        match self.target {
            Target::Gain(gain) => model.structure.controller.as_ref().map(|c| match gain {
                Gain::K => c.k,
                Gain::C => c.c,
                Gain::KI => c.k_i,
            }),
            Target::Compensation(i, key) => (model.compensation.get(i))
                .and_then(|c| c.stated_model(model.robot(), std::path::Path::new("")).ok())
                .map(|stated| stated.get(key.name)),
            Target::CompensationError(i, key) => {
                (model.compensation.get(i)).map(|c| c.error.get(key.name).copied().unwrap_or(0.0))
            }
            Target::Observer(key) => model.observer.map(|o| o.get(key)),
            Target::PlatformVelocity
            | Target::Alpha
            | Target::Beta
            | Target::Spread(_)
            | Target::Reference(_) => None,
            _ => Some(self.read_robot(model.robot())),
        }
    }

    /// Writes `value` into the study after checking the parameter's rule. The
    /// LuGre rule that joins two keys (`f_s >= f_c`) is checked when the model
    /// is assembled, once every override is in. A robot-file value is written
    /// over the scenario's `[overrides]`: they are applied to `robot` first
    /// and taken out of `scenario`, so a study parameter the scenario also
    /// overrides takes the study's value, and a scale (`alpha`, `beta`,
    /// `spread.*`) scales the overridden value.
    pub fn write(
        &self,
        scenario: &mut Scenario,
        robot: &mut RobotSpec,
        value: f64,
    ) -> Result<(), LoadError> {
        self.check(value)
            .map_err(|m| scenario.error(&self.path, m))?;
        match self.target {
            Target::Gain(gain) => {
                if let Some(c) = scenario.controller.as_mut() {
                    *c.gain_mut(gain) = value;
                }
            }
            Target::PlatformVelocity => scenario.platform_velocity = value,
            Target::Compensation(i, key) => {
                if let Some(c) = scenario.compensation.get_mut(i) {
                    c.values.insert(key.name, value);
                }
            }
            Target::CompensationError(i, key) => {
                if let Some(c) = scenario.compensation.get_mut(i) {
                    c.error.insert(key.name, value);
                }
            }
            Target::Observer(key) => {
                if let Some(o) = scenario.observer.as_mut() {
                    *o.get_mut(key) = value;
                }
            }
            Target::Reference(key) => {
                let slot = scenario
                    .reference
                    .numbers_mut()
                    .into_iter()
                    .find(|(k, _)| *k == key);
                if let Some((_, slot)) = slot {
                    *slot = value;
                }
            }
            _ => {
                // The scenario's own overrides go in first, so the study's
                // value is the last word on its key (applied after it, an
                // override would silently replace a drawn or swept value).
                if !scenario.overrides.is_empty() {
                    crate::assembly::apply_overrides(robot, scenario)?;
                    scenario.overrides.clear();
                }
                self.write_robot(robot, value);
            }
        }
        Ok(())
    }

    /// Writes a robot-file parameter (every target but the scenario's gains
    /// and platform velocity) without checking its rule.
    fn write_robot(&self, robot: &mut RobotSpec, value: f64) {
        match self.target {
            Target::Gain(_)
            | Target::PlatformVelocity
            | Target::Compensation(..)
            | Target::CompensationError(..)
            | Target::Observer(_)
            | Target::Reference(_) => {}
            Target::Alpha => {
                for isolator in &mut robot.isolators {
                    isolator.stiffness[0] *= value;
                    isolator.damping[0] *= value;
                }
            }
            Target::Beta => {
                for link in &mut robot.links {
                    if robot.frictions.iter().any(|f| f.link == link.name) {
                        link.mass *= value;
                        link.inertia *= value;
                    }
                }
            }
            Target::Spread(keys) => {
                let n = robot.frictions.len();
                for (i, friction) in robot.frictions.iter_mut().enumerate() {
                    let weight = 1.0 - 2.0 * i as f64 / (n - 1) as f64;
                    for key in keys.iter().filter_map(|k| LugreParams::key(k)) {
                        let spread = key.get(&friction.lugre) * (1.0 + value * weight);
                        key.set(&mut friction.lugre, spread);
                    }
                }
            }
            Target::Lugre(i, key) => key.set(&mut robot.frictions[i].lugre, value),
            Target::Isolator(i, key) => robot.isolators[i].set(key, value),
            Target::Point(element, axis) => match element {
                Element::Friction(i) => robot.frictions[i].point[axis] = value,
                Element::Isolator(i) => robot.isolators[i].origin.translation.vector[axis] = value,
                Element::Actuator(i) => robot.actuators[i].point[axis] = value,
                Element::Sensor(i) => robot.sensors[i].point[axis] = value,
            },
            Target::LinkMass(i) => {
                let link = &mut robot.links[i];
                if link.mass > 0.0 {
                    link.inertia *= value / link.mass;
                }
                link.mass = value;
            }
        }
    }

    /// Checks a value against the rule; the message is the one every reader gives.
    pub fn check(&self, value: f64) -> Result<(), String> {
        let rule = self.rule();
        match self.target {
            Target::Lugre(_, key) if !rule.admits(value) => {
                Err(InvalidLugreParameter::new(key.name, value, rule).to_string())
            }
            _ => rule.check(value).map_err(|e| e.to_string()),
        }
    }
}

fn element_name(robot: &RobotSpec, element: Element) -> &str {
    match element {
        Element::Friction(i) => &robot.frictions[i].name,
        Element::Isolator(i) => &robot.isolators[i].name,
        Element::Actuator(i) => &robot.actuators[i].name,
        Element::Sensor(i) => &robot.sensors[i].name,
    }
}

/// Paths every study accepts besides `overrides.<element>.<key>`.
pub const GLOBAL_PATHS: [&str; 7] = [
    "controller.k",
    "controller.c",
    "controller.k_i",
    "platform.velocity",
    "alpha",
    "beta",
    "spread.friction",
];

fn resolve_target(path: &str, scenario: &Scenario, robot: &RobotSpec) -> Result<Target, LoadError> {
    let error = |message: String| scenario.error(path, message);
    if let Some(key) = path.strip_prefix("controller.") {
        let gain = Gain::ALL
            .into_iter()
            .find(|g| g.key() == key)
            .ok_or_else(|| error("unknown servo gain (use k, c or k_i)".into()))?;
        if scenario.controller.is_none() {
            return Err(error("the scenario has no [controller]".into()));
        }
        return Ok(Target::Gain(gain));
    }
    if let Some(rest) = path.strip_prefix("compensation.") {
        return compensation_target(rest, scenario).map_err(error);
    }
    if let Some(key) = path.strip_prefix("dob.") {
        let key = ObserverKey::ALL
            .into_iter()
            .find(|k| k.name() == key)
            .ok_or_else(|| {
                error("unknown observer parameter (use bandwidth or nominal_mass)".into())
            })?;
        if scenario.observer.is_none() {
            return Err(error("the scenario has no [dob]".into()));
        }
        return Ok(Target::Observer(key));
    }
    if let Some(key) = path.strip_prefix("reference.") {
        let keys = scenario.reference.number_keys();
        return match keys.iter().find(|k| **k == key) {
            Some(key) => Ok(Target::Reference(key)),
            None if keys.is_empty() => Err(error("this reference has no numbers to set".into())),
            None => Err(error(format!(
                "this reference has no number \"{key}\" (it has {})",
                keys.join(", ")
            ))),
        };
    }
    if let Some(key) = path.strip_prefix("spread.") {
        let keys: &'static [&'static str] = if key == "friction" {
            &SPREAD_FRICTION
        } else {
            let key = LugreParams::key(key).ok_or_else(|| {
                error(format!(
                    "unknown LuGre parameter \"{key}\" (use friction or one of {})",
                    LugreParams::NAMES.join(", ")
                ))
            })?;
            std::slice::from_ref(&key.name)
        };
        if robot.frictions.len() < 2 {
            return Err(error(format!(
                "spreads mismatch friction contacts, and {} has {}",
                robot.file.display(),
                robot.frictions.len()
            )));
        }
        return Ok(Target::Spread(keys));
    }
    match path {
        "platform.velocity" => return Ok(Target::PlatformVelocity),
        "alpha" if robot.isolators.is_empty() => {
            return Err(error(format!(
                "scales isolators, and {} has none",
                robot.file.display()
            )));
        }
        "alpha" => return Ok(Target::Alpha),
        "beta" if robot.frictions.is_empty() => {
            return Err(error(format!(
                "scales the links that carry friction, and {} has none",
                robot.file.display()
            )));
        }
        "beta" => return Ok(Target::Beta),
        _ => {}
    }
    let Some((name, key)) = path
        .strip_prefix("overrides.")
        .and_then(|rest| rest.rsplit_once('.'))
    else {
        return Err(error(format!(
            "unknown parameter (use {}, spread.<lugre key> or overrides.<element>.<key>)",
            GLOBAL_PATHS.join(", ")
        )));
    };
    element_target(name, key, robot).map_err(|(at, message)| scenario.error(at, message))
}

/// The target of `compensation.<key>` or `compensation.error.<key>` (the
/// one compensator), or of `compensation.<element>.<key>` or
/// `compensation.<element>.error.<key>` (the one that models `<element>`).
fn compensation_target(rest: &str, scenario: &Scenario) -> Result<Target, String> {
    if scenario.compensation.is_empty() {
        return Err("the scenario has no [compensation] (or its kind is none)".into());
    }
    let named = (scenario.compensation.iter().enumerate()).find_map(|(i, c)| {
        let element = c.element.as_deref()?;
        Some((i, rest.strip_prefix(element)?.strip_prefix('.')?))
    });
    let (index, rest) = match named {
        Some(found) => found,
        None if scenario.compensation.len() == 1 => (0, rest),
        None => {
            let elements: Vec<&str> = (scenario.compensation.iter())
                .filter_map(|c| c.element.as_deref())
                .collect();
            return Err(format!(
                "the scenario has several compensators: name the element, compensation.<element>.{rest} (elements: {})",
                elements.join(", ")
            ));
        }
    };
    let kind: CompensationKind = scenario.compensation[index].kind;
    let (name, relative) = match rest.strip_prefix("error.") {
        Some(name) => (name, true),
        None => (rest, false),
    };
    let key = kind.key(name).ok_or_else(|| {
        let names: Vec<&str> = kind.keys().iter().map(|k| k.name).collect();
        format!(
            "a {} model has no parameter \"{name}\" (it has {})",
            kind.name(),
            names.join(", ")
        )
    })?;
    Ok(if relative {
        Target::CompensationError(index, key)
    } else {
        Target::Compensation(index, key)
    })
}

/// The unit of a number key of `[reference]`.
fn reference_unit(key: &str) -> &'static str {
    match key {
        "time" | "start" | "duration" | "move_time" | "dwell" => "s",
        "frequency" => "Hz",
        "phase" => "rad",
        "velocity" | "tangential_velocity" => "m/s",
        _ => "m",
    }
}

/// Applies one `[overrides.<name>] key = value` of `scenario` to `robot`.
pub(crate) fn apply_override(
    scenario: &Scenario,
    robot: &mut RobotSpec,
    name: &str,
    key: &str,
    value: f64,
) -> Result<(), LoadError> {
    let parameter = Parameter {
        path: format!("overrides.{name}.{key}"),
        target: element_target(name, key, robot)
            .map_err(|(at, message)| scenario.error(at, message))?,
    };
    parameter
        .check(value)
        .map_err(|m| scenario.error(&parameter.path, m))?;
    parameter.write_robot(robot, value);
    Ok(())
}

/// The target of `overrides.<name>.<key>`; an error says at which key path.
fn element_target(name: &str, key: &str, robot: &RobotSpec) -> Result<Target, (String, String)> {
    let unknown_key = |allowed: Vec<&str>| {
        (
            format!("overrides.{name}.{key}"),
            format!(
                "\"{name}\" has no parameter \"{key}\" (allowed: {})",
                allowed.join(", ")
            ),
        )
    };
    let point = POINT_KEYS.iter().position(|k| *k == key);
    if let Some(i) = robot.frictions.iter().position(|f| f.name == name) {
        if let Some(lugre) = LugreParams::key(key) {
            return Ok(Target::Lugre(i, lugre));
        }
        return match point {
            Some(axis) => Ok(Target::Point(Element::Friction(i), axis)),
            None => Err(unknown_key(
                LugreParams::NAMES.into_iter().chain(POINT_KEYS).collect(),
            )),
        };
    }
    if let Some(i) = robot.isolators.iter().position(|s| s.name == name) {
        if let Some(axis) = point {
            return Ok(Target::Point(Element::Isolator(i), axis));
        }
        return match IsolatorSpec::key(key) {
            Some(k) => Ok(Target::Isolator(i, k)),
            None => Err(unknown_key(
                (IsolatorSpec::KEYS.iter().map(|k| k.name))
                    .chain(POINT_KEYS)
                    .collect(),
            )),
        };
    }
    let point_element = (robot.actuators.iter().position(|a| a.name == name))
        .map(Element::Actuator)
        .or_else(|| (robot.sensors.iter().position(|s| s.name == name)).map(Element::Sensor));
    if let Some(element) = point_element {
        return match point {
            Some(axis) => Ok(Target::Point(element, axis)),
            None => Err(unknown_key(POINT_KEYS.to_vec())),
        };
    }
    if name == "world" {
        return Err((
            format!("overrides.{name}"),
            "the world link does not move: it has nothing to override".into(),
        ));
    }
    if let Some(i) = robot.links.iter().position(|l| l.name == name) {
        return match key {
            "mass" => Ok(Target::LinkMass(i)),
            _ => Err(unknown_key(vec!["mass"])),
        };
    }
    Err((
        format!("overrides.{name}"),
        format!(
            "no element or link named \"{name}\" in {}",
            robot.file.display()
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper(name: &str) -> (Scenario, RobotSpec) {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/paper");
        let scenario = Scenario::from_file(&dir.join(name)).expect("scenario");
        let robot = RobotSpec::from_file(&scenario.robot).expect("robot");
        (scenario, robot)
    }

    fn fig05b() -> (Scenario, RobotSpec) {
        paper("fig05b_fi.toml")
    }

    /// Every entry reads back what was written, and refuses what its rule
    /// refuses, on a plain study and on compensated ones (feedforward models,
    /// their errors, the observer, the reference's numbers).
    #[test]
    fn every_entry_round_trips_and_checks_its_rule() {
        for name in ["fig05b_fi.toml", "fig03a_ff_fi.toml", "fig03b_dob_fi.toml"] {
            round_trips(paper(name));
        }
        let (scenario, robot) = paper("fig03a_ff_fi.toml");
        let paths: Vec<String> = (Parameter::all(&scenario, &robot).iter())
            .map(|p| p.path().to_string())
            .collect();
        for path in [
            "compensation.bearing_friction.sigma",
            "compensation.bearing_friction.error.f_c",
            "reference.tangential_velocity",
        ] {
            assert!(paths.iter().any(|p| p == path), "{path} in {paths:?}");
        }
    }

    /// A study value on a key the scenario also overrides is the one the
    /// model gets (the damped four-bearing study overrides every isolator's
    /// c_x and draws it too), and a scale scales the overridden value.
    #[test]
    fn a_study_value_wins_over_the_scenarios_override_of_its_key() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
        let scenario =
            Scenario::from_file(&dir.join("robust/four_bearing_damped.toml")).expect("scenario");
        let file = RobotSpec::from_file(&scenario.robot).expect("robot");
        let path = "overrides.isolator_fl.c_x";
        let built = |assignments: &[(&str, f64)]| {
            let (mut s, mut r) = (scenario.clone(), file.clone());
            for &(path, value) in assignments {
                let parameter = Parameter::resolve(path, &s, &r).expect("resolves");
                parameter.write(&mut s, &mut r, value).expect("writes");
            }
            let (_, model) = crate::assemble(r, &s).expect("assembles");
            let parameter = Parameter::resolve(path, &s, model.robot()).expect("resolves");
            parameter.read_model(&model).expect("a robot value")
        };
        assert_eq!(built(&[]), 80.0, "the scenario's override");
        assert_eq!(built(&[(path, 123.0)]), 123.0);
        let scaled = built(&[("alpha", 0.5)]);
        assert!(
            (scaled - 40.0).abs() < 1e-12,
            "alpha scales the override: {scaled}"
        );
        // Another element's override still holds beside a written value.
        let (mut s, mut r) = (scenario.clone(), file.clone());
        Parameter::resolve(path, &s, &r)
            .expect("resolves")
            .write(&mut s, &mut r, 123.0)
            .expect("writes");
        let (_, model) = crate::assemble(r, &s).expect("assembles");
        let other = Parameter::resolve("overrides.isolator_rr.c_x", &s, model.robot())
            .expect("resolves")
            .read_model(&model);
        assert_eq!(other, Some(80.0));
    }

    fn round_trips((scenario, robot): (Scenario, RobotSpec)) {
        let all = Parameter::all(&scenario, &robot);
        assert!(all.len() > 20, "{} entries", all.len());
        for parameter in &all {
            let again = Parameter::resolve(parameter.path(), &scenario, &robot).expect("resolves");
            assert_eq!(&again, parameter);
            let (mut s, mut r) = (scenario.clone(), robot.clone());
            let value = if parameter.rule() == Rule::Spread {
                0.25
            } else {
                parameter.read(&s, &r).abs() * 1.5 + 0.5
            };
            parameter.write(&mut s, &mut r, value).expect("valid value");
            if !parameter.is_relative() {
                assert_eq!(parameter.read(&s, &r), value, "{parameter}");
            }
            let refused = match parameter.rule() {
                Rule::Finite => f64::NAN,
                Rule::Spread => 1.0,
                _ => -1.0,
            };
            assert!(
                parameter.write(&mut s, &mut r, refused).is_err(),
                "{parameter}"
            );
        }
    }

    #[test]
    fn unknown_paths_name_what_exists() {
        let (scenario, robot) = fig05b();
        let message = |path: &str| {
            Parameter::resolve(path, &scenario, &robot)
                .unwrap_err()
                .to_string()
        };
        assert!(message("overrides.nope.k_x").contains("no element or link named \"nope\""));
        assert!(message("overrides.bearing_friction.k_x").contains("allowed: sigma0"));
        assert!(message("spread.friction").contains("has 1"));
        assert!(message("controller.q").contains("unknown servo gain"));
        assert!(message("gamma").contains("unknown parameter"));
    }
}

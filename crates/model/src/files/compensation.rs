//! The `[compensation]` and `[dob]` tables of a scenario: model-based
//! feedforward friction compensation and a disturbance observer, as written
//! and checked, before the model is assembled.
//!
//! ```toml
//! [compensation]
//! kind = "lugre"                 # none | lugre | dahl
//! element = "bearing_friction"   # the friction element it models (its parameters are the default)
//! error = { sigma0 = 0.5 }       # relative errors on the model: +50% sigma0
//! # explicit model parameters instead of (or on top of) the element's:
//! # sigma0 = 2.2e6, f_c = 5.1, ...   (dahl: sigma, also named sigma0, f_c, exponent)
//! isolator = "dynamic"           # dynamic | static | ignore (default dynamic when an
//!                                # isolator carries the element)
//!
//! [dob]
//! bandwidth = 50.0               # Hz, the Q-filter's cut-off
//! nominal_mass = 1.5             # kg, the nominal plant 1 / (m s^2)
//! ```
//!
//! A stage with several friction elements takes one compensator per element,
//! as an array of tables, each as above and each naming its element (the
//! single table is the one-entry case):
//!
//! ```toml
//! [[compensation]]
//! kind = "lugre"
//! element = "friction_fl"
//!
//! [[compensation]]
//! kind = "lugre"
//! element = "friction_fr"
//! error = { f_c = 0.4 }
//! ```
//!
//! The compensator's model is the element's parameters, then the explicit
//! values, then the relative errors (`value * (1 + error)`). A Dahl model
//! taken from a LuGre element starts from `sigma = sigma0`, the element's
//! `f_c` and `exponent = 1`. When an isolator joins the element's link to the
//! rest of the stage, the compensator models the friction *as felt through
//! the isolator*: with `isolator = "dynamic"` it simulates the bearing behind
//! the isolator (its mass, the isolator's stiffness and damping along the
//! contact axis, the friction model) driven by the reference, and feeds
//! forward the isolator's pull on the table ([`crate::elements::VirtualBearing`]);
//! with `"static"` it neglects the bearing's mass and feeds forward the
//! friction model with its pre-motion stiffness and damping in series with
//! the isolator's (paper Eq. 1, [`crate::elements::FrictionModel::felt_through`]);
//! with `"ignore"` it feeds the model forward as if it acted at the table.

use std::collections::BTreeMap;

use crate::dahl::DahlParams;
use crate::elements::FrictionModel;
use crate::error::LoadError;
use crate::lugre::LugreParams;
use crate::robot::RobotSpec;
use crate::rule::Rule;

/// The most compensators one servo carries: one per friction element of the
/// eight-bearing stage. The servo's values hold their states in fixed arrays
/// of this size (no allocation in an evaluation).
pub const MAX_COMPENSATORS: usize = 8;

/// Which friction model the feedforward compensator simulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CompensationKind {
    /// LuGre, the six parameters of [`LugreParams`].
    Lugre,
    /// Dahl, the three parameters of [`DahlParams`].
    Dahl,
}

/// One parameter of a compensator model, whichever the kind.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelKey {
    /// Name in files and parameter paths.
    pub name: &'static str,
    /// SI unit.
    pub unit: &'static str,
    /// The rule its value meets.
    pub rule: Rule,
    /// What it is, in a few words.
    pub description: &'static str,
}

impl CompensationKind {
    /// The name in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Lugre => "lugre",
            Self::Dahl => "dahl",
        }
    }

    /// The model's parameters in file order.
    pub fn keys(self) -> Vec<ModelKey> {
        let key = |name, unit, rule, description| ModelKey {
            name,
            unit,
            rule,
            description,
        };
        match self {
            Self::Lugre => (LugreParams::KEYS.iter())
                .map(|k| key(k.name, k.unit, k.rule, k.description))
                .collect(),
            Self::Dahl => (DahlParams::KEYS.iter())
                .map(|k| key(k.name, k.unit, k.rule, k.description))
                .collect(),
        }
    }

    /// The parameter named `name`. A Dahl model also takes `sigma0` for its
    /// rest stiffness `sigma` (both are the pre-motion stiffness k_f).
    pub fn key(self, name: &str) -> Option<ModelKey> {
        let name = match (self, name) {
            (Self::Dahl, "sigma0") => "sigma",
            _ => name,
        };
        self.keys().into_iter().find(|k| k.name == name)
    }

    fn names(self) -> String {
        let names: Vec<&str> = self.keys().iter().map(|k| k.name).collect();
        names.join(", ")
    }
}

/// The `[compensation]` table, checked.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensationSettings {
    /// The model simulated.
    pub kind: CompensationKind,
    /// The friction element modelled, whose parameters are the default.
    pub element: Option<String>,
    /// Explicit model parameters, by key name.
    pub values: BTreeMap<&'static str, f64>,
    /// Relative errors on the model, by key name: `value * (1 + error)`.
    pub error: BTreeMap<&'static str, f64>,
    /// How the isolator that carries the element enters the model (`None`:
    /// dynamically whenever one does).
    pub isolator: Option<IsolatorTreatment>,
}

/// How a compensator treats the isolator that carries the modelled element.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum IsolatorTreatment {
    /// Simulate the bearing behind it: mass, isolator, friction.
    Dynamic,
    /// Series stiffness and damping, bearing mass neglected (paper Eq. 1).
    Static,
    /// As if the friction acted at the table.
    Ignore,
}

impl IsolatorTreatment {
    /// The name in files.
    pub fn name(self) -> &'static str {
        match self {
            Self::Dynamic => "dynamic",
            Self::Static => "static",
            Self::Ignore => "ignore",
        }
    }
}

/// The disturbance observer's parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ObserverKey {
    /// `bandwidth`, Hz: the cut-off of the first-order Q-filter.
    Bandwidth,
    /// `nominal_mass`, kg: the nominal plant `1 / (m s^2)`.
    NominalMass,
}

impl ObserverKey {
    /// Both, in file order.
    pub const ALL: [ObserverKey; 2] = [ObserverKey::Bandwidth, ObserverKey::NominalMass];

    /// Name under `[dob]`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Bandwidth => "bandwidth",
            Self::NominalMass => "nominal_mass",
        }
    }

    /// SI unit.
    pub fn unit(self) -> &'static str {
        match self {
            Self::Bandwidth => "Hz",
            Self::NominalMass => "kg",
        }
    }

    /// What it is, in a few words.
    pub fn description(self) -> &'static str {
        match self {
            Self::Bandwidth => "disturbance observer Q-filter bandwidth",
            Self::NominalMass => "disturbance observer nominal mass",
        }
    }

    /// Both must be positive.
    pub const RULE: Rule = Rule::Positive;
}

/// The `[dob]` table, checked.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObserverSettings {
    /// Q-filter cut-off, Hz.
    pub bandwidth: f64,
    /// Nominal mass, kg.
    pub nominal_mass: f64,
}

impl ObserverSettings {
    /// One parameter.
    pub fn get(&self, key: ObserverKey) -> f64 {
        match key {
            ObserverKey::Bandwidth => self.bandwidth,
            ObserverKey::NominalMass => self.nominal_mass,
        }
    }

    /// One parameter, to write (unchecked: see [`crate::Parameter`]).
    pub fn get_mut(&mut self, key: ObserverKey) -> &mut f64 {
        match key {
            ObserverKey::Bandwidth => &mut self.bandwidth,
            ObserverKey::NominalMass => &mut self.nominal_mass,
        }
    }
}

/// The rule of a relative model error: the factor `1 + error` stays positive.
pub const ERROR_RULE: Rule = Rule::RelativeChange;

/// A number of a table, by path, for the readers below.
fn number(path: &str, value: &toml::Value) -> Result<f64, String> {
    match value {
        toml::Value::Float(v) => Ok(*v),
        toml::Value::Integer(v) => Ok(*v as f64),
        other => Err(format!(
            "{path}: must be a number, got {}",
            other.type_str()
        )),
    }
}

/// Reads `[compensation]` or `[[compensation]]`: the compensators in file
/// order, without those of kind `none`. Several must each name a distinct
/// friction element (their parameters are addressed by it). An error is
/// (key path, message).
pub(crate) fn read_compensations(
    value: &toml::Value,
) -> Result<Vec<CompensationSettings>, (String, String)> {
    let entries: Vec<(String, &toml::Table)> = match value {
        toml::Value::Table(table) => vec![("compensation".to_string(), table)],
        toml::Value::Array(entries) => (entries.iter().enumerate())
            .map(|(i, entry)| match entry {
                toml::Value::Table(table) => Ok((format!("compensation[{}]", i + 1), table)),
                other => Err((
                    format!("compensation[{}]", i + 1),
                    format!("must be a table, got {}", other.type_str()),
                )),
            })
            .collect::<Result<_, _>>()?,
        other => {
            return Err((
                "compensation".into(),
                format!(
                    "must be a table or an array of tables, got {}",
                    other.type_str()
                ),
            ));
        }
    };
    let mut compensators: Vec<(String, CompensationSettings)> = Vec::new();
    for (prefix, table) in entries {
        if let Some(settings) = read_compensation(table, &prefix)? {
            compensators.push((prefix, settings));
        }
    }
    if compensators.len() > MAX_COMPENSATORS {
        return Err((
            "compensation".into(),
            format!(
                "{} compensators, and a servo carries at most {MAX_COMPENSATORS}",
                compensators.len()
            ),
        ));
    }
    if compensators.len() > 1 {
        for (i, (prefix, settings)) in compensators.iter().enumerate() {
            let Some(element) = &settings.element else {
                return Err((
                    format!("{prefix}.element"),
                    "missing: with several compensators each names the friction element it models"
                        .into(),
                ));
            };
            let earlier = compensators[..i]
                .iter()
                .find(|(_, other)| other.element.as_ref() == Some(element));
            if let Some((first, _)) = earlier {
                return Err((
                    format!("{prefix}.element"),
                    format!("\"{element}\" is already compensated by {first}"),
                ));
            }
        }
    }
    Ok(compensators.into_iter().map(|(_, s)| s).collect())
}

/// Reads one compensator's table key by key; `Ok(None)` for `kind =
/// "none"`. Key paths start with `prefix` (`compensation` or
/// `compensation[2]`).
fn read_compensation(
    table: &toml::Table,
    prefix: &str,
) -> Result<Option<CompensationSettings>, (String, String)> {
    let at = |key: &str, message: String| (format!("{prefix}.{key}"), message);
    let kind = match table.get("kind") {
        None => return Err(at("kind", "missing: none, lugre or dahl".into())),
        Some(toml::Value::String(kind)) => match kind.as_str() {
            "none" => None,
            "lugre" => Some(CompensationKind::Lugre),
            "dahl" => Some(CompensationKind::Dahl),
            other => {
                return Err(at(
                    "kind",
                    format!("unknown kind \"{other}\" (none, lugre or dahl)"),
                ));
            }
        },
        Some(other) => {
            return Err(at(
                "kind",
                format!("must be a string, got {}", other.type_str()),
            ));
        }
    };
    let Some(kind) = kind else {
        // Switched off: the other keys may stay (a template toggled by its
        // kind), but each must be one the table knows.
        let known = |key: &str| {
            ["kind", "element", "error", "isolator"].contains(&key)
                || CompensationKind::Lugre.key(key).is_some()
                || CompensationKind::Dahl.key(key).is_some()
        };
        return match table.keys().find(|k| !known(k)) {
            Some(key) => Err(at(key, "unknown key".into())),
            None => Ok(None),
        };
    };
    let mut settings = CompensationSettings {
        kind,
        element: None,
        values: BTreeMap::new(),
        error: BTreeMap::new(),
        isolator: None,
    };
    for (key, value) in table {
        match (key.as_str(), value) {
            ("kind", _) => {}
            ("element", toml::Value::String(name)) if name.is_empty() => {
                return Err(at(key, "is empty: name a friction element".into()));
            }
            ("element", toml::Value::String(name)) => settings.element = Some(name.clone()),
            ("isolator", toml::Value::String(name)) => {
                let treatment = [
                    IsolatorTreatment::Dynamic,
                    IsolatorTreatment::Static,
                    IsolatorTreatment::Ignore,
                ]
                .into_iter()
                .find(|t| t.name() == name)
                .ok_or_else(|| {
                    at(
                        key,
                        format!("unknown treatment \"{name}\" (dynamic, static or ignore)"),
                    )
                })?;
                settings.isolator = Some(treatment);
            }
            ("element" | "isolator", other) => {
                let wanted = if key == "element" {
                    "a string"
                } else {
                    "\"dynamic\", \"static\" or \"ignore\""
                };
                return Err(at(
                    key,
                    format!("must be {wanted}, got {}", other.type_str()),
                ));
            }
            ("error", toml::Value::Table(errors)) => {
                for (name, value) in errors {
                    let path = format!("{prefix}.error.{name}");
                    let model_key = kind.key(name).ok_or_else(|| {
                        (
                            path.clone(),
                            format!(
                                "a {} model has no parameter \"{name}\" (it has {})",
                                kind.name(),
                                kind.names()
                            ),
                        )
                    })?;
                    let value = number(&path, value).map_err(|m| (path.clone(), m))?;
                    ERROR_RULE
                        .check(value)
                        .map_err(|e| (path.clone(), e.to_string()))?;
                    settings.error.insert(model_key.name, value);
                }
            }
            ("error", other) => {
                return Err(at(
                    key,
                    format!(
                        "must be a table of relative errors such as {{ sigma0 = 0.5 }}, got {}",
                        other.type_str()
                    ),
                ));
            }
            (name, value) => {
                let model_key = kind.key(name).ok_or_else(|| {
                    at(
                        name,
                        format!(
                            "unknown key (kind, element, error, isolator, or a {} parameter: {})",
                            kind.name(),
                            kind.names()
                        ),
                    )
                })?;
                let path = format!("{prefix}.{name}");
                let value = number(&path, value).map_err(|m| (path.clone(), m))?;
                model_key
                    .rule
                    .check(value)
                    .map_err(|e| (path.clone(), e.to_string()))?;
                settings.values.insert(model_key.name, value);
            }
        }
    }
    Ok(Some(settings))
}

/// Reads `[dob]` key by key. An error is (key path, message).
pub(crate) fn read_observer(table: &toml::Table) -> Result<ObserverSettings, (String, String)> {
    if let Some(key) = table
        .keys()
        .find(|k| ObserverKey::ALL.iter().all(|o| o.name() != k.as_str()))
    {
        return Err((
            format!("dob.{key}"),
            "unknown key (bandwidth, nominal_mass)".into(),
        ));
    }
    let value = |key: ObserverKey| -> Result<f64, (String, String)> {
        let path = format!("dob.{}", key.name());
        let value = table.get(key.name()).ok_or_else(|| {
            (
                path.clone(),
                format!("missing: the observer needs its {}", key.description()),
            )
        })?;
        let value = number(&path, value).map_err(|m| (path.clone(), m))?;
        ObserverKey::RULE
            .check(value)
            .map_err(|e| (path.clone(), e.to_string()))?;
        Ok(value)
    };
    Ok(ObserverSettings {
        bandwidth: value(ObserverKey::Bandwidth)?,
        nominal_mass: value(ObserverKey::NominalMass)?,
    })
}

impl CompensationSettings {
    /// The model before its errors: the element's parameters (a Dahl model
    /// takes `sigma0` and `f_c` with exponent 1), then the explicit values.
    /// A parameter with neither is named.
    pub fn stated_model(
        &self,
        robot: &RobotSpec,
        file: &std::path::Path,
    ) -> Result<FrictionModel, LoadError> {
        let error = |key: &str, message: String| LoadError::scenario(file, key, message);
        let element = match &self.element {
            Some(name) => Some(
                robot
                    .frictions
                    .iter()
                    .find(|f| &f.name == name)
                    .ok_or_else(|| {
                        let names: Vec<&str> =
                            robot.frictions.iter().map(|f| f.name.as_str()).collect();
                        error(
                            "compensation.element",
                            format!(
                                "no friction element \"{name}\" in {} (it has: {})",
                                robot.file.display(),
                                if names.is_empty() {
                                    "none".to_string()
                                } else {
                                    names.join(", ")
                                }
                            ),
                        )
                    })?,
            ),
            None => None,
        };
        let mut model = match (self.kind, element) {
            (CompensationKind::Lugre, Some(f)) => FrictionModel::Lugre(f.lugre),
            (CompensationKind::Dahl, Some(f)) => FrictionModel::Dahl(DahlParams {
                sigma: f.lugre.sigma0,
                f_c: f.lugre.f_c,
                exponent: 1.0,
            }),
            (kind, None) => {
                if let Some(missing) = kind
                    .keys()
                    .iter()
                    .find(|k| !self.values.contains_key(k.name))
                {
                    return Err(error(
                        &format!("compensation.{}", missing.name),
                        format!(
                            "missing: name an element, or give every {} parameter ({})",
                            kind.name(),
                            kind.names()
                        ),
                    ));
                }
                unset_model(kind)
            }
        };
        for (name, value) in &self.values {
            model.set(name, *value);
        }
        Ok(model)
    }

    /// The model the compensator simulates at the bearing: the stated model
    /// with its relative errors applied, checked by what makes the
    /// compensator's law defined (each key's own rule), not by a friction
    /// element's ordering: a study of an overestimated Coulomb level is
    /// legal. With it, what is physically odd about the model, one sentence
    /// each (f_s below f_c).
    pub fn bearing_model(
        &self,
        robot: &RobotSpec,
        file: &std::path::Path,
    ) -> Result<(FrictionModel, Vec<String>), LoadError> {
        let mut model = self.stated_model(robot, file)?;
        for (name, error) in &self.error {
            let value = model.get(name) * (1.0 + error);
            model.set(name, value);
        }
        model.validate_law().map_err(|(key, message)| {
            LoadError::scenario(
                file,
                "compensation",
                format!("the compensator's model breaks a rule after its errors: {key} {message}"),
            )
        })?;
        Ok((model, model.oddities()))
    }
}

/// A model of `kind` with every parameter unset (NaN), to be filled.
fn unset_model(kind: CompensationKind) -> FrictionModel {
    let nan = f64::NAN;
    match kind {
        CompensationKind::Lugre => FrictionModel::Lugre(LugreParams {
            sigma0: nan,
            sigma1: nan,
            sigma2: nan,
            f_c: nan,
            f_s: nan,
            v_s: nan,
        }),
        CompensationKind::Dahl => FrictionModel::Dahl(DahlParams {
            sigma: nan,
            f_c: nan,
            exponent: nan,
        }),
    }
}

//! The variables an exported stage offers, in value-reference order:
//! parameters (servo gains, every LuGre contact's six parameters, every
//! isolator's stiffness and damping), then the model inputs (reference,
//! external servo force, platform velocity), then every output signal.

use fistage_model::{Inputs, LugreParams, Model, Scenario};

/// Role of a variable (FMI 2.0 causality).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialisation (variability "fixed").
    Parameter,
    /// Set by the importer between steps (variability "continuous").
    Input,
    /// Computed by the unit (variability "continuous").
    Output,
}

/// What a variable reads or writes in the model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Binding {
    /// Servo gain: 0 = k, 1 = c, 2 = k_i.
    ControllerGain(usize),
    /// A parameter of a named force element, as a scenario override would set it.
    Element {
        /// Element name (LuGre contact or isolator).
        element: String,
        /// Override key, e.g. `sigma0` or `k_x`.
        key: &'static str,
    },
    /// Model input, index into [`Inputs::NAMES`].
    Input(usize),
    /// Model output signal, index into the model's signals.
    Output(usize),
}

/// One real scalar variable.
#[derive(Debug, Clone, PartialEq)]
pub struct Variable {
    /// Structured name, e.g. `controller.k`, `bearing_friction.sigma0`, `encoder.position`.
    pub name: String,
    /// FMI value reference.
    pub value_reference: u32,
    /// Role.
    pub causality: Causality,
    /// Start value (parameters and inputs).
    pub start: Option<f64>,
    /// Unit name, as declared in the model description's unit definitions.
    pub unit: &'static str,
    /// Human description.
    pub description: String,
    /// What it reads or writes.
    pub binding: Binding,
}

const LUGRE_UNITS: [&str; 6] = ["N/m", "N.s/m", "N.s/m", "N", "N", "m/s"];
const ISOLATOR_KEYS: [(&str, &str); 12] = [
    ("k_x", "N/m"),
    ("k_y", "N/m"),
    ("k_z", "N/m"),
    ("k_rx", "N.m/rad"),
    ("k_ry", "N.m/rad"),
    ("k_rz", "N.m/rad"),
    ("c_x", "N.s/m"),
    ("c_y", "N.s/m"),
    ("c_z", "N.s/m"),
    ("c_rx", "N.m.s/rad"),
    ("c_ry", "N.m.s/rad"),
    ("c_rz", "N.m.s/rad"),
];

/// What each input does, in the order of [`Inputs::NAMES`].
const INPUT_DESCRIPTIONS: [&str; 4] = [
    "reference position offset, added to the scenario's reference profile; held over each communication step",
    "reference velocity offset, added to the scenario's reference profile; held over each communication step",
    "external servo force added to the actuator force (the whole force with zero gains); held over each communication step",
    "counter-surface velocity along every contact axis; held over each communication step",
];

/// FMI unit name of a model signal unit.
fn fmi_unit(unit: &'static str) -> &'static str {
    match unit {
        "m s" => "m.s",
        other => other,
    }
}

/// Every variable of the unit for this model and scenario, in value-reference order.
pub fn variables(model: &Model, scenario: &Scenario) -> Vec<Variable> {
    let mut list: Vec<Variable> = Vec::new();
    let mut push = |name: String, causality, start, unit, description: String, binding| {
        let value_reference = list.len() as u32;
        list.push(Variable {
            name,
            value_reference,
            causality,
            start,
            unit,
            description,
            binding,
        });
    };
    if let Some(controller) = &model.controller {
        for (index, (key, value, unit, what)) in [
            ("k", controller.k, "N/m", "proportional gain"),
            ("c", controller.c, "N.s/m", "derivative gain"),
            ("k_i", controller.k_i, "N/(m.s)", "integral gain"),
        ]
        .into_iter()
        .enumerate()
        {
            push(
                format!("controller.{key}"),
                Causality::Parameter,
                Some(value),
                unit,
                format!("servo {what}"),
                Binding::ControllerGain(index),
            );
        }
    }
    for friction in &model.frictions {
        for ((name, value), unit) in LugreParams::NAMES
            .iter()
            .zip(friction.lugre.values())
            .zip(LUGRE_UNITS)
        {
            push(
                format!("{}.{name}", friction.name),
                Causality::Parameter,
                Some(value),
                unit,
                format!("LuGre {name} of {}", friction.name),
                Binding::Element {
                    element: friction.name.clone(),
                    key: name,
                },
            );
        }
    }
    for isolator in &model.isolators {
        for (index, (key, unit)) in ISOLATOR_KEYS.iter().enumerate() {
            let value = if index < 6 {
                isolator.stiffness[index]
            } else {
                isolator.damping[index - 6]
            };
            push(
                format!("{}.{key}", isolator.name),
                Causality::Parameter,
                Some(value),
                unit,
                format!("isolator {} {key}", isolator.name),
                Binding::Element {
                    element: isolator.name.clone(),
                    key,
                },
            );
        }
    }
    let defaults = Inputs {
        platform_velocity: scenario.platform_velocity,
        ..Inputs::default()
    };
    let input_starts = [
        defaults.reference.position,
        defaults.reference.velocity,
        defaults.servo_force,
        defaults.platform_velocity,
    ];
    for (index, ((name, unit), start)) in Inputs::NAMES.iter().zip(input_starts).enumerate() {
        push(
            (*name).to_string(),
            Causality::Input,
            Some(start),
            unit,
            INPUT_DESCRIPTIONS[index].to_string(),
            Binding::Input(index),
        );
    }
    for (index, signal) in model.signals.iter().enumerate() {
        push(
            signal.name.clone(),
            Causality::Output,
            None,
            fmi_unit(signal.unit),
            format!("output {}", signal.name),
            Binding::Output(index),
        );
    }
    list
}

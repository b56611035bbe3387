//! The variables an exported stage offers, in value-reference order:
//! parameters (the entries of the model's parameter table that an FMU offers:
//! servo gains, every LuGre contact's six parameters, every isolator's
//! stiffness and damping), then the model inputs (reference, external servo
//! force, platform velocity), then every output signal, then the continuous
//! states (`state.<name>`) and their derivatives (`der(state.<name>)`), which
//! Model Exchange importers integrate.

use fistage_model::{Inputs, Model, Parameter, Scenario};

/// Role of a variable (FMI 2.0 causality).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Causality {
    /// Set before initialisation (variability "fixed").
    Parameter,
    /// Set by the importer between steps (variability "continuous").
    Input,
    /// Computed by the unit (variability "continuous").
    Output,
    /// A continuous state or state derivative (causality "local").
    Local,
}

/// What a variable reads or writes in the model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Binding {
    /// An entry of the model's parameter table, written with its rule.
    Parameter(Parameter),
    /// Model input, index into [`Inputs::NAMES`].
    Input(usize),
    /// Model output signal, index into the model's signals.
    Output(usize),
    /// Continuous state, index into the state vector.
    State(usize),
    /// Derivative of a continuous state, index into the state vector.
    Derivative(usize),
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

/// FMI unit name of the rate of a quantity in `unit`.
fn rate_unit(unit: &'static str) -> &'static str {
    match unit {
        "m" => "m/s",
        "rad" => "rad/s",
        "1" => "1/s",
        "m/s" => "m/s2",
        "rad/s" => "rad/s2",
        "m s" => "m",
        "N" => "N/s",
        _ => "",
    }
}

/// Every variable of the unit for this model and its scenario, in value-reference order.
pub fn variables(model: &Model, scenario: &Scenario) -> Vec<Variable> {
    let robot = model.robot();
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
    for parameter in Parameter::all(scenario, robot) {
        if parameter.is_fmi_variable() {
            push(
                parameter.short_name().to_string(),
                Causality::Parameter,
                parameter.read_model(model),
                parameter.unit(),
                parameter.description(robot),
                Binding::Parameter(parameter),
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
    for (index, signal) in model.signals().iter().enumerate() {
        push(
            signal.name.clone(),
            Causality::Output,
            None,
            fmi_unit(signal.unit),
            format!("output {}", signal.name),
            Binding::Output(index),
        );
    }
    let layout = model.layout();
    for (index, (name, kind)) in layout.names.iter().zip(&layout.kinds).enumerate() {
        push(
            format!("state.{name}"),
            Causality::Local,
            None,
            fmi_unit(kind.unit()),
            format!("continuous state {name}"),
            Binding::State(index),
        );
    }
    for (index, (name, kind)) in layout.names.iter().zip(&layout.kinds).enumerate() {
        push(
            format!("der(state.{name})"),
            Causality::Local,
            None,
            rate_unit(kind.unit()),
            format!("time derivative of state {name}"),
            Binding::Derivative(index),
        );
    }
    list
}

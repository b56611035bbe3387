//! `modelDescription.xml` for FMI 2.0 Model Exchange and Co-Simulation in
//! one unit: unit definitions, both interfaces' capabilities, the default
//! experiment from the scenario, every variable of [`crate::variables()`]
//! (the continuous states with their derivatives), and the model structure
//! (outputs, derivatives and initial unknowns). The GUID is a hash of the description itself, so the
//! same model always gets the same GUID and any change gets a new one.

use fistage_model::{Model, Scenario};

use crate::variables::{Binding, Causality, Variable, variables};

/// The C identifier of the exported functions' library (`binaries/linux64/<id>.so`).
pub const MODEL_IDENTIFIER: &str = "fistage_stage";

/// What the unit promises importers.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Capabilities {
    /// `canGetAndSetFMUstate` and `canSerializeFMUstate`.
    pub fmu_state: bool,
    /// `providesDirectionalDerivative`.
    pub directional_derivatives: bool,
}

/// SI base-unit exponents (kg, m, s, rad) of each unit name used.
pub(crate) const UNITS: [(&str, [i32; 4]); 18] = [
    ("1", [0, 0, 0, 0]),
    ("1/s", [0, 0, -1, 0]),
    ("m", [0, 1, 0, 0]),
    ("m/s", [0, 1, -1, 0]),
    ("m/s2", [0, 1, -2, 0]),
    ("rad/s2", [0, 0, -2, 1]),
    ("N/s", [1, 1, -3, 0]),
    ("m.s", [0, 1, 1, 0]),
    ("N", [1, 1, -2, 0]),
    ("N/m", [1, 0, -2, 0]),
    ("N.s/m", [1, 0, -1, 0]),
    ("N/(m.s)", [1, 0, -3, 0]),
    ("rad", [0, 0, 0, 1]),
    ("rad/s", [0, 0, -1, 1]),
    ("N.m/rad", [1, 2, -2, -1]),
    ("N.m.s/rad", [1, 2, -1, -1]),
    ("kg", [1, 0, 0, 0]),
    ("s", [0, 0, 1, 0]),
];

pub(crate) fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Shortest round-trip decimal form of a start value.
pub(crate) fn number(value: f64) -> String {
    format!("{value:?}")
}

pub(crate) fn unit_definitions(used: &[&str]) -> String {
    let mut xml = String::from("  <UnitDefinitions>\n");
    for (name, [kg, m, s, rad]) in UNITS.iter().filter(|(name, _)| used.contains(name)) {
        let mut base = String::new();
        for (exponent, symbol) in [(kg, "kg"), (m, "m"), (s, "s"), (rad, "rad")] {
            if *exponent != 0 {
                base.push_str(&format!(" {symbol}=\"{exponent}\""));
            }
        }
        xml.push_str(&format!(
            "    <Unit name=\"{}\"><BaseUnit{base}/></Unit>\n",
            escape(name)
        ));
    }
    xml.push_str("  </UnitDefinitions>\n");
    xml
}

/// One `<ScalarVariable>`; `derivative_of` is the 1-based index of the
/// state a derivative variable differentiates.
fn scalar_variable(variable: &Variable, derivative_of: Option<usize>) -> String {
    let (causality, variability, initial) = attributes(variable.causality);
    let start = start_and_derivative(variable, derivative_of);
    format!(
        "    <ScalarVariable name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{causality}\" variability=\"{variability}\"{initial}>\n      <Real unit=\"{}\"{start}/>\n    </ScalarVariable>\n",
        escape(&variable.name),
        variable.value_reference,
        escape(&variable.description),
        escape(variable.unit),
    )
}

/// The causality, variability and initial attribute (with its leading
/// space, or empty) of a variable of `causality`, in both standards.
pub(crate) fn attributes(causality: Causality) -> (&'static str, &'static str, &'static str) {
    match causality {
        Causality::Parameter => ("parameter", "fixed", " initial=\"exact\""),
        Causality::Input => ("input", "continuous", ""),
        Causality::Output => ("output", "continuous", " initial=\"calculated\""),
        Causality::Local => ("local", "continuous", " initial=\"calculated\""),
    }
}

/// The ` start="..."` and ` derivative="..."` attributes (either may be absent).
pub(crate) fn start_and_derivative(
    variable: &Variable,
    derivative_of: Option<impl std::fmt::Display>,
) -> String {
    let mut text = variable
        .start
        .map(|s| format!(" start=\"{}\"", number(s)))
        .unwrap_or_default();
    if let Some(state) = derivative_of {
        text.push_str(&format!(" derivative=\"{state}\""));
    }
    text
}

/// The tightest default tolerance a description offers importers: their
/// default solver settings must run the stiff model (FMPy's CVode with 500
/// steps per output interval fails on Fig. 5b at 1e-8 and runs at 1e-6),
/// and Co-Simulation at 1e-6 still gives Fig. 5b's 69.26 um limit cycle.
const TIGHTEST_DEFAULT_TOLERANCE: f64 = 1e-6;

/// The `DefaultExperiment` tolerance: the scenario's, at most as tight as
/// [`TIGHTEST_DEFAULT_TOLERANCE`]. An importer may ask for a tighter one;
/// without one the unit steps at the scenario's own.
pub(crate) fn default_tolerance(scenario: &Scenario) -> f64 {
    scenario.solver.rtol.max(TIGHTEST_DEFAULT_TOLERANCE)
}

/// Whether a name follows FMI's structured naming: identifiers
/// (`[A-Za-z_][A-Za-z0-9_]*`) joined by dots, or `der(` such a name `)`.
pub(crate) fn is_structured(name: &str) -> bool {
    let name = name
        .strip_prefix("der(")
        .and_then(|inner| inner.strip_suffix(')'))
        .unwrap_or(name);
    name.split('.').all(|part| {
        let mut chars = part.chars();
        chars
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
    })
}

/// A 128-bit FNV-1a hash of the text, as an FMI GUID.
pub(crate) fn guid(text: &str) -> String {
    let hash = |seed: u64| {
        text.bytes().fold(seed, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
        })
    };
    let (a, b) = (hash(0xcbf2_9ce4_8422_2325), hash(0x84222325cbf29ce4));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}

/// The complete `modelDescription.xml`.
pub fn model_description(model: &Model, scenario: &Scenario, capabilities: Capabilities) -> String {
    let variables = variables(model, scenario);
    let mut used: Vec<&str> = variables.iter().map(|v| v.unit).collect();
    used.sort_unstable();
    used.dedup();
    let mut body = unit_definitions(&used);
    let mut categories = String::from("  <LogCategories>\n");
    for (name, description) in crate::logger::LOG_CATEGORIES {
        categories.push_str(&format!(
            "    <Category name=\"{name}\" description=\"{}\"/>\n",
            escape(description)
        ));
    }
    categories.push_str("  </LogCategories>\n");
    body.push_str(&categories);
    body.push_str(&format!(
        "  <DefaultExperiment startTime=\"0.0\" stopTime=\"{}\" tolerance=\"{}\" stepSize=\"{}\"/>\n",
        number(scenario.duration),
        number(default_tolerance(scenario)),
        number(1.0 / scenario.sample_rate)
    ));
    // 1-based index of each state's variable.
    let state_index = |state: usize| {
        (variables.iter())
            .position(|v| v.binding == Binding::State(state))
            .map(|i| i + 1)
    };
    body.push_str("  <ModelVariables>\n");
    for variable in &variables {
        let derivative_of = match variable.binding {
            Binding::Derivative(state) => state_index(state),
            _ => None,
        };
        body.push_str(&scalar_variable(variable, derivative_of));
    }
    let indices = |keep: &dyn Fn(&Variable) -> bool| -> Vec<usize> {
        (variables.iter().enumerate())
            .filter(|(_, v)| keep(v))
            .map(|(i, _)| i + 1)
            .collect()
    };
    let outputs = indices(&|v| v.causality == Causality::Output);
    let derivatives = indices(&|v| matches!(v.binding, Binding::Derivative(_)));
    // Outputs, states and derivatives are all computed at initialisation.
    let initial = indices(&|v| matches!(v.causality, Causality::Output | Causality::Local));
    body.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    for (element, list) in [
        ("Outputs", &outputs),
        ("Derivatives", &derivatives),
        ("InitialUnknowns", &initial),
    ] {
        if list.is_empty() {
            continue;
        }
        body.push_str(&format!("    <{element}>\n"));
        for index in list {
            body.push_str(&format!("      <Unknown index=\"{index}\"/>\n"));
        }
        body.push_str(&format!("    </{element}>\n"));
    }
    body.push_str("  </ModelStructure>\n");
    let flag = |b: bool| if b { "true" } else { "false" };
    let title = if scenario.title.is_empty() {
        model.name().to_string()
    } else {
        scenario.title.clone()
    };
    // Element names from the robot file may not be identifiers (a dash, a
    // space): then the names are declared flat.
    let convention = if variables.iter().all(|v| is_structured(&v.name)) {
        "structured"
    } else {
        "flat"
    };
    let head = format!(
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"{}\" description=\"{}\" generationTool=\"fistage {}\" variableNamingConvention=\"{convention}\" numberOfEventIndicators=\"0\"",
        escape(model.name()),
        escape(&title),
        env!("CARGO_PKG_VERSION"),
    );
    let model_exchange = format!(
        "  <ModelExchange modelIdentifier=\"{MODEL_IDENTIFIER}\" needsExecutionTool=\"false\" completedIntegratorStepNotNeeded=\"true\" canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"{}\" canSerializeFMUstate=\"{}\" providesDirectionalDerivative=\"{}\"/>\n",
        flag(capabilities.fmu_state),
        flag(capabilities.fmu_state),
        flag(capabilities.directional_derivatives),
    );
    let cosimulation = format!(
        "{model_exchange}  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" needsExecutionTool=\"false\" canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"false\" maxOutputDerivativeOrder=\"0\" canRunAsynchronuously=\"false\" canBeInstantiatedOnlyOncePerProcess=\"false\" canNotUseMemoryManagementFunctions=\"true\" canGetAndSetFMUstate=\"{}\" canSerializeFMUstate=\"{}\" providesDirectionalDerivative=\"{}\"/>\n",
        flag(capabilities.fmu_state),
        flag(capabilities.fmu_state),
        flag(capabilities.directional_derivatives),
    );
    let identity = guid(&format!("{head}{cosimulation}{body}"));
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n{head} guid=\"{identity}\">\n{cosimulation}{body}</fmiModelDescription>\n"
    )
}

#[cfg(test)]
mod naming_tests {
    use super::is_structured;

    #[test]
    fn structured_names_are_dotted_identifiers() {
        for name in ["controller.k", "friction_fl.sigma0", "table.x", "_a.b1"] {
            assert!(is_structured(name), "{name}");
        }
        for name in ["rail-fl.q", "my table.x", "1st.q", "a..b", ""] {
            assert!(!is_structured(name), "{name}");
        }
    }
}

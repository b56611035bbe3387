//! `modelDescription.xml` for FMI 3.0: Model Exchange and Co-Simulation in
//! one unit, unit definitions, the default experiment, the independent
//! variable `time`, every variable of [`crate::variables()`] as Float64
//! (states and their derivatives, the derivative naming its state by value
//! reference), and the model structure. The instantiation token is the
//! FMI 2.0 description's GUID of the same model, which an instance checks
//! at instantiation exactly as in FMI 2.0.

use fistage_model::{Model, Scenario};

use crate::model_description::{
    Capabilities, MODEL_IDENTIFIER, attributes, default_tolerance, escape, is_structured,
    model_description as fmi2_description, number, start_and_derivative, unit_definitions,
};
use crate::variables::{Binding, Causality, Variable, variables};

/// One `<Float64>` variable; `derivative_of` is the value reference of the
/// state a derivative differentiates.
fn float64(variable: &Variable, derivative_of: Option<u32>) -> String {
    let (causality, variability, initial) = attributes(variable.causality);
    let extra = start_and_derivative(variable, derivative_of);
    format!(
        "    <Float64 name=\"{}\" valueReference=\"{}\" description=\"{}\" causality=\"{causality}\" variability=\"{variability}\"{initial} unit=\"{}\"{extra}/>\n",
        escape(&variable.name),
        variable.value_reference,
        escape(&variable.description),
        escape(variable.unit),
    )
}

/// The complete FMI 3.0 `modelDescription.xml`.
pub fn model_description(model: &Model, scenario: &Scenario, capabilities: Capabilities) -> String {
    let token = crate::instance::description_guid(&fmi2_description(model, scenario, capabilities));
    let variables = variables(model, scenario);
    let time_reference = variables.len();
    let mut used: Vec<&str> = variables.iter().map(|v| v.unit).collect();
    used.push("s");
    used.sort_unstable();
    used.dedup();
    let flag = |b: bool| if b { "true" } else { "false" };
    let common = format!(
        "modelIdentifier=\"{MODEL_IDENTIFIER}\" needsExecutionTool=\"false\" canBeInstantiatedOnlyOncePerProcess=\"false\" canGetAndSetFMUState=\"{}\" canSerializeFMUState=\"{}\" providesDirectionalDerivatives=\"{}\" providesAdjointDerivatives=\"{}\"",
        flag(capabilities.fmu_state),
        flag(capabilities.fmu_state),
        flag(capabilities.directional_derivatives),
        flag(capabilities.directional_derivatives),
    );
    let mut xml = format!(
        "  <ModelExchange {common} needsCompletedIntegratorStep=\"false\"/>\n  <CoSimulation {common} canHandleVariableCommunicationStepSize=\"true\" maxOutputDerivativeOrder=\"0\" hasEventMode=\"false\"/>\n"
    );
    xml.push_str(&unit_definitions(&used));
    xml.push_str("  <LogCategories>\n");
    for (name, description) in crate::logger::LOG_CATEGORIES {
        xml.push_str(&format!(
            "    <Category name=\"{name}\" description=\"{}\"/>\n",
            escape(&description.replace("fmi2", "fmi3"))
        ));
    }
    xml.push_str("  </LogCategories>\n");
    xml.push_str(&format!(
        "  <DefaultExperiment startTime=\"0.0\" stopTime=\"{}\" tolerance=\"{}\" stepSize=\"{}\"/>\n",
        number(scenario.duration),
        number(default_tolerance(scenario)),
        number(1.0 / scenario.sample_rate)
    ));
    xml.push_str("  <ModelVariables>\n");
    xml.push_str(&format!(
        "    <Float64 name=\"time\" valueReference=\"{time_reference}\" description=\"simulation time\" causality=\"independent\" variability=\"continuous\" unit=\"s\"/>\n"
    ));
    let state_reference = |state: usize| {
        (variables.iter())
            .find(|v| v.binding == Binding::State(state))
            .map(|v| v.value_reference)
    };
    for variable in &variables {
        let derivative_of = match variable.binding {
            Binding::Derivative(state) => state_reference(state),
            _ => None,
        };
        xml.push_str(&float64(variable, derivative_of));
    }
    xml.push_str("  </ModelVariables>\n  <ModelStructure>\n");
    let references = |keep: &dyn Fn(&Variable) -> bool| -> Vec<u32> {
        (variables.iter())
            .filter(|v| keep(v))
            .map(|v| v.value_reference)
            .collect()
    };
    for (element, list) in [
        ("Output", references(&|v| v.causality == Causality::Output)),
        (
            "ContinuousStateDerivative",
            references(&|v| matches!(v.binding, Binding::Derivative(_))),
        ),
        (
            "InitialUnknown",
            references(&|v| matches!(v.causality, Causality::Output | Causality::Local)),
        ),
    ] {
        for vr in list {
            xml.push_str(&format!("    <{element} valueReference=\"{vr}\"/>\n"));
        }
    }
    xml.push_str("  </ModelStructure>\n");
    let title = if scenario.title.is_empty() {
        model.name().to_string()
    } else {
        scenario.title.clone()
    };
    let convention = if variables.iter().all(|v| is_structured(&v.name)) {
        "structured"
    } else {
        "flat"
    };
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<fmiModelDescription fmiVersion=\"3.0\" modelName=\"{}\" description=\"{}\" generationTool=\"fistage {}\" instantiationToken=\"{token}\" variableNamingConvention=\"{convention}\">\n{xml}</fmiModelDescription>\n",
        escape(model.name()),
        escape(&title),
        env!("CARGO_PKG_VERSION"),
    )
}

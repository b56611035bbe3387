//! System Structure and Parameterization (SSP 1.0) packages: the plant's
//! FMU with the controller FMUs around it, their connections by variable
//! name and the values of their parameters, in one `.ssp` archive that
//! co-simulation tools open as a system.
//!
//! ```text
//! loop.ssp
//! ├── SystemStructure.ssd        the system: components, connectors,
//! │                              connections, parameter bindings
//! └── resources/
//!     ├── plant.fmu
//!     └── controller.fmu
//! ```
//!
//! Every component is read before anything is written: its
//! `modelDescription.xml` must be FMI 2.0 with Co-Simulation (what SSP 1.0
//! describes), each connection must run from an output to an input of the
//! same type, each input may be driven once, and each parameter value must
//! name a parameter (or input) of its component and parse as its type. A
//! connector is declared for each connected variable; parameter values are
//! bound to their component inline (`ssd:ParameterBindings` holding an
//! `ssv:ParameterSet`), by the FMU's own variable names.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::io::{Read, Write as _};

use thiserror::Error;

/// The archive's system description, at its root as SSP requires.
pub const SSD_FILE: &str = "SystemStructure.ssd";

/// Why a system could not be packaged.
#[derive(Debug, Error, PartialEq)]
pub enum SspError {
    /// A component's archive or description cannot be read.
    #[error("component \"{component}\": {reason}")]
    Component {
        /// The component's name.
        component: String,
        /// What is wrong.
        reason: String,
    },
    /// A component name is unusable.
    #[error("component name \"{0}\": {1}")]
    Name(String, String),
    /// A connection is unusable.
    #[error("connection {connection}: {reason}")]
    Connection {
        /// The connection as given (`from -> to`).
        connection: String,
        /// What is wrong.
        reason: String,
    },
    /// A parameter value is unusable.
    #[error("parameter {parameter}: {reason}")]
    Parameter {
        /// The parameter as given (`component.variable`).
        parameter: String,
        /// What is wrong.
        reason: String,
    },
    /// The archive could not be written.
    #[error("writing the SSP archive: {0}")]
    Archive(String),
}

/// One FMU of the system: its name in the system and the archive's bytes.
#[derive(Debug, Clone)]
pub struct ComponentFile {
    /// The name connections and parameters use (no dots).
    pub name: String,
    /// The `.fmu` archive.
    pub fmu: Vec<u8>,
}

/// A variable of a component, `component.variable`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Endpoint {
    /// The component's name.
    pub component: String,
    /// The FMU variable's name.
    pub variable: String,
}

impl Endpoint {
    /// Splits `component.variable` at its first dot (component names have
    /// none; variable names may, as `encoder.position`).
    pub fn parse(text: &str) -> Option<Self> {
        let (component, variable) = text.trim().split_once('.')?;
        (!component.is_empty() && !variable.is_empty()).then(|| Self {
            component: component.to_string(),
            variable: variable.to_string(),
        })
    }
}

impl std::fmt::Display for Endpoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}.{}", self.component, self.variable)
    }
}

/// A connection from an output to an input.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    /// The output that drives it.
    pub from: Endpoint,
    /// The input it drives.
    pub to: Endpoint,
}

impl std::fmt::Display for Connection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} -> {}", self.from, self.to)
    }
}

/// A parameter value as written (`"6e4"`, `"true"`): parsed by the type of
/// the variable it names.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParameterValue {
    /// The parameter.
    pub at: Endpoint,
    /// Its value as text.
    pub value: String,
}

/// A whole system: its components, connections and parameter values, and
/// the experiment it suggests.
#[derive(Debug, Clone, Default)]
pub struct SystemSpec {
    /// The system's name.
    pub name: String,
    /// The components, in the order they are listed.
    pub components: Vec<ComponentFile>,
    /// The connections.
    pub connections: Vec<Connection>,
    /// The parameter values.
    pub parameters: Vec<ParameterValue>,
    /// The suggested stop time, s (a `DefaultExperiment` from 0).
    pub stop_time: Option<f64>,
}

/// The type of a variable, as SSP names it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum VariableType {
    Real,
    Integer,
    Boolean,
    String,
    Enumeration,
}

impl VariableType {
    fn from_fmi2(element: &str) -> Option<Self> {
        match element {
            "Real" => Some(Self::Real),
            "Integer" => Some(Self::Integer),
            "Boolean" => Some(Self::Boolean),
            "String" => Some(Self::String),
            "Enumeration" => Some(Self::Enumeration),
            _ => None,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::Real => "Real",
            Self::Integer => "Integer",
            Self::Boolean => "Boolean",
            Self::String => "String",
            Self::Enumeration => "Enumeration",
        }
    }
}

/// What a component's description says about one variable.
#[derive(Debug, Clone, PartialEq, Eq)]
struct VariableInfo {
    causality: String,
    kind: VariableType,
}

/// A component read: its variables by name.
#[derive(Debug)]
struct ComponentInfo {
    variables: BTreeMap<String, VariableInfo>,
}

/// Reads a component's `modelDescription.xml` from its archive.
fn read_component(component: &ComponentFile) -> Result<ComponentInfo, SspError> {
    let fail = |reason: String| SspError::Component {
        component: component.name.clone(),
        reason,
    };
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(&component.fmu))
        .map_err(|e| fail(format!("not an FMU archive ({e})")))?;
    let mut text = String::new();
    archive
        .by_name("modelDescription.xml")
        .map_err(|_| fail("the archive has no modelDescription.xml".into()))?
        .read_to_string(&mut text)
        .map_err(|e| fail(format!("modelDescription.xml: {e}")))?;
    let document = roxmltree::Document::parse(&text)
        .map_err(|e| fail(format!("modelDescription.xml: {e}")))?;
    let root = document.root_element();
    match root.attribute("fmiVersion") {
        Some("2.0") => {}
        Some(other) => {
            return Err(fail(format!(
                "FMI {other}: an SSP 1.0 system holds FMI 2.0 units (build the plant with --fmi-version 2)"
            )));
        }
        None => return Err(fail("modelDescription.xml has no fmiVersion".into())),
    }
    if !root.children().any(|c| c.has_tag_name("CoSimulation")) {
        return Err(fail(
            "the FMU has no Co-Simulation interface, which a system of FMUs steps".into(),
        ));
    }
    let mut variables = BTreeMap::new();
    let list = root.children().find(|c| c.has_tag_name("ModelVariables"));
    for variable in list.iter().flat_map(|l| l.children()) {
        if !variable.has_tag_name("ScalarVariable") {
            continue;
        }
        let Some(name) = variable.attribute("name") else {
            continue;
        };
        let kind = (variable.children())
            .filter(|c| c.is_element())
            .find_map(|c| VariableType::from_fmi2(c.tag_name().name()));
        let Some(kind) = kind else {
            return Err(fail(format!("variable \"{name}\" has no type element")));
        };
        let causality = variable
            .attribute("causality")
            .unwrap_or("local")
            .to_string();
        variables.insert(name.to_string(), VariableInfo { causality, kind });
    }
    Ok(ComponentInfo { variables })
}

/// A component name SSP and the endpoints' dotted form can carry.
fn check_name(name: &str) -> Result<(), SspError> {
    let reason = if name.is_empty() {
        Some("is empty")
    } else if name.contains('.') {
        Some("has a dot (a dot separates the component from its variable)")
    } else if name
        .chars()
        .any(|c| c.is_whitespace() || c == '/' || c == '\\')
    {
        Some("has a space or a slash")
    } else {
        None
    };
    match reason {
        Some(reason) => Err(SspError::Name(name.to_string(), reason.to_string())),
        None => Ok(()),
    }
}

/// The variable an endpoint names, or what is wrong with it.
fn variable<'a>(
    components: &'a BTreeMap<&str, ComponentInfo>,
    at: &Endpoint,
) -> Result<&'a VariableInfo, String> {
    let component = components.get(at.component.as_str()).ok_or_else(|| {
        let names: Vec<&str> = components.keys().copied().collect();
        format!(
            "no component \"{}\" (the system has {})",
            at.component,
            names.join(", ")
        )
    })?;
    component.variables.get(&at.variable).ok_or_else(|| {
        format!(
            "component \"{}\" has no variable \"{}\"",
            at.component, at.variable
        )
    })
}

/// A parameter's value in the SSV form for its type.
fn parameter_element(kind: VariableType, text: &str) -> Result<String, String> {
    let text = text.trim();
    match kind {
        VariableType::Real => {
            let value: f64 = text
                .parse()
                .map_err(|_| format!("\"{text}\" is not a number"))?;
            if !value.is_finite() {
                return Err(format!("{value} is not finite"));
            }
            Ok(format!("<ssv:Real value=\"{value:?}\"/>"))
        }
        VariableType::Integer | VariableType::Enumeration => {
            let value: i64 = text
                .parse()
                .map_err(|_| format!("\"{text}\" is not an integer"))?;
            let element = if kind == VariableType::Integer {
                "Integer"
            } else {
                "Enumeration"
            };
            Ok(format!("<ssv:{element} value=\"{value}\"/>"))
        }
        VariableType::Boolean => match text {
            "true" | "1" => Ok("<ssv:Boolean value=\"true\"/>".into()),
            "false" | "0" => Ok("<ssv:Boolean value=\"false\"/>".into()),
            _ => Err(format!("\"{text}\" is not true or false")),
        },
        VariableType::String => Ok(format!("<ssv:String value=\"{}\"/>", escape(text))),
    }
}

/// Text safe inside an XML attribute.
fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Checks a whole system against its components' descriptions.
fn check(spec: &SystemSpec) -> Result<BTreeMap<&str, ComponentInfo>, SspError> {
    let mut components = BTreeMap::new();
    for component in &spec.components {
        check_name(&component.name)?;
        if components.contains_key(component.name.as_str()) {
            return Err(SspError::Name(
                component.name.clone(),
                "is given twice".into(),
            ));
        }
        components.insert(component.name.as_str(), read_component(component)?);
    }
    let mut driven: BTreeMap<String, String> = BTreeMap::new();
    for connection in &spec.connections {
        let fail = |reason: String| SspError::Connection {
            connection: connection.to_string(),
            reason,
        };
        let from = variable(&components, &connection.from).map_err(fail)?;
        let to = variable(&components, &connection.to).map_err(fail)?;
        if from.causality != "output" {
            return Err(fail(format!(
                "{} is {} (a connection starts at an output)",
                connection.from, from.causality
            )));
        }
        if to.causality != "input" {
            return Err(fail(format!(
                "{} is {} (a connection ends at an input)",
                connection.to, to.causality
            )));
        }
        if from.kind != to.kind {
            return Err(fail(format!(
                "{} is {} and {} is {}",
                connection.from,
                from.kind.name(),
                connection.to,
                to.kind.name()
            )));
        }
        if let Some(earlier) = driven.insert(connection.to.to_string(), connection.to_string()) {
            return Err(fail(format!(
                "{} is already driven by {earlier}",
                connection.to
            )));
        }
    }
    for parameter in &spec.parameters {
        let fail = |reason: String| SspError::Parameter {
            parameter: parameter.at.to_string(),
            reason,
        };
        let info = variable(&components, &parameter.at).map_err(fail)?;
        if !matches!(info.causality.as_str(), "parameter" | "input") {
            return Err(fail(format!(
                "is {} (a value binds to a parameter or an input)",
                info.causality
            )));
        }
        parameter_element(info.kind, &parameter.value).map_err(fail)?;
    }
    Ok(components)
}

/// The system description (`SystemStructure.ssd`) of a checked system.
fn system_description(spec: &SystemSpec, components: &BTreeMap<&str, ComponentInfo>) -> String {
    let mut xml = String::new();
    let name = escape(&spec.name);
    let _ = writeln!(xml, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>");
    let _ = writeln!(
        xml,
        "<ssd:SystemStructureDescription version=\"1.0\" name=\"{name}\" generationTool=\"fistage {}\"\n    \
         xmlns:ssc=\"http://ssp-standard.org/SSP1/SystemStructureCommon\"\n    \
         xmlns:ssd=\"http://ssp-standard.org/SSP1/SystemStructureDescription\"\n    \
         xmlns:ssv=\"http://ssp-standard.org/SSP1/SystemStructureParameterValues\">",
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(xml, "  <ssd:System name=\"{name}\">");
    let _ = writeln!(xml, "    <ssd:Elements>");
    for component in &spec.components {
        component_element(
            &mut xml,
            spec,
            component,
            &components[component.name.as_str()],
        );
    }
    let _ = writeln!(xml, "    </ssd:Elements>");
    if !spec.connections.is_empty() {
        let _ = writeln!(xml, "    <ssd:Connections>");
        for c in &spec.connections {
            let _ = writeln!(
                xml,
                "      <ssd:Connection startElement=\"{}\" startConnector=\"{}\" endElement=\"{}\" endConnector=\"{}\"/>",
                escape(&c.from.component),
                escape(&c.from.variable),
                escape(&c.to.component),
                escape(&c.to.variable)
            );
        }
        let _ = writeln!(xml, "    </ssd:Connections>");
    }
    let _ = writeln!(xml, "  </ssd:System>");
    if let Some(stop) = spec.stop_time {
        let _ = writeln!(
            xml,
            "  <ssd:DefaultExperiment startTime=\"0.0\" stopTime=\"{stop:?}\"/>"
        );
    }
    let _ = writeln!(xml, "</ssd:SystemStructureDescription>");
    xml
}

/// One `ssd:Component`: a connector per connected variable, then its
/// parameter values bound inline.
fn component_element(
    xml: &mut String,
    spec: &SystemSpec,
    component: &ComponentFile,
    info: &ComponentInfo,
) {
    let name = &component.name;
    let _ = writeln!(
        xml,
        "      <ssd:Component name=\"{}\" type=\"application/x-fmu-sharedlibrary\" source=\"resources/{}.fmu\">",
        escape(name),
        escape(name)
    );
    let mut connected: Vec<&str> = Vec::new();
    for c in &spec.connections {
        for end in [&c.from, &c.to] {
            if &end.component == name && !connected.contains(&end.variable.as_str()) {
                connected.push(&end.variable);
            }
        }
    }
    if !connected.is_empty() {
        let _ = writeln!(xml, "        <ssd:Connectors>");
        for variable in connected {
            let v = &info.variables[variable];
            let _ = writeln!(
                xml,
                "          <ssd:Connector name=\"{}\" kind=\"{}\"><ssc:{}/></ssd:Connector>",
                escape(variable),
                v.causality,
                v.kind.name()
            );
        }
        let _ = writeln!(xml, "        </ssd:Connectors>");
    }
    let values: Vec<&ParameterValue> = (spec.parameters.iter())
        .filter(|p| &p.at.component == name)
        .collect();
    if !values.is_empty() {
        let _ = writeln!(xml, "        <ssd:ParameterBindings>");
        let _ = writeln!(xml, "          <ssd:ParameterBinding>");
        let _ = writeln!(xml, "            <ssd:ParameterValues>");
        let _ = writeln!(
            xml,
            "              <ssv:ParameterSet version=\"1.0\" name=\"{}\">",
            escape(name)
        );
        let _ = writeln!(xml, "                <ssv:Parameters>");
        for p in values {
            let kind = info.variables[&p.at.variable].kind;
            // Checked in `check`: the value parses as its type.
            let value = parameter_element(kind, &p.value).unwrap_or_default();
            let _ = writeln!(
                xml,
                "                  <ssv:Parameter name=\"{}\">{value}</ssv:Parameter>",
                escape(&p.at.variable)
            );
        }
        let _ = writeln!(xml, "                </ssv:Parameters>");
        let _ = writeln!(xml, "              </ssv:ParameterSet>");
        let _ = writeln!(xml, "            </ssd:ParameterValues>");
        let _ = writeln!(xml, "          </ssd:ParameterBinding>");
        let _ = writeln!(xml, "        </ssd:ParameterBindings>");
    }
    let _ = writeln!(xml, "      </ssd:Component>");
}

/// The bytes of the `.ssp` archive of a system, after checking every
/// component, connection and parameter value against the components'
/// descriptions.
pub fn build_ssp(spec: &SystemSpec) -> Result<Vec<u8>, SspError> {
    let components = check(spec)?;
    let ssd = system_description(spec, &components);
    let archive_error = |e: zip::result::ZipError| SspError::Archive(e.to_string());
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(zip::DateTime::default());
    zip.start_file(SSD_FILE, options).map_err(archive_error)?;
    zip.write_all(ssd.as_bytes())
        .map_err(|e| SspError::Archive(e.to_string()))?;
    for component in &spec.components {
        // An FMU is already deflated: stored as it is.
        let stored = options.compression_method(zip::CompressionMethod::Stored);
        zip.start_file(format!("resources/{}.fmu", component.name), stored)
            .map_err(archive_error)?;
        zip.write_all(&component.fmu)
            .map_err(|e| SspError::Archive(e.to_string()))?;
    }
    let cursor = zip.finish().map_err(archive_error)?;
    Ok(cursor.into_inner())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal FMI 2.0 Co-Simulation archive with the given variables
    /// (name, causality, type).
    fn fmu(variables: &[(&str, &str, &str)]) -> Vec<u8> {
        let mut xml = String::from(
            "<?xml version=\"1.0\"?>\n<fmiModelDescription fmiVersion=\"2.0\" modelName=\"m\" guid=\"{0}\">\n\
             <CoSimulation modelIdentifier=\"m\"/>\n<ModelVariables>\n",
        );
        for (name, causality, kind) in variables {
            xml += &format!(
                "<ScalarVariable name=\"{name}\" valueReference=\"0\" causality=\"{causality}\"><{kind}/></ScalarVariable>\n"
            );
        }
        xml += "</ModelVariables>\n</fmiModelDescription>\n";
        let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
        zip.start_file(
            "modelDescription.xml",
            zip::write::SimpleFileOptions::default(),
        )
        .expect("entry");
        zip.write_all(xml.as_bytes()).expect("write");
        zip.finish().expect("finish").into_inner()
    }

    fn at(text: &str) -> Endpoint {
        Endpoint::parse(text).expect("endpoint")
    }

    fn system() -> SystemSpec {
        SystemSpec {
            name: "loop".into(),
            components: vec![
                ComponentFile {
                    name: "plant".into(),
                    fmu: fmu(&[
                        ("servo_force", "input", "Real"),
                        ("encoder.position", "output", "Real"),
                        ("controller.k", "parameter", "Real"),
                        ("mode", "parameter", "Integer"),
                    ]),
                },
                ComponentFile {
                    name: "controller".into(),
                    fmu: fmu(&[
                        ("position", "input", "Real"),
                        ("force", "output", "Real"),
                        ("on", "parameter", "Boolean"),
                    ]),
                },
            ],
            connections: vec![
                Connection {
                    from: at("controller.force"),
                    to: at("plant.servo_force"),
                },
                Connection {
                    from: at("plant.encoder.position"),
                    to: at("controller.position"),
                },
            ],
            parameters: vec![
                ParameterValue {
                    at: at("plant.controller.k"),
                    value: "0".into(),
                },
                ParameterValue {
                    at: at("controller.on"),
                    value: "true".into(),
                },
            ],
            stop_time: Some(0.5),
        }
    }

    #[test]
    fn a_system_packs_its_description_and_its_units() {
        let bytes = build_ssp(&system()).expect("package");
        let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes)).expect("zip");
        let mut ssd = String::new();
        archive
            .by_name(SSD_FILE)
            .expect("ssd")
            .read_to_string(&mut ssd)
            .expect("text");
        let document = roxmltree::Document::parse(&ssd).expect("well-formed");
        let connections: Vec<(&str, &str)> = (document.descendants())
            .filter(|n| n.has_tag_name("Connection"))
            .map(|n| {
                (
                    n.attribute("startConnector").unwrap_or_default(),
                    n.attribute("endConnector").unwrap_or_default(),
                )
            })
            .collect();
        assert_eq!(
            connections,
            [("force", "servo_force"), ("encoder.position", "position")]
        );
        let parameters: Vec<&str> = (document.descendants())
            .filter(|n| n.has_tag_name("Parameter"))
            .filter_map(|n| n.attribute("name"))
            .collect();
        assert_eq!(parameters, ["controller.k", "on"]);
        assert!(ssd.contains("<ssv:Real value=\"0.0\"/>"), "{ssd}");
        assert!(ssd.contains("stopTime=\"0.5\""), "{ssd}");
        for unit in ["resources/plant.fmu", "resources/controller.fmu"] {
            assert!(archive.by_name(unit).is_ok(), "{unit}");
        }
    }

    #[test]
    fn a_wrong_system_is_refused_by_name() {
        type Change = Box<dyn Fn(&mut SystemSpec)>;
        let cases: Vec<(Change, &str)> = vec![
            (
                Box::new(|s| s.connections[0].to = at("plant.servo_forse")),
                "has no variable \"servo_forse\"",
            ),
            (
                Box::new(|s| s.connections[1] = s.connections[0].clone()),
                "already driven",
            ),
            (
                Box::new(|s| s.connections[1].to = at("plant.controller.k")),
                "is parameter (a connection ends at an input)",
            ),
            (
                Box::new(|s| s.connections[1].from = at("pump.flow")),
                "no component \"pump\"",
            ),
            (
                Box::new(|s| s.parameters[0].value = "stiff".into()),
                "\"stiff\" is not a number",
            ),
            (
                Box::new(|s| s.parameters[1].value = "2".into()),
                "is not true or false",
            ),
            (
                Box::new(|s| s.parameters[0].at = at("plant.encoder.position")),
                "is output",
            ),
            (
                Box::new(|s| s.components[1].name = "ctl.pd".into()),
                "has a dot",
            ),
            (
                Box::new(|s| s.components[1].fmu = b"not a zip".to_vec()),
                "not an FMU archive",
            ),
        ];
        for (change, expected) in cases {
            let mut spec = system();
            change(&mut spec);
            let message = build_ssp(&spec).err().map(|e| e.to_string());
            assert!(
                message.as_deref().is_some_and(|m| m.contains(expected)),
                "{expected}: {message:?}"
            );
        }
    }
}

//! `fistage ssp SCENARIO --fmu controller=pd.fmu --connect FROM->TO ...
//! --set COMPONENT.VARIABLE=VALUE ... -o loop.ssp`: the scenario's plant as
//! an FMU (component `plant`) with controller FMUs around it, connected by
//! variable name and parameterised, as one SSP 1.0 package that
//! co-simulation tools open as a system.

use std::path::PathBuf;

#[cfg(feature = "fmu")]
use anyhow::{Context, bail};

/// Arguments of `fistage ssp`.
#[derive(clap::Args)]
pub struct SspArgs {
    /// Scenario file (TOML) of the plant, packed as the component `plant`.
    pub scenario: PathBuf,
    /// A controller FMU (FMI 2.0, Co-Simulation) and its name in the
    /// system: NAME=FILE. Repeat for several.
    #[arg(long = "fmu", value_name = "NAME=FILE")]
    pub fmus: Vec<String>,
    /// A connection from an output to an input, each COMPONENT.VARIABLE:
    /// "controller.force->plant.servo_force". Repeat for several.
    #[arg(long = "connect", value_name = "FROM->TO")]
    pub connections: Vec<String>,
    /// A parameter value bound in the system: COMPONENT.VARIABLE=VALUE
    /// ("plant.controller.k=0", "controller.k=6e4"). Repeat for several.
    #[arg(long = "set", value_name = "COMPONENT.VARIABLE=VALUE")]
    pub parameters: Vec<String>,
    /// Where to write the package.
    #[arg(short = 'o', long = "output", default_value = "system.ssp")]
    pub output: PathBuf,
    /// The system's name (default: the output file's stem).
    #[arg(long)]
    pub name: Option<String>,
    /// The suggested stop time, s (default: the scenario's duration).
    #[arg(long)]
    pub stop: Option<f64>,
    /// The FMI library to pack in the plant's FMU (default: beside this program).
    #[arg(long = "library")]
    pub shared_object: Option<PathBuf>,
}

/// A lean build (without the `fmu` feature) has no FMI library to pack.
#[cfg(not(feature = "fmu"))]
pub fn run(_args: &SspArgs) -> anyhow::Result<()> {
    crate::absent::refuse("ssp", "fmu")
}

/// Runs the command.
#[cfg(feature = "fmu")]
pub fn run(args: &SspArgs) -> anyhow::Result<()> {
    use fistage_fmi::ssp::{ComponentFile, SystemSpec, build_ssp};

    let connections = (args.connections.iter())
        .map(|text| parse_connection(text))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let parameters = (args.parameters.iter())
        .map(|text| parse_parameter(text))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let loaded = fistage_model::load(&args.scenario)?;
    check_plant_values(&parameters, &loaded)?;
    let library = crate::fmu::find_library(args.shared_object.as_ref())?;
    let plant =
        fistage_fmi::build_fmu_version(&args.scenario, &library, fistage_fmi::FmiVersion::Fmi2)?;
    let mut components = vec![ComponentFile {
        name: "plant".into(),
        fmu: plant,
    }];
    for text in &args.fmus {
        let (name, file) = text
            .split_once('=')
            .with_context(|| format!("--fmu {text}: write NAME=FILE (controller=pd.fmu)"))?;
        let name = name.trim();
        if name == "plant" {
            bail!(
                "--fmu {text}: \"plant\" is the scenario's own component; name this one otherwise"
            );
        }
        let fmu = std::fs::read(file.trim())
            .with_context(|| format!("--fmu {text}: cannot read {file}"))?;
        components.push(ComponentFile {
            name: name.to_string(),
            fmu,
        });
    }
    let name = (args.name.clone())
        .or_else(|| (args.output.file_stem()).map(|s| s.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "system".into());
    let spec = SystemSpec {
        name,
        components,
        connections,
        parameters,
        stop_time: Some(args.stop.unwrap_or(loaded.scenario.duration)),
    };
    let bytes = build_ssp(&spec)?;
    crate::fmu::write_archive(&args.output, &bytes)?;
    println!(
        "{}: SSP 1.0 system \"{}\" of {} FMUs ({}), {} connections, {} parameter values, {:.1} MB",
        args.output.display(),
        spec.name,
        spec.components.len(),
        (spec.components.iter())
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>()
            .join(", "),
        spec.connections.len(),
        spec.parameters.len(),
        bytes.len() as f64 / 1e6
    );
    Ok(())
}

/// `FROM->TO`, each `COMPONENT.VARIABLE`.
#[cfg(feature = "fmu")]
fn parse_connection(text: &str) -> anyhow::Result<fistage_fmi::ssp::Connection> {
    use fistage_fmi::ssp::{Connection, Endpoint};
    let (from, to) = text.split_once("->").with_context(|| {
        format!("--connect {text}: write FROM->TO (\"controller.force->plant.servo_force\")")
    })?;
    let endpoint = |side: &str| {
        Endpoint::parse(side).with_context(|| {
            format!(
                "--connect {text}: \"{}\" is not COMPONENT.VARIABLE",
                side.trim()
            )
        })
    };
    Ok(Connection {
        from: endpoint(from)?,
        to: endpoint(to)?,
    })
}

/// `COMPONENT.VARIABLE=VALUE`.
#[cfg(feature = "fmu")]
fn parse_parameter(text: &str) -> anyhow::Result<fistage_fmi::ssp::ParameterValue> {
    use fistage_fmi::ssp::{Endpoint, ParameterValue};
    let (at, value) = text
        .rsplit_once('=')
        .with_context(|| format!("--set {text}: write COMPONENT.VARIABLE=VALUE"))?;
    let at = Endpoint::parse(at)
        .with_context(|| format!("--set {text}: \"{}\" is not COMPONENT.VARIABLE", at.trim()))?;
    Ok(ParameterValue {
        at,
        value: value.trim().to_string(),
    })
}

/// The plant's values are held to their parameters' rules here, where the
/// rule is known, rather than refused by the unit at run time.
#[cfg(feature = "fmu")]
fn check_plant_values(
    parameters: &[fistage_fmi::ssp::ParameterValue],
    loaded: &fistage_model::Loaded,
) -> anyhow::Result<()> {
    for p in parameters.iter().filter(|p| p.at.component == "plant") {
        let Ok(parameter) =
            fistage_model::Parameter::resolve(&p.at.variable, &loaded.scenario, &loaded.robot)
        else {
            // Not a table parameter (an input's start value, say): the
            // package checks it against the unit's description.
            continue;
        };
        let Ok(value) = p.value.parse::<f64>() else {
            continue;
        };
        if let Err(message) = parameter.check(value) {
            bail!("--set {}={}: {message}", p.at, p.value);
        }
    }
    Ok(())
}

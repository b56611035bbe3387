//! What the `identify` subcommands share: the simulation and output
//! arguments, the refusal of undetermined parameters, the report printing
//! and the unit flags.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;
use fistage_ident::report::DEFAULT_ELEMENT;
use fistage_ident::{Quantity, Unit};

/// Arguments shared by the simulated measurements.
#[derive(Args)]
pub(super) struct SimulateArgs {
    /// The stage: a robot file (.urdf) or a scenario (.toml: its robot and
    /// overrides, and its servo's sensor and actuator; its gains, reference
    /// and platform are not used).
    pub(crate) stage: PathBuf,
    /// The file to write (CSV; a MAT-file for a record named `.mat`).
    #[arg(long, value_name = "FILE")]
    pub(crate) out: PathBuf,
    /// Seed of the sensor errors.
    #[arg(long, default_value_t = 1)]
    pub(crate) seed: u64,
    /// No sensor errors (noise, scatter, quantisation, disturbance).
    #[arg(long)]
    pub(crate) exact: bool,
}

/// Output options shared by both fits.
#[derive(Args)]
pub(super) struct OutputArgs {
    /// Print the JSON report instead of the table.
    #[arg(long)]
    pub(crate) json: bool,
    /// Write fit.json, override.toml, data_vs_fit.csv (and fit_curve.csv for
    /// curves and FRFs) and the data-vs-fit plot fit.svg / fit.png into DIR.
    #[arg(long, value_name = "DIR")]
    pub(crate) out: Option<PathBuf>,
    /// Friction element that override.toml applies to.
    #[arg(long, value_name = "NAME", default_value = DEFAULT_ELEMENT)]
    pub(crate) element: String,
    /// Replace an earlier result in the --out folder (as a whole).
    #[arg(long)]
    pub(crate) force: bool,
    /// Exit 0 even when a parameter is not identifiable from the data (it is
    /// still named, and still left out of override.toml).
    #[arg(long)]
    pub(crate) allow_undetermined: bool,
    /// Skip the HTML page (report.html) in the --out folder.
    #[arg(long)]
    pub(crate) no_report: bool,
}

/// The refusal of an undetermined fit, saying that `--out` was left as it was.
pub(super) fn nothing_written(error: anyhow::Error, output: &OutputArgs) -> anyhow::Error {
    match &output.out {
        Some(dir) => error.context(format!(
            "nothing written to {} (--allow-undetermined writes the fit)",
            dir.display()
        )),
        None => error,
    }
}

/// Fails, after the report is shown, when the data leave parameters
/// undetermined and the user did not allow it (then nothing is written).
pub(super) fn refuse_undetermined(
    output: &OutputArgs,
    not_identifiable: &[fistage_ident::NotIdentifiable],
) -> Result<()> {
    if not_identifiable.is_empty() || output.allow_undetermined {
        return Ok(());
    }
    let names: Vec<String> = not_identifiable
        .iter()
        .map(|n| format!("{} ({})", n.parameter, n.reason))
        .collect();
    bail!(
        "not identifiable from these data: {} (--allow-undetermined accepts the fit as it is)",
        names.join("; ")
    )
}

/// `--element` names a friction element of a robot file: the same rules.
pub(super) fn check_element(output: &OutputArgs) -> Result<()> {
    fistage_model::rule::check_name(&output.element).map_err(|why| {
        anyhow::anyhow!(
            "--element {:?}: {why} (it must be a name a robot file accepts)",
            output.element
        )
    })
}

pub(super) fn print_report(json: bool, json_text: &str, table: &str) {
    if json {
        println!("{json_text}");
    } else {
        print!("{table}");
    }
}

/// The unit given by a `--*-unit` flag, checked against its quantity.
pub(super) fn unit_flag(quantity: Quantity, flag: &Option<String>) -> Result<Option<Unit>> {
    let Some(text) = flag else {
        return Ok(None);
    };
    match Unit::parse(quantity, text) {
        Some(unit) => Ok(Some(unit)),
        None => bail!(
            "{}: '{text}' is not a {quantity} unit (known: {})",
            quantity.unit_flag(),
            quantity.known_units()
        ),
    }
}

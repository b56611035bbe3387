//! `fistage fmu SCENARIO -o stage.fmu [--fmi-version 2|3]`: package the
//! scenario as an FMU with Model Exchange and Co-Simulation (model
//! description, shared library, resources), FMI 2.0 or 3.0.

use std::path::PathBuf;

#[cfg(feature = "fmu")]
use anyhow::{Context, bail};
#[cfg(feature = "fmu")]
use fistage_fmi::package::{LIBRARY_FILE, default_library_locations};

/// Arguments of `fistage fmu`.
#[derive(clap::Args)]
pub struct FmuArgs {
    /// Scenario file (TOML).
    pub scenario: PathBuf,
    /// Where to write the FMU.
    #[arg(short = 'o', long = "output", default_value = "stage.fmu")]
    pub output: PathBuf,
    /// The shared library to package (default: `libfistage_fmi.so` beside this program,
    /// as `cargo build -p fistage-fmi` places it).
    #[arg(long = "library")]
    pub shared_object: Option<PathBuf>,
    /// The FMI standard: 2 (2.0) or 3 (3.0).
    #[arg(long = "fmi-version", default_value = "2", value_parser = ["2", "3"])]
    pub fmi_version: String,
}

/// The FMI library to pack: `named` (`--library`), or the one beside this
/// program.
#[cfg(feature = "fmu")]
pub(crate) fn find_library(named: Option<&PathBuf>) -> anyhow::Result<PathBuf> {
    if let Some(library) = named {
        if !library.is_file() {
            bail!("--library {}: no such file", library.display());
        }
        return Ok(library.clone());
    }
    let program = std::env::current_exe().context("cannot locate this program")?;
    let candidates = default_library_locations(&program);
    candidates
        .iter()
        .find(|path| path.is_file())
        .cloned()
        .with_context(|| {
            format!(
                "{LIBRARY_FILE} not found (looked in {}); build it with `cargo build --release -p fistage-fmi` or name it with --library",
                candidates
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
}

/// Writes an archive whole (its folder made first): the file holds the
/// complete archive or nothing.
#[cfg(feature = "fmu")]
pub(crate) fn write_archive(path: &std::path::Path, bytes: &[u8]) -> anyhow::Result<()> {
    if let Some(folder) = path.parent()
        && !folder.as_os_str().is_empty()
    {
        std::fs::create_dir_all(folder)
            .with_context(|| format!("cannot create {}", folder.display()))?;
    }
    fistage_model::output::write_whole(path, bytes)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// A lean build (without the `fmu` feature) has no FMI library to pack.
#[cfg(not(feature = "fmu"))]
pub fn run(_args: &FmuArgs) -> anyhow::Result<()> {
    crate::absent::refuse("fmu", "fmu")
}

/// Runs the command.
#[cfg(feature = "fmu")]
pub fn run(args: &FmuArgs) -> anyhow::Result<()> {
    let library = find_library(args.shared_object.as_ref())?;
    let version = match args.fmi_version.as_str() {
        "3" => fistage_fmi::FmiVersion::Fmi3,
        _ => fistage_fmi::FmiVersion::Fmi2,
    };
    let bytes = fistage_fmi::build_fmu_version(&args.scenario, &library, version)?;
    write_archive(&args.output, &bytes)?;
    println!(
        "{}: FMI {}.0 FMU (Model Exchange and Co-Simulation), {:.1} MB (library {})",
        args.output.display(),
        args.fmi_version,
        bytes.len() as f64 / 1e6,
        library.display()
    );
    Ok(())
}

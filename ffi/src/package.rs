//! Packaging a scenario as an `.fmu` archive: `modelDescription.xml`,
//! `binaries/linux64/fistage_stage.so` and `resources/` holding the scenario
//! (its robot path rewritten to the copy beside it) and the robot file, plus
//! a reference CSV when the scenario uses one. The description is generated
//! from the packaged resources themselves, so the GUID an instance computes
//! at fmi2Instantiate is the one in the archive.
//!
//! Entries are deflate-compressed with a fixed time stamp (archives do not
//! depend on when they were built), and the library is packaged without its
//! debug information and static symbol table: the system's `strip
//! --strip-all` (binutils, which the Rust toolchain's linker brings) writes a
//! copy that keeps the code and the dynamic symbols importers resolve the FMI
//! functions by.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;

use thiserror::Error;

use crate::instance::{CAPABILITIES, Instance};
use crate::model_description::{MODEL_IDENTIFIER, model_description};

pub use crate::resources::{REFERENCE_FILE, ROBOT_FILE, SCENARIO_FILE};
/// The shared library's file name as the cdylib build writes it.
pub const LIBRARY_FILE: &str = "libfistage_fmi.so";

/// Why an FMU could not be built.
#[derive(Debug, Error)]
pub enum PackageError {
    /// A file could not be read or written.
    #[error("{file}: {reason}")]
    Io {
        /// The file.
        file: PathBuf,
        /// What went wrong.
        reason: std::io::Error,
    },
    /// The scenario or robot is invalid.
    #[error(transparent)]
    Load(#[from] fistage_model::LoadError),
    /// The scenario file is not valid TOML.
    #[error("{file}: {reason}")]
    Scenario {
        /// The scenario file.
        file: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// The packaged resources do not load as an instance.
    #[error("the packaged resources do not load: {0}")]
    Resources(String),
    /// The archive could not be written.
    #[error("writing the FMU archive: {0}")]
    Archive(String),
    /// The library named is not one this FMU can carry.
    #[error("{file}: {reason}")]
    Library {
        /// The library file.
        file: PathBuf,
        /// What is wrong.
        reason: String,
    },
}

fn read(file: &Path) -> Result<Vec<u8>, PackageError> {
    std::fs::read(file).map_err(|reason| PackageError::Io {
        file: file.to_path_buf(),
        reason,
    })
}

fn write(file: &Path, bytes: &[u8]) -> Result<(), PackageError> {
    std::fs::write(file, bytes).map_err(|reason| PackageError::Io {
        file: file.to_path_buf(),
        reason,
    })
}

/// The files of `resources/`: the rewritten scenario, the robot and any reference CSV.
fn resource_files(
    scenario_path: &Path,
    text: &str,
) -> Result<Vec<(&'static str, Vec<u8>)>, PackageError> {
    let scenario = fistage_model::Scenario::from_str(text, scenario_path)?;
    let bad = |reason: String| PackageError::Scenario {
        file: scenario_path.to_path_buf(),
        reason,
    };
    let mut table: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| bad(e.to_string()))?;
    table.insert("robot".into(), toml::Value::String(ROBOT_FILE.into()));
    let mut files = vec![(ROBOT_FILE, read(&scenario.robot)?)];
    if let Some(reference) = table
        .get_mut("reference")
        .and_then(toml::Value::as_table_mut)
        && let Some(file) = reference.get("file").and_then(toml::Value::as_str)
    {
        let base = scenario_path.parent().unwrap_or(Path::new(""));
        files.push((REFERENCE_FILE, read(&base.join(file))?));
        reference.insert("file".into(), toml::Value::String(REFERENCE_FILE.into()));
    }
    let rewritten = toml::to_string(&table).map_err(|e| bad(e.to_string()))?;
    files.insert(0, (SCENARIO_FILE, rewritten.into_bytes()));
    Ok(files)
}

/// A scratch folder removed when dropped.
struct Scratch(PathBuf);

impl Scratch {
    fn new() -> Result<Self, PackageError> {
        // Unique within the process too: two packagings at the same instant
        // (parallel tests) must not share, and remove, one folder.
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let serial = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_nanos())
            .unwrap_or_default();
        let dir = std::env::temp_dir().join(format!(
            "fistage-fmu-{}-{nanos}-{serial}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).map_err(|reason| PackageError::Io {
            file: dir.clone(),
            reason,
        })?;
        Ok(Self(dir))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Writes the FMU's `resources/` files for a scenario into `folder` (which
/// must exist): what an instance loads at fmi2Instantiate.
pub fn write_resources(scenario_path: &Path, folder: &Path) -> Result<(), PackageError> {
    let text = String::from_utf8_lossy(&read(scenario_path)?).into_owned();
    for (name, bytes) in resource_files(scenario_path, &text)? {
        write(&folder.join(name), &bytes)?;
    }
    Ok(())
}

/// The bytes of an `.fmu` for the scenario, with `library` as its binary.
pub fn build_fmu(scenario_path: &Path, library: &Path) -> Result<Vec<u8>, PackageError> {
    build_fmu_version(scenario_path, library, FmiVersion::Fmi2)
}

/// Which FMI standard an archive follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FmiVersion {
    /// FMI 2.0: `binaries/linux64/`, `fmiVersion="2.0"`.
    #[default]
    Fmi2,
    /// FMI 3.0: `binaries/x86_64-linux/`, `fmiVersion="3.0"`.
    Fmi3,
}

/// [`build_fmu`] for the FMI standard `version` (the same library serves both).
pub fn build_fmu_version(
    scenario_path: &Path,
    library: &Path,
    version: FmiVersion,
) -> Result<Vec<u8>, PackageError> {
    let text = String::from_utf8_lossy(&read(scenario_path)?).into_owned();
    build_fmu_from_text_version(&text, scenario_path, library, version)
}

/// [`build_fmu`] for a scenario given as text, its relative paths resolved
/// against `scenario_path` (which need not exist).
pub fn build_fmu_from_text(
    text: &str,
    scenario_path: &Path,
    library: &Path,
) -> Result<Vec<u8>, PackageError> {
    build_fmu_from_text_version(text, scenario_path, library, FmiVersion::Fmi2)
}

/// [`build_fmu_from_text`] for the FMI standard `version`.
pub fn build_fmu_from_text_version(
    text: &str,
    scenario_path: &Path,
    library: &Path,
    version: FmiVersion,
) -> Result<Vec<u8>, PackageError> {
    let resources = resource_files(scenario_path, text)?;
    let scratch = Scratch::new()?;
    for (name, bytes) in &resources {
        write(&scratch.0.join(name), bytes)?;
    }
    let instance =
        Instance::new(&scratch.0, None).map_err(|e| PackageError::Resources(e.to_string()))?;
    let loaded = fistage_model::load(&scratch.0.join(SCENARIO_FILE))?;
    let (description, platform) = match version {
        FmiVersion::Fmi2 => (
            model_description(&loaded.model, &loaded.scenario, CAPABILITIES),
            "linux64",
        ),
        FmiVersion::Fmi3 => (
            crate::fmi3::model_description::model_description(
                &loaded.model,
                &loaded.scenario,
                CAPABILITIES,
            ),
            "x86_64-linux",
        ),
    };
    debug_assert!(description.contains(instance.guid()));
    let library_bytes = library_without_debug_info(library, &scratch.0)?;
    let mut entries: Vec<(String, &[u8])> = vec![
        ("modelDescription.xml".into(), description.as_bytes()),
        (
            format!("binaries/{platform}/{MODEL_IDENTIFIER}.so"),
            &library_bytes,
        ),
    ];
    for (name, bytes) in &resources {
        entries.push((format!("resources/{name}"), bytes));
    }
    deflated_archive(&entries)
}

/// A ZIP archive of the entries, deflate-compressed, time-stamped 1980-01-01.
fn deflated_archive(entries: &[(String, &[u8])]) -> Result<Vec<u8>, PackageError> {
    let archive_error = |e: &dyn std::fmt::Display| PackageError::Archive(e.to_string());
    let mut zip = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let options = zip::write::SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .compression_level(Some(9))
        .last_modified_time(zip::DateTime::default())
        .unix_permissions(0o644);
    for (name, bytes) in entries {
        zip.start_file(name.as_str(), options)
            .map_err(|e| archive_error(&e))?;
        zip.write_all(bytes).map_err(|e| archive_error(&e))?;
    }
    let cursor = zip.finish().map_err(|e| archive_error(&e))?;
    Ok(cursor.into_inner())
}

/// The library's bytes without debug sections and static symbols. It must
/// be an ELF shared object exporting the FMI functions, before and after;
/// `strip --strip-all` writes the copy (a shared object keeps its dynamic
/// symbols), and on a system without `strip` the library is packaged as it
/// is.
fn library_without_debug_info(library: &Path, scratch: &Path) -> Result<Vec<u8>, PackageError> {
    let bytes = read(library)?;
    check_fmi_library(&bytes).map_err(|reason| PackageError::Library {
        file: library.to_path_buf(),
        reason,
    })?;
    let stripped = scratch.join("library.so");
    let status = Command::new("strip")
        .arg("--strip-all")
        .arg("-o")
        .arg(&stripped)
        .arg(library)
        .status();
    match status {
        Ok(status) if status.success() => {
            let stripped_bytes = read(&stripped)?;
            check_fmi_library(&stripped_bytes).map_err(|reason| PackageError::Library {
                file: library.to_path_buf(),
                reason: format!("after strip --strip-all: {reason}"),
            })?;
            Ok(stripped_bytes)
        }
        // No `strip` on this system: the library goes in as it is.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(bytes),
        // A `strip` that fails must not silently ship the debug information.
        Ok(status) => Err(PackageError::Library {
            file: library.to_path_buf(),
            reason: format!("strip --strip-all failed ({status})"),
        }),
        Err(e) => Err(PackageError::Library {
            file: library.to_path_buf(),
            reason: format!("strip --strip-all could not run: {e}"),
        }),
    }
}

/// The FMI functions every packaged library must export.
const REQUIRED_EXPORTS: [&str; 7] = [
    "fmi3InstantiateCoSimulation",
    "fmi3GetContinuousStateDerivatives",
    "fmi2GetDerivatives",
    "fmi2Instantiate",
    "fmi2DoStep",
    "fmi2GetReal",
    "fmi2GetTypesPlatform",
];

/// An ELF shared object (not an executable) whose dynamic symbols include
/// the FMI entry points.
fn check_fmi_library(bytes: &[u8]) -> Result<(), String> {
    use object::read::elf::{ElfFile64, ProgramHeader};
    use object::{Object, ObjectKind};
    let file = ElfFile64::<object::Endianness>::parse(bytes)
        .map_err(|_| "not an ELF shared library (64-bit)".to_string())?;
    let endian = file.endian();
    let interpreter = file
        .elf_program_headers()
        .iter()
        .any(|h| h.p_type(endian) == object::elf::PT_INTERP);
    if file.kind() != ObjectKind::Dynamic || interpreter {
        return Err("an ELF file, but not a shared library".into());
    }
    let exports = file
        .exports()
        .map_err(|e| format!("unreadable dynamic symbols: {e}"))?
        .collect::<Result<Vec<_>, _>>()
        .map_err(|e| format!("unreadable dynamic symbols: {e}"))?;
    for symbol in REQUIRED_EXPORTS {
        if !exports
            .iter()
            .any(|e| e.name() == object::NameOrOrdinal::Name(symbol.as_bytes()))
        {
            return Err(format!(
                "does not export {symbol}: not a fistage FMI library"
            ));
        }
    }
    Ok(())
}

/// Where the shared library is looked for when none is named: beside the
/// running program (and in its `deps/` folder), as a cargo build places it.
pub fn default_library_locations(program: &Path) -> Vec<PathBuf> {
    let Some(folder) = program.parent() else {
        return Vec::new();
    };
    vec![
        folder.join(LIBRARY_FILE),
        folder.join("deps").join(LIBRARY_FILE),
    ]
}

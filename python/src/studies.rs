//! The studies of a scenario from Python: its `[sweep]` grid and its
//! `[robust]` tolerance analysis, computed as `fistage sweep` and `fistage
//! robust` compute them (the interpreter released, in chunks between which
//! Ctrl-C and the progress callback are heard), and the scenario packaged
//! as an FMU. Results come back as the table text the program
//! writes (`points.csv`, `samples.csv`) and `summary.json`; the Python side
//! turns them into numpy columns.

use std::path::{Path, PathBuf};

use fistage_analysis::assess::worker_threads;
use fistage_analysis::robust::{RobustSpec, Summary, table};
use fistage_analysis::sweep::{SweepSpec, header, row, run_points};
use fistage_model::{Loaded, RobotSpec};
use pyo3::prelude::*;

use crate::{Error, LoadError_};

/// Runs `compute` over `0..total` in chunks of a few points per thread,
/// with the interpreter released; between chunks it takes the interpreter
/// back, stops on Ctrl-C (or an exception from `progress`) and calls
/// `progress(done, total)`.
fn in_chunks<T: Send>(
    py: Python<'_>,
    total: usize,
    threads: usize,
    progress: Option<&Py<PyAny>>,
    compute: impl Fn(&[usize]) -> Vec<T> + Sync,
) -> PyResult<Vec<T>> {
    let chunk = (4 * threads).max(8);
    let mut results = Vec::with_capacity(total);
    let indices: Vec<usize> = (0..total).collect();
    for part in indices.chunks(chunk) {
        results.extend(py.detach(|| compute(part)));
        py.check_signals()?;
        if let Some(callback) = progress {
            callback.call1(py, (results.len(), total))?;
        }
    }
    Ok(results)
}

/// The program's rule for `--threads` ([`worker_threads`]).
fn threads_or_all(threads: Option<usize>) -> PyResult<usize> {
    worker_threads(threads).map_err(Error::new_err)
}

/// The `[sweep]` grid: `points.csv` as text.
pub fn sweep(
    py: Python<'_>,
    loaded: &Loaded,
    robot: &RobotSpec,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let spec = SweepSpec::from_scenario(&loaded.scenario)
        .map_err(|e| LoadError_::new_err(e.to_string()))?;
    spec.check_against(&loaded.scenario, robot)
        .map_err(|e| LoadError_::new_err(e.to_string()))?;
    let threads = threads_or_all(threads)?;
    let results = in_chunks(py, spec.len(), threads, progress.as_ref(), |part| {
        run_points(loaded, robot, &spec, part, threads, &|_, _| {})
    })?;
    let lines: Vec<String> = std::iter::once(header(&spec))
        .chain(results.iter().map(row))
        .collect();
    Ok(lines.join("\n") + "\n")
}

/// The `[robust]` tolerance analysis: `samples.csv` as text and
/// `summary.json`.
pub fn robust(
    py: Python<'_>,
    loaded: &Loaded,
    robot: &RobotSpec,
    samples: Option<usize>,
    seed: Option<u64>,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<(String, String)> {
    let spec = RobustSpec::from_scenario(&loaded.scenario, robot, samples, seed)
        .map_err(|e| LoadError_::new_err(e.to_string()))?;
    let threads = threads_or_all(threads)?;
    let results = in_chunks(py, spec.samples, threads, progress.as_ref(), |part| {
        spec.run(loaded, robot, part, threads, &|_, _| {})
    })?;
    let lines: Vec<String> = std::iter::once(table::header(&spec))
        .chain(results.iter().map(table::row))
        .collect();
    let text = lines.join("\n") + "\n";
    let summary = Summary::of(&spec, &results);
    let json = serde_json::to_string(&summary).map_err(|e| Error::new_err(e.to_string()))?;
    Ok((text, json))
}

/// The FMU's shared library, built with this package (see `build.rs`).
const EMBEDDED_LIBRARY: &[u8] = include_bytes!(env!("FISTAGE_FMI_EMBEDDED"));

/// A file removed when dropped.
struct TemporaryFile(PathBuf);

impl Drop for TemporaryFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// Packages the scenario (its text, its robot) as an FMU of the FMI
/// standard `version` (Model Exchange and Co-Simulation) at `path`, with
/// `library` as its binary or the one built with this package.
pub fn export_fmu(
    text: &str,
    file: &Path,
    path: &Path,
    library: Option<PathBuf>,
    version: fistage_fmi::FmiVersion,
) -> PyResult<PathBuf> {
    let (_temporary, library) = match library {
        Some(given) if given.is_file() => (None, given),
        Some(given) => {
            return Err(Error::new_err(format!(
                "library={}: not found",
                given.display()
            )));
        }
        None => {
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.subsec_nanos());
            let file =
                std::env::temp_dir().join(format!("fistage-fmi-{}-{nanos}.so", std::process::id()));
            std::fs::write(&file, EMBEDDED_LIBRARY)
                .map_err(|e| Error::new_err(format!("{}: cannot write: {e}", file.display())))?;
            (Some(TemporaryFile(file.clone())), file)
        }
    };
    let bytes = fistage_fmi::build_fmu_from_text_version(text, file, &library, version)
        .map_err(|e| Error::new_err(e.to_string()))?;
    std::fs::write(path, bytes)
        .map_err(|e| Error::new_err(format!("{}: cannot write: {e}", path.display())))?;
    Ok(path.to_path_buf())
}

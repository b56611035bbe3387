//! The studies of a scenario from Python: its `[sweep]` grid and its
//! `[robust]` tolerance analysis, computed as `fistage sweep` and `fistage
//! robust` compute them (the interpreter released), and the scenario
//! packaged as an FMU. Results come back as the table text the program
//! writes (`points.csv`, `samples.csv`) and `summary.json`; the Python side
//! turns them into numpy columns.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use fistage_analysis::robust::{RobustSpec, Summary, table};
use fistage_analysis::sweep::{SweepSpec, header, row, run_points};
use fistage_model::{Loaded, RobotSpec};
use pyo3::prelude::*;

use crate::{Error, LoadError_};

/// Calls `progress(done, total)` from whichever thread finished a point,
/// keeping the first exception it raises.
struct Progress {
    callback: Option<Py<PyAny>>,
    total: usize,
    done: Mutex<(usize, Option<PyErr>)>,
}

impl Progress {
    fn new(callback: Option<Py<PyAny>>, total: usize) -> Self {
        Self {
            callback,
            total,
            done: Mutex::new((0, None)),
        }
    }

    fn tick(&self) {
        let Ok(mut state) = self.done.lock() else {
            return;
        };
        state.0 += 1;
        if let (Some(callback), None) = (&self.callback, &state.1) {
            let done = state.0;
            if let Err(e) = Python::attach(|py| callback.call1(py, (done, self.total))) {
                state.1 = Some(e);
            }
        }
    }

    /// The callback's exception, if it raised one.
    fn raised(self) -> Option<PyErr> {
        self.done.into_inner().ok().and_then(|s| s.1)
    }
}

fn threads_or_all(threads: Option<usize>) -> PyResult<usize> {
    match threads {
        Some(0) => Err(Error::new_err("threads must be at least 1")),
        Some(n) => Ok(n),
        None => Ok(std::thread::available_parallelism().map_or(1, |n| n.get())),
    }
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
    let indices: Vec<usize> = (0..spec.len()).collect();
    let ticks = Progress::new(progress, indices.len());
    let results = py.detach(|| {
        run_points(loaded, robot, &spec, &indices, threads, &|_, _| {
            ticks.tick()
        })
    });
    if let Some(e) = ticks.raised() {
        return Err(e);
    }
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
    let indices: Vec<usize> = (0..spec.samples).collect();
    let ticks = Progress::new(progress, indices.len());
    let results = py.detach(|| spec.run(loaded, robot, &indices, threads, &|_, _| ticks.tick()));
    if let Some(e) = ticks.raised() {
        return Err(e);
    }
    let lines: Vec<String> = std::iter::once(table::header(&spec))
        .chain(results.iter().map(table::row))
        .collect();
    let text = lines.join("\n") + "\n";
    let summary = Summary::of(&spec, &results);
    let json = serde_json::to_string(&summary).map_err(|e| Error::new_err(e.to_string()))?;
    Ok((text, json))
}

/// Where the FMU's shared library is looked for: `library`, then the
/// `FISTAGE_FMI_LIBRARY` environment variable, then the repository this
/// package was built from (`target/release`, `target/debug`).
fn fmu_library(library: Option<PathBuf>) -> PyResult<PathBuf> {
    let name = fistage_fmi::package::LIBRARY_FILE;
    if let Some(given) = library {
        return if given.is_file() {
            Ok(given)
        } else {
            Err(Error::new_err(format!(
                "library={}: not found",
                given.display()
            )))
        };
    }
    let repository = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let candidates: Vec<PathBuf> = std::env::var_os("FISTAGE_FMI_LIBRARY")
        .map(PathBuf::from)
        .into_iter()
        .chain(["release", "debug"].map(|p| repository.join("target").join(p).join(name)))
        .collect();
    candidates
        .iter()
        .find(|p| p.is_file())
        .cloned()
        .ok_or_else(|| {
            Error::new_err(format!(
                "{name} not found (looked in {}): build it in the repository with `cargo build \
                 --release -p fistage-fmi`, or pass library=... or set FISTAGE_FMI_LIBRARY",
                candidates
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
}

/// Packages the scenario (its text, its robot) as an FMI 2.0
/// Co-Simulation FMU at `path`.
pub fn export_fmu(
    text: &str,
    file: &Path,
    path: &Path,
    library: Option<PathBuf>,
) -> PyResult<PathBuf> {
    let library = fmu_library(library)?;
    let bytes = fistage_fmi::build_fmu_from_text(text, file, &library)
        .map_err(|e| Error::new_err(e.to_string()))?;
    std::fs::write(path, bytes)
        .map_err(|e| Error::new_err(format!("{}: cannot write: {e}", path.display())))?;
    Ok(path.to_path_buf())
}

//! The studies of a scenario from Python: its `[sweep]` grid and its
//! `[robust]` tolerance analysis, computed as `fistage sweep` and `fistage
//! robust` compute them (the interpreter released, in chunks between which
//! Ctrl-C and the progress callback are heard; with `out=` journaled into a
//! result folder, resumed, sharded and merged by the same driver,
//! `fistage_analysis::study`), and the scenario packaged as an FMU. Results come back as the table text the program
//! writes (`points.csv`, `samples.csv`) and `summary.json`; the Python side
//! turns them into numpy columns.

use std::path::{Path, PathBuf};

use fistage_analysis::assess::worker_threads;
use fistage_analysis::robust::{RobustSpec, RobustStudy, Summary};
use fistage_analysis::study::{
    Provenance, Study, StudyError, StudyOptions, StudyRun, merge, parse_shard, table_text,
    write_table,
};
use fistage_analysis::sweep::{SweepSpec, SweepStudy};
use fistage_model::{Loaded, RobotSpec};
use pyo3::prelude::*;

use crate::{Error, LoadError_};

/// Runs `compute` over `indices` in chunks of a few items per thread,
/// with the interpreter released; between chunks it takes the interpreter
/// back, stops on Ctrl-C (or an exception from `progress`) and calls
/// `progress(done, total)`.
fn in_chunks<T: Send>(
    py: Python<'_>,
    indices: &[usize],
    threads: usize,
    progress: Option<&Py<PyAny>>,
    compute: impl Fn(&[usize]) -> Vec<T> + Sync,
) -> PyResult<Vec<T>> {
    let chunk = (4 * threads).max(8);
    let mut results = Vec::with_capacity(indices.len());
    for part in indices.chunks(chunk) {
        results.extend(py.detach(|| compute(part)));
        py.check_signals()?;
        if let Some(callback) = progress {
            callback.call1(py, (results.len(), indices.len()))?;
        }
    }
    Ok(results)
}

/// The program's rule for `--threads` ([`worker_threads`]).
fn threads_or_all(threads: Option<usize>) -> PyResult<usize> {
    worker_threads(threads).map_err(Error::new_err)
}

fn study_error(e: StudyError) -> PyErr {
    Error::new_err(e.to_string())
}

/// How a study is run from Python: as the program's `--threads`,
/// `--shard`, `--out`, `--merge`, `--force` and `--no-resume`.
pub struct StudyCall {
    /// Worker threads (default: all).
    pub threads: Option<usize>,
    /// `progress(done, total)` after each chunk.
    pub progress: Option<Py<PyAny>>,
    /// The result folder, journaled and resumed as the program's.
    pub out: Option<PathBuf>,
    /// `"i/n"`: only that shard.
    pub shard: Option<String>,
    /// Shard folders to merge into `out` instead of computing.
    pub merge: Vec<PathBuf>,
    /// Replace other work in `out`.
    pub force: bool,
    /// Take up items already done in `out` or its journal.
    pub resume: bool,
}

impl StudyCall {
    /// The call's flags as Python passes them (`merge=None` merges nothing).
    pub fn new(
        threads: Option<usize>,
        progress: Option<Py<PyAny>>,
        (out, shard, merge): (Option<PathBuf>, Option<String>, Option<Vec<PathBuf>>),
        force: bool,
        resume: bool,
    ) -> Self {
        Self {
            threads,
            progress,
            out,
            shard,
            merge: merge.unwrap_or_default(),
            force,
            resume,
        }
    }
}

/// The rows of `study` (or of its shard): merged from shard folders,
/// computed into `out` through its journal (resuming what is there), or
/// computed in memory. A folder also gets the table, `extra` files and the
/// provenance, and is committed whole.
fn run_study<S: Study>(
    py: Python<'_>,
    study: &S,
    call: &StudyCall,
    provenance: impl FnOnce(Option<(usize, usize)>) -> Result<Provenance, StudyError>,
    extra: impl FnOnce(&[S::Row], &Path) -> std::io::Result<()>,
) -> PyResult<Vec<S::Row>> {
    let threads = threads_or_all(call.threads)?;
    let shard = call
        .shard
        .as_deref()
        .map(parse_shard)
        .transpose()
        .map_err(study_error)?;
    let options = StudyOptions {
        shard,
        no_resume: !call.resume,
        force: call.force,
    };
    let compute = |part: &[usize], run: Option<&StudyRun<'_, S>>| {
        study.compute(part, threads, &|row, _| {
            if let Some(run) = run {
                run.record(row);
            }
        })
    };
    let (folder, rows) = match (&call.out, call.merge.is_empty()) {
        (None, true) => {
            let mine: Vec<usize> = (0..study.len())
                .filter(|k| shard.is_none_or(|(i, n)| k % n == i))
                .collect();
            let rows = in_chunks(py, &mine, threads, call.progress.as_ref(), |part| {
                compute(part, None)
            })?;
            return Ok(rows);
        }
        (None, false) => {
            return Err(Error::new_err(
                "merge= needs out=, the folder to merge into",
            ));
        }
        (Some(out), false) => {
            let provenance = provenance(None).map_err(study_error)?;
            merge(study, &call.merge, out, call.force, &provenance).map_err(study_error)?
        }
        (Some(out), true) => {
            let provenance = provenance(shard).map_err(study_error)?;
            let run = StudyRun::start(study, &options, out, &provenance).map_err(study_error)?;
            let computed = in_chunks(py, run.todo(), threads, call.progress.as_ref(), |part| {
                compute(part, Some(&run))
            })?;
            run.finish(computed)
        }
    };
    write_table(study, &rows, &folder).map_err(study_error)?;
    extra(&rows, folder.path()).map_err(|e| Error::new_err(e.to_string()))?;
    folder.commit().map_err(|e| Error::new_err(e.to_string()))?;
    Ok(rows)
}

/// The scenario as a study input: its text, and the overrides made in
/// Python (which the program's runs of the file do not have).
pub struct ScenarioInput<'a> {
    /// The scenario's TOML text.
    pub text: &'a str,
    /// `path=value` of every override, in order.
    pub overrides: String,
}

impl ScenarioInput<'_> {
    fn mark(&self, provenance: Provenance) -> Provenance {
        if self.overrides.is_empty() {
            provenance
        } else {
            provenance.with_item("overrides", self.overrides.clone())
        }
    }
}

/// The `[sweep]` grid: `points.csv` as text, and its page's section as JSON.
pub fn sweep(
    py: Python<'_>,
    loaded: &Loaded,
    robot: &RobotSpec,
    input: &ScenarioInput<'_>,
    call: &StudyCall,
) -> PyResult<(String, String)> {
    let spec = SweepSpec::from_scenario(&loaded.scenario)
        .map_err(|e| LoadError_::new_err(e.to_string()))?;
    spec.check_against(&loaded.scenario, robot)
        .map_err(|e| LoadError_::new_err(e.to_string()))?;
    let grid = SweepStudy {
        loaded,
        robot_file: robot,
        spec: &spec,
    };
    let rows = run_study(
        py,
        &grid,
        call,
        |shard| Ok(input.mark(grid.provenance(Some(input.text.as_bytes()), shard)?)),
        |rows, folder| std::fs::write(folder.join("points.json"), grid.points_json(rows)),
    )?;
    let section = fistage_report::sections::sweep::section(loaded, &spec, &rows);
    Ok((table_text(&grid, &rows), crate::section_json(&section)?))
}

/// The `[robust]` tolerance analysis: `samples.csv` as text,
/// `summary.json`, and its page's section as JSON.
pub fn robust(
    py: Python<'_>,
    loaded: &Loaded,
    robot: &RobotSpec,
    input: &ScenarioInput<'_>,
    (samples, seed): (Option<usize>, Option<u64>),
    call: &StudyCall,
) -> PyResult<(String, String, String)> {
    let spec = RobustSpec::from_scenario(&loaded.scenario, robot, samples, seed)
        .map_err(|e| LoadError_::new_err(e.to_string()))?;
    let population = RobustStudy {
        loaded,
        robot_file: robot,
        spec: &spec,
    };
    let summary_json = |rows: &[_]| {
        serde_json::to_string_pretty(&Summary::of(&spec, rows)).unwrap_or_default() + "\n"
    };
    let rows = run_study(
        py,
        &population,
        call,
        |shard| Ok(input.mark(population.provenance(Some(input.text.as_bytes()), shard)?)),
        |rows, folder| std::fs::write(folder.join("summary.json"), summary_json(rows)),
    )?;
    let summary = Summary::of(&spec, &rows);
    let section = fistage_report::sections::robust::section(loaded, &spec, &rows, &summary);
    Ok((
        table_text(&population, &rows),
        summary_json(&rows),
        crate::section_json(&section)?,
    ))
}

/// Sets the scenario's `[robust] from_fit` and `from_fit_draw` (a table
/// with every default when it has none); a relative `from_fit` is taken
/// from the working folder, as Python reads paths.
pub fn draw_from_fit(
    loaded: &mut Loaded,
    from_fit: Option<PathBuf>,
    draw: Option<&str>,
) -> PyResult<()> {
    let table = loaded.scenario.robust.get_or_insert_with(Default::default);
    if let Some(file) = from_fit {
        let file = std::path::absolute(&file)
            .map_err(|e| Error::new_err(format!("from_fit={}: {e}", file.display())))?;
        table.from_fit = Some(file);
    }
    if let Some(draw) = draw {
        table.from_fit_draw = match draw {
            "normal" => fistage_model::studies::FitDraw::Normal,
            "replicates" => fistage_model::studies::FitDraw::Replicates,
            other => {
                return Err(Error::new_err(format!(
                    "from_fit_draw must be \"normal\" or \"replicates\", got \"{other}\""
                )));
            }
        };
    }
    Ok(())
}

/// The FMU's shared library, built with this package (see `build.rs`).
#[cfg(feature = "embed-fmu")]
const EMBEDDED_LIBRARY: Option<&[u8]> = Some(include_bytes!(env!("FISTAGE_FMI_EMBEDDED")));
/// Built without `embed-fmu` (a cargo build, not maturin's): no library inside.
#[cfg(not(feature = "embed-fmu"))]
const EMBEDDED_LIBRARY: Option<&[u8]> = None;

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
            let Some(embedded) = EMBEDDED_LIBRARY else {
                return Err(Error::new_err(
                    "this build of the package holds no FMU library (built without the \
                     `embed-fmu` feature): give library=, or install with pip install ./python",
                ));
            };
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.subsec_nanos());
            let file =
                std::env::temp_dir().join(format!("fistage-fmi-{}-{nanos}.so", std::process::id()));
            std::fs::write(&file, embedded)
                .map_err(|e| Error::new_err(format!("{}: cannot write: {e}", file.display())))?;
            (Some(TemporaryFile(file.clone())), file)
        }
    };
    let bytes = fistage_fmi::build_fmu_from_text_version(text, file, &library, version)
        .map_err(|e| Error::new_err(e.to_string()))?;
    // Written whole or not at all: a failed write leaves an earlier FMU.
    fistage_model::output::write_whole(path, &bytes)
        .map_err(|e| Error::new_err(format!("{}: cannot write: {e}", path.display())))?;
    Ok(path.to_path_buf())
}

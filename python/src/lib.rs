//! The extension module `fistage._fistage`: the library for Python, a thin
//! face like the command line. A [`Scenario`] is the scenario file's text,
//! the path its relative paths resolve against, and the parameter-table
//! overrides set from Python; every call loads and checks it the way
//! `fistage run` does, so errors carry the program's messages. Long work
//! runs with the interpreter released.

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use fistage_analysis::assess::apply_parameter;
use fistage_model::{
    EngineKind, LoadError, Loaded, Parameter, RobotSpec, SolverSettings, assemble,
};
use numpy::PyArray1;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyKeyError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

create_exception!(_fistage, Error, PyException, "Every error fistage raises.");
create_exception!(
    _fistage,
    LoadError_,
    Error,
    "A scenario, robot or parameter that the loader refuses (the message names file, key and fault)."
);
create_exception!(
    _fistage,
    SimulationError,
    Error,
    "A run that the engine could not complete."
);
create_exception!(
    _fistage,
    IdentificationError,
    Error,
    "A fit the data or the options do not allow."
);

mod identify;
mod plant;
mod studies;

fn load_error(e: LoadError) -> PyErr {
    LoadError_::new_err(e.to_string())
}

/// A scenario: its TOML text, the file its relative paths resolve against,
/// and parameter-table values set on top of it.
#[pyclass(module = "fistage._fistage", frozen)]
#[derive(Clone)]
struct Scenario {
    text: String,
    file: PathBuf,
    overrides: Vec<(String, f64)>,
}

impl Scenario {
    /// The scenario and the robot file as read, the overrides written into
    /// them through the parameter table (each checked by its rule).
    fn study(&self) -> Result<(fistage_model::Scenario, RobotSpec), LoadError> {
        let mut scenario = fistage_model::Scenario::from_str(&self.text, &self.file)?;
        let mut robot = RobotSpec::from_file(&scenario.robot)?;
        for (path, value) in &self.overrides {
            apply_parameter(&mut scenario, &mut robot, path, *value)?;
        }
        Ok((scenario, robot))
    }

    /// The scenario as a study's input: its text and its overrides.
    fn input(&self) -> studies::ScenarioInput<'_> {
        let overrides: Vec<String> = self
            .overrides
            .iter()
            .map(|(path, value)| format!("{path}={value:e}"))
            .collect();
        studies::ScenarioInput {
            text: &self.text,
            overrides: overrides.join(", "),
        }
    }

    /// The study, loaded and checked, overrides applied.
    fn loaded(&self) -> Result<Loaded, LoadError> {
        let (scenario, robot) = self.study()?;
        let (robot, model) = assemble(robot, &scenario)?;
        Ok(Loaded {
            scenario,
            robot,
            model,
        })
    }
}

#[pymethods]
impl Scenario {
    /// Scenario.from_toml(text, base_dir=None): a scenario from TOML text;
    /// its relative paths (the robot file) resolve against `base_dir`
    /// (default: the working directory).
    #[staticmethod]
    #[pyo3(signature = (text, base_dir=None))]
    fn from_toml(text: String, base_dir: Option<PathBuf>) -> PyResult<Self> {
        let file = base_dir.unwrap_or_default().join("scenario.toml");
        let scenario = Self {
            text,
            file,
            overrides: Vec::new(),
        };
        scenario.loaded().map_err(load_error)?;
        Ok(scenario)
    }

    /// with_overrides({path: value, ...}) -> Scenario: a new scenario with
    /// these parameter-table values (paths as `fistage` names them:
    /// "controller.c", "overrides.bearing_friction.f_s", ...), each checked
    /// by its rule; the original is unchanged.
    fn with_overrides(&self, values: &Bound<'_, PyDict>) -> PyResult<Self> {
        let mut next = self.clone();
        for (key, value) in values.iter() {
            let path: String = key.extract()?;
            let value: f64 = value.extract()?;
            next.overrides.push((path, value));
        }
        next.loaded().map_err(load_error)?;
        Ok(next)
    }

    /// parameters() -> list of dict: every entry of the parameter table
    /// (path, value, unit, rule, description), values after the overrides.
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.loaded().map_err(load_error)?;
        let (scenario, robot) = self.study().map_err(load_error)?;
        Parameter::all(&scenario, &robot)
            .iter()
            .map(|p| {
                let entry = PyDict::new(py);
                entry.set_item("path", p.path())?;
                entry.set_item("value", p.read(&scenario, &robot))?;
                entry.set_item("unit", p.unit())?;
                entry.set_item("rule", p.rule().requirement())?;
                entry.set_item("description", p.description(&robot))?;
                Ok(entry)
            })
            .collect()
    }

    /// run(rtol=None, engine=None, progress=None) -> Result: simulates the
    /// scenario (with the interpreter released) and gives its signals as
    /// numpy arrays. `engine` is "auto" (the default), "native", "imex",
    /// "dop853", "rk4", "rosenbrock" or "rapier".
    /// `progress(fraction)` is called now and then (every 2048 steps);
    /// Ctrl-C, or an exception in the callback, stops the run.
    #[pyo3(signature = (rtol=None, engine=None, progress=None))]
    fn run(
        &self,
        py: Python<'_>,
        rtol: Option<f64>,
        engine: Option<&str>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<RunResult> {
        let mut loaded = self.loaded().map_err(load_error)?;
        if let Some(rtol) = rtol {
            SolverSettings::check_rtol(rtol)
                .map_err(|why| Error::new_err(format!("rtol {why}")))?;
            loaded.scenario.solver.rtol = rtol;
        }
        if let Some(engine) = engine {
            let kind: EngineKind = engine.parse().map_err(Error::new_err)?;
            loaded.scenario.solver.engine = kind;
        }
        let mut raised: Option<PyErr> = None;
        let output = py.detach(|| {
            fistage_sim::run_scenario(&loaded, &mut |fraction| {
                Python::attach(|py| {
                    let stop = py.check_signals().err().or_else(|| {
                        progress
                            .as_ref()
                            .and_then(|callback| callback.call1(py, (fraction,)).err())
                    });
                    match stop {
                        Some(e) => {
                            raised = Some(e);
                            ControlFlow::Break(())
                        }
                        None => ControlFlow::Continue(()),
                    }
                })
            })
        });
        if let Some(e) = raised {
            return Err(e);
        }
        let output = output.map_err(|e| SimulationError::new_err(e.to_string()))?;
        let summary = serde_json::to_string(&fistage_sim::summary::document(&loaded, &output))
            .map_err(|e| Error::new_err(e.to_string()))?;
        let json = py.import("json")?;
        let summary = json.call_method1("loads", (summary,))?.unbind();
        let section = fistage_report::sections::run::section(&loaded, &output);
        let table = output.signals;
        let signals = PyDict::new(py);
        let units = PyDict::new(py);
        for ((name, unit), column) in table.names.iter().zip(&table.units).zip(table.columns) {
            signals.set_item(name, PyArray1::from_vec(py, column))?;
            units.set_item(name, unit)?;
        }
        Ok(RunResult {
            time: PyArray1::from_vec(py, table.times).into_any().unbind(),
            signals: signals.unbind(),
            units: units.unbind(),
            summary,
            section,
        })
    }

    /// plant() -> Plant: the stage as an ODE x' = f(t, x) for Python's own
    /// integrators: `rhs(t, x)`, `jacobian(t, x)`, `x0`, `nominal`,
    /// `sample_times`, `breakpoints` (restart an integrator there).
    fn plant(&self) -> PyResult<plant::Plant> {
        plant::Plant::new(self.loaded().map_err(load_error)?).map_err(load_error)
    }

    /// modes(equilibrium="slipping") -> dict: the linearisation at the
    /// sticking or slipping equilibrium, as modes.json holds it (verdict,
    /// max_real_part, state, coordinates, modes with frequency, damping
    /// ratio and energy shares), plus numpy arrays `eigenvalues` (complex),
    /// `frequency_hz` and `damping_ratio`. A verdict the numerics cannot
    /// back is "undetermined".
    #[pyo3(signature = (equilibrium = "slipping"))]
    fn _modes<'py>(
        &self,
        py: Python<'py>,
        equilibrium: &str,
    ) -> PyResult<(Bound<'py, PyAny>, String)> {
        let kind = match equilibrium {
            "sticking" => fistage_model::EquilibriumKind::Sticking,
            "slipping" => fistage_model::EquilibriumKind::Slipping,
            other => {
                return Err(Error::new_err(format!(
                    "equilibrium must be \"sticking\" or \"slipping\", got \"{other}\""
                )));
            }
        };
        let loaded = self.loaded().map_err(load_error)?;
        let inputs = fistage_analysis::modes::equilibrium_inputs(&loaded.scenario);
        let start =
            fistage_sim::initial_state(&loaded.model, &loaded.scenario).map_err(load_error)?;
        let analysis = py
            .detach(|| fistage_analysis::modal_analysis(&loaded.model, &inputs, kind, &start))
            .map_err(|e| Error::new_err(e.to_string()))?;
        let text = serde_json::to_string(&analysis).map_err(|e| Error::new_err(e.to_string()))?;
        let result = py.import("json")?.call_method1("loads", (text,))?;
        let numpy = py.import("numpy")?;
        let column = |values: Vec<f64>| numpy.call_method1("array", (values,));
        let real: Vec<f64> = analysis.modes.iter().map(|m| m.real).collect();
        let imag: Vec<f64> = analysis.modes.iter().map(|m| m.imag).collect();
        let eigenvalues = column(real)?.add(column(imag)?.mul(py.eval(c"1j", None, None)?)?)?;
        result.set_item("eigenvalues", eigenvalues)?;
        result.set_item(
            "frequency_hz",
            column(analysis.modes.iter().map(|m| m.frequency_hz).collect())?,
        )?;
        result.set_item(
            "damping_ratio",
            column(analysis.modes.iter().map(|m| m.damping_ratio).collect())?,
        )?;
        let section = fistage_report::sections::modes::section(&loaded, &[analysis], &[]);
        Ok((result, section_json(&section)?))
    }

    /// sweep(threads=None, progress=None, out=None, shard=None, merge=None,
    /// force=False, resume=True) -> (points.csv text): the scenario's
    /// `[sweep]` grid as `fistage sweep` computes it, on `threads` threads
    /// (default: all); `progress(done, total)` after each chunk of points;
    /// Ctrl-C stops it (with `out`, the journal keeps what was done). With
    /// `out` the result folder is written as the program writes it
    /// (journal, resume, `shard` "i/n", `merge` of shard folders, `force`).
    /// The Python side turns it into numpy columns.
    #[pyo3(signature = (threads=None, progress=None, out=None, shard=None, merge=None, force=false, resume=true))]
    #[allow(clippy::too_many_arguments)]
    fn _sweep(
        &self,
        py: Python<'_>,
        threads: Option<usize>,
        progress: Option<Py<PyAny>>,
        out: Option<PathBuf>,
        shard: Option<String>,
        merge: Option<Vec<PathBuf>>,
        force: bool,
        resume: bool,
    ) -> PyResult<(String, String)> {
        let loaded = self.loaded().map_err(load_error)?;
        let (_, robot) = self.study().map_err(load_error)?;
        let call = studies::StudyCall::new(threads, progress, (out, shard, merge), force, resume);
        studies::sweep(py, &loaded, &robot, &self.input(), &call)
    }

    /// robust(samples=None, seed=None, threads=None, progress=None,
    /// out=None, shard=None, merge=None, force=False, resume=True,
    /// from_fit=None, from_fit_draw=None) -> (samples.csv text, summary.json
    /// text): the scenario's `[robust]` tolerance analysis as `fistage
    /// robust` computes it (`out` and the rest as for sweep). `from_fit`
    /// (a fit's fit.json, relative to the working folder) and
    /// `from_fit_draw` ("normal" or "replicates") stand for the table's
    /// keys; a scenario without `[robust]` then draws the fit alone.
    #[pyo3(signature = (samples=None, seed=None, threads=None, progress=None, out=None, shard=None, merge=None, force=false, resume=true, from_fit=None, from_fit_draw=None))]
    #[allow(clippy::too_many_arguments)]
    fn _robust(
        &self,
        py: Python<'_>,
        samples: Option<usize>,
        seed: Option<u64>,
        threads: Option<usize>,
        progress: Option<Py<PyAny>>,
        out: Option<PathBuf>,
        shard: Option<String>,
        merge: Option<Vec<PathBuf>>,
        force: bool,
        resume: bool,
        from_fit: Option<PathBuf>,
        from_fit_draw: Option<String>,
    ) -> PyResult<(String, String, String)> {
        let mut loaded = self.loaded().map_err(load_error)?;
        let (_, robot) = self.study().map_err(load_error)?;
        if from_fit.is_some() || from_fit_draw.is_some() {
            studies::draw_from_fit(&mut loaded, from_fit, from_fit_draw.as_deref())?;
        }
        let call = studies::StudyCall::new(threads, progress, (out, shard, merge), force, resume);
        studies::robust(py, &loaded, &robot, &self.input(), (samples, seed), &call)
    }

    /// export_fmu(path, library=None, fmi_version=2) -> path: the scenario
    /// as an FMI 2.0 (or 3.0) FMU with Model Exchange and Co-Simulation, as
    /// `fistage fmu` packages it. The FMU's shared
    /// library is `library`, else the one built with this package.
    /// Overrides set from Python are not in the scenario's text, so a
    /// scenario with overrides is refused: an importer sets the FMU's
    /// parameters itself.
    #[pyo3(signature = (path, library=None, fmi_version=2))]
    fn export_fmu(
        &self,
        path: PathBuf,
        library: Option<PathBuf>,
        fmi_version: u8,
    ) -> PyResult<PathBuf> {
        let version = match fmi_version {
            2 => fistage_fmi::FmiVersion::Fmi2,
            3 => fistage_fmi::FmiVersion::Fmi3,
            other => {
                return Err(Error::new_err(format!(
                    "fmi_version must be 2 or 3, got {other}"
                )));
            }
        };
        if !self.overrides.is_empty() {
            return Err(Error::new_err(format!(
                "export_fmu packages the scenario's text; its {} Python overrides would be \
                 lost: write them into the TOML, or set them as the FMU's parameters in the \
                 importer",
                self.overrides.len()
            )));
        }
        studies::export_fmu(&self.text, &self.file, &path, library, version)
    }

    /// The scenario's title.
    #[getter]
    fn title(&self) -> PyResult<String> {
        let scenario =
            fistage_model::Scenario::from_str(&self.text, &self.file).map_err(load_error)?;
        Ok(scenario.title)
    }

    /// The overrides set from Python, as a dict.
    #[getter]
    fn overrides<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        for (path, value) in &self.overrides {
            dict.set_item(path, value)?;
        }
        Ok(dict)
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario({}, {} overrides)",
            self.file.display(),
            self.overrides.len()
        )
    }

    /// Pickling: the text, the file and the overrides.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyTuple>> {
        let restore = py
            .import("fistage._fistage")?
            .getattr("_restore_scenario")?;
        let state = (
            self.text.clone(),
            self.file.display().to_string(),
            self.overrides.clone(),
        );
        PyTuple::new(
            py,
            [restore.into_any(), state.into_pyobject(py)?.into_any()],
        )
    }
}

/// A finished run: `time` and every signal as numpy arrays, units and the
/// summary (as summary.json holds it).
#[pyclass(module = "fistage._fistage", name = "Result", frozen)]
struct RunResult {
    #[pyo3(get)]
    time: Py<PyAny>,
    #[pyo3(get)]
    signals: Py<PyDict>,
    #[pyo3(get)]
    units: Py<PyDict>,
    #[pyo3(get)]
    summary: Py<PyAny>,
    /// The run's part of its HTML page.
    section: fistage_report::Section,
}

#[pymethods]
impl RunResult {
    /// result["encoder.position"]: one signal.
    fn __getitem__<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
        let signals = self.signals.bind(py);
        match signals.get_item(name)? {
            Some(values) => Ok(values),
            None => {
                let names: Vec<String> = signals.keys().extract()?;
                Err(PyKeyError::new_err(format!(
                    "no signal \"{name}\" (signals: {})",
                    names.join(", ")
                )))
            }
        }
    }

    fn __repr__(&self, py: Python<'_>) -> String {
        format!("Result({} signals)", self.signals.bind(py).len())
    }

    /// report(path): writes the run's HTML page (as `fistage run` writes
    /// report.html): one self-contained file.
    fn report(&self, path: PathBuf) -> PyResult<()> {
        fistage_report::write(&self.page(), &path).map_err(|e| Error::new_err(e.to_string()))
    }

    /// The page in Jupyter: the same plots, in a frame of the notebook.
    fn _repr_html_(&self) -> PyResult<String> {
        frame(&self.page())
    }
}

impl RunResult {
    fn page(&self) -> fistage_report::Page {
        fistage_report::Page::single(self.section.clone())
    }
}

/// A page in an iframe of its own, as a notebook shows HTML.
fn frame(page: &fistage_report::Page) -> PyResult<String> {
    let html = fistage_report::render(page).map_err(|e| Error::new_err(e.to_string()))?;
    Ok(format!(
        "<iframe srcdoc=\"{}\" style=\"width: 100%; height: 720px; border: none\"></iframe>",
        html.replace('&', "&amp;").replace('"', "&quot;")
    ))
}

/// A section of a page as the JSON the Python side keeps.
fn section_json(section: &fistage_report::Section) -> PyResult<String> {
    serde_json::to_string(section).map_err(|e| Error::new_err(e.to_string()))
}

/// The page of a section kept as JSON.
fn page_of(section: &str) -> PyResult<fistage_report::Page> {
    let section: fistage_report::Section =
        serde_json::from_str(section).map_err(|e| Error::new_err(e.to_string()))?;
    Ok(fistage_report::Page::single(section))
}

/// _page_frame(section) -> the section's page in an iframe (`_repr_html_`
/// of the Python-side results).
#[pyfunction]
fn _page_frame(section: &str) -> PyResult<String> {
    frame(&page_of(section)?)
}

/// _page_write(section, path): writes the section's page.
#[pyfunction]
fn _page_write(section: &str, path: PathBuf) -> PyResult<()> {
    fistage_report::write(&page_of(section)?, &path).map_err(|e| Error::new_err(e.to_string()))
}

/// load(path) -> Scenario: reads and checks a scenario file and its robot.
#[pyfunction]
fn load(path: PathBuf) -> PyResult<Scenario> {
    let text = fistage_model::input::read_text(&path, fistage_model::input::MAX_DESCRIPTION_BYTES)
        .map_err(|reason| {
            load_error(LoadError::Io {
                file: path.clone(),
                reason,
            })
        })?;
    let scenario = Scenario {
        text,
        file: path,
        overrides: Vec::new(),
    };
    scenario.loaded().map_err(load_error)?;
    Ok(scenario)
}

/// Unpickling.
#[pyfunction]
fn _restore_scenario(text: String, file: String, overrides: Vec<(String, f64)>) -> Scenario {
    Scenario {
        text,
        file: Path::new(&file).to_path_buf(),
        overrides,
    }
}

#[pymodule]
fn _fistage(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Scenario>()?;
    m.add_class::<RunResult>()?;
    m.add_class::<plant::Plant>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(_restore_scenario, m)?)?;
    m.add_function(wrap_pyfunction!(_page_frame, m)?)?;
    m.add_function(wrap_pyfunction!(_page_write, m)?)?;
    m.add("Error", m.py().get_type::<Error>())?;
    m.add("LoadError", m.py().get_type::<LoadError_>())?;
    m.add("SimulationError", m.py().get_type::<SimulationError>())?;
    m.add(
        "IdentificationError",
        m.py().get_type::<IdentificationError>(),
    )?;
    m.add_function(wrap_pyfunction!(identify::_stribeck, m)?)?;
    m.add_function(wrap_pyfunction!(identify::_record, m)?)?;
    m.add_function(wrap_pyfunction!(identify::_stage, m)?)?;
    m.add_function(wrap_pyfunction!(identify::_read_record, m)?)?;
    m.add_function(wrap_pyfunction!(identify::_simulate_record, m)?)?;
    m.add_function(wrap_pyfunction!(identify::_frf, m)?)?;
    Ok(())
}

//! `Scenario.plant()`: the assembled model as an ODE for Python's own
//! integrators (SciPy's `solve_ivp`, a notebook's hand-written scheme): the
//! state derivative and its exact Jacobian at (t, x) under the scenario's
//! excitation, the start state, the nominal state sizes, the output grid and
//! the times where the inputs jump (where an integrator should restart).

use fistage_model::{Inputs, Loaded};
use fistage_sim::{Excitation, ScenarioExcitation};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray1};
use pyo3::prelude::*;

use crate::Error;

/// The scenario's stage as `x' = f(t, x)`.
#[pyclass(module = "fistage._fistage", frozen)]
pub struct Plant {
    loaded: Loaded,
    excitation: ScenarioExcitation,
    start: Vec<f64>,
}

impl Plant {
    pub fn new(loaded: Loaded) -> Result<Self, fistage_model::LoadError> {
        let start = fistage_sim::initial_state(&loaded.model, &loaded.scenario)?;
        let excitation = ScenarioExcitation::from_scenario(&loaded.scenario);
        // An integrator calls the plant many times: its right-hand side as
        // machine code (a model that does not compile is evaluated generically).
        let _ = fistage_codegen::machine_code(&loaded.model, fistage_codegen::Function::Rhs);
        Ok(Self {
            loaded,
            excitation,
            start,
        })
    }

    fn state(&self, x: &PyReadonlyArray1<'_, f64>) -> PyResult<Vec<f64>> {
        let x = x.as_slice()?;
        let n = self.loaded.model.n_states();
        if x.len() != n {
            return Err(Error::new_err(format!(
                "x has {} entries; the model has {n} states ({})",
                x.len(),
                self.loaded.model.layout().names.join(", ")
            )));
        }
        Ok(x.to_vec())
    }

    fn inputs(&self, t: f64) -> Inputs {
        self.excitation.inputs(t)
    }
}

#[pymethods]
impl Plant {
    /// Number of states.
    #[getter]
    fn n_states(&self) -> usize {
        self.loaded.model.n_states()
    }

    /// State names, in the order of x.
    #[getter]
    fn state_names(&self) -> Vec<String> {
        self.loaded.model.layout().names.clone()
    }

    /// The scenario's start state (as `fistage run` starts).
    #[getter]
    fn x0<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.start.clone())
    }

    /// Typical size of each state; `fistage` uses `rtol * atol_scale * nominal` as absolute tolerance.
    #[getter]
    fn nominal<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_vec(py, self.loaded.model.layout().nominal.clone())
    }

    /// The scenario's `solver.atol_scale`.
    #[getter]
    fn atol_scale(&self) -> f64 {
        self.loaded.scenario.solver.atol_scale
    }

    /// Simulated duration, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.loaded.scenario.duration
    }

    /// The output grid of `fistage run`, s.
    #[getter]
    fn sample_times<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let scenario = &self.loaded.scenario;
        PyArray1::from_vec(
            py,
            fistage_sim::sample_times(scenario.duration, 1.0 / scenario.sample_rate),
        )
    }

    /// Times where the inputs jump, sorted, inside (0, duration): restart an integrator there.
    #[getter]
    fn breakpoints(&self) -> Vec<f64> {
        let mut points: Vec<f64> = self
            .excitation
            .breakpoints()
            .into_iter()
            .filter(|&b| b > 0.0 && b < self.loaded.scenario.duration)
            .collect();
        points.sort_by(f64::total_cmp);
        points.dedup();
        points
    }

    /// rhs(t, x) -> ndarray: the state derivative, the very evaluation `fistage run` integrates.
    fn rhs<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        x: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let x = self.state(&x)?;
        let model = &self.loaded.model;
        let mut dx = vec![0.0; x.len()];
        let mut workspace = model.workspace();
        model.rhs(&x, &self.inputs(t), &mut dx, &mut workspace);
        Ok(PyArray1::from_vec(py, dx))
    }

    /// jacobian(t, x) -> ndarray (n x n): d rhs / dx, exact (dual numbers through the same evaluation).
    fn jacobian<'py>(
        &self,
        py: Python<'py>,
        t: f64,
        x: PyReadonlyArray1<'py, f64>,
    ) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let x = self.state(&x)?;
        let n = x.len();
        let jacobian = self.loaded.model.jacobian(&x, &self.inputs(t));
        let rows: Vec<f64> = (0..n * n).map(|k| jacobian[(k / n, k % n)]).collect();
        PyArray1::from_vec(py, rows).reshape([n, n])
    }

    fn __repr__(&self) -> String {
        format!(
            "Plant({}: {} states, {} s)",
            self.loaded.model.name(),
            self.loaded.model.n_states(),
            self.loaded.scenario.duration
        )
    }
}

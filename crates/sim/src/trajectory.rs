//! Trajectories (states on a time grid), the output-signal table computed from
//! them, and CSV export with a header naming each signal and its unit.

use std::io::Write;

use fistage_model::Model;
use serde::Serialize;

use fistage_model::excitation::Excitation;
use fistage_ode::StepCounts;

/// What the engine did.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SolverStats {
    /// Engine name.
    pub engine: String,
    /// Steps, rejections and right-hand-side evaluations.
    #[serde(flatten)]
    pub counts: StepCounts,
    /// Wall-clock time of the integration, s.
    pub wall_time_s: f64,
}

/// States sampled on a time grid.
#[derive(Debug, Clone, Default)]
pub struct Trajectory {
    /// Sample times, s.
    pub times: Vec<f64>,
    /// States, sample after sample (`times.len() * n_states` values).
    pub states: Vec<f64>,
    /// Number of states per sample.
    pub n_states: usize,
    /// Solver statistics.
    pub stats: SolverStats,
    /// Signals of things outside the model (e.g. a rapier payload), one value per sample.
    pub extra: Vec<ExtraSignal>,
}

/// A signal an engine records beside the model's states.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ExtraSignal {
    /// Name, e.g. `payload.slip`.
    pub name: String,
    /// SI unit.
    pub unit: &'static str,
    /// One value per sample.
    pub values: Vec<f64>,
}

impl Trajectory {
    /// An empty trajectory with room for `samples` samples.
    pub fn with_capacity(n_states: usize, samples: usize) -> Self {
        Self {
            times: Vec::with_capacity(samples),
            states: Vec::with_capacity(samples * n_states),
            n_states,
            stats: SolverStats::default(),
            extra: Vec::new(),
        }
    }

    /// Appends a sample.
    pub fn push(&mut self, t: f64, x: &[f64]) {
        self.times.push(t);
        self.states.extend_from_slice(x);
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.times.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.times.is_empty()
    }

    /// State at sample k.
    pub fn state(&self, k: usize) -> &[f64] {
        &self.states[k * self.n_states..(k + 1) * self.n_states]
    }

    /// The last state.
    pub fn last_state(&self) -> &[f64] {
        self.state(self.len() - 1)
    }

    /// Every output signal of the model along the trajectory.
    pub fn signals(&self, model: &Model, excitation: &dyn Excitation) -> SignalTable {
        let mut workspace = model.workspace();
        let m = model.signals().len();
        let mut columns = vec![Vec::with_capacity(self.len()); m];
        let mut out = vec![0.0; m];
        for (k, &t) in self.times.iter().enumerate() {
            model.outputs(
                self.state(k),
                &excitation.inputs(t),
                &mut out,
                &mut workspace,
            );
            for (column, value) in columns.iter_mut().zip(&out) {
                column.push(*value);
            }
        }
        let mut table = SignalTable {
            names: model.signals().iter().map(|s| s.name.clone()).collect(),
            units: model.signals().iter().map(|s| s.unit.to_string()).collect(),
            times: self.times.clone(),
            columns,
        };
        for extra in &self.extra {
            table.names.push(extra.name.clone());
            table.units.push(extra.unit.to_string());
            table.columns.push(extra.values.clone());
        }
        table
    }
}

/// Named signals on a common time grid.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SignalTable {
    /// Signal names.
    pub names: Vec<String>,
    /// Signal units.
    pub units: Vec<String>,
    /// Sample times, s.
    pub times: Vec<f64>,
    /// One column per signal.
    pub columns: Vec<Vec<f64>>,
}

impl SignalTable {
    /// Writes the table as a version 7 MAT-file ([`fistage_model::mat`]).
    pub fn write_mat<W: std::io::Write>(&self, out: &mut W) -> std::io::Result<()> {
        fistage_model::mat::Signals {
            times: &self.times,
            names: &self.names,
            units: &self.units,
            columns: &self.columns,
        }
        .write_mat(out)
    }

    /// The column of a named signal.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(|i| self.columns[i].as_slice())
    }

    /// Keeps only the named signals, in the given order; returns the unknown names.
    pub fn select(&self, wanted: &[String]) -> Result<SignalTable, Vec<String>> {
        let mut missing = Vec::new();
        let mut table = SignalTable {
            times: self.times.clone(),
            ..SignalTable::default()
        };
        for name in wanted {
            match self.names.iter().position(|n| n == name) {
                Some(i) => {
                    table.names.push(self.names[i].clone());
                    table.units.push(self.units[i].clone());
                    table.columns.push(self.columns[i].clone());
                }
                None => missing.push(name.clone()),
            }
        }
        if missing.is_empty() {
            Ok(table)
        } else {
            Err(missing)
        }
    }

    /// Writes CSV: a header `time [s],<name> [<unit>],...` then one row per sample,
    /// numbers in shortest round-trip form.
    pub fn write_csv(&self, writer: &mut dyn Write) -> std::io::Result<()> {
        let mut header = String::from("time [s]");
        for (name, unit) in self.names.iter().zip(&self.units) {
            header.push_str(&format!(",{name} [{unit}]"));
        }
        writeln!(writer, "{header}")?;
        let mut line = String::new();
        for (k, t) in self.times.iter().enumerate() {
            line.clear();
            line.push_str(&format!("{t}"));
            for column in &self.columns {
                line.push_str(&format!(",{:e}", column[k]));
            }
            writeln!(writer, "{line}")?;
        }
        Ok(())
    }
}

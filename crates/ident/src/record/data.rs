//! A recorded stage run: sample times, the force command and the encoder
//! position, with where each sample came from (for messages) and the state
//! the stage starts in.
//!
//! Conventions (the README and `fistage identify record --help` say them too):
//! the force is held over each sample interval, `force[k]` acting on
//! `[t_k, t_k+1)` (zero-order hold); `position[k]` is sampled at `t_k`
//! before `force[k]` acts; the stage starts at rest with relaxed bristles
//! unless a [`StartState`] says otherwise.

use crate::error::{IdentError, Result};

/// The fewest samples a record may have.
pub const MIN_SAMPLES: usize = 20;

/// The stage's state at the first sample.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StartState {
    /// Velocity, m/s.
    pub velocity: f64,
    /// Bristle deflection z, m.
    pub bristle: f64,
}

/// A further position column of a record: the reading of a named sensor
/// (`bearing_encoder_nm` is sensor `bearing_encoder`), SI units. The
/// position column proper is the stage's main sensor.
#[derive(Debug, Clone, PartialEq)]
pub struct SensorColumn {
    /// The sensor's name, from the column's name without its unit.
    pub sensor: String,
    /// The column (or variable) as written.
    pub column: String,
    /// The readings, m, one per sample.
    pub values: Vec<f64>,
}

/// A recorded run in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// The file (or `<array>`), for messages.
    pub source: String,
    /// Names of the time, force and position columns (or variables) as written.
    pub columns: [String; 3],
    /// Where each sample is in the file: the physical line of a CSV file, the
    /// element (from 1) of a MAT-file variable.
    pub rows: Vec<u64>,
    /// What `rows` counts, for messages (`line` or `element`).
    pub row_word: &'static str,
    /// Sample times, s.
    pub time: Vec<f64>,
    /// Force command, N, held over each sample interval.
    pub force: Vec<f64>,
    /// Encoder position, m.
    pub position: Vec<f64>,
    /// The state at the first sample.
    pub start: StartState,
    /// Further sensors' readings (columns named `<sensor>_<unit>`), for a
    /// stage fit; the one-mass fit reads only `position`.
    pub sensors: Vec<SensorColumn>,
}

impl Record {
    /// A record from arrays (SI units); `source` names it in messages.
    /// Checked by [`Record::check`].
    pub fn from_arrays(
        source: impl Into<String>,
        time: Vec<f64>,
        force: Vec<f64>,
        position: Vec<f64>,
    ) -> Result<Self> {
        let record = Self {
            source: source.into(),
            columns: ["t".into(), "force".into(), "position".into()],
            rows: (1..=time.len() as u64).collect(),
            row_word: "element",
            time,
            force,
            position,
            start: StartState::default(),
            sensors: Vec::new(),
        };
        record.check()?;
        Ok(record)
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// True for a record without samples.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// The median sample interval, s.
    pub fn sample_interval(&self) -> f64 {
        let mut steps: Vec<f64> = self.time.windows(2).map(|w| w[1] - w[0]).collect();
        if steps.is_empty() {
            return f64::NAN;
        }
        let mid = steps.len() / 2;
        steps.select_nth_unstable_by(mid, f64::total_cmp);
        steps[mid]
    }

    /// Duration from the first to the last sample, s.
    pub fn duration(&self) -> f64 {
        match (self.time.first(), self.time.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }

    /// The record seen from a counter-surface moving at `velocity`: the
    /// position less `velocity (t - t_0)`, so that its rate is the slip
    /// velocity the friction sees (the acceleration is unchanged).
    pub fn relative_to_platform(&self, velocity: f64) -> Self {
        let t0 = self.time.first().copied().unwrap_or(0.0);
        let mut out = self.clone();
        for (x, t) in out.position.iter_mut().zip(&self.time) {
            *x -= velocity * (t - t0);
        }
        out.start.velocity -= velocity;
        out
    }

    /// Checks lengths, finiteness and strictly increasing times; errors name
    /// the column and the row.
    pub fn check(&self) -> Result<()> {
        let n = self.time.len();
        for (column, values) in [(1, &self.force), (2, &self.position)] {
            if values.len() != n {
                return Err(self.error(
                    column,
                    None,
                    format!("{} values against {n} times", values.len()),
                ));
            }
        }
        if n < MIN_SAMPLES {
            return Err(IdentError::InsufficientData {
                file: self.source.clone(),
                column: self.columns[0].clone(),
                message: format!("{n} samples; a record needs at least {MIN_SAMPLES}"),
            });
        }
        for (column, values) in [(0, &self.time), (1, &self.force), (2, &self.position)] {
            if let Some(k) = values.iter().position(|v| !v.is_finite()) {
                return Err(self.error(column, Some(k), format!("{} is not finite", values[k])));
            }
        }
        for (i, sensor) in self.sensors.iter().enumerate() {
            let error = |k: Option<usize>, message: String| self.sensor_error(sensor, k, message);
            if sensor.values.len() != n {
                return Err(error(
                    None,
                    format!("{} values against {n} times", sensor.values.len()),
                ));
            }
            if let Some(k) = sensor.values.iter().position(|v| !v.is_finite()) {
                return Err(error(
                    Some(k),
                    format!("{} is not finite", sensor.values[k]),
                ));
            }
            if let Some(other) = self.sensors[..i].iter().find(|o| o.sensor == sensor.sensor) {
                return Err(error(
                    None,
                    format!(
                        "ambiguous: both '{}' and this column read sensor '{}'; rename one",
                        other.column, sensor.sensor
                    ),
                ));
            }
        }
        if let Some(k) = self.time.windows(2).position(|w| w[1] <= w[0]) {
            return Err(self.error(
                0,
                Some(k + 1),
                format!(
                    "time {} s does not increase past the previous {} s",
                    self.time[k + 1],
                    self.time[k]
                ),
            ));
        }
        let [v, z] = [self.start.velocity, self.start.bristle];
        if !(v.is_finite() && z.is_finite()) {
            return Err(IdentError::InvalidOption(format!(
                "the start state (velocity {v}, bristle {z}) must be finite"
            )));
        }
        Ok(())
    }

    /// An error about sample `k` (or the whole column) of a sensor column.
    pub(crate) fn sensor_error(
        &self,
        sensor: &SensorColumn,
        k: Option<usize>,
        message: String,
    ) -> IdentError {
        match k {
            Some(k) if self.row_word == "element" => IdentError::BadElement {
                file: self.source.clone(),
                variable: sensor.column.clone(),
                element: k + 1,
                message,
            },
            Some(k) => IdentError::BadCell {
                file: self.source.clone(),
                line: self.rows.get(k).copied().unwrap_or(k as u64 + 1),
                row: k + 1,
                column: sensor.column.clone(),
                message,
            },
            None => IdentError::InsufficientData {
                file: self.source.clone(),
                column: sensor.column.clone(),
                message,
            },
        }
    }

    /// An error about sample `k` (or the whole column) of column `column`.
    pub(crate) fn error(&self, column: usize, k: Option<usize>, message: String) -> IdentError {
        match k {
            Some(k) if self.row_word == "element" => IdentError::BadElement {
                file: self.source.clone(),
                variable: self.columns[column].clone(),
                element: k + 1,
                message,
            },
            Some(k) => IdentError::BadCell {
                file: self.source.clone(),
                line: self.rows.get(k).copied().unwrap_or(k as u64 + 1),
                row: k + 1,
                column: self.columns[column].clone(),
                message,
            },
            None => IdentError::InsufficientData {
                file: self.source.clone(),
                column: self.columns[column].clone(),
                message,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp(n: usize) -> Vec<f64> {
        (0..n).map(|k| k as f64 * 1e-4).collect()
    }

    #[test]
    fn bad_arrays_are_named_by_column_and_row() {
        let n = 50;
        let ok = Record::from_arrays("<array>", ramp(n), vec![0.0; n], vec![0.0; n]);
        assert!(ok.is_ok());
        let mut time = ramp(n);
        time[7] = time[6];
        let e = Record::from_arrays("<array>", time, vec![0.0; n], vec![0.0; n])
            .unwrap_err()
            .to_string();
        assert!(e.contains("element 8") && e.contains("'t'"), "{e}");
        let mut force = vec![0.0; n];
        force[3] = f64::NAN;
        let e = Record::from_arrays("<array>", ramp(n), force, vec![0.0; n])
            .unwrap_err()
            .to_string();
        assert!(e.contains("element 4") && e.contains("'force'"), "{e}");
        let e = Record::from_arrays("<array>", ramp(n), vec![0.0; n - 1], vec![0.0; n])
            .unwrap_err()
            .to_string();
        assert!(e.contains("49 values against 50"), "{e}");
        let e = Record::from_arrays("<array>", ramp(5), vec![0.0; 5], vec![0.0; 5])
            .unwrap_err()
            .to_string();
        assert!(e.contains("at least 20"), "{e}");
    }
}

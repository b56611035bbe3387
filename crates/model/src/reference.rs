//! Reference trajectories for the servo: constant, step, sine, smooth
//! point-to-point and a CSV time series. Each gives position and velocity at any
//! time, and the times where it is not smooth so that an engine can restart there.

use std::path::Path;

use crate::error::LoadError;

/// Position (m) and velocity (m/s) of the reference at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReferenceSample {
    /// Reference position, m.
    pub position: f64,
    /// Reference velocity, m/s.
    pub velocity: f64,
}

/// A reference trajectory x_r(t).
#[derive(Debug, Clone, PartialEq)]
pub enum Reference {
    /// x_r = value.
    Constant {
        /// Position, m.
        value: f64,
    },
    /// x_r = initial before `time`, `value` from then on.
    Step {
        /// Switching time, s.
        time: f64,
        /// Position before the step, m.
        initial: f64,
        /// Position after the step, m.
        value: f64,
    },
    /// x_r = initial before `start`, then initial + velocity (t - start): a
    /// constant-velocity traverse.
    Ramp {
        /// Start time, s.
        start: f64,
        /// Position before the start, m.
        initial: f64,
        /// Traverse velocity, m/s.
        velocity: f64,
    },
    /// x_r = offset + amplitude sin(2 pi frequency t + phase).
    Sine {
        /// Amplitude, m.
        amplitude: f64,
        /// Frequency, Hz.
        frequency_hz: f64,
        /// Phase, rad.
        phase: f64,
        /// Offset, m.
        offset: f64,
    },
    /// A move of `distance` starting at `start` lasting `duration`, with the
    /// minimum-jerk (quintic) profile: zero velocity and acceleration at both ends.
    PointToPoint {
        /// Start time, s.
        start: f64,
        /// Move time, s.
        duration: f64,
        /// Position before the move, m.
        initial: f64,
        /// Signed move length, m.
        distance: f64,
    },
    /// A sampled trajectory, interpolated by piecewise cubic Hermite polynomials
    /// with centred-difference slopes (continuous position and velocity), held
    /// constant outside the samples.
    Samples {
        /// Strictly increasing times, s.
        times: Vec<f64>,
        /// Positions, m.
        positions: Vec<f64>,
    },
}

impl Default for Reference {
    fn default() -> Self {
        Self::Constant { value: 0.0 }
    }
}

impl Reference {
    /// Position and velocity at time t.
    pub fn sample(&self, t: f64) -> ReferenceSample {
        match *self {
            Self::Constant { value } => ReferenceSample {
                position: value,
                velocity: 0.0,
            },
            Self::Step {
                time,
                initial,
                value,
            } => ReferenceSample {
                position: if t < time { initial } else { value },
                velocity: 0.0,
            },
            Self::Ramp {
                start,
                initial,
                velocity,
            } => {
                if t < start {
                    ReferenceSample {
                        position: initial,
                        velocity: 0.0,
                    }
                } else {
                    ReferenceSample {
                        position: initial + velocity * (t - start),
                        velocity,
                    }
                }
            }
            Self::Sine {
                amplitude,
                frequency_hz,
                phase,
                offset,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency_hz;
                let angle = w * t + phase;
                ReferenceSample {
                    position: offset + amplitude * angle.sin(),
                    velocity: amplitude * w * angle.cos(),
                }
            }
            Self::PointToPoint {
                start,
                duration,
                initial,
                distance,
            } => {
                let tau = ((t - start) / duration).clamp(0.0, 1.0);
                let shape = tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
                let slope = 30.0 * tau * tau * (1.0 - tau) * (1.0 - tau);
                ReferenceSample {
                    position: initial + distance * shape,
                    velocity: distance * slope / duration,
                }
            }
            Self::Samples {
                ref times,
                ref positions,
            } => hermite_sample(times, positions, t),
        }
    }

    /// The velocity the reference settles to (a ramp's slope; 0 otherwise):
    /// the stage's steady traverse velocity.
    pub fn traverse_velocity(&self) -> f64 {
        match *self {
            Self::Ramp { velocity, .. } => velocity,
            _ => 0.0,
        }
    }

    /// Times at which the reference or its velocity jumps.
    pub fn breakpoints(&self) -> Vec<f64> {
        match *self {
            Self::Step { time, .. } => vec![time],
            Self::Ramp { start, .. } => vec![start],
            Self::PointToPoint {
                start, duration, ..
            } => vec![start, start + duration],
            Self::Samples { ref times, .. } => {
                let mut ends = Vec::new();
                if let (Some(&first), Some(&last)) = (times.first(), times.last()) {
                    ends.extend([first, last]);
                }
                ends
            }
            _ => Vec::new(),
        }
    }

    /// Reads a two-column time series. Column names carry units as suffixes
    /// (`time_s`, `time_ms`, `position_m`, `position_mm`, `position_um`,
    /// `position_nm`); a bare `time` is seconds and a bare `position` is metres.
    pub fn from_csv(
        path: &Path,
        time_column: &str,
        position_column: &str,
    ) -> Result<Self, LoadError> {
        let bad = |at: String, message: String| LoadError::Data {
            file: path.to_path_buf(),
            at,
            message,
        };
        let text = crate::input::read_text(path, crate::input::MAX_DATA_BYTES)
            .map_err(|e| bad("file".into(), format!("cannot read: {e}")))?;
        let mut reader = csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let headers = reader
            .headers()
            .map_err(|e| bad("header".into(), e.to_string()))?
            .clone();
        let find = |wanted: &str| -> Result<(usize, f64), LoadError> {
            headers
                .iter()
                .enumerate()
                .find_map(|(i, h)| unit_scale(h, wanted).map(|s| (i, s)))
                .ok_or_else(|| {
                    bad(
                        format!("column \"{wanted}\""),
                        format!(
                            "not found (columns: {}); name it {wanted}, {wanted}_s/_ms for time or {wanted}_m/_mm/_um/_nm for position",
                            headers.iter().collect::<Vec<_>>().join(", ")
                        ),
                    )
                })
        };
        let (time_index, time_scale) = find(time_column)?;
        let (position_index, position_scale) = find(position_column)?;
        let mut times = Vec::new();
        let mut positions = Vec::new();
        for (row, record) in reader.records().enumerate() {
            let row_number = row + 2; // 1-based line number, after the header line
            let record = record.map_err(|e| bad(format!("line {row_number}"), e.to_string()))?;
            let cell = |index: usize, name: &str| -> Result<f64, LoadError> {
                let text = record.get(index).unwrap_or("");
                text.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        bad(
                            format!("line {row_number}, column \"{name}\""),
                            format!("\"{text}\" is not a finite number"),
                        )
                    })
            };
            let t = cell(time_index, &headers[time_index])? * time_scale;
            if let Some(&previous) = times.last()
                && t <= previous
            {
                return Err(bad(
                    format!("line {row_number}, column \"{}\"", &headers[time_index]),
                    format!("times must increase strictly, {t} follows {previous}"),
                ));
            }
            times.push(t);
            positions.push(cell(position_index, &headers[position_index])? * position_scale);
        }
        if times.len() < 2 {
            return Err(bad("file".into(), "needs at least two samples".into()));
        }
        Ok(Self::Samples { times, positions })
    }
}

/// Scale to SI if `header` is `base` or `base_<unit>` with a known unit.
fn unit_scale(header: &str, base: &str) -> Option<f64> {
    if header == base {
        return Some(1.0);
    }
    let unit = header.strip_prefix(base)?.strip_prefix('_')?;
    match unit {
        "s" | "m" => Some(1.0),
        "ms" | "mm" => Some(1e-3),
        "us" | "um" => Some(1e-6),
        "nm" => Some(1e-9),
        _ => None,
    }
}

fn hermite_sample(times: &[f64], positions: &[f64], t: f64) -> ReferenceSample {
    let n = times.len();
    if n == 0 {
        return ReferenceSample::default();
    }
    if t <= times[0] || n == 1 {
        return ReferenceSample {
            position: positions[0],
            velocity: 0.0,
        };
    }
    if t >= times[n - 1] {
        return ReferenceSample {
            position: positions[n - 1],
            velocity: 0.0,
        };
    }
    let i = times.partition_point(|&ti| ti <= t) - 1;
    let slope = |k: usize| -> f64 {
        let lo = k.saturating_sub(1);
        let hi = (k + 1).min(n - 1);
        (positions[hi] - positions[lo]) / (times[hi] - times[lo])
    };
    let (t0, t1) = (times[i], times[i + 1]);
    let h = t1 - t0;
    let s = (t - t0) / h;
    let (p0, p1, m0, m1) = (
        positions[i],
        positions[i + 1],
        slope(i) * h,
        slope(i + 1) * h,
    );
    let s2 = s * s;
    let s3 = s2 * s;
    let position = (2.0 * s3 - 3.0 * s2 + 1.0) * p0
        + (s3 - 2.0 * s2 + s) * m0
        + (-2.0 * s3 + 3.0 * s2) * p1
        + (s3 - s2) * m1;
    let derivative = (6.0 * s2 - 6.0 * s) * p0
        + (3.0 * s2 - 4.0 * s + 1.0) * m0
        + (-6.0 * s2 + 6.0 * s) * p1
        + (3.0 * s2 - 2.0 * s) * m1;
    ReferenceSample {
        position,
        velocity: derivative / h,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn numeric_velocity(reference: &Reference, t: f64) -> f64 {
        let h = 1e-6;
        (reference.sample(t + h).position - reference.sample(t - h).position) / (2.0 * h)
    }

    #[test]
    fn velocities_are_derivatives_of_positions() {
        let references = [
            Reference::Sine {
                amplitude: 1e-3,
                frequency_hz: 0.1,
                phase: 0.3,
                offset: 2e-3,
            },
            Reference::PointToPoint {
                start: 0.1,
                duration: 0.5,
                initial: 1e-3,
                distance: -5e-3,
            },
            Reference::Samples {
                times: vec![0.0, 0.1, 0.3, 0.4, 1.0],
                positions: vec![0.0, 1e-3, 0.5e-3, 2e-3, 2e-3],
            },
        ];
        for reference in &references {
            for k in 1..100 {
                let t = 0.0101 * k as f64;
                let analytic = reference.sample(t).velocity;
                let numeric = numeric_velocity(reference, t);
                assert!(
                    (analytic - numeric).abs() < 1e-6 * (1.0 + analytic.abs()),
                    "{reference:?} at t = {t}: {analytic} vs {numeric}"
                );
            }
        }
    }

    #[test]
    fn point_to_point_reaches_target_smoothly() {
        let reference = Reference::PointToPoint {
            start: 1.0,
            duration: 0.2,
            initial: 0.0,
            distance: 1e-3,
        };
        assert_eq!(reference.sample(0.5).position, 0.0);
        assert!((reference.sample(1.1).position - 0.5e-3).abs() < 1e-15);
        assert!((reference.sample(1.2).position - 1e-3).abs() < 1e-15);
        assert!(reference.sample(1.2).velocity.abs() < 1e-20);
        assert_eq!(reference.sample(1.3).velocity, 0.0);
        let breakpoints = reference.breakpoints();
        assert_eq!(breakpoints[0], 1.0);
        assert!((breakpoints[1] - 1.2).abs() < 1e-15);
    }

    #[test]
    fn samples_interpolate_through_the_data() {
        let times = vec![0.0, 0.5, 1.0, 2.0];
        let positions = vec![0.0, 1.0, -1.0, 3.0];
        let reference = Reference::Samples {
            times: times.clone(),
            positions: positions.clone(),
        };
        for (t, p) in times.iter().zip(&positions) {
            assert!((reference.sample(*t).position - p).abs() < 1e-12);
        }
    }

    #[test]
    fn unit_suffixes() {
        assert_eq!(unit_scale("position_mm", "position"), Some(1e-3));
        assert_eq!(unit_scale("time", "time"), Some(1.0));
        assert_eq!(unit_scale("time_ms", "time"), Some(1e-3));
        assert_eq!(unit_scale("position_furlong", "position"), None);
        assert_eq!(unit_scale("positions", "position"), None);
    }
}

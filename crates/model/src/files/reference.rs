//! Reference trajectories for the servo: constant, step, sine, smooth
//! point-to-point and a CSV time series. Each gives position and velocity at any
//! time, and the times where it is not smooth so that an engine can restart there.

use crate::rule::Rule;
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
    /// The x axis of a circle test: x_r = R sin(v t / R), the tangential
    /// velocity v reversing the x motion every half turn (the quadrant glitches
    /// of a circle test happen there).
    Circle {
        /// Radius R, m.
        radius: f64,
        /// Tangential velocity v, m/s.
        tangential_velocity: f64,
    },
    /// A staircase of `steps` point-to-point moves of `step` each, the first
    /// starting at `start`, each lasting `move_time` and followed by a rest of
    /// `dwell`.
    Staircase {
        /// Start of the first move, s.
        start: f64,
        /// Position before the first move, m.
        initial: f64,
        /// Signed length of every move, m.
        step: f64,
        /// Duration of every move, s.
        move_time: f64,
        /// Rest after every move, s.
        dwell: f64,
        /// Number of moves.
        steps: usize,
        /// Shape of every move.
        profile: MoveProfile,
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

/// The shape of a point-to-point move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MoveProfile {
    /// Quintic: zero velocity and acceleration at both ends.
    MinimumJerk,
    /// Constant acceleration over the first quarter of the move, constant
    /// velocity over the middle half, constant deceleration over the last quarter.
    Trapezoidal,
}

impl MoveProfile {
    /// (fraction of the distance, its rate per unit of normalised time) at
    /// normalised time tau in [0, 1].
    fn shape(self, tau: f64) -> (f64, f64) {
        match self {
            Self::MinimumJerk => (
                tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau),
                30.0 * tau * tau * (1.0 - tau) * (1.0 - tau),
            ),
            Self::Trapezoidal => {
                // Peak rate 4/3 reached at tau = 1/4, held to 3/4.
                let peak = 4.0 / 3.0;
                if tau < 0.25 {
                    (0.5 * peak * tau * tau / 0.25, peak * tau / 0.25)
                } else if tau <= 0.75 {
                    (peak * (tau - 0.125), peak)
                } else {
                    let rest = 1.0 - tau;
                    (1.0 - 0.5 * peak * rest * rest / 0.25, peak * rest / 0.25)
                }
            }
        }
    }

    /// Normalised times where the acceleration jumps.
    fn corners(self) -> &'static [f64] {
        match self {
            Self::MinimumJerk => &[],
            Self::Trapezoidal => &[0.25, 0.75],
        }
    }
}

impl Default for Reference {
    fn default() -> Self {
        Self::Constant { value: 0.0 }
    }
}

impl Reference {
    /// The rule of a number key of `[reference]` (the same for every kind
    /// that takes it).
    pub fn key_rule(key: &str) -> Rule {
        match key {
            "time" | "start" | "dwell" => Rule::NonNegative,
            "frequency" | "duration" | "radius" | "move_time" | "steps" => Rule::Positive,
            _ => Rule::Finite,
        }
    }

    /// The number keys of this reference with their values, to read and
    /// write through the parameter table (a staircase's `steps` and the
    /// samples of a `csv` reference are not numbers to tune).
    pub fn numbers_mut(&mut self) -> Vec<(&'static str, &mut f64)> {
        match self {
            Self::Constant { value } => vec![("value", value)],
            Self::Step {
                time,
                initial,
                value,
            } => vec![("time", time), ("initial", initial), ("value", value)],
            Self::Ramp {
                start,
                initial,
                velocity,
            } => vec![
                ("start", start),
                ("initial", initial),
                ("velocity", velocity),
            ],
            Self::Sine {
                amplitude,
                frequency_hz,
                phase,
                offset,
            } => vec![
                ("amplitude", amplitude),
                ("frequency", frequency_hz),
                ("phase", phase),
                ("offset", offset),
            ],
            Self::PointToPoint {
                start,
                duration,
                initial,
                distance,
            } => vec![
                ("start", start),
                ("duration", duration),
                ("initial", initial),
                ("distance", distance),
            ],
            Self::Circle {
                radius,
                tangential_velocity,
            } => vec![
                ("radius", radius),
                ("tangential_velocity", tangential_velocity),
            ],
            Self::Staircase {
                start,
                initial,
                step,
                move_time,
                dwell,
                ..
            } => vec![
                ("start", start),
                ("initial", initial),
                ("step", step),
                ("move_time", move_time),
                ("dwell", dwell),
            ],
            Self::Samples { .. } => Vec::new(),
        }
    }

    /// The value of a number key (see [`Self::numbers_mut`]).
    pub fn number(&self, key: &str) -> Option<f64> {
        self.numbers()
            .into_iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v)
    }

    /// The number keys of this reference.
    pub fn number_keys(&self) -> Vec<&'static str> {
        self.numbers().into_iter().map(|(k, _)| k).collect()
    }

    /// The number keys with their values (a sampled reference, which has
    /// none, is not copied to find that out).
    fn numbers(&self) -> Vec<(&'static str, f64)> {
        if matches!(self, Self::Samples { .. }) {
            return Vec::new();
        }
        (self.clone().numbers_mut().into_iter())
            .map(|(k, v)| (k, *v))
            .collect()
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
            Self::Circle {
                radius,
                tangential_velocity,
            } => {
                let angle = tangential_velocity * t / radius;
                ReferenceSample {
                    position: radius * angle.sin(),
                    velocity: tangential_velocity * angle.cos(),
                }
            }
            Self::Staircase {
                start,
                initial,
                step,
                move_time,
                dwell,
                steps,
                profile,
            } => {
                let period = move_time + dwell;
                let since = t - start;
                if since <= 0.0 {
                    return ReferenceSample {
                        position: initial,
                        velocity: 0.0,
                    };
                }
                let k = ((since / period).floor() as usize).min(steps);
                if k == steps {
                    return ReferenceSample {
                        position: initial + step * steps as f64,
                        velocity: 0.0,
                    };
                }
                let tau = ((since - k as f64 * period) / move_time).min(1.0);
                let (fraction, rate) = profile.shape(tau);
                ReferenceSample {
                    position: initial + step * (k as f64 + fraction),
                    velocity: if tau < 1.0 {
                        step * rate / move_time
                    } else {
                        0.0
                    },
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
            Self::Staircase {
                start,
                move_time,
                dwell,
                steps,
                profile,
                ..
            } => (0..steps)
                .flat_map(|k| {
                    let begin = start + k as f64 * (move_time + dwell);
                    std::iter::once(begin)
                        .chain(profile.corners().iter().map(move |c| begin + c * move_time))
                        .chain(std::iter::once(begin + move_time))
                })
                .collect(),
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

    /// The velocity of a reference is the derivative of its position
    /// (central differences), away from its breakpoints.
    fn assert_consistent(reference: &Reference, t_end: f64) {
        let breaks = reference.breakpoints();
        let h = 1e-7;
        for i in 1..2000 {
            let t = t_end * i as f64 / 2000.0;
            if breaks.iter().any(|b| (b - t).abs() < 10.0 * h) {
                continue;
            }
            let slope =
                (reference.sample(t + h).position - reference.sample(t - h).position) / (2.0 * h);
            let v = reference.sample(t).velocity;
            assert!(
                (slope - v).abs() <= 1e-6 * v.abs().max(1e-3),
                "t = {t}: {slope} vs {v}"
            );
        }
    }

    #[test]
    fn a_circle_test_reverses_at_each_half_turn() {
        let circle = Reference::Circle {
            radius: 0.02,
            tangential_velocity: 0.05,
        };
        let quarter = std::f64::consts::FRAC_PI_2 * 0.02 / 0.05;
        let top = circle.sample(quarter);
        assert!((top.position - 0.02).abs() < 1e-15 && top.velocity.abs() < 1e-15);
        assert!((circle.sample(0.0).velocity - 0.05).abs() < 1e-15);
        assert!(circle.sample(3.0 * quarter).position < -0.0199);
        assert_consistent(&circle, 8.0 * quarter);
    }

    #[test]
    fn a_staircase_rests_on_each_step() {
        for profile in [MoveProfile::MinimumJerk, MoveProfile::Trapezoidal] {
            let stairs = Reference::Staircase {
                start: 0.1,
                initial: 1e-3,
                step: 50e-6,
                move_time: 0.05,
                dwell: 0.2,
                steps: 4,
                profile,
            };
            for k in 0..4 {
                let resting = stairs.sample(0.1 + k as f64 * 0.25 + 0.1);
                let expected = 1e-3 + 50e-6 * (k + 1) as f64;
                assert!(
                    (resting.position - expected).abs() < 1e-15,
                    "{profile:?} step {k}"
                );
                assert_eq!(resting.velocity, 0.0);
            }
            assert_eq!(stairs.sample(0.05).position, 1e-3);
            assert!((stairs.sample(5.0).position - (1e-3 + 200e-6)).abs() < 1e-15);
            assert_consistent(&stairs, 1.2);
            let peak = (0..1000)
                .map(|i| stairs.sample(0.1 + 0.05 * i as f64 / 1000.0).velocity)
                .fold(0.0, f64::max);
            let expected = match profile {
                MoveProfile::MinimumJerk => 1.875 * 50e-6 / 0.05,
                MoveProfile::Trapezoidal => 4.0 / 3.0 * 50e-6 / 0.05,
            };
            assert!(
                (peak - expected).abs() < 1e-3 * expected,
                "{profile:?}: {peak} vs {expected}"
            );
        }
        let trapezoid = Reference::Staircase {
            start: 0.0,
            initial: 0.0,
            step: 1.0,
            move_time: 1.0,
            dwell: 1.0,
            steps: 2,
            profile: MoveProfile::Trapezoidal,
        };
        assert_eq!(
            trapezoid.breakpoints(),
            vec![0.0, 0.25, 0.75, 1.0, 2.0, 2.25, 2.75, 3.0]
        );
    }
}

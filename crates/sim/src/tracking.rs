//! Tracking metrics of a servo run, as `summary.json` reports them: the RMS
//! tracking error over the statistics window; the peak error around each
//! velocity reversal of the reference (the quadrant glitch of a circle test);
//! and, for a staircase reference, the settling time of each step: from the
//! end of the move (when the reference comes to rest) until the error enters
//! the band of +-`settle_window` around zero for good (until the next move);
//! 0 when it is inside by the time the move ends. Each list comes with its mean
//! and standard deviation.

use fistage_model::reference::Reference;
use serde::Serialize;

use crate::trajectory::SignalTable;

/// Values with their mean and (population) standard deviation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Spread {
    /// One value per event, in time order.
    pub values: Vec<f64>,
    /// Mean (NaN-free: `None` without values).
    pub mean: Option<f64>,
    /// Standard deviation about the mean.
    pub std: Option<f64>,
}

impl Spread {
    fn of(values: Vec<f64>) -> Self {
        let n = values.len() as f64;
        let mean = (!values.is_empty()).then(|| values.iter().sum::<f64>() / n);
        let std = mean.map(|m| (values.iter().map(|v| (v - m).powi(2)).sum::<f64>() / n).sqrt());
        Self { values, mean, std }
    }
}

/// Settling times of a staircase's steps.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settling {
    /// Half-width of the band, m.
    pub window_m: f64,
    /// Settling times of the steps that settled, s.
    #[serde(flatten)]
    pub times: Spread,
    /// Steps (wholly inside the run) that never settled before the next move.
    pub unsettled: usize,
}

/// The tracking metrics of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackingMetrics {
    /// RMS of the tracking error over the statistics window, m.
    pub rms_error: f64,
    /// Largest |error| around each velocity reversal of the reference, m.
    pub reversal_peak_error: Spread,
    /// With a staircase reference: each step's settling time.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settling: Option<Settling>,
}

/// The metrics of a run whose signals include `controller.error` (a run
/// with a servo); `None` without it.
pub fn tracking_metrics(
    reference: &Reference,
    table: &SignalTable,
    window: [f64; 2],
    settle_window: f64,
) -> Option<TrackingMetrics> {
    let error = table.column("controller.error")?;
    let times = &table.times;
    let in_window: Vec<f64> = times
        .iter()
        .zip(error)
        .filter(|(t, _)| **t >= window[0] && **t <= window[1])
        .map(|(_, e)| *e)
        .collect();
    let rms_error = if in_window.is_empty() {
        f64::NAN
    } else {
        (in_window.iter().map(|e| e * e).sum::<f64>() / in_window.len() as f64).sqrt()
    };
    Some(TrackingMetrics {
        rms_error,
        reversal_peak_error: Spread::of(reversal_peaks(reference, times, error)),
        settling: settling(reference, times, error, settle_window),
    })
}

/// Times where the reference velocity changes sign (between samples).
fn reversals(reference: &Reference, times: &[f64]) -> Vec<f64> {
    let mut found = Vec::new();
    let mut last_sign = 0.0;
    for pair in times.windows(2) {
        let v = reference.sample(pair[1]).velocity;
        let sign = if v > 0.0 {
            1.0
        } else if v < 0.0 {
            -1.0
        } else {
            0.0
        };
        if sign != 0.0 {
            if last_sign != 0.0 && sign != last_sign {
                found.push(0.5 * (pair[0] + pair[1]));
            }
            last_sign = sign;
        }
    }
    found
}

/// The peak |error| within a quarter of the gap to the neighbouring
/// reversals (or to the run's start and end) around each reversal whose
/// neighbourhood lies wholly inside the run.
fn reversal_peaks(reference: &Reference, times: &[f64], error: &[f64]) -> Vec<f64> {
    let (Some(&first), Some(&last)) = (times.first(), times.last()) else {
        return Vec::new();
    };
    let at = reversals(reference, times);
    let mut peaks = Vec::new();
    for (k, &t) in at.iter().enumerate() {
        let before = if k == 0 { t - first } else { t - at[k - 1] };
        let after = at.get(k + 1).map_or(last - t, |next| next - t);
        let reach = 0.25 * before.min(after);
        if reach <= 0.0 || t + reach > last {
            continue;
        }
        let peak = times
            .iter()
            .zip(error)
            .filter(|(s, _)| (**s - t).abs() <= reach)
            .map(|(_, e)| e.abs())
            .fold(0.0, f64::max);
        peaks.push(peak);
    }
    peaks
}

fn settling(reference: &Reference, times: &[f64], error: &[f64], band: f64) -> Option<Settling> {
    let Reference::Staircase {
        start,
        move_time,
        dwell,
        steps,
        ..
    } = *reference
    else {
        return None;
    };
    let end = *times.last()?;
    let period = move_time + dwell;
    let mut settled = Vec::new();
    let mut unsettled = 0;
    for k in 0..steps {
        let begin = start + k as f64 * period;
        let next = begin + period;
        if next > end + 1e-12 {
            break;
        }
        // The last sample of the step outside the band; settled at the
        // sample after it, counted from the end of the move.
        let arrival = begin + move_time;
        let samples: Vec<(f64, f64)> = times
            .iter()
            .zip(error)
            .filter(|(t, _)| **t >= begin && **t < next)
            .map(|(t, e)| (*t, *e))
            .collect();
        match samples.iter().rposition(|(_, e)| e.abs() > band) {
            None => settled.push(0.0),
            Some(i) if i + 1 < samples.len() => {
                settled.push((samples[i + 1].0 - arrival).max(0.0));
            }
            Some(_) => unsettled += 1,
        }
    }
    Some(Settling {
        window_m: band,
        times: Spread::of(settled),
        unsettled,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use fistage_model::reference::MoveProfile;

    fn table(times: Vec<f64>, error: Vec<f64>) -> SignalTable {
        SignalTable {
            names: vec!["controller.error".into()],
            units: vec!["m".into()],
            times,
            columns: vec![error],
        }
    }

    /// A circle at v = 0.05 m/s, R = 0.02 m reverses every pi R / v; an
    /// error spike placed at each reversal is the peak found there.
    #[test]
    fn reversal_peaks_sit_at_the_half_turns() {
        let circle = Reference::Circle {
            radius: 0.02,
            tangential_velocity: 0.05,
        };
        let half = std::f64::consts::PI * 0.02 / 0.05;
        let times: Vec<f64> = (0..=40_000).map(|i| i as f64 * 1e-4).collect();
        let error: Vec<f64> = times
            .iter()
            .map(|&t| {
                let k = ((t / half - 0.5).round() + 0.5) * half;
                if (t - k).abs() < 2e-4 {
                    1e-6 * (1.0 + (k / half).floor())
                } else {
                    1e-9
                }
            })
            .collect();
        let metrics =
            tracking_metrics(&circle, &table(times, error), [0.0, 4.0], 5e-8).expect("metrics");
        // Reversals at 0.5, 1.5, 2.5 half periods (1.26 s apart) fit in 4 s.
        assert_eq!(metrics.reversal_peak_error.values.len(), 3, "{metrics:?}");
        for (k, peak) in metrics.reversal_peak_error.values.iter().enumerate() {
            assert!((peak - 1e-6 * (k + 1) as f64).abs() < 1e-12, "{k}: {peak}");
        }
        assert!((metrics.reversal_peak_error.mean.unwrap() - 2e-6).abs() < 1e-12);
        assert!(metrics.settling.is_none());
    }

    /// Settling times of a staircase: an error decaying as e^{-t/tau} from
    /// each move start enters the band at tau ln(e0 / band), which is that
    /// time less the move time after the move's end (0 when sooner).
    #[test]
    fn staircase_steps_settle_when_the_error_stays_in_the_band() {
        let stairs = Reference::Staircase {
            start: 0.0,
            initial: 0.0,
            step: 50e-6,
            move_time: 0.05,
            dwell: 0.25,
            steps: 3,
            profile: MoveProfile::MinimumJerk,
        };
        let tau = [0.01, 0.02, 1.0];
        let times: Vec<f64> = (0..=9000).map(|i| i as f64 * 1e-4).collect();
        let error: Vec<f64> = times
            .iter()
            .map(|&t| {
                let k = ((t / 0.3).floor() as usize).min(2);
                1e-6 * (-(t - 0.3 * k as f64) / tau[k]).exp()
            })
            .collect();
        let metrics =
            tracking_metrics(&stairs, &table(times, error), [0.0, 0.9], 5e-8).expect("metrics");
        let settling = metrics.settling.expect("a staircase");
        assert_eq!(settling.times.values.len(), 2);
        assert_eq!(
            settling.unsettled, 1,
            "tau = 1 s never settles within 0.3 s"
        );
        for (k, t) in settling.times.values.iter().enumerate() {
            let expected = (tau[k] * (1e-6f64 / 5e-8).ln() - 0.05).max(0.0);
            assert!(
                (t - expected).abs() <= 1.5e-4,
                "step {k}: {t} vs {expected}"
            );
        }
    }
}

//! The statistics of a tolerance analysis: a probability with its Wilson
//! score interval, empirical quantiles, and Spearman's rank correlation (the
//! sensitivity measure: how monotonically a parameter drives the outcome).

use serde::Serialize;

/// z of a two-sided 95% normal interval.
const Z95: f64 = 1.959_963_984_540_054;

/// A probability estimated from `n` trials.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Probability {
    /// Successes / trials (0 when there are no trials).
    pub estimate: f64,
    /// Wilson score 95% interval.
    pub ci95: [f64; 2],
    /// Trials.
    pub n: usize,
}

impl Probability {
    /// `k` of `n`, with the Wilson score interval (the whole [0, 1] for no
    /// trials). It keeps its coverage at small n and at p near 0 or 1, where
    /// the normal approximation collapses to a point.
    pub fn of(k: usize, n: usize) -> Self {
        if n == 0 {
            return Self {
                estimate: 0.0,
                ci95: [0.0, 1.0],
                n,
            };
        }
        let (k, nf) = (k as f64, n as f64);
        let p = k / nf;
        let z2 = Z95 * Z95;
        let centre = (p + z2 / (2.0 * nf)) / (1.0 + z2 / nf);
        let half = Z95 / (1.0 + z2 / nf) * (p * (1.0 - p) / nf + z2 / (4.0 * nf * nf)).sqrt();
        Self {
            estimate: p,
            ci95: [(centre - half).max(0.0), (centre + half).min(1.0)],
            n,
        }
    }
}

impl Probability {
    /// `k` of `n` determined trials, with `unknown` more trials whose outcome
    /// could not be determined: the estimate is over the determined ones, and
    /// the interval spans every way the unknown ones could have gone (from
    /// the Wilson lower end with none of them counted to the upper end with
    /// all of them), so it never claims more than the data back. With no
    /// unknown trials it is [`Probability::of`].
    pub fn with_unknown(k: usize, n: usize, unknown: usize) -> Self {
        if unknown == 0 {
            return Self::of(k, n);
        }
        let all = n + unknown;
        Self {
            estimate: if n == 0 { 0.0 } else { k as f64 / n as f64 },
            ci95: [Self::of(k, all).ci95[0], Self::of(k + unknown, all).ci95[1]],
            n,
        }
    }
}

/// The empirical quantile q in [0, 1] of sorted values (linear
/// interpolation between order statistics); `None` for no values.
pub fn quantile(sorted: &[f64], q: f64) -> Option<f64> {
    let last = sorted.len().checked_sub(1)?;
    let position = q.clamp(0.0, 1.0) * last as f64;
    let (below, t) = (position.floor() as usize, position.fract());
    let above = (below + 1).min(last);
    Some(sorted[below] + t * (sorted[above] - sorted[below]))
}

/// Ranks of values (1-based), ties sharing their mean rank.
fn ranks(values: &[f64]) -> Vec<f64> {
    let mut order: Vec<usize> = (0..values.len()).collect();
    order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
    let mut ranks = vec![0.0; values.len()];
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && values[order[end]] == values[order[start]] {
            end += 1;
        }
        let mean_rank = (start + end + 1) as f64 / 2.0;
        for &i in &order[start..end] {
            ranks[i] = mean_rank;
        }
        start = end;
    }
    ranks
}

/// Spearman's rank correlation of paired values; `None` with fewer than
/// three pairs or when either side is constant.
pub fn spearman(x: &[f64], y: &[f64]) -> Option<f64> {
    if x.len() != y.len() || x.len() < 3 {
        return None;
    }
    let (rx, ry) = (ranks(x), ranks(y));
    let mean = (x.len() as f64 + 1.0) / 2.0;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in rx.iter().zip(&ry) {
        sxy += (a - mean) * (b - mean);
        sxx += (a - mean) * (a - mean);
        syy += (b - mean) * (b - mean);
    }
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Textbook values of the Wilson interval: 0 of 10, 5 of 10, 1 of 1000.
    #[test]
    fn wilson_intervals() {
        let p = Probability::of(0, 10);
        assert_eq!(p.ci95[0], 0.0);
        assert!((p.ci95[1] - 0.277_532).abs() < 1e-5, "{:?}", p.ci95);
        let p = Probability::of(5, 10);
        assert!((p.ci95[0] - 0.236_593).abs() < 1e-5 && (p.ci95[1] - 0.763_407).abs() < 1e-5);
        let p = Probability::of(1, 1000);
        assert!((p.ci95[0] - 0.000_176_6).abs() < 1e-6, "{:?}", p.ci95);
        assert!((p.ci95[1] - 0.005_642_6).abs() < 1e-6, "{:?}", p.ci95);
        assert_eq!(Probability::of(0, 0).ci95, [0.0, 1.0]);
    }

    /// Over many binomial experiments the 95% interval covers the true p
    /// about 95% of the time (Wilson is close to nominal at n = 200, p = 0.1).
    #[test]
    fn wilson_coverage_is_near_nominal() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha12Rng::seed_from_u64(5);
        let (p, n, experiments) = (0.1, 200, 4000);
        let covered = (0..experiments)
            .filter(|_| {
                let k = (0..n).filter(|_| rng.random::<f64>() < p).count();
                let ci = Probability::of(k, n).ci95;
                ci[0] <= p && p <= ci[1]
            })
            .count();
        let coverage = covered as f64 / experiments as f64;
        assert!((0.93..0.97).contains(&coverage), "coverage {coverage}");
    }

    /// Undetermined trials widen the interval to every outcome they could
    /// have had, and change nothing when there are none.
    #[test]
    fn unknown_trials_widen_the_interval() {
        assert_eq!(Probability::with_unknown(5, 10, 0), Probability::of(5, 10));
        let p = Probability::with_unknown(5, 10, 5);
        assert_eq!(p.estimate, 0.5);
        assert_eq!(p.ci95[0], Probability::of(5, 15).ci95[0]);
        assert_eq!(p.ci95[1], Probability::of(10, 15).ci95[1]);
        assert!(p.ci95[0] < Probability::of(5, 10).ci95[0]);
        assert!(p.ci95[1] > Probability::of(5, 10).ci95[1]);
    }

    #[test]
    fn quantiles_interpolate() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(quantile(&v, 0.5), Some(3.0));
        assert_eq!(quantile(&v, 0.125), Some(1.5));
        assert_eq!(quantile(&v, 1.0), Some(5.0));
        assert_eq!(quantile(&[], 0.5), None);
    }

    #[test]
    fn spearman_sees_monotone_relations_and_ties() {
        let x: Vec<f64> = (0..50).map(f64::from).collect();
        let cubic: Vec<f64> = x.iter().map(|v| (v - 20.0).powi(3)).collect();
        assert!((spearman(&x, &cubic).unwrap() - 1.0).abs() < 1e-12);
        let falling: Vec<f64> = x.iter().map(|v| -v.exp()).collect();
        assert!((spearman(&x, &falling).unwrap() + 1.0).abs() < 1e-12);
        // Known value with ties: x = 1 2 2 3, y = 1 3 2 4 -> 0.9487 (ranks 1, 2.5, 2.5, 4).
        let r = spearman(&[1.0, 2.0, 2.0, 3.0], &[1.0, 3.0, 2.0, 4.0]).unwrap();
        assert!((r - 0.948_683).abs() < 1e-5, "{r}");
        assert_eq!(spearman(&[1.0, 1.0, 1.0], &[1.0, 2.0, 3.0]), None);
    }
}

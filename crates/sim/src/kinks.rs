//! Steps that end on the friction law's kinks. The bristle rate
//! `z' = v - |v| z / g(v)` is continuous but not differentiable where a
//! contact's slip velocity `v` changes sign, so the solution's second
//! derivative jumps there. A Runge-Kutta step across such a point makes a
//! local error of order `h^2` instead of `h^(p+1)`: on a stage that sticks
//! and slips on four bearings, one attempt in five was rejected, and the
//! steps that passed carried most of the global error.
//!
//! Before each step the driver asks [`KinkPredictor::next_crossing`] where
//! the next sign change falls, from the quadratic through each contact's
//! slip velocity at the last three step ends (the start of the segment
//! counts as one), and lets the step
//! stop there. A crossing closer than a small fraction of the proposed step
//! is taken to be at the step's start; one farther than the proposed step
//! is left to a later step; a slip within a velocity tolerance of zero at
//! all three step ends is round-off around a resting contact, not a kink
//! worth a step. The error control still judges every step: a prediction
//! that misses only costs what the kink cost before.

/// Fraction of the proposed step within which a predicted crossing counts
/// as at the start of the step (no step is cut for it). A kink at a
/// fraction `f` into a step leaves an error of about `f` times that of one
/// in its middle (the first stage sees the other side of the kink), so the
/// fraction is small; a crossing predicted a little early costs one short
/// step, whose own prediction, over a short distance, is close.
const AT_START: f64 = 1e-5;

/// The slip velocities of the last three accepted step ends, in a ring.
#[derive(Debug, Clone)]
pub(crate) struct KinkPredictor {
    contacts: usize,
    times: [f64; 3],
    /// `contacts` slip velocities per recorded time, ring slot by ring slot.
    slips: Vec<f64>,
    /// The ring slot of the newest record.
    newest: usize,
    /// How many of the three are known since the last [`Self::forget`].
    known: usize,
    /// Slip velocities this small on all three records are not a kink worth a step.
    floor: f64,
}

impl KinkPredictor {
    /// A predictor for `contacts` friction contacts (none: it never cuts)
    /// that leaves alone contacts whose slip stays within `floor` of zero
    /// (round-off around a resting contact changes sign at random).
    pub(crate) fn new(contacts: usize, floor: f64) -> Self {
        Self {
            floor,
            contacts,
            times: [f64::NAN; 3],
            slips: vec![0.0; 3 * contacts],
            newest: 0,
            known: 0,
        }
    }

    /// Drops the history, as at a discontinuity of the inputs.
    pub(crate) fn forget(&mut self) {
        self.known = 0;
    }

    /// Records the slip velocities at `t`, written into the slice by
    /// `slips`; the newest record's time is not recorded again.
    pub(crate) fn record(&mut self, t: f64, slips: impl FnOnce(&mut [f64])) {
        if self.contacts == 0 || (self.known > 0 && self.times[self.newest] == t) {
            return;
        }
        self.newest = (self.newest + 1) % 3;
        self.times[self.newest] = t;
        let start = self.newest * self.contacts;
        slips(&mut self.slips[start..start + self.contacts]);
        self.known = (self.known + 1).min(3);
    }

    /// Ring slot of the record `back` steps before the newest.
    fn slot(&self, back: usize) -> usize {
        (self.newest + 3 - back) % 3
    }

    /// The slip velocities of a ring slot.
    fn slips_of(&self, slot: usize) -> &[f64] {
        &self.slips[slot * self.contacts..(slot + 1) * self.contacts]
    }

    /// Where the next step should stop for the first predicted sign change
    /// of a slip velocity within the `proposed` step, if any.
    pub(crate) fn next_crossing(&self, proposed: f64) -> Option<f64> {
        if self.known < 3 {
            return None;
        }
        let [newest, middle, oldest] = [0, 1, 2].map(|back| self.slot(back));
        let [t0, t1, t2] = [newest, middle, oldest].map(|slot| self.times[slot]);
        let (h1, h2) = (t0 - t1, t0 - t2);
        let (over_h1, over_gap, over_h2) = (1.0 / h1, 1.0 / (h2 - h1), 1.0 / h2);
        // Not before a few units in the last place of t either: a stop that
        // rounds back to t would be a step of length zero.
        let window = (AT_START * proposed).max(4.0 * f64::EPSILON * t0.abs())..proposed;
        let mut first: Option<f64> = None;
        let [newest_slips, middle_slips, oldest_slips] =
            [newest, middle, oldest].map(|slot| self.slips_of(slot));
        for ((&s0, &s1), &s2) in newest_slips.iter().zip(middle_slips).zip(oldest_slips) {
            // Newton form about the newest point, p(tau) = s0 + d1 tau +
            // d2 tau (tau + h1), that is a tau^2 + b tau + s0.
            let d1 = (s0 - s1) * over_h1;
            let a = (d1 - (s1 - s2) * over_gap) * over_h2;
            let b = d1 + a * h1;
            // |p - s0| <= (|b| + |a| P) P on [0, P]: most contacts are
            // nowhere near a sign change and stop here.
            if s0.abs() > (b.abs() + a.abs() * proposed) * proposed
                || s0.abs().max(s1.abs()).max(s2.abs()) <= self.floor
            {
                continue;
            }
            let root = quadratic_roots(a, b, s0)
                .into_iter()
                .flatten()
                .filter(|tau| window.contains(tau))
                .min_by(f64::total_cmp);
            first = match (first, root) {
                (Some(f), Some(r)) => Some(f.min(r)),
                (f, r) => f.or(r),
            };
        }
        first.map(|tau| t0 + tau).filter(|&stop| stop > t0)
    }
}

/// The real roots of `a tau^2 + b tau + c` (of `b tau + c` when `a` is 0),
/// without cancellation.
fn quadratic_roots(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
    if a == 0.0 {
        return [(b != 0.0).then(|| -c / b), None];
    }
    let discriminant = b * b - 4.0 * a * c;
    // Negative or NaN: no real root.
    if discriminant.is_nan() || discriminant < 0.0 {
        return [None, None];
    }
    let q = -0.5 * (b + b.signum() * discriminant.sqrt());
    [Some(q / a), (q != 0.0).then(|| c / q)]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn predictor_over(times: [f64; 3], slip: impl Fn(f64) -> f64) -> KinkPredictor {
        let mut predictor = KinkPredictor::new(1, 0.0);
        for t in times {
            predictor.record(t, |out| out[0] = slip(t));
        }
        predictor
    }

    #[test]
    fn a_crossing_ahead_is_predicted_to_third_order() {
        // sin(w t) - 0.3 crosses zero at asin(0.3) / w; steps of h before it.
        let w = 2.0e3;
        let root = 0.3f64.asin() / w;
        let mut errors = Vec::new();
        for h in [4e-5, 2e-5, 1e-5] {
            let t0 = root - 0.5 * h;
            let predictor = predictor_over([t0 - 2.0 * h, t0 - h, t0], |t| (w * t).sin() - 0.3);
            let stop = predictor
                .next_crossing(h)
                .expect("a crossing within the step");
            errors.push((stop - root).abs());
        }
        // Third order: halving h divides the error by about 8.
        assert!(errors[0] < 1e-2 * 4e-5, "{errors:?}");
        assert!(
            errors[1] < errors[0] / 6.0 && errors[2] < errors[1] / 6.0,
            "{errors:?}"
        );
    }

    #[test]
    fn no_cut_without_a_crossing_in_the_step() {
        let h = 1e-4;
        // Moving away from zero.
        let away = predictor_over([0.0, h, 2.0 * h], |t| 0.01 + t);
        assert_eq!(away.next_crossing(h), None);
        // A crossing three steps ahead is a later step's.
        let later = predictor_over([0.0, h, 2.0 * h], |t| 5.0 * h - t);
        assert_eq!(later.next_crossing(h), None);
        assert!(later.next_crossing(4.0 * h).is_some());
        // Resting exactly at zero (no platform motion): nothing to find.
        let resting = predictor_over([0.0, h, 2.0 * h], |_| 0.0);
        assert_eq!(resting.next_crossing(h), None);
        // At the crossing already: taken to be at the start of the step.
        let at = predictor_over([0.0, h, 2.0 * h], |t| 2.0 * h - t + 1e-7 * h);
        assert_eq!(at.next_crossing(h), None);
        // Round-off around a resting contact, within the floor: no kink.
        let mut noise = KinkPredictor::new(1, 1e-12);
        for (t, s) in [(0.0, 3e-13), (h, -2e-13), (2.0 * h, 1e-13)] {
            noise.record(t, |out| out[0] = s);
        }
        assert_eq!(noise.next_crossing(h), None);
        // Far from t = 0 a crossing closer than the spacing of floats is
        // not a stop: it would round back to t.
        let (t0, short) = (1.0e6, 1e-9);
        let mut tiny = KinkPredictor::new(1, 0.0);
        for (t, s) in [
            (t0 - 2.0 * short, 2.0 * short),
            (t0 - short, short),
            (t0, 0.0),
        ] {
            tiny.record(t, |out| out[0] = s + 1e-12);
        }
        assert_eq!(tiny.next_crossing(short), None);
        // Two points are not enough; a forgotten history neither.
        let mut short = predictor_over([0.0, h, 2.0 * h], |t| 2.5 * h - t);
        assert!(short.next_crossing(h).is_some());
        short.forget();
        short.record(3.0 * h, |out| out[0] = -0.5 * h);
        assert_eq!(short.next_crossing(h), None);
    }

    #[test]
    fn the_earliest_contact_sets_the_stop() {
        let h = 1e-4;
        let mut predictor = KinkPredictor::new(2, 0.0);
        for t in [0.0, h, 2.0 * h] {
            predictor.record(t, |out| {
                out[0] = 2.8 * h - t;
                out[1] = t - 2.4 * h;
            });
        }
        let stop = predictor
            .next_crossing(h)
            .expect("both cross within the step");
        assert!((stop - 2.4 * h).abs() < 1e-12 * h, "{stop}");
    }

    #[test]
    fn quadratic_roots_are_exact_without_cancellation() {
        let roots = quadratic_roots(1.0, -1e8, 1.0);
        let mut found: Vec<f64> = roots.into_iter().flatten().collect();
        found.sort_by(f64::total_cmp);
        assert!((found[0] - 1e-8).abs() < 1e-22, "{found:?}");
        assert!((found[1] - 1e8).abs() < 1e-6, "{found:?}");
        assert_eq!(quadratic_roots(1.0, 0.0, 1.0), [None, None]);
        assert_eq!(quadratic_roots(0.0, 2.0, -1.0), [Some(0.5), None]);
    }
}

//! Noisy synthetic data (force-sensor noise, speed ripple, encoder quantisation;
//! FRF noise on magnitude and phase): estimates within a few percent, the truth
//! inside the 95% intervals, and interval coverage over many seeds close to 95%.

use crate::common;

use common::{frf_errors, parameter_sets, stribeck_errors, stribeck_truth};
use fistage_ident::synth::{FrfSynth, StribeckSynth};
use fistage_ident::{Estimate, FrfOptions, StribeckOptions, fit_frf, fit_stribeck};

const SEEDS: u64 = 100;

/// Coverage of each parameter over the seeds, and the mean squared
/// standardised error (about 1 when the standard errors are right).
struct Coverage {
    covered: Vec<usize>,
    z2: Vec<f64>,
    trials: usize,
}

impl Coverage {
    fn new(params: usize) -> Self {
        Self {
            covered: vec![0; params],
            z2: vec![0.0; params],
            trials: 0,
        }
    }

    fn add(&mut self, estimates: &[Estimate], truth: &[f64]) {
        self.trials += 1;
        for (k, (e, t)) in estimates.iter().zip(truth).enumerate() {
            if e.covers(*t) {
                self.covered[k] += 1;
            }
            self.z2[k] += ((e.value - t) / e.std_error.unwrap()).powi(2);
        }
    }

    /// Each parameter covered in at least 88% of the trials (95% expected; with
    /// 100 trials fewer than 88 has a probability below 1%), and standard
    /// errors neither too small nor too large.
    fn check(&self, what: &str) {
        let n = self.trials as f64;
        for (k, &c) in self.covered.iter().enumerate() {
            assert!(
                c as f64 >= 0.88 * n,
                "{what}: parameter {k} covered {c} of {n}"
            );
            let mean_z2 = self.z2[k] / n;
            assert!(
                (0.6..1.6).contains(&mean_z2),
                "{what}: parameter {k} mean z^2 {mean_z2}"
            );
        }
        let mean_z2: Vec<String> = self.z2.iter().map(|z| format!("{:.2}", z / n)).collect();
        println!(
            "{what}: covered {:?} of {n}, mean z^2 {mean_z2:?}",
            self.covered
        );
    }
}

#[test]
fn noisy_stribeck_within_a_few_percent_and_inside_intervals() {
    for (name, p, _) in parameter_sets() {
        for seed in 1..=3 {
            let data = StribeckSynth::noisy(p, seed).generate();
            let fit = fit_stribeck(&data, &StribeckOptions::default()).unwrap();
            let errors = stribeck_errors(&fit, &p);
            assert!(
                errors.iter().all(|e| *e < 0.05),
                "{name} seed {seed}: {errors:?}"
            );
            for (e, t) in fit.estimates().iter().zip(stribeck_truth(&p)) {
                assert!(e.covers(t), "{name} seed {seed}: {t} outside {e:?}");
            }
            assert!(fit.residuals.r_squared > 0.999 && fit.residuals.suspected_outliers.is_empty());
        }
    }
}

#[test]
fn stribeck_interval_coverage_is_plausible() {
    for (name, p, _) in parameter_sets() {
        let mut coverage = Coverage::new(4);
        for seed in 100..100 + SEEDS {
            let data = StribeckSynth::noisy(p, seed).generate();
            let fit = fit_stribeck(&data, &StribeckOptions::default()).unwrap();
            coverage.add(&fit.estimates(), &stribeck_truth(&p));
        }
        coverage.check(&format!("stribeck {name}"));
    }
}

#[test]
fn noisy_frf_within_a_few_percent_and_inside_intervals() {
    for (name, p, mass) in parameter_sets() {
        for seed in [1, 4, 5] {
            let data = FrfSynth::noisy(&p, mass, seed).generate();
            for options in [FrfOptions::with_mass(mass), FrfOptions::default()] {
                let fit = fit_frf(&data, &options).unwrap();
                let errors = frf_errors(&fit, &p, mass);
                assert!(
                    errors.iter().all(|e| *e < 0.03),
                    "{name} seed {seed}: {errors:?}"
                );
                assert!(fit.sigma0.covers(p.sigma0) && fit.damping.covers(p.sigma1 + p.sigma2));
                assert!(fit.mass.covers(mass), "{name} seed {seed}: {:?}", fit.mass);
                let r = &fit.residuals;
                assert!(
                    r.rms_magnitude_db < 0.2 && r.rms_phase_deg.unwrap() < 1.0,
                    "{r:?}"
                );
            }
        }
    }
}

#[test]
fn frf_interval_coverage_is_plausible() {
    for (name, p, mass) in parameter_sets() {
        let truth = [p.sigma0, p.sigma1 + p.sigma2, mass];
        let mut with_phase = Coverage::new(3);
        let mut magnitude = Coverage::new(2);
        for seed in 100..100 + SEEDS {
            let data = FrfSynth::noisy(&p, mass, seed).generate();
            let fit = fit_frf(&data, &FrfOptions::default()).unwrap();
            with_phase.add(&[fit.sigma0, fit.damping, fit.mass], &truth);
            let fit = fit_frf(&data.magnitude_only(), &FrfOptions::with_mass(mass)).unwrap();
            magnitude.add(&[fit.sigma0, fit.damping], &truth[..2]);
        }
        with_phase.check(&format!("frf {name}, magnitude and phase, fitted mass"));
        magnitude.check(&format!("frf {name}, magnitude only, known mass"));
    }
}

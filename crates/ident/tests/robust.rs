//! A few gross outliers (force-sensor glitches of about f_C): plain least
//! squares is off by far more than a few percent, the robust losses (Huber, L1,
//! each a convex program per v_s) recover the parameters, and the outliers are
//! reported by line.

use crate::common;

use common::{max, parameter_sets, stribeck_errors};
use fistage_ident::synth::StribeckSynth;
use fistage_ident::{Loss, StribeckOptions, fit_stribeck};

const SEEDS: std::ops::Range<u64> = 0..6;

#[test]
fn robust_fits_succeed_where_least_squares_fails() {
    for (name, p, _) in parameter_sets() {
        for seed in SEEDS {
            let synth = StribeckSynth::noisy(p, seed).with_outliers(4, p.f_c);
            let (data, outliers) = synth.generate_with_outliers();
            let plain = fit_stribeck(&data, &StribeckOptions::default()).unwrap();
            let plain_errors = stribeck_errors(&plain, &p);
            assert!(
                max(&plain_errors) > 0.09,
                "{name} seed {seed}: L2 {plain_errors:?}"
            );
            for loss in [Loss::Huber, Loss::L1] {
                let options = StribeckOptions {
                    loss,
                    ..StribeckOptions::default()
                };
                let fit = fit_stribeck(&data, &options).unwrap();
                let errors = stribeck_errors(&fit, &p);
                println!("{name} seed {seed}: L2 {plain_errors:.3?}, {loss:?} {errors:.4?}");
                assert!(
                    max(&errors) < 0.06,
                    "{name} seed {seed} {loss:?}: {errors:?}"
                );
                assert!(
                    errors[0] < 0.01 && errors[1] < 0.01,
                    "{name} seed {seed} {loss:?}: {errors:?}"
                );
                let injected: Vec<u64> = outliers.iter().map(|&i| data.lines[i]).collect();
                assert_eq!(
                    fit.residuals.suspected_outliers, injected,
                    "{name} seed {seed} {loss:?}"
                );
            }
        }
    }
}

#[test]
fn huber_threshold_follows_the_noise() {
    let (_, p, _) = parameter_sets()[0];
    let data = StribeckSynth::noisy(p, 3)
        .with_outliers(4, p.f_c)
        .generate();
    let fit = fit_stribeck(&data, &StribeckOptions::robust()).unwrap();
    let noise = 0.01 * p.f_c;
    let delta = fit.huber_delta.unwrap();
    assert!(
        (0.8 * 1.345 * noise..1.25 * 1.345 * noise).contains(&delta),
        "delta {delta}"
    );
    assert!((0.8 * noise..1.25 * noise).contains(&fit.residuals.robust_scale));
    // A given threshold is used as is.
    let given = StribeckOptions {
        huber_delta: Some(0.1),
        ..StribeckOptions::robust()
    };
    assert_eq!(fit_stribeck(&data, &given).unwrap().huber_delta, Some(0.1));
}

#[test]
fn robust_fits_of_clean_data_are_exact_enough() {
    for (name, p, _) in parameter_sets() {
        let data = StribeckSynth::clean(p).generate();
        for loss in [Loss::Huber, Loss::L1] {
            let options = StribeckOptions {
                loss,
                ..StribeckOptions::default()
            };
            let errors = stribeck_errors(&fit_stribeck(&data, &options).unwrap(), &p);
            assert!(max(&errors) < 1e-4, "{name} {loss:?}: {errors:?}");
        }
    }
}

#[test]
fn robust_intervals_cover_the_truth_despite_outliers() {
    for (name, p, _) in parameter_sets() {
        let mut covered = 0;
        let mut total = 0;
        for seed in 10..30 {
            let data = StribeckSynth::noisy(p, seed)
                .with_outliers(4, p.f_c)
                .generate();
            let fit = fit_stribeck(&data, &StribeckOptions::robust()).unwrap();
            for (e, t) in fit.estimates().iter().zip(common::stribeck_truth(&p)) {
                total += 1;
                covered += usize::from(e.covers(t));
            }
        }
        println!("{name}: robust intervals cover {covered} of {total}");
        assert!(
            covered as f64 >= 0.85 * total as f64,
            "{name}: {covered} of {total}"
        );
    }
}

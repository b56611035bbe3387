//! The fits need no initial guess. A starting value (even an absurd one) only
//! adds a candidate to the global search, so the answer is the same.

use crate::common;

use common::{parameter_sets, rel};
use fistage_ident::synth::{FrfSynth, StribeckSynth};
use fistage_ident::{FrfOptions, FrfStart, StribeckOptions, fit_frf, fit_stribeck};

#[test]
fn stribeck_fit_ignores_absurd_starting_v_s() {
    for (name, p, _) in parameter_sets() {
        let data = StribeckSynth::noisy(p, 11).generate();
        for base in [StribeckOptions::default(), StribeckOptions::robust()] {
            let reference = fit_stribeck(&data, &base).unwrap();
            let tolerance = if base.loss == fistage_ident::Loss::L2 {
                1e-8
            } else {
                1e-4
            };
            for start in [1e-9, 1e-6, p.v_s, 1.0, 1e3] {
                let options = StribeckOptions {
                    v_s_start: Some(start),
                    ..base.clone()
                };
                let fit = fit_stribeck(&data, &options).unwrap();
                for (a, b) in fit.estimates().iter().zip(reference.estimates()) {
                    assert!(
                        rel(a.value, b.value) < tolerance,
                        "{name}, {:?}, start {start}: {} vs {}",
                        base.loss,
                        a.value,
                        b.value
                    );
                }
                // The absurd start widened the search range but did not end up at its edge.
                assert!(!fit.v_s_at_search_limit);
                assert!(fit.v_s_search[0] <= start && start <= fit.v_s_search[1]);
            }
        }
    }
}

#[test]
fn frf_fit_ignores_absurd_starts() {
    let absurd = [
        FrfStart {
            sigma0: 1.0,
            damping: 1e6,
            mass: 1e3,
        },
        FrfStart {
            sigma0: 1e12,
            damping: 1e-6,
            mass: 1e-6,
        },
        FrfStart {
            sigma0: 3.0,
            damping: 3.0,
            mass: 3.0,
        },
    ];
    for (name, p, mass) in parameter_sets() {
        let data = FrfSynth::noisy(&p, mass, 11).generate();
        for (kind, d) in [
            ("complex", data.clone()),
            ("magnitude", data.magnitude_only()),
        ] {
            for base in [FrfOptions::default(), FrfOptions::with_mass(mass)] {
                let reference = fit_frf(&d, &base).unwrap();
                for start in absurd {
                    let options = FrfOptions {
                        start: Some(start),
                        ..base.clone()
                    };
                    let fit = fit_frf(&d, &options).unwrap();
                    for (a, b) in [
                        (fit.sigma0.value, reference.sigma0.value),
                        (fit.damping.value, reference.damping.value),
                        (fit.mass.value, reference.mass.value),
                    ] {
                        assert!(rel(a, b) < 1e-8, "{name} {kind} {start:?}: {a} vs {b}");
                    }
                }
            }
        }
    }
}

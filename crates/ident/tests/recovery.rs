//! Exact synthetic data (Table 1 and a small stage) are recovered to 1e-6
//! relative, in memory and through lab-style CSV files in non-SI units.

use crate::common;

use common::{frf_errors, max, parameter_sets, stribeck_errors};
use fistage_ident::synth::{FrfCsvLayout, FrfSynth, StribeckSynth, frf_csv, stribeck_csv, unit};
use fistage_ident::{
    FrfOptions, Quantity, StribeckOptions, UnitOverrides, fit_frf, fit_stribeck, parse_frf_csv,
    parse_stribeck_csv,
};

const EXACT: f64 = 1e-6;

#[test]
fn clean_stribeck_curves_are_recovered() {
    for (name, p, _) in parameter_sets() {
        let data = StribeckSynth::clean(p).generate();
        let fit = fit_stribeck(&data, &StribeckOptions::default()).unwrap();
        let errors = stribeck_errors(&fit, &p);
        assert!(max(&errors) < EXACT, "{name}: relative errors {errors:?}");
        assert!(
            fit.residuals.rms < 1e-9 * p.f_s,
            "{name}: {:?}",
            fit.residuals
        );
        assert!(!fit.v_s_at_search_limit);
    }
}

#[test]
fn clean_stribeck_curves_survive_csv_in_lab_units() {
    for (name, p, _) in parameter_sets() {
        let data = StribeckSynth::clean(p).generate();
        for (v_unit, f_unit) in [("mm/s", "N"), ("um/s", "mN"), ("m/s", "N")] {
            let text = stribeck_csv(
                &data,
                unit(Quantity::Velocity, v_unit),
                unit(Quantity::Force, f_unit),
            );
            let read = parse_stribeck_csv("clean.csv", &text, &UnitOverrides::default()).unwrap();
            let fit = fit_stribeck(&read, &StribeckOptions::default()).unwrap();
            let errors = stribeck_errors(&fit, &p);
            assert!(
                max(&errors) < EXACT,
                "{name} in {v_unit}, {f_unit}: {errors:?}"
            );
        }
    }
}

#[test]
fn clean_frfs_are_recovered_with_known_and_fitted_mass() {
    for (name, p, mass) in parameter_sets() {
        let data = FrfSynth::clean(&p, mass).generate();
        for options in [FrfOptions::with_mass(mass), FrfOptions::default()] {
            for (kind, d) in [
                ("complex", data.clone()),
                ("magnitude", data.magnitude_only()),
            ] {
                let fit = fit_frf(&d, &options).unwrap();
                let errors = frf_errors(&fit, &p, mass);
                assert!(
                    max(&errors) < EXACT,
                    "{name}, {kind}, {:?}: {errors:?}",
                    options.mass
                );
                assert_eq!(
                    fit.mass_fitted,
                    options.mass == fistage_ident::MassOption::Fit
                );
            }
        }
    }
}

#[test]
fn clean_frfs_survive_csv_in_lab_units() {
    let layouts = [
        ("Hz", FrfCsvLayout::Complex(unit(Quantity::RealPart, "m/N"))),
        (
            "Hz",
            FrfCsvLayout::Complex(unit(Quantity::RealPart, "nm/N")),
        ),
        (
            "rad/s",
            FrfCsvLayout::MagnitudePhase(
                unit(Quantity::Magnitude, "um/N"),
                unit(Quantity::Phase, "deg"),
            ),
        ),
        (
            "Hz",
            FrfCsvLayout::MagnitudePhase(
                unit(Quantity::Magnitude, "dB"),
                unit(Quantity::Phase, "rad"),
            ),
        ),
        (
            "kHz",
            FrfCsvLayout::Magnitude(unit(Quantity::Magnitude, "dB")),
        ),
    ];
    for (name, p, mass) in parameter_sets() {
        let data = FrfSynth::clean(&p, mass).generate();
        for (freq, layout) in layouts {
            let text = frf_csv(&data, unit(Quantity::Frequency, freq), layout);
            let read = parse_frf_csv("clean.csv", &text, &UnitOverrides::default()).unwrap();
            assert_eq!(
                read.has_phase,
                !matches!(layout, FrfCsvLayout::Magnitude(_))
            );
            let fit = fit_frf(&read, &FrfOptions::with_mass(mass)).unwrap();
            let errors = frf_errors(&fit, &p, mass);
            assert!(max(&errors) < EXACT, "{name}, {layout:?}: {errors:?}");
        }
    }
}

#[test]
fn sigma1_is_split_off_with_sigma2_from_the_stribeck_fit() {
    for (name, p, mass) in parameter_sets() {
        let stribeck = fit_stribeck(
            &StribeckSynth::clean(p).generate(),
            &StribeckOptions::default(),
        )
        .unwrap();
        let options = FrfOptions {
            sigma2: Some(fistage_ident::Sigma2Input {
                value: stribeck.sigma2.value,
                ci95: stribeck.sigma2.ci95,
            }),
            ..FrfOptions::with_mass(mass)
        };
        let fit = fit_frf(&FrfSynth::clean(&p, mass).generate(), &options).unwrap();
        let sigma1 = fit.sigma1.unwrap();
        assert!(
            common::rel(sigma1.value, p.sigma1) < EXACT,
            "{name}: {sigma1:?}"
        );
        let tuned = fit.apply_to(stribeck.apply_to(p));
        for (got, want) in tuned.values().iter().zip(p.values()) {
            assert!(common::rel(*got, want) < EXACT, "{name}: {tuned:?}");
        }
    }
}

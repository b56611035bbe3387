//! Asymmetric friction (the negative branch with lower f_C and f_S) is flagged
//! with a tiny p-value; symmetric noisy data are not flagged (beyond the 5%
//! false-alarm rate the test allows). Both the F test (least squares) and the
//! Wald test (robust fits) are exercised.

use crate::common;

use common::{parameter_sets, rel};
use fistage_ident::stribeck::AsymmetryTestKind;
use fistage_ident::synth::StribeckSynth;
use fistage_ident::{StribeckOptions, fit_stribeck_asymmetric};
use fistage_model::LugreParams;

fn weaker_negative(p: &LugreParams) -> LugreParams {
    LugreParams {
        f_c: 0.9 * p.f_c,
        f_s: 0.95 * p.f_s,
        ..*p
    }
}

#[test]
fn asymmetric_branches_are_flagged_and_fitted() {
    for (name, p, _) in parameter_sets() {
        let negative = weaker_negative(&p);
        for seed in 1..=3 {
            let data = StribeckSynth::noisy(p, seed)
                .with_negative(negative)
                .generate();
            let fit = fit_stribeck_asymmetric(&data, &StribeckOptions::default()).unwrap();
            println!(
                "{name} seed {seed}: F = {:.1}, p = {:.2e}",
                fit.test.statistic, fit.test.p_value
            );
            assert_eq!(fit.test.test, AsymmetryTestKind::F);
            assert_eq!(fit.test.dof, vec![4, data.len() - 8]);
            assert!(
                fit.test.significant && fit.test.p_value < 1e-10,
                "{name}: {:?}",
                fit.test
            );
            assert!(rel(fit.positive.f_c.value, p.f_c) < 0.02 && fit.positive.f_c.covers(p.f_c));
            assert!(rel(fit.negative.f_c.value, negative.f_c) < 0.02);
            assert!(fit.negative.f_c.covers(negative.f_c) && fit.negative.f_s.covers(negative.f_s));
            let robust = fit_stribeck_asymmetric(&data, &StribeckOptions::robust()).unwrap();
            assert_eq!(robust.test.test, AsymmetryTestKind::Wald);
            assert!(
                robust.test.significant && robust.test.p_value < 1e-10,
                "{:?}",
                robust.test
            );
        }
    }
}

#[test]
fn a_small_asymmetry_is_still_detected() {
    // 3% lower Coulomb friction on the negative branch: about 8 standard errors.
    let (_, p, _) = parameter_sets()[0];
    let negative = LugreParams {
        f_c: 0.97 * p.f_c,
        ..p
    };
    let data = StribeckSynth::noisy(p, 7)
        .with_negative(negative)
        .generate();
    let fit = fit_stribeck_asymmetric(&data, &StribeckOptions::default()).unwrap();
    println!("3% asymmetry: p = {:.2e}", fit.test.p_value);
    assert!(fit.test.significant, "{:?}", fit.test);
}

#[test]
fn symmetric_data_are_not_flagged() {
    for (name, p, _) in parameter_sets() {
        let seeds = 200..220;
        let mut flagged = 0;
        let mut robust_flagged = 0;
        let mut p_values = Vec::new();
        for seed in seeds.clone() {
            let data = StribeckSynth::noisy(p, seed).generate();
            let fit = fit_stribeck_asymmetric(&data, &StribeckOptions::default()).unwrap();
            flagged += usize::from(fit.test.significant);
            p_values.push(fit.test.p_value);
            if seed < 205 {
                let robust = fit_stribeck_asymmetric(&data, &StribeckOptions::robust()).unwrap();
                robust_flagged += usize::from(robust.test.significant);
            }
        }
        println!(
            "{name}: {flagged} of {} flagged; p-values {p_values:.3?}",
            p_values.len()
        );
        // At alpha = 0.05, 3 or more false alarms in 20 has probability 7.5%;
        // 4 or more, 1.6%.
        assert!(flagged <= 3, "{name}: {flagged} false alarms");
        assert!(
            robust_flagged <= 1,
            "{name}: {robust_flagged} robust false alarms in 5"
        );
        // The p-values of a correct test are uniform: not all large, not all small.
        let mean = p_values.iter().sum::<f64>() / p_values.len() as f64;
        assert!((0.25..0.75).contains(&mean), "{name}: mean p {mean}");
    }
}

#[test]
fn one_branch_too_short_is_rejected() {
    let (_, p, _) = parameter_sets()[0];
    let mut data = StribeckSynth::noisy(p, 1).generate();
    // Keep only 3 negative points.
    let keep: Vec<usize> = (0..data.len())
        .filter(|&i| data.velocity[i] > 0.0 || i < 3)
        .collect();
    data.velocity = keep.iter().map(|&i| data.velocity[i]).collect();
    data.force = keep.iter().map(|&i| data.force[i]).collect();
    data.lines = keep.iter().map(|&i| data.lines[i]).collect();
    let message = fit_stribeck_asymmetric(&data, &StribeckOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("negative velocities: 3 data rows (lines 2-4)"),
        "{message}"
    );
    assert!(message.contains("column 'velocity'"), "{message}");
}

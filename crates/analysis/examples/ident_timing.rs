//! Times the standard identification cases: the 80-point Table 1 f_ss curve
//! (least squares, Huber, L1, asymmetric) and the 100-point Table 1 FRF (known
//! and fitted mass, complex and magnitude-only); then the simulated lab tests
//! of the rigid stage (40 constant-velocity runs, a 30-frequency stepped sine).
//! Run with `cargo run --release -p fistage-analysis --example ident_timing`.

use std::time::{Duration, Instant};

use fistage_analysis::lab::{FrfLab, LabStage, StribeckLab};
use fistage_ident::synth::{TABLE1_MASS, benchmark_frf_data, benchmark_stribeck_data};
use fistage_ident::{
    FrfOptions, Loss, StribeckOptions, fit_frf, fit_stribeck, fit_stribeck_asymmetric,
};

/// Median time of `runs` calls.
fn time(runs: usize, mut f: impl FnMut()) -> Duration {
    f();
    let mut times: Vec<Duration> = (0..runs)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed()
        })
        .collect();
    times.sort();
    times[runs / 2]
}

fn report(name: &str, t: Duration) {
    println!("{name:<44} {:>9.3} ms", t.as_secs_f64() * 1e3);
}

fn main() {
    let stribeck = benchmark_stribeck_data();
    let title = format!("f_ss, {} points", stribeck.len());
    for (loss, runs) in [(Loss::L2, 101), (Loss::Huber, 21), (Loss::L1, 21)] {
        let options = StribeckOptions {
            loss,
            ..StribeckOptions::default()
        };
        let t = time(runs, || {
            fit_stribeck(&stribeck, &options).expect("fit");
        });
        report(&format!("{title}, {}", loss.name()), t);
    }
    let t = time(51, || {
        fit_stribeck_asymmetric(&stribeck, &StribeckOptions::default()).expect("fit");
    });
    report(&format!("{title}, l2, asymmetric (3 fits)"), t);

    let frf = benchmark_frf_data();
    let title = format!("FRF, {} points", frf.len());
    let magnitude = frf.magnitude_only();
    for (name, data, options) in [
        (
            "complex, known mass",
            &frf,
            FrfOptions::with_mass(TABLE1_MASS),
        ),
        ("complex, fitted mass", &frf, FrfOptions::default()),
        (
            "magnitude, known mass",
            &magnitude,
            FrfOptions::with_mass(TABLE1_MASS),
        ),
        ("magnitude, fitted mass", &magnitude, FrfOptions::default()),
    ] {
        let t = time(101, || {
            fit_frf(data, &options).expect("fit");
        });
        report(&format!("{title}, {name}"), t);
    }

    let robot =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../robots/stage_1dof_rigid.urdf");
    let stage = LabStage::load(&robot).expect("the rigid stage");
    let t = time(5, || {
        StribeckLab::paper_like(20, 1)
            .measure(&stage)
            .expect("f_ss test");
    });
    report("simulated f_ss test, 40 runs", t);
    let t = time(5, || {
        FrfLab::paper_like(30, 1).measure(&stage).expect("FRF test");
    });
    report("simulated FRF test, 30 frequencies", t);
}

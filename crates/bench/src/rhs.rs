//! `fistage bench --rhs`: the cost of one right-hand side of the assembled
//! model (its machine code, and its generic evaluation) against a
//! hand-written kernel of the same equations, side by side in one run, on one-axis stages of one, four and eight bearings (each with
//! its own isolator and LuGre friction: 5, 14 and 26 states) and, model
//! only, on the six-degree-of-freedom four-bearing stage. The hand kernel is
//! paper Eq. 2 written out bearing by bearing for that layout, with nothing
//! general left: it is what a model outside the assembly's fixed-size paths
//! is measured against (no speed cliff). Before timing, both are evaluated
//! at random states and must agree to 1e-9.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Context;
use fistage_codegen::{Function, machine_code};
use fistage_model::{Inputs, Loaded, LugreParams};

/// One bearing of the hand kernel.
struct HandBearing {
    mass: f64,
    stiffness: f64,
    damping: f64,
    lugre: LugreParams,
}

/// A table on bearings along one axis under a PD servo about x = 0, the
/// states laid out as the assembly lays them out: positions (table first),
/// velocities, bristle deflections.
struct HandStage {
    table_mass: f64,
    k: f64,
    c: f64,
    bearings: Vec<HandBearing>,
}

impl HandStage {
    /// The stage of a loaded one-axis scenario, if it is one.
    fn of(loaded: &Loaded) -> anyhow::Result<Self> {
        let model = &loaded.model;
        let controller = model
            .controller()
            .context("the hand kernel needs a servo")?;
        let bodies = model.bodies();
        let robot = &loaded.robot;
        anyhow::ensure!(
            bodies.len() == robot.isolators.len() + 1
                && robot.frictions.len() == robot.isolators.len(),
            "not a table on bearings each with one isolator and one friction"
        );
        let bearings = robot
            .isolators
            .iter()
            .zip(&robot.frictions)
            .zip(&bodies[1..])
            .map(|((isolator, friction), body)| HandBearing {
                mass: body.mass,
                stiffness: isolator.stiffness[0],
                damping: isolator.damping[0],
                lugre: friction.lugre,
            })
            .collect();
        Ok(Self {
            table_mass: bodies[0].mass,
            k: controller.k,
            c: controller.c,
            bearings,
        })
    }

    #[inline(never)]
    fn rhs(&self, x: &[f64], platform_velocity: f64, dx: &mut [f64]) {
        let n = self.bearings.len();
        let (xt, vt) = (x[0], x[n + 1]);
        let mut table = -self.k * xt - self.c * vt;
        for (i, b) in self.bearings.iter().enumerate() {
            let (xb, vb, z) = (x[1 + i], x[n + 2 + i], x[2 * n + 2 + i]);
            let link = b.damping * (vt - vb) + b.stiffness * (xt - xb);
            table -= link;
            let slip = vb - platform_velocity;
            let l = &b.lugre;
            let r = slip / l.v_s;
            let level = l.f_c + (l.f_s - l.f_c) * (-r * r).exp();
            let z_rate = slip - slip.abs() * l.sigma0 / level * z;
            let friction = l.sigma0 * z + l.sigma1 * z_rate + l.sigma2 * slip;
            dx[1 + i] = vb;
            dx[n + 2 + i] = (link - friction) / b.mass;
            dx[2 * n + 2 + i] = z_rate;
        }
        dx[0] = vt;
        dx[n + 1] = table / self.table_mass;
    }
}

/// The scenarios timed: one-axis stages (with a hand kernel) and the 6-DOF stage.
const CASES: [&str; 4] = [
    "scenarios/paper/fig05b_fi.toml",
    "scenarios/bench/axis_4fi_fig05b.toml",
    "scenarios/bench/axis_8fi_fig05b.toml",
    "scenarios/coupling/symmetric_fig05b.toml",
];

/// Random states near the slipping motion of the stage about its zero
/// configuration (positions of micrometres, velocities of mm/s, bristles
/// within their steady deflection, small rotations).
fn states(loaded: &Loaded, count: usize) -> Vec<Vec<f64>> {
    let mut seed = 0x5EED_u64;
    let mut uniform = move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let nominal = &loaded.model.layout().nominal;
    let zero = loaded.model.zero_state();
    (0..count)
        .map(|_| {
            zero.iter()
                .zip(nominal)
                .map(|(zero, scale)| zero + scale * uniform())
                .collect()
        })
        .collect()
}

/// Median over `rounds` of the time per evaluation, ns.
fn time_per_call(rounds: usize, calls: usize, mut evaluate: impl FnMut()) -> f64 {
    let mut samples: Vec<f64> = (0..rounds)
        .map(|_| {
            let started = Instant::now();
            for _ in 0..calls {
                evaluate();
            }
            started.elapsed().as_secs_f64() * 1e9 / calls as f64
        })
        .collect();
    crate::timing::median(&mut samples)
}

/// Prints the Markdown table.
pub fn rhs_table(repeat: usize) -> anyhow::Result<()> {
    println!(
        "Cost of one right-hand side (median of {repeat} rounds of 200 000 evaluations at random states near slipping, platform 20 mm/s; release build):\n"
    );
    println!(
        "| scenario | states | evaluation path | generic ns/RHS | compiled ns/RHS | hand kernel ns/RHS | compiled / hand | compiled ns per state |"
    );
    println!("|---|---:|---|---:|---:|---:|---:|---:|");
    for case in CASES {
        let path = PathBuf::from(case);
        let loaded = fistage_model::load(Path::new(&path))?;
        let model = &loaded.model;
        let n = model.n_states();
        let inputs = Inputs {
            platform_velocity: 0.02,
            ..Inputs::default()
        };
        let states = states(&loaded, 64);
        let mut ws = model.workspace();
        let mut dx = vec![0.0; n];
        let hand = HandStage::of(&loaded)
            .ok()
            .filter(|h| 3 * h.bearings.len() + 2 == n);
        if let Some(hand) = &hand {
            let mut expected = vec![0.0; n];
            for x in &states {
                model.rhs(x, &inputs, &mut dx, &mut ws);
                hand.rhs(x, inputs.platform_velocity, &mut expected);
                for (i, (a, b)) in dx.iter().zip(&expected).enumerate() {
                    anyhow::ensure!(
                        (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1e-12),
                        "{case}: the hand kernel's {} is {b}, the model's {a}",
                        model.layout().names[i]
                    );
                }
            }
        }
        // A model compiles in a run after its first evaluations; here the
        // compiled column must be the machine code from the first call.
        if let Err(why) = machine_code(model, Function::Rhs) {
            println!(
                "`{case}`: the right-hand side is not compiled ({why}); its compiled column is the generic evaluation"
            );
        }
        let calls = 200_000;
        let mut k = 0;
        let generic = model.interpreted();
        let generic_ns = time_per_call(repeat, calls, || {
            k = (k + 1) % states.len();
            generic.rhs(black_box(&states[k]), &inputs, &mut dx, &mut ws);
            black_box(&dx);
        });
        let model_ns = time_per_call(repeat, calls, || {
            k = (k + 1) % states.len();
            model.rhs(black_box(&states[k]), &inputs, &mut dx, &mut ws);
            black_box(&dx);
        });
        let hand_ns = hand.as_ref().map(|hand| {
            time_per_call(repeat, calls, || {
                k = (k + 1) % states.len();
                hand.rhs(black_box(&states[k]), inputs.platform_velocity, &mut dx);
                black_box(&dx);
            })
        });
        let (hand_cell, ratio_cell) = match hand_ns {
            Some(h) => (format!("{h:.1}"), format!("{:.2}", model_ns / h)),
            None => ("-".into(), "-".into()),
        };
        println!(
            "| `{case}` | {n} | {:?} | {generic_ns:.1} | {model_ns:.1} | {hand_cell} | {ratio_cell} | {:.2} |",
            model.evaluation_path(),
            model_ns / n as f64
        );
    }
    Ok(())
}

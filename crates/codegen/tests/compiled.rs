//! The compiled right-hand side ([`fistage_codegen::machine_code`]) against the
//! generic evaluation it was recorded from, on every shipped stage: the
//! same numbers at states all over the operating range (sliding both ways,
//! sticking, moving platform, servo inputs), a bail-out (not a wrong number)
//! where a branch goes the other way, and a stated reason where a model is
//! not compiled.

use std::path::{Path, PathBuf};

use fistage_codegen::{Function, NotCompiled, machine_code};
use fistage_model::{InputValues, Model};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every shipped scenario file.
fn scenarios() -> Vec<PathBuf> {
    let mut found = Vec::new();
    let mut folders = vec![root().join("scenarios")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("scenario folder") {
            let path = entry.expect("entry").path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "toml") {
                found.push(path);
            }
        }
    }
    found.sort();
    found
}

/// A deterministic stream of numbers in [-1, 1).
struct Numbers(u64);

impl Numbers {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// A state and inputs around the operating range: every state up to twice
/// its nominal size, some exactly zero (a contact at rest), rotations kept
/// small as a stage's are.
fn state_and_inputs(model: &Model, numbers: &mut Numbers) -> (Vec<f64>, InputValues<f64>) {
    let nominal = &model.layout().nominal;
    let x: Vec<f64> = model
        .zero_state()
        .iter()
        .zip(nominal)
        .map(|(zero, scale)| {
            let r = numbers.next();
            if r.abs() < 0.05 {
                *zero
            } else {
                zero + 2.0 * scale * numbers.next()
            }
        })
        .collect();
    let inputs = InputValues {
        reference_position: 1e-3 * numbers.next(),
        reference_velocity: 2e-2 * numbers.next(),
        servo_force: numbers.next(),
        platform_velocity: 5e-2 * numbers.next(),
    };
    (x, inputs)
}

fn same(a: f64, b: f64) -> bool {
    a == b || (a.is_nan() && b.is_nan())
}

#[test]
fn compiled_functions_give_the_evaluations_numbers_on_every_shipped_stage() {
    let mut compiled = 0;
    for path in scenarios() {
        let loaded = fistage_model::load(&path).expect("shipped scenario loads");
        let model = &loaded.model;
        let name = path.strip_prefix(root()).unwrap_or(&path).display();
        let n = model.n_states();
        let mut numbers = Numbers(7);
        for function in [Function::Rhs, Function::ImplicitStage] {
            let native = match machine_code(model, function) {
                Ok(native) => native,
                Err(NotCompiled::NoBristles) if function == Function::ImplicitStage => continue,
                Err(other) => panic!("{name}: {function:?} not compiled: {other}"),
            };
            compiled += 1;
            let mut ws = model.workspace();
            let mut bailed = 0;
            for _ in 0..200 {
                let (x, inputs) = state_and_inputs(model, &mut numbers);
                let (mut expected, mut got) = (vec![0.0; n], vec![f64::NAN; n]);
                let (mut x_expected, mut x_got) = (x.clone(), x.clone());
                let ran = match function {
                    Function::Rhs => {
                        model.rhs_of(&x, &inputs, &mut expected, &mut ws);
                        native.rhs(&x, &inputs, &mut got)
                    }
                    Function::ImplicitStage => {
                        let step = 1e-4 * (1.0 + numbers.next());
                        model.rhs_implicit_of(
                            &mut x_expected,
                            &inputs,
                            step,
                            &mut expected,
                            &mut ws,
                        );
                        native.implicit_stage(&mut x_got, &inputs, step, &mut got)
                    }
                };
                if ran.is_err() {
                    // Nothing was written.
                    assert!(got.iter().all(|v| v.is_nan()), "{name}");
                    assert_eq!(x_got, x, "{name}");
                    bailed += 1;
                    continue;
                }
                for i in 0..n {
                    assert!(
                        same(got[i], expected[i]) && same(x_got[i], x_expected[i]),
                        "{name}: {function:?}: {}: compiled {} / {}, evaluated {} / {}",
                        model.layout().names[i],
                        got[i],
                        x_got[i],
                        expected[i],
                        x_expected[i]
                    );
                }
            }
            // Stages turn little: the recorded branches hold almost always.
            assert!(
                bailed <= 20,
                "{name}: {function:?} gave up {bailed} times in 200"
            );
        }
    }
    assert!(compiled > 60, "{compiled} functions compiled");
}

#[test]
fn a_branch_the_other_way_gives_up_and_the_model_evaluates_as_before() {
    let loaded = fistage_model::load(&root().join("scenarios/coupling/friction20_traverse.toml"))
        .expect("loads");
    let model = &loaded.model;
    let native = machine_code(model, Function::Rhs).expect("the traverse compiles");
    assert!(native.guards() > 0, "the bushing rotations are guarded");
    let n = model.n_states();
    // Turn the table by 0.1 rad about z: the bushings' rotation logarithm
    // leaves its series (recorded below 0.01 rad) for the arctangent.
    let mut x = model.zero_state();
    let qw = model
        .layout()
        .names
        .iter()
        .position(|s| s == "table.qw")
        .expect("qw");
    let angle: f64 = 0.1;
    x[qw] = (angle / 2.0).cos();
    x[qw + 3] = (angle / 2.0).sin();
    let inputs = InputValues {
        reference_position: 0.0,
        reference_velocity: 0.0,
        servo_force: 0.0,
        platform_velocity: 0.0,
    };
    let mut got = vec![f64::NAN; n];
    assert!(native.rhs(&x, &inputs, &mut got).is_err());
    assert!(got.iter().all(|v| v.is_nan()), "nothing written");
    let (mut through_model, mut generic) = (vec![0.0; n], vec![0.0; n]);
    let mut ws = model.workspace();
    let plain = fistage_model::Inputs::default();
    model.rhs(&x, &plain, &mut through_model, &mut ws);
    model.rhs_of(&x, &plain.values(), &mut generic, &mut ws);
    assert_eq!(through_model, generic);
    assert!(
        generic.iter().any(|v| v.abs() > 1.0),
        "the turned table is pulled back"
    );
}

#[test]
fn an_interpreted_model_compiles_nothing_and_gives_the_same_numbers() {
    let loaded =
        fistage_model::load(&root().join("scenarios/paper/fig05b_fi.toml")).expect("loads");
    let model = &loaded.model;
    let interpreted = model.interpreted();
    assert!(matches!(
        machine_code(&interpreted, Function::Rhs),
        Err(NotCompiled::Disabled)
    ));
    assert!(machine_code(model, Function::Rhs).is_ok());
    let mut numbers = Numbers(3);
    let (x, inputs) = state_and_inputs(model, &mut numbers);
    let inputs = fistage_model::Inputs {
        platform_velocity: inputs.platform_velocity,
        servo_force: inputs.servo_force,
        ..Default::default()
    };
    let (mut a, mut b) = (vec![0.0; 5], vec![0.0; 5]);
    model.rhs(&x, &inputs, &mut a, &mut model.workspace());
    interpreted.rhs(&x, &inputs, &mut b, &mut interpreted.workspace());
    assert_eq!(a, b);
}

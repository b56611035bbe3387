//! A fistage model's right-hand side as machine code: the only `unsafe`
//! code of the model stack.
//!
//! The generic evaluation ([`Model::rhs_of`]) runs once on [`Traced`]
//! values, which record every floating-point operation it performs (module
//! `tape`); that record is compiled to a native function (module `emit`,
//! through Cranelift). Everything the structure decides (the evaluation
//! path, which elements exist, the servo's options, zero rows) is decided
//! once, while recording; what is left is straight-line arithmetic with the
//! model's numbers in the instructions, the cost a kernel written by hand for
//! that one stage would have, for any robot file.
//!
//! The compiled function performs the evaluation's operations in the same
//! order, so it gives the same numbers (up to the sign of a zero, and for
//! finite states); [`compile`] checks that on states of its own before it
//! hands the function out, and the tests check it on every shipped stage.
//! Where the evaluation branched on a value (the rotation of a bushing above
//! or below 0.01 rad, say), the compiled function checks that the branch
//! still goes the recorded way and otherwise gives up ([`Bail`]); the
//! caller then evaluates as before. An evaluation that does what compiled
//! code cannot repeat (reads a value out as a number instead of comparing
//! it, as the rotation logarithm does within a few degrees of half a turn)
//! is not compiled at all ([`NotCompiled`]).
//!
//! Two functions are compiled: the right-hand side, and the implicit stage
//! of the bristle states ([`Model::rhs_implicit_bristles`]) when the model
//! has any. The model keeps what [`machine_code`] compiled and runs it from
//! [`Model::rhs`] from then on (the engines of `fistage-sim` compile once a
//! run has made 10 000 evaluations). A fit's forward sensitivities get a
//! third kind of function, kept by the caller: the right-hand side or the
//! signals differentiated along several state directions on the tape
//! itself ([`sensitivity_kernel`], [`parametric_kernel`]).
//!
//! ```
//! use fistage_codegen::{Function, machine_code};
//!
//! let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
//! let loaded = fistage_model::load(&root.join("scenarios/paper/fig05b_fi.toml"))?;
//! let model = &loaded.model;
//! let code = machine_code(model, Function::Rhs).expect("a rail stage compiles");
//! assert!(code.operations() > 0 && code.guards() == 0);
//!
//! // The same derivative as the generic evaluation, now run as machine code.
//! let x = model.zero_state();
//! let inputs = fistage_model::Inputs::default();
//! let (mut fast, mut generic) = (vec![0.0; x.len()], vec![0.0; x.len()]);
//! model.rhs(&x, &inputs, &mut fast, &mut model.workspace());
//! model
//!     .interpreted()
//!     .rhs(&x, &inputs, &mut generic, &mut model.workspace());
//! assert_eq!(fast, generic);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

// Without Cranelift nothing is recorded or emitted: the recorder's and the
// library calls' helpers are unused in that build.
#![cfg_attr(not(feature = "cranelift"), allow(dead_code))]

mod calls;
#[cfg(feature = "cranelift")]
mod emit;
#[cfg(not(feature = "cranelift"))]
#[path = "emit_none.rs"]
mod emit;
mod sensitivity;
mod tangent;
mod tape;
mod traced;

use std::fmt;

pub use sensitivity::{Differentiated, SensitivityKernel, parametric_kernel, sensitivity_kernel};
pub use traced::Traced;

use fistage_model::machine_code::Compiled;
pub use fistage_model::machine_code::{Bail, Function, MachineCode, NotCompiled};
use fistage_model::{InputValues, Model};

use emit::{Code, Generator, KernelFn};
use tape::{Output, Slot, Tape};

/// One compiled function of a model: its right-hand side ([`Native::rhs`])
/// or the implicit stage of its bristle states ([`Native::implicit_stage`]).
pub struct Native {
    n_states: usize,
    function: KernelFn,
    operations: usize,
    guards: usize,
    compile_time: std::time::Duration,
    /// Owns the memory the function lives in (freed on drop).
    _code: Code,
}

impl fmt::Debug for Native {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Native")
            .field("n_states", &self.n_states)
            .field("operations", &self.operations)
            .field("guards", &self.guards)
            .field("compile_time", &self.compile_time)
            .finish()
    }
}

impl MachineCode for Native {
    fn operations(&self) -> usize {
        self.operations
    }

    fn guards(&self) -> usize {
        self.guards
    }

    fn compile_time(&self) -> std::time::Duration {
        self.compile_time
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }

    #[inline]
    fn rhs(&self, x: &[f64], inputs: &InputValues<f64>, dx: &mut [f64]) -> Result<(), Bail> {
        if x.len() < self.n_states || dx.len() < self.n_states {
            return Err(Bail);
        }
        let inputs = input_array(inputs);
        // SAFETY: a right-hand side reads `n_states` entries of `x` and four
        // of `inputs` and writes `n_states` entries of `dx`; it stores nothing
        // into `x`. The lengths are checked above.
        let status = unsafe {
            (self.function)(x.as_ptr().cast_mut(), dx.as_mut_ptr(), inputs.as_ptr(), 0.0)
        };
        if status == 0 { Ok(()) } else { Err(Bail) }
    }

    #[inline]
    fn implicit_stage(
        &self,
        x: &mut [f64],
        inputs: &InputValues<f64>,
        step: f64,
        dx: &mut [f64],
    ) -> Result<(), Bail> {
        if x.len() < self.n_states || dx.len() < self.n_states {
            return Err(Bail);
        }
        let inputs = input_array(inputs);
        // SAFETY: as for `rhs`; the implicit stage also stores the solved
        // bristle states into `x`, within its `n_states` entries, after
        // every load and only when every guard held.
        let status =
            unsafe { (self.function)(x.as_mut_ptr(), dx.as_mut_ptr(), inputs.as_ptr(), step) };
        if status == 0 { Ok(()) } else { Err(Bail) }
    }
}

/// The inputs in the order the compiled functions read them.
#[inline]
fn input_array(inputs: &InputValues<f64>) -> [f64; 4] {
    [
        inputs.reference_position,
        inputs.reference_velocity,
        inputs.servo_force,
        inputs.platform_velocity,
    ]
}

/// The state and inputs the evaluation is recorded at: the zero
/// configuration moved a little in every coordinate (so that no value sits
/// exactly on a branch point), with small rotations and slow motion, where
/// stages spend their time.
fn recording_point(model: &Model, seed: u64) -> (Vec<f64>, InputValues<f64>) {
    let mut state = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let nominal = &model.layout().nominal;
    let x = model
        .zero_state()
        .iter()
        .zip(nominal)
        .map(|(zero, scale)| zero + 0.1 * scale * next())
        .collect();
    let inputs = InputValues {
        reference_position: 1e-4 * next(),
        reference_velocity: 1e-3 * next(),
        servo_force: 0.1 * next(),
        platform_velocity: 0.02 * next(),
    };
    (x, inputs)
}

/// The state and inputs as the traced inputs of a recording.
fn traced_point(x: &[f64], inputs: &InputValues<f64>) -> (Vec<Traced>, InputValues<Traced>) {
    let state = x
        .iter()
        .enumerate()
        .map(|(i, v)| Traced::input(Slot::State(i as u32), *v))
        .collect();
    let input = |k: u32, v: f64| Traced::input(Slot::Input(k), v);
    let traced_inputs = InputValues {
        reference_position: input(0, inputs.reference_position),
        reference_velocity: input(1, inputs.reference_velocity),
        servo_force: input(2, inputs.servo_force),
        platform_velocity: input(3, inputs.platform_velocity),
    };
    (state, traced_inputs)
}

/// Records `function` at `x`, `inputs`.
fn trace(
    model: &Model,
    x: &[f64],
    inputs: &InputValues<f64>,
    function: Function,
) -> Result<Tape, NotCompiled> {
    let n = model.n_states();
    tape::record(|| {
        let (mut state, traced_inputs) = traced_point(x, inputs);
        let mut ws = model.workspace_of::<Traced>();
        let mut dx = vec![<Traced as fistage_model::Scalar>::constant(0.0); n];
        let mut outputs = Vec::with_capacity(n);
        if function == Function::ImplicitStage {
            let step = Traced::input(Slot::Step, 1e-5);
            model.rhs_implicit_of(&mut state, &traced_inputs, step, &mut dx, &mut ws);
            outputs.extend(
                model
                    .bristle_states()
                    .into_iter()
                    .map(|i| (Output::State(i as u32), state[i].node())),
            );
        } else {
            model.rhs_of(&state, &traced_inputs, &mut dx, &mut ws);
        }
        outputs.extend(
            dx.iter()
                .enumerate()
                .map(|(i, d)| (Output::Derivative(i as u32), d.node())),
        );
        outputs
    })
    .map_err(NotCompiled::Unsupported)
}

/// `function` of `model` as machine code: compiled on the first call for
/// the model (or any clone of it) and kept by the model, which then runs it
/// from [`Model::rhs`]; or why it is not compiled.
pub fn machine_code(model: &Model, function: Function) -> Result<&dyn MachineCode, &NotCompiled> {
    model.compile_with(function, compile_boxed)
}

/// [`machine_code`] as the concrete [`Native`] (whose calls an engine's
/// loop inlines); `None` where the model's function is not compiled.
pub fn native(model: &Model, function: Function) -> Option<&Native> {
    machine_code(model, function).ok()?.as_any().downcast_ref()
}

/// The model's `function` as [`Native`] if a call compiled it already.
pub fn compiled_native(model: &Model, function: Function) -> Option<&Native> {
    model.compiled(function)?.as_any().downcast_ref()
}

fn compile_boxed(model: &Model, function: Function) -> Compiled {
    compile(model, function).map(|native| Box::new(native) as Box<dyn MachineCode>)
}

/// Compiles `function` of `model` and checks it against the evaluation at
/// states of its own.
pub fn compile(model: &Model, function: Function) -> Result<Native, NotCompiled> {
    let started = std::time::Instant::now();
    if !emit::AVAILABLE {
        return Err(NotCompiled::NoCodeGenerator);
    }
    if function == Function::ImplicitStage && model.bristle_states().is_empty() {
        return Err(NotCompiled::NoBristles);
    }
    let (x, inputs) = recording_point(model, 1);
    let tape = trace(model, &x, &inputs, function)?;
    let mut generator = Generator::host().map_err(NotCompiled::CodeGeneration)?;
    let id = generator
        .add("function", &tape)
        .map_err(NotCompiled::CodeGeneration)?;
    let (function_pointer, code) = generator.finish(id).map_err(NotCompiled::CodeGeneration)?;
    let mut native = Native {
        n_states: model.n_states(),
        function: function_pointer,
        operations: tape.operations(),
        guards: tape.guards.len(),
        compile_time: std::time::Duration::ZERO,
        _code: code,
    };
    for seed in 1..=4 {
        check(model, &native, function, seed)?;
    }
    native.compile_time = started.elapsed();
    Ok(native)
}

/// The compiled `function` against the evaluation at the recording state of
/// `seed`: the same numbers, or the reason not to use it.
fn check(model: &Model, native: &Native, function: Function, seed: u64) -> Result<(), NotCompiled> {
    let n = model.n_states();
    let (x, inputs) = recording_point(model, seed);
    let names = &model.layout().names;
    let mut ws = model.workspace();
    let (mut expected, mut got) = (vec![0.0; n], vec![0.0; n]);
    let (mut x_expected, mut x_got) = (x.clone(), x);
    let ran = match function {
        Function::Rhs => {
            model.rhs_of(&x_expected, &inputs, &mut expected, &mut ws);
            native.rhs(&x_got, &inputs, &mut got)
        }
        Function::ImplicitStage => {
            let step = 2e-5;
            model.rhs_implicit_of(&mut x_expected, &inputs, step, &mut expected, &mut ws);
            native.implicit_stage(&mut x_got, &inputs, step, &mut got)
        }
    };
    if ran.is_err() {
        return Ok(());
    }
    let pairs = (got.iter().zip(&expected).map(|(g, e)| ("rate", g, e)))
        .chain(x_got.iter().zip(&x_expected).map(|(g, e)| ("value", g, e)));
    for (i, (what, &compiled, &evaluated)) in pairs.enumerate() {
        let same = compiled == evaluated || (compiled.is_nan() && evaluated.is_nan());
        if !same {
            return Err(NotCompiled::Disagrees {
                function: function.name(),
                quantity: format!("the {what} of {}", names[i % n]),
                compiled,
                evaluated,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stage of each kind: on a rail with FI, four bearings on one axis,
    /// the 6-DOF table, and a servo with an observer.
    const SHIPPED: [&str; 4] = [
        "scenarios/paper/fig05b_fi.toml",
        "scenarios/bench/axis_4fi_fig05b.toml",
        "scenarios/coupling/friction20_traverse.toml",
        "scenarios/paper/fig03b_dob_fi.toml",
    ];

    fn shipped(scenario: &str) -> fistage_model::Loaded {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        fistage_model::load(&root.join(scenario)).expect("loads")
    }

    /// The tape itself, evaluated in Rust, gives the evaluation's numbers:
    /// the recording (not only its machine code) is faithful.
    #[test]
    fn the_recorded_tape_gives_the_evaluations_numbers() {
        for scenario in SHIPPED {
            let model = &shipped(scenario).model;
            let n = model.n_states();
            let (x0, inputs0) = recording_point(model, 1);
            for function in [Function::Rhs, Function::ImplicitStage] {
                let tape = trace(model, &x0, &inputs0, function).expect("records");
                let mut ws = model.workspace();
                for seed in 2..12 {
                    let (x, inputs) = recording_point(model, seed);
                    let step = 3e-5;
                    let (mut x_expected, mut expected) = (x.clone(), vec![0.0; n]);
                    match function {
                        Function::Rhs => model.rhs_of(&x, &inputs, &mut expected, &mut ws),
                        Function::ImplicitStage => model.rhs_implicit_of(
                            &mut x_expected,
                            &inputs,
                            step,
                            &mut expected,
                            &mut ws,
                        ),
                    }
                    let got = tape
                        .evaluate(&x, &input_array(&inputs), step)
                        .expect("the recorded branches hold near the recording state");
                    for (&(output, _), value) in tape.outputs.iter().zip(got) {
                        let wanted = match output {
                            Output::Derivative(i) => expected[i as usize],
                            Output::State(i) => x_expected[i as usize],
                        };
                        assert_eq!(value, wanted, "{scenario}: {function:?} {output:?}");
                    }
                }
            }
        }
    }

    /// The compiled sensitivity kernel of every kind of shipped stage
    /// agrees with dual-number evaluations of its right-hand side (the
    /// check `sensitivity_kernel` runs before handing it out), for one
    /// direction and for many.
    #[test]
    fn sensitivity_kernels_agree_with_dual_numbers() {
        for scenario in SHIPPED {
            let model = &shipped(scenario).model;
            for function in [Differentiated::Rhs, Differentiated::Signals] {
                for directions in [1, 9] {
                    let kernel =
                        sensitivity_kernel(model, function, directions).unwrap_or_else(|why| {
                            panic!("{scenario}, {function:?}, {directions}: {why}")
                        });
                    assert!(kernel.operations() > 0);
                }
            }
        }
    }

    /// Structure is decided while recording: a rail stage's tape holds
    /// arithmetic only (no guard), and products with the zero entries of
    /// its rows are not recorded.
    #[test]
    fn a_rail_stage_records_straight_line_arithmetic() {
        let model = &shipped("scenarios/paper/fig05b_fi.toml").model;
        let (x, inputs) = recording_point(model, 1);
        let tape = trace(model, &x, &inputs, Function::Rhs).expect("records");
        assert!(tape.guards.is_empty());
        // Two masses, one bushing, one contact and a PD servo: a few dozen
        // operations (the hand-written kernel of bench --rhs has about 25).
        let operations = tape.operations();
        assert!((20..60).contains(&operations), "{operations}");
        // The Dahl compensator's direction is a sign taken without a branch:
        // a reversal of the motion does not make the code give up.
        let dahl = &shipped("scenarios/paper/fig03a_ff_fi.toml").model;
        let (x, inputs) = recording_point(dahl, 1);
        let tape = trace(dahl, &x, &inputs, Function::Rhs).expect("records");
        assert!(tape.guards.len() <= 1, "{:?}", tape.guards);
    }
}

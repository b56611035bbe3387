//! A model's right-hand side, or its signals, with the state Jacobian
//! applied to several directions at once, as machine code: the state part
//! of a forward-sensitivity system `S_j' = (df/dx) S_j + df/dtheta_j`, and
//! of its readings `dy/dtheta_j = (dg/dx) S_j + ...`
//! ([`SensitivityKernel`]). The function's tape is recorded as for
//! [`crate::compile`], differentiated forward ([`super::tangent`]) and
//! compiled; the result is checked against the generic evaluation in dual
//! numbers before it is handed out.

use std::fmt;

use fistage_model::{Dual64, InputValues, Model, Scalar};

use super::emit::{Code, Generator, KernelFn};
use super::tangent::Seeds;
use super::tape::{self, Node, NodeId, Output, Tape};
use super::{
    Bail, Function, NotCompiled, Traced, input_array, recording_point, tangent, trace, traced_point,
};

/// Which function of a model a [`SensitivityKernel`] differentiates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Differentiated {
    /// The right-hand side ([`Model::rhs`]): `n` outputs.
    Rhs,
    /// The signals ([`Model::outputs`]): one output per signal.
    Signals,
}

/// `f(x)` and `(df/dx) s_j` for `p` directions, compiled for one model.
pub struct SensitivityKernel {
    n_states: usize,
    n_outputs: usize,
    directions: usize,
    /// Per direction, whether it includes its parameter's own effect.
    includes_parameter: Vec<bool>,
    function: KernelFn,
    operations: usize,
    /// Owns the memory the function lives in (freed on drop).
    _code: Code,
}

impl fmt::Debug for SensitivityKernel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SensitivityKernel")
            .field("n_states", &self.n_states)
            .field("directions", &self.directions)
            .field("operations", &self.operations)
            .finish()
    }
}

impl SensitivityKernel {
    /// The number of directions `p`.
    pub fn directions(&self) -> usize {
        self.directions
    }

    /// Floating-point operations in the compiled function.
    pub fn operations(&self) -> usize {
        self.operations
    }

    /// Whether direction `j` gives `(df/dx) s_j + df/d ln(theta_j)` (see
    /// [`parametric_kernel`]) rather than `(df/dx) s_j` alone.
    pub fn includes_parameter(&self, j: usize) -> bool {
        self.includes_parameter.get(j).copied().unwrap_or(false)
    }

    /// The number of outputs `m` of the function (`n` for a right-hand side).
    pub fn outputs(&self) -> usize {
        self.n_outputs
    }

    /// From `y = [x, s_1, ..., s_p]` (`n` entries each) the values
    /// `dy = [f(x), (df/dx) s_1, ..., (df/dx) s_p]` (`m` entries each);
    /// `Err(Bail)` (nothing stored) where a branch of the evaluation goes
    /// another way than recorded, or the slices are too short.
    #[inline]
    pub fn evaluate(
        &self,
        y: &[f64],
        inputs: &InputValues<f64>,
        dy: &mut [f64],
    ) -> Result<(), Bail> {
        let reads = self.n_states * (1 + self.directions);
        let writes = self.n_outputs * (1 + self.directions);
        if y.len() < reads || dy.len() < writes {
            return Err(Bail);
        }
        let inputs = input_array(inputs);
        // SAFETY: the function reads `reads` entries of `y` and four of
        // `inputs` and writes `writes` entries of `dy`, storing nothing into
        // `y`; the lengths are checked above.
        let status = unsafe {
            (self.function)(y.as_ptr().cast_mut(), dy.as_mut_ptr(), inputs.as_ptr(), 0.0)
        };
        if status == 0 { Ok(()) } else { Err(Bail) }
    }
}

/// The compiled [`SensitivityKernel`] of `model`'s `function` for
/// `directions` directions, or why there is none (the function is not
/// compiled, a derivative is not, or the build has no code generator).
pub fn sensitivity_kernel(
    model: &Model,
    function: Differentiated,
    directions: usize,
) -> Result<SensitivityKernel, NotCompiled> {
    let (tape, m) = record_function(model, function)?;
    let kernel = build(model, &tape, m, directions, &Seeds::new())?;
    for seed in 1..=4 {
        check(model, &kernel, function, (&[], 0.0), seed)?;
    }
    Ok(kernel)
}

/// The right-hand side's [`SensitivityKernel`] for one direction per
/// parameter of a fit, with each parameter's own effect included where the
/// models show it: `shifted[j]` are `model` with parameter `j` moved by
/// `exp(+-log_step)`. Where their recordings have the same operations as
/// `model`'s (only constants differ), the constants that moved get the
/// derivative `(up - down) / (2 log_step)` and direction `j` gives
/// `(df/dx) s_j + df/d ln(theta_j)` ([`SensitivityKernel::includes_parameter`]);
/// elsewhere (a parameter that changes which operations run) it gives
/// `(df/dx) s_j` alone and the caller differences the models itself.
pub fn parametric_kernel(
    model: &Model,
    shifted: &[(&Model, &Model)],
    log_step: f64,
) -> Result<SensitivityKernel, NotCompiled> {
    let (tape, m) = record_function(model, Differentiated::Rhs)?;
    let mut seeds = Seeds::new();
    let mut includes = vec![false; shifted.len()];
    for (j, (up, down)) in shifted.iter().enumerate() {
        let (up, _) = record_at(up, model, Differentiated::Rhs)?;
        let (down, _) = record_at(down, model, Differentiated::Rhs)?;
        if !(same_operations(&tape, &up) && same_operations(&tape, &down)) {
            continue;
        }
        includes[j] = true;
        for (i, node) in tape.nodes.iter().enumerate() {
            if let (Node::Const(_), Node::Const(a), Node::Const(b)) =
                (node, up.nodes[i], down.nodes[i])
            {
                let d = (a - b) / (2.0 * log_step);
                if d != 0.0 {
                    seeds.entry(i as NodeId).or_default().push((j, d));
                }
            }
        }
    }
    let mut kernel = build(model, &tape, m, shifted.len(), &seeds)?;
    kernel.includes_parameter = includes;
    for seed in 1..=4 {
        check(
            model,
            &kernel,
            Differentiated::Rhs,
            (shifted, log_step),
            seed,
        )?;
    }
    Ok(kernel)
}

/// `function`'s tape recorded at `model`'s first recording point, and its
/// number of outputs.
fn record_function(model: &Model, function: Differentiated) -> Result<(Tape, usize), NotCompiled> {
    record_at(model, model, function)
}

/// `function` of `model` recorded at `at`'s first recording point (the
/// same state for models that differ in a parameter).
fn record_at(
    model: &Model,
    at: &Model,
    function: Differentiated,
) -> Result<(Tape, usize), NotCompiled> {
    if !super::emit::AVAILABLE {
        return Err(NotCompiled::NoCodeGenerator);
    }
    let (x, inputs) = recording_point(at, 1);
    Ok(match function {
        Differentiated::Rhs => (trace(model, &x, &inputs, Function::Rhs)?, model.n_states()),
        Differentiated::Signals => (trace_signals(model, &x, &inputs)?, model.signals().len()),
    })
}

/// Whether two recordings perform the same operations on the same operands
/// with the same guards and outputs (their constants may differ).
fn same_operations(a: &Tape, b: &Tape) -> bool {
    let same_node =
        |(x, y): (&Node, &Node)| matches!((x, y), (Node::Const(_), Node::Const(_))) || x == y;
    a.nodes.len() == b.nodes.len()
        && a.nodes.iter().zip(&b.nodes).all(same_node)
        && a.guards == b.guards
        && a.outputs == b.outputs
}

/// Differentiates and compiles `tape` (`m` outputs) for `directions`.
fn build(
    model: &Model,
    tape: &Tape,
    m: usize,
    directions: usize,
    seeds: &Seeds,
) -> Result<SensitivityKernel, NotCompiled> {
    let n = model.n_states();
    let tangent =
        tangent::tangent_tape(tape, n, m, directions, seeds).map_err(NotCompiled::Unsupported)?;
    let mut generator = Generator::host().map_err(NotCompiled::CodeGeneration)?;
    let id = generator
        .add("sensitivity", &tangent)
        .map_err(NotCompiled::CodeGeneration)?;
    let (code_entry, code) = generator.finish(id).map_err(NotCompiled::CodeGeneration)?;
    Ok(SensitivityKernel {
        n_states: n,
        n_outputs: m,
        directions,
        includes_parameter: vec![false; directions],
        function: code_entry,
        operations: tangent.operations(),
        _code: code,
    })
}

/// Records the model's signals at `x`, `inputs` (each signal an output).
fn trace_signals(model: &Model, x: &[f64], inputs: &InputValues<f64>) -> Result<Tape, NotCompiled> {
    tape::record(|| {
        let (state, traced_inputs) = traced_point(x, inputs);
        let mut ws = model.workspace_of::<Traced>();
        let mut out = vec![<Traced as Scalar>::constant(0.0); model.signals().len()];
        model.outputs_of(&state, &traced_inputs, &mut out, &mut ws);
        out.iter()
            .enumerate()
            .map(|(i, v)| (Output::Derivative(i as u32), v.node()))
            .collect()
    })
    .map_err(NotCompiled::Unsupported)
}

/// `function` of `model` in any scalar type.
fn evaluate<S: Scalar>(
    model: &Model,
    function: Differentiated,
    x: &[S],
    inputs: &InputValues<S>,
    out: &mut [S],
) {
    let mut ws = model.workspace_of::<S>();
    match function {
        Differentiated::Rhs => model.rhs_of(x, inputs, out, &mut ws),
        Differentiated::Signals => model.outputs_of(x, inputs, out, &mut ws),
    }
}

/// The kernel against the generic evaluation at the recording state of
/// `seed` with directions of its own: `f` to the bit, each direction's
/// derivative against a dual-number evaluation to rounding, plus, where the
/// direction includes its parameter, the central difference of the
/// `shifted` models' evaluations (to the differences' own error).
fn check(
    model: &Model,
    kernel: &SensitivityKernel,
    function: Differentiated,
    (shifted, log_step): (&[(&Model, &Model)], f64),
    seed: u64,
) -> Result<(), NotCompiled> {
    let (n, m, p) = (model.n_states(), kernel.n_outputs, kernel.directions);
    let (x, inputs) = recording_point(model, seed);
    let mut y = x.clone();
    for j in 0..p {
        let (direction, _) = recording_point(model, seed * 1000 + j as u64 + 7);
        y.extend(direction.iter().zip(&x).map(|(d, x)| d - x));
    }
    let mut dy = vec![0.0; m * (1 + p)];
    if kernel.evaluate(&y, &inputs, &mut dy).is_err() {
        return Ok(());
    }
    let names: Vec<String> = match function {
        Differentiated::Rhs => model.layout().names.clone(),
        Differentiated::Signals => model.signals().iter().map(|s| s.name.clone()).collect(),
    };
    let disagrees = |quantity: String, compiled: f64, evaluated: f64| NotCompiled::Disagrees {
        function: "sensitivity kernel",
        quantity,
        compiled,
        evaluated,
    };
    let mut expected = vec![0.0; m];
    evaluate(model, function, &x, &inputs, &mut expected);
    for c in 0..m {
        if dy[c] != expected[c] && !(dy[c].is_nan() && expected[c].is_nan()) {
            return Err(disagrees(
                format!("the rate of {}", names[c]),
                dy[c],
                expected[c],
            ));
        }
    }
    let dual_inputs = InputValues {
        reference_position: Dual64::constant(inputs.reference_position),
        reference_velocity: Dual64::constant(inputs.reference_velocity),
        servo_force: Dual64::constant(inputs.servo_force),
        platform_velocity: Dual64::constant(inputs.platform_velocity),
    };
    let mut dx = vec![Dual64::constant(0.0); m];
    for j in 0..p {
        let direction = &y[n * (1 + j)..n * (2 + j)];
        let xd: Vec<Dual64> = x
            .iter()
            .zip(direction)
            .map(|(&v, &d)| Dual64::new(v, d))
            .collect();
        evaluate(model, function, &xd, &dual_inputs, &mut dx);
        let mut wanted: Vec<f64> = dx.iter().map(|d| d.eps).collect();
        let mut tolerance = 1e-10;
        if kernel.includes_parameter(j)
            && let Some((up, down)) = shifted.get(j)
        {
            let (mut f_up, mut f_down) = (vec![0.0; m], vec![0.0; m]);
            evaluate(up, function, &x, &inputs, &mut f_up);
            evaluate(down, function, &x, &inputs, &mut f_down);
            for c in 0..m {
                wanted[c] += (f_up[c] - f_down[c]) / (2.0 * log_step);
            }
            tolerance = 1e-6;
        }
        let scale = wanted
            .iter()
            .fold(0.0f64, |largest, d| largest.max(d.abs()));
        for c in 0..m {
            let (compiled, evaluated) = (dy[m * (1 + j) + c], wanted[c]);
            let close = (compiled - evaluated).abs() <= tolerance * scale;
            if !close {
                return Err(disagrees(
                    format!(
                        "the derivative of the rate of {} along direction {j}",
                        names[c]
                    ),
                    compiled,
                    evaluated,
                ));
            }
        }
    }
    Ok(())
}

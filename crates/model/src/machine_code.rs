//! What the model knows of its machine code: which functions can be
//! compiled ([`Function`]), what a compiled one offers ([`MachineCode`]),
//! and why one may not exist ([`NotCompiled`]). The code generator is the
//! crate `fistage-codegen`, the model stack's only `unsafe` code; a model
//! keeps what it compiled ([`crate::Model::compile_with`]) and runs it from
//! [`crate::Model::rhs`].

use std::fmt;
use std::time::Duration;

use crate::values::InputValues;

/// Which function of a model.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Function {
    /// The right-hand side, as [`crate::Model::rhs`].
    Rhs,
    /// The implicit stage of the bristle states, as
    /// [`crate::Model::rhs_implicit_bristles`].
    ImplicitStage,
}

impl Function {
    /// The function in words.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rhs => "right-hand side",
            Self::ImplicitStage => "implicit bristle stage",
        }
    }
}

/// A compiled function found a branch of the evaluation going another way
/// than when it was recorded, and stored nothing: evaluate as before.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Bail;

/// One function of a model as machine code, giving the numbers of the
/// generic evaluation it was recorded from.
pub trait MachineCode: Send + Sync + fmt::Debug {
    /// The state derivative at `x`, as [`crate::Model::rhs`] (for the
    /// compiled right-hand side).
    fn rhs(&self, x: &[f64], inputs: &InputValues<f64>, dx: &mut [f64]) -> Result<(), Bail>;

    /// The implicit stage of the bristle states, as
    /// [`crate::Model::rhs_implicit_bristles`] (for the compiled implicit stage).
    fn implicit_stage(
        &self,
        x: &mut [f64],
        inputs: &InputValues<f64>,
        step: f64,
        dx: &mut [f64],
    ) -> Result<(), Bail>;

    /// Floating-point operations in the compiled function.
    fn operations(&self) -> usize;

    /// Branches of the evaluation the compiled function checks.
    fn guards(&self) -> usize;

    /// How long recording, compiling and checking it took.
    fn compile_time(&self) -> Duration;

    /// The code generator's own type behind this trait, so that its crate
    /// can call it without the trait's indirection (an engine's hot loop).
    fn as_any(&self) -> &dyn std::any::Any;
}

/// Why a model's function is not compiled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NotCompiled {
    /// The evaluation does something compiled code cannot repeat.
    #[error("{0}")]
    Unsupported(String),
    /// The machine or the code generator could not produce the code.
    #[error("no native code: {0}")]
    CodeGeneration(String),
    /// The compiled function disagreed with the evaluation on a check state.
    #[error(
        "the compiled {function} gave {compiled:e} for {quantity} where the evaluation gives {evaluated:e}"
    )]
    Disagrees {
        /// Which function.
        function: &'static str,
        /// Which output.
        quantity: String,
        /// The compiled function's value.
        compiled: f64,
        /// The evaluation's value.
        evaluated: f64,
    },
    /// The model has no bristle states, so no implicit stage.
    #[error("the model has no bristle states")]
    NoBristles,
    /// Switched off for this model ([`crate::Model::interpreted`]).
    #[error("switched off")]
    Disabled,
    /// The program was built without a code generator (a lean build: the
    /// generic evaluation gives the same numbers, more slowly).
    #[error("this build has no code generator: the program's `machine-code` feature is off")]
    NoCodeGenerator,
}

/// A compiled function as a model keeps it (shared by the model's clones).
pub type Compiled = Result<Box<dyn MachineCode>, NotCompiled>;

//! The code generator of a build without Cranelift (the `cranelift` feature
//! off): there is none. [`Generator::host`] says so, and no [`Code`] can
//! exist, so nothing here ever runs; the model is evaluated generically.

use super::tape::Tape;

/// This build generates no code.
pub(crate) const AVAILABLE: bool = false;

/// The C signature compiled functions would have (see the Cranelift emitter).
pub(crate) type KernelFn = unsafe extern "C" fn(*mut f64, *mut f64, *const f64, f64) -> u32;

/// A code generator that cannot be made.
pub(crate) enum Generator {}

/// Compiled code that cannot exist.
pub(crate) enum Code {}

/// The handle of a function added to a generator.
pub(crate) struct FuncId;

impl Generator {
    /// Always the reason there is no generator.
    pub(crate) fn host() -> Result<Self, String> {
        Err("this build has no code generator (its `cranelift` feature is off)".into())
    }

    /// Unreachable: no generator exists.
    pub(crate) fn add(&mut self, _name: &str, _tape: &Tape) -> Result<FuncId, String> {
        match *self {}
    }

    /// Unreachable: no generator exists.
    pub(crate) fn finish(self, _id: FuncId) -> Result<(KernelFn, Code), String> {
        match self {}
    }
}

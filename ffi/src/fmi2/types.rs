//! The FMI 2.0 C types as the official headers `fmi2TypesPlatform.h` and
//! `fmi2FunctionTypes.h` define them. The generated header excludes these
//! names and includes the official headers instead, so the two cannot drift.
//! Enumerations that arrive from C (`fmi2Type`, `fmi2StatusKind`) are plain
//! `c_int` here: an out-of-range value in a Rust enum would be undefined
//! behaviour.
#![allow(non_camel_case_types, non_snake_case)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// Pointer to an instance.
pub type fmi2Component = *mut c_void;
/// Pointer to the importer's environment, passed back to callbacks.
pub type fmi2ComponentEnvironment = *mut c_void;
/// Pointer to a saved FMU state.
pub type fmi2FMUstate = *mut c_void;
/// Value reference.
pub type fmi2ValueReference = c_uint;
/// Real.
pub type fmi2Real = f64;
/// Integer.
pub type fmi2Integer = c_int;
/// Boolean (0 false, anything else true).
pub type fmi2Boolean = c_int;
/// Character.
pub type fmi2Char = c_char;
/// Zero-terminated string.
pub type fmi2String = *const fmi2Char;
/// Byte of a serialized state.
pub type fmi2Byte = c_char;
/// `fmi2Status` (enum in C).
pub type fmi2Status = c_int;
/// `fmi2Type` (enum in C).
pub type fmi2Type = c_int;
/// `fmi2StatusKind` (enum in C).
pub type fmi2StatusKind = c_int;

/// The logger callback (printf-like).
pub type fmi2CallbackLogger = Option<
    unsafe extern "C" fn(
        fmi2ComponentEnvironment,
        fmi2String,
        fmi2Status,
        fmi2String,
        fmi2String,
        ...
    ),
>;
/// Memory allocation callback (unused: the unit does not need it).
pub type fmi2CallbackAllocateMemory = Option<unsafe extern "C" fn(usize, usize) -> *mut c_void>;
/// Memory release callback (unused).
pub type fmi2CallbackFreeMemory = Option<unsafe extern "C" fn(*mut c_void)>;
/// Asynchronous step callback (unused: steps are synchronous).
pub type fmi2StepFinished = Option<unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status)>;

/// The callbacks an importer passes to fmi2Instantiate.
#[repr(C)]
pub struct fmi2CallbackFunctions {
    /// Logger.
    pub logger: fmi2CallbackLogger,
    /// Allocator.
    pub allocateMemory: fmi2CallbackAllocateMemory,
    /// Deallocator.
    pub freeMemory: fmi2CallbackFreeMemory,
    /// Step-finished notification.
    pub stepFinished: fmi2StepFinished,
    /// Environment pointer for the callbacks.
    pub componentEnvironment: fmi2ComponentEnvironment,
}

/// `fmi2Type` value of Model Exchange.
pub(crate) const MODEL_EXCHANGE: c_int = 0;
/// `fmi2Type` value of Co-Simulation.
pub(crate) const CO_SIMULATION: c_int = 1;

/// What fmi2NewDiscreteStates tells a Model Exchange importer.
#[repr(C)]
pub struct fmi2EventInfo {
    /// Another event iteration is needed.
    pub newDiscreteStatesNeeded: fmi2Boolean,
    /// The simulation should end.
    pub terminateSimulation: fmi2Boolean,
    /// The nominal values of the states changed.
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    /// The values of the states changed.
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    /// `nextEventTime` holds the next time event.
    pub nextEventTimeDefined: fmi2Boolean,
    /// The next time event, s.
    pub nextEventTime: fmi2Real,
}

/// `fmi2StatusKind` values.
pub(crate) mod status_kind {
    use std::ffi::c_int;
    pub(crate) const DO_STEP_STATUS: c_int = 0;
    pub(crate) const PENDING_STATUS: c_int = 1;
    pub(crate) const LAST_SUCCESSFUL_TIME: c_int = 2;
    pub(crate) const TERMINATED: c_int = 3;
}

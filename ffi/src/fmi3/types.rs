//! The FMI 3.0 C types as the official headers `fmi3PlatformTypes.h` and
//! `fmi3FunctionTypes.h` define them. The generated header excludes these
//! names and includes the official headers instead. `fmi3Boolean` is C's
//! `bool`, which Rust's `bool` matches.
#![allow(non_camel_case_types)]

use std::ffi::{c_char, c_int, c_void};

/// Pointer to an instance.
pub type fmi3Instance = *mut c_void;
/// Pointer to the importer's environment, passed back to callbacks.
pub type fmi3InstanceEnvironment = *mut c_void;
/// Pointer to a saved FMU state.
pub type fmi3FMUState = *mut c_void;
/// Value reference.
pub type fmi3ValueReference = u32;
/// Float32.
pub type fmi3Float32 = f32;
/// Float64.
pub type fmi3Float64 = f64;
/// Int8.
pub type fmi3Int8 = i8;
/// UInt8.
pub type fmi3UInt8 = u8;
/// Int16.
pub type fmi3Int16 = i16;
/// UInt16.
pub type fmi3UInt16 = u16;
/// Int32.
pub type fmi3Int32 = i32;
/// UInt32.
pub type fmi3UInt32 = u32;
/// Int64.
pub type fmi3Int64 = i64;
/// UInt64.
pub type fmi3UInt64 = u64;
/// Boolean (C `bool`).
pub type fmi3Boolean = bool;
/// Character.
pub type fmi3Char = c_char;
/// Zero-terminated string.
pub type fmi3String = *const fmi3Char;
/// Byte.
pub type fmi3Byte = u8;
/// Binary value.
pub type fmi3Binary = *const fmi3Byte;
/// Clock value (C `bool`).
pub type fmi3Clock = bool;
/// `fmi3Status` (enum in C; the same values as FMI 2.0's).
pub type fmi3Status = c_int;
/// `fmi3DependencyKind` (enum in C).
pub type fmi3DependencyKind = c_int;
/// `fmi3IntervalQualifier` (enum in C).
pub type fmi3IntervalQualifier = c_int;

/// The logger callback.
pub type fmi3LogMessageCallback =
    Option<unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String)>;
/// Clock update callback (unused: no clocks).
pub type fmi3ClockUpdateCallback = Option<unsafe extern "C" fn(fmi3InstanceEnvironment)>;
/// Intermediate update callback (unused: no early return).
pub type fmi3IntermediateUpdateCallback = Option<
    unsafe extern "C" fn(
        fmi3InstanceEnvironment,
        fmi3Float64,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        fmi3Boolean,
        *mut fmi3Boolean,
        *mut fmi3Float64,
    ),
>;
/// Preemption lock callback (unused: no Scheduled Execution).
pub type fmi3LockPreemptionCallback = Option<unsafe extern "C" fn()>;
/// Preemption unlock callback (unused).
pub type fmi3UnlockPreemptionCallback = Option<unsafe extern "C" fn()>;

//! The FMI 3.0 functions, as `extern "C"` symbols beside FMI 2.0's in the
//! same library. Each is a thin face over [`Instance`], through the same
//! checks as the FMI 2.0 functions (live instance, array pointers and
//! lengths, `catch_unwind`, every refusal explained through the importer's
//! logger); where FMI 2.0 has the same call, the body is shared
//! (`crate::shared::calls`) and only the name differs. Functions for what the plant leaves out (clocks, Scheduled
//! Execution, configuration mode, types other than Float64) refuse with a
//! reason; they are spelled out one by one rather than made by a macro, so
//! that cbindgen (which does not expand macros) declares every one.
#![allow(non_snake_case)] // parameter names as in the FMI 3.0 standard

use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use super::types::*;
use crate::shared::c_args::{input_slice, output_slice, text};
use crate::shared::calls;
use crate::shared::instance::{CallError, Instance, Interface};
use crate::shared::logger::Logger;
use crate::shared::registry::{self, panic_text, register, with_slot};
use crate::shared::status::Status;

/// The value reference of the independent variable `time` (after every
/// variable of [`crate::variables()`]).
fn time_reference(instance: &Instance) -> u32 {
    instance.variables().len() as u32
}

fn instantiate(
    call: &'static str,
    name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    logger: Logger,
    interface: Interface,
) -> fmi3Instance {
    let _ = name;
    let fail = |message: String| {
        logger.error(Status::Error, &format!("{call}: {message}"));
        std::ptr::null_mut()
    };
    let Some(token) = text(token) else {
        return fail("instantiationToken is a null pointer".into());
    };
    let Some(path) = text(resource_path) else {
        return fail("resourcePath is a null pointer".into());
    };
    let folder = PathBuf::from(path);
    let instance = match Instance::for_interface(&folder, Some(&token), interface) {
        Ok(instance) => instance,
        Err(error) => return fail(error.to_string()),
    };
    logger.trace(&format!("{call}: resources {}", folder.display()));
    register(instance, logger)
}

/// Runs an instantiation, a panic becoming a logged null.
fn guarded(
    call: &'static str,
    logger: &Logger,
    body: impl FnOnce() -> fmi3Instance,
) -> fmi3Instance {
    catch_unwind(AssertUnwindSafe(body)).unwrap_or_else(|payload| {
        logger.error(
            Status::Fatal,
            &format!("{call}: internal error ({})", panic_text(payload.as_ref())),
        );
        std::ptr::null_mut()
    })
}

/// fmi3GetVersion.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3GetVersion() -> *const c_char {
    c"3.0".as_ptr()
}

/// fmi3SetDebugLogging: turns call traces on or off; categories must be declared ones.
///
/// # Safety
/// `categories` is null or points to `nCategories` strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetDebugLogging(
    instance: fmi3Instance,
    loggingOn: fmi3Boolean,
    nCategories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::set_debug_logging(
            instance,
            "fmi3SetDebugLogging",
            loggingOn,
            nCategories,
            categories,
        )
    }
}

/// fmi3InstantiateModelExchange: loads the robot and scenario from
/// `resourcePath`; null (and a logged reason) on any failure.
///
/// # Safety
/// Strings are null or NUL-terminated; `logMessage` is null or valid for
/// the lifetime of the instance.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateModelExchange(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
) -> fmi3Instance {
    let _ = visible;
    let call = "fmi3InstantiateModelExchange";
    let name = text(instanceName).unwrap_or_default();
    let logger = Logger::fmi3(logMessage, instanceEnvironment, &name, loggingOn);
    let reporter = logger.clone();
    guarded(call, &reporter, || {
        instantiate(
            call,
            instanceName,
            instantiationToken,
            resourcePath,
            logger,
            Interface::ModelExchange,
        )
    })
}

/// fmi3InstantiateCoSimulation: as Model Exchange; event mode, early return
/// and intermediate variables are not offered (asked for, the call fails).
///
/// # Safety
/// As [`fmi3InstantiateModelExchange`]; `requiredIntermediateVariables` is
/// null or points to `nRequiredIntermediateVariables` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateCoSimulation(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    eventModeUsed: fmi3Boolean,
    earlyReturnAllowed: fmi3Boolean,
    requiredIntermediateVariables: *const fmi3ValueReference,
    nRequiredIntermediateVariables: usize,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    intermediateUpdate: fmi3IntermediateUpdateCallback,
) -> fmi3Instance {
    let _ = (
        visible,
        earlyReturnAllowed,
        requiredIntermediateVariables,
        intermediateUpdate,
    );
    let call = "fmi3InstantiateCoSimulation";
    let name = text(instanceName).unwrap_or_default();
    let logger = Logger::fmi3(logMessage, instanceEnvironment, &name, loggingOn);
    if eventModeUsed || nRequiredIntermediateVariables > 0 {
        logger.error(
            Status::Error,
            &format!(
                "{call}: event mode and intermediate variables are not offered \
                 (hasEventMode = false, no intermediate update)"
            ),
        );
        return std::ptr::null_mut();
    }
    let reporter = logger.clone();
    guarded(call, &reporter, || {
        instantiate(
            call,
            instanceName,
            instantiationToken,
            resourcePath,
            logger,
            Interface::CoSimulation,
        )
    })
}

/// fmi3InstantiateScheduledExecution: not offered; returns null.
///
/// # Safety
/// As [`fmi3InstantiateModelExchange`].
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3InstantiateScheduledExecution(
    instanceName: fmi3String,
    instantiationToken: fmi3String,
    resourcePath: fmi3String,
    visible: fmi3Boolean,
    loggingOn: fmi3Boolean,
    instanceEnvironment: fmi3InstanceEnvironment,
    logMessage: fmi3LogMessageCallback,
    clockUpdate: fmi3ClockUpdateCallback,
    lockPreemption: fmi3LockPreemptionCallback,
    unlockPreemption: fmi3UnlockPreemptionCallback,
) -> fmi3Instance {
    let _ = (instantiationToken, resourcePath, visible, clockUpdate);
    let _ = (lockPreemption, unlockPreemption);
    let name = text(instanceName).unwrap_or_default();
    Logger::fmi3(logMessage, instanceEnvironment, &name, loggingOn).error(
        Status::Error,
        "fmi3InstantiateScheduledExecution: the unit offers Model Exchange and Co-Simulation only",
    );
    std::ptr::null_mut()
}

/// fmi3FreeInstance.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3FreeInstance(instance: fmi3Instance) {
    registry::free(instance);
}

/// fmi3EnterInitializationMode: the experiment (tolerance, start, stop)
/// and initialisation mode in one call.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterInitializationMode(
    instance: fmi3Instance,
    toleranceDefined: fmi3Boolean,
    tolerance: fmi3Float64,
    startTime: fmi3Float64,
    stopTimeDefined: fmi3Boolean,
    stopTime: fmi3Float64,
) -> fmi3Status {
    with_slot(instance, "fmi3EnterInitializationMode", |slot| {
        slot.instance.setup_experiment(
            toleranceDefined.then_some(tolerance),
            startTime,
            stopTimeDefined.then_some(stopTime),
        )?;
        slot.instance.enter_initialization()?;
        Ok(Status::Ok)
    })
}

/// fmi3ExitInitializationMode: Model Exchange to event mode, Co-Simulation
/// to step mode.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3ExitInitializationMode(instance: fmi3Instance) -> fmi3Status {
    calls::change(instance, "fmi3ExitInitializationMode", |i| {
        i.exit_initialization().map(drop)
    })
}

/// fmi3EnterEventMode (Model Exchange; Co-Simulation has no event mode).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterEventMode(instance: fmi3Instance) -> fmi3Status {
    calls::change(instance, "fmi3EnterEventMode", |i| {
        i.enter_event_mode().map(drop)
    })
}

/// fmi3Terminate.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3Terminate(instance: fmi3Instance) -> fmi3Status {
    calls::change(instance, "fmi3Terminate", |i| i.terminate().map(drop))
}

/// fmi3Reset.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3Reset(instance: fmi3Instance) -> fmi3Status {
    calls::change(instance, "fmi3Reset", |i| i.reset().map(drop))
}

/// fmi3GetFloat64: every variable is Float64; `time` too.
///
/// # Safety
/// `valueReferences` and `values` are null or have the given lengths.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    with_slot(instance, "fmi3GetFloat64", |slot| {
        scalars(nValueReferences, nValues)?;
        // SAFETY: by the caller's guarantee.
        let (vrs, values) = unsafe {
            (
                input_slice(valueReferences, nValueReferences, "valueReferences")?,
                output_slice(values, nValues, "values")?,
            )
        };
        let time = time_reference(&slot.instance);
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            *value = match *vr == time {
                true => slot.instance.time(),
                false => {
                    let mut one = [0.0];
                    slot.instance.get_real(&[*vr], &mut one)?;
                    one[0]
                }
            };
        }
        Ok(Status::Ok)
    })
}

/// fmi3SetFloat64: parameters before initialisation ends, inputs any time.
///
/// # Safety
/// `valueReferences` and `values` are null or have the given lengths.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    with_slot(instance, "fmi3SetFloat64", |slot| {
        scalars(nValueReferences, nValues)?;
        // SAFETY: by the caller's guarantee.
        let (vrs, values) = unsafe {
            (
                input_slice(valueReferences, nValueReferences, "valueReferences")?,
                input_slice(values, nValues, "values")?,
            )
        };
        if vrs.contains(&time_reference(&slot.instance)) {
            return Err(CallError::NotSettable {
                name: "time".into(),
                why: "it is the independent variable (fmi3SetTime sets it in Model Exchange)"
                    .into(),
            });
        }
        slot.instance.set_real(vrs, values)?;
        Ok(Status::Ok)
    })
}

/// Every variable is a scalar: as many values as references.
fn scalars(references: usize, values: usize) -> Result<(), CallError> {
    match references == values {
        true => Ok(()),
        false => Err(CallError::InvalidArgument(format!(
            "nValues = {values} for {references} scalar variables"
        ))),
    }
}

/// Refuses any value reference of a type the unit has none of.
fn no_variables(
    instance: fmi3Instance,
    call: &'static str,
    n: usize,
    first: *const fmi3ValueReference,
    kind: &'static str,
) -> fmi3Status {
    with_slot(instance, call, |_| {
        if n == 0 {
            return Ok(Status::Ok);
        }
        // SAFETY: a non-null pointer of a call with n > 0 points to n references.
        let vr = unsafe { input_slice(first, n, "valueReferences") }?[0];
        Err(CallError::InvalidArgument(format!(
            "unknown value reference {vr}: this unit has no {kind} variables"
        )))
    })
}

/// fmi3GetFloat32: the unit has no Float32 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFloat32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Float32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetFloat32",
        nValueReferences,
        valueReferences,
        "Float32",
    )
}

/// fmi3SetFloat32: the unit has no Float32 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetFloat32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Float32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetFloat32",
        nValueReferences,
        valueReferences,
        "Float32",
    )
}

/// fmi3GetInt8: the unit has no Int8 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetInt8",
        nValueReferences,
        valueReferences,
        "Int8",
    )
}

/// fmi3SetInt8: the unit has no Int8 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetInt8",
        nValueReferences,
        valueReferences,
        "Int8",
    )
}

/// fmi3GetUInt8: the unit has no UInt8 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetUInt8",
        nValueReferences,
        valueReferences,
        "UInt8",
    )
}

/// fmi3SetUInt8: the unit has no UInt8 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt8(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt8,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetUInt8",
        nValueReferences,
        valueReferences,
        "UInt8",
    )
}

/// fmi3GetInt16: the unit has no Int16 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetInt16",
        nValueReferences,
        valueReferences,
        "Int16",
    )
}

/// fmi3SetInt16: the unit has no Int16 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetInt16",
        nValueReferences,
        valueReferences,
        "Int16",
    )
}

/// fmi3GetUInt16: the unit has no UInt16 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetUInt16",
        nValueReferences,
        valueReferences,
        "UInt16",
    )
}

/// fmi3SetUInt16: the unit has no UInt16 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt16(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt16,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetUInt16",
        nValueReferences,
        valueReferences,
        "UInt16",
    )
}

/// fmi3GetInt32: the unit has no Int32 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetInt32",
        nValueReferences,
        valueReferences,
        "Int32",
    )
}

/// fmi3SetInt32: the unit has no Int32 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetInt32",
        nValueReferences,
        valueReferences,
        "Int32",
    )
}

/// fmi3GetUInt32: the unit has no UInt32 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetUInt32",
        nValueReferences,
        valueReferences,
        "UInt32",
    )
}

/// fmi3SetUInt32: the unit has no UInt32 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt32(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt32,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetUInt32",
        nValueReferences,
        valueReferences,
        "UInt32",
    )
}

/// fmi3GetInt64: the unit has no Int64 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetInt64",
        nValueReferences,
        valueReferences,
        "Int64",
    )
}

/// fmi3SetInt64: the unit has no Int64 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Int64,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetInt64",
        nValueReferences,
        valueReferences,
        "Int64",
    )
}

/// fmi3GetUInt64: the unit has no UInt64 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetUInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3UInt64,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetUInt64",
        nValueReferences,
        valueReferences,
        "UInt64",
    )
}

/// fmi3SetUInt64: the unit has no UInt64 variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetUInt64(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3UInt64,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetUInt64",
        nValueReferences,
        valueReferences,
        "UInt64",
    )
}

/// fmi3GetBoolean: the unit has no Boolean variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetBoolean",
        nValueReferences,
        valueReferences,
        "Boolean",
    )
}

/// fmi3SetBoolean: the unit has no Boolean variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBoolean(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Boolean,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetBoolean",
        nValueReferences,
        valueReferences,
        "Boolean",
    )
}

/// fmi3GetString: the unit has no String variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3String,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3GetString",
        nValueReferences,
        valueReferences,
        "String",
    )
}

/// fmi3SetString: the unit has no String variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetString(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3String,
    nValues: usize,
) -> fmi3Status {
    let _ = (values, nValues);
    no_variables(
        instance,
        "fmi3SetString",
        nValueReferences,
        valueReferences,
        "String",
    )
}

/// fmi3GetBinary: the unit has no Binary variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    valueSizes: *mut usize,
    values: *mut fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    let _ = (valueSizes, values, nValues);
    no_variables(
        instance,
        "fmi3GetBinary",
        nValueReferences,
        valueReferences,
        "Binary",
    )
}

/// fmi3SetBinary: the unit has no Binary variables.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetBinary(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    valueSizes: *const usize,
    values: *const fmi3Binary,
    nValues: usize,
) -> fmi3Status {
    let _ = (valueSizes, values, nValues);
    no_variables(
        instance,
        "fmi3SetBinary",
        nValueReferences,
        valueReferences,
        "Binary",
    )
}

/// fmi3GetClock: the unit has no clocks.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *mut fmi3Clock,
) -> fmi3Status {
    let _ = values;
    no_variables(
        instance,
        "fmi3GetClock",
        nValueReferences,
        valueReferences,
        "Clock",
    )
}

/// fmi3SetClock: the unit has no clocks.
///
/// # Safety
/// `valueReferences` is null or points to `nValueReferences` references.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetClock(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    values: *const fmi3Clock,
) -> fmi3Status {
    let _ = values;
    no_variables(
        instance,
        "fmi3SetClock",
        nValueReferences,
        valueReferences,
        "Clock",
    )
}

/// A refusal of a function for something the unit leaves out.
fn refuse(instance: fmi3Instance, call: &'static str, why: &'static str) -> fmi3Status {
    with_slot(instance, call, |_| Err(CallError::Unsupported(why.into())))
}

/// fmi3GetNumberOfVariableDependencies: not provided (the description
/// declares no dependencies, meaning every known).
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfVariableDependencies(
    instance: fmi3Instance,
    valueReference: fmi3ValueReference,
    nDependencies: *mut usize,
) -> fmi3Status {
    let _ = (valueReference, nDependencies);
    refuse(
        instance,
        "fmi3GetNumberOfVariableDependencies",
        DEPENDENCIES,
    )
}

/// fmi3GetVariableDependencies: not provided.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetVariableDependencies(
    instance: fmi3Instance,
    dependent: fmi3ValueReference,
    elementIndicesOfDependent: *mut usize,
    independents: *mut fmi3ValueReference,
    elementIndicesOfIndependents: *mut usize,
    dependencyKinds: *mut fmi3DependencyKind,
    nDependencies: usize,
) -> fmi3Status {
    let _ = (dependent, elementIndicesOfDependent, independents);
    let _ = (elementIndicesOfIndependents, dependencyKinds, nDependencies);
    refuse(instance, "fmi3GetVariableDependencies", DEPENDENCIES)
}

const DEPENDENCIES: &str =
    "variable dependencies are not provided: the model structure declares every known";

/// fmi3GetFMUState.
///
/// # Safety
/// `FMUState` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::get_state(instance, "fmi3GetFMUState", FMUState) }
}

/// fmi3SetFMUState.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetFMUState(instance: fmi3Instance, FMUState: fmi3FMUState) -> fmi3Status {
    calls::set_state(instance, "fmi3SetFMUState", FMUState)
}

/// fmi3FreeFMUState.
///
/// # Safety
/// `FMUState` is null or points to a state pointer.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3FreeFMUState(
    instance: fmi3Instance,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::free_state(instance, "fmi3FreeFMUState", FMUState) }
}

/// fmi3SerializedFMUStateSize.
///
/// # Safety
/// `size` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializedFMUStateSize(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    size: *mut usize,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::serialized_size(instance, "fmi3SerializedFMUStateSize", FMUState, size) }
}

/// fmi3SerializeFMUState.
///
/// # Safety
/// `serializedState` is null or points to `size` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SerializeFMUState(
    instance: fmi3Instance,
    FMUState: fmi3FMUState,
    serializedState: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    let calls = ("fmi3SerializeFMUState", "fmi3SerializedFMUStateSize");
    // SAFETY: by the caller's guarantee.
    unsafe { calls::serialize(instance, calls, FMUState, serializedState, size) }
}

/// fmi3DeserializeFMUState.
///
/// # Safety
/// `serializedState` is null or points to `size` bytes; `FMUState` is null
/// or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DeserializeFMUState(
    instance: fmi3Instance,
    serializedState: *const fmi3Byte,
    size: usize,
    FMUState: *mut fmi3FMUState,
) -> fmi3Status {
    let bytes = (serializedState, size);
    // SAFETY: by the caller's guarantee.
    unsafe { calls::deserialize(instance, "fmi3DeserializeFMUState", bytes, FMUState) }
}

/// fmi3GetDirectionalDerivative: outputs and state derivatives along a
/// direction of inputs and states, exact.
///
/// # Safety
/// The arrays are null or have the given lengths.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetDirectionalDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: usize,
    knowns: *const fmi3ValueReference,
    nKnowns: usize,
    seed: *const fmi3Float64,
    nSeed: usize,
    sensitivity: *mut fmi3Float64,
    nSensitivity: usize,
) -> fmi3Status {
    with_slot(instance, "fmi3GetDirectionalDerivative", |slot| {
        scalars(nKnowns, nSeed)?;
        scalars(nUnknowns, nSensitivity)?;
        // SAFETY: by the caller's guarantee.
        let (unknowns, knowns, seed, sensitivity) = unsafe {
            (
                input_slice(unknowns, nUnknowns, "unknowns")?,
                input_slice(knowns, nKnowns, "knowns")?,
                input_slice(seed, nSeed, "seed")?,
                output_slice(sensitivity, nSensitivity, "sensitivity")?,
            )
        };
        slot.instance
            .directional_derivative(unknowns, knowns, seed, sensitivity)?;
        Ok(Status::Ok)
    })
}

/// fmi3GetAdjointDerivative: the seed (over the unknowns) times the exact
/// Jacobian of the unknowns over the knowns, one forward pass per known.
///
/// # Safety
/// The arrays are null or have the given lengths.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetAdjointDerivative(
    instance: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    nUnknowns: usize,
    knowns: *const fmi3ValueReference,
    nKnowns: usize,
    seed: *const fmi3Float64,
    nSeed: usize,
    sensitivity: *mut fmi3Float64,
    nSensitivity: usize,
) -> fmi3Status {
    with_slot(instance, "fmi3GetAdjointDerivative", |slot| {
        scalars(nUnknowns, nSeed)?;
        scalars(nKnowns, nSensitivity)?;
        // SAFETY: by the caller's guarantee.
        let (unknowns, knowns, seed, sensitivity) = unsafe {
            (
                input_slice(unknowns, nUnknowns, "unknowns")?,
                input_slice(knowns, nKnowns, "knowns")?,
                input_slice(seed, nSeed, "seed")?,
                output_slice(sensitivity, nSensitivity, "sensitivity")?,
            )
        };
        let mut column = vec![0.0; unknowns.len()];
        for (known, out) in knowns.iter().zip(sensitivity.iter_mut()) {
            slot.instance
                .directional_derivative(unknowns, &[*known], &[1.0], &mut column)?;
            *out = column.iter().zip(seed).map(|(j, v)| j * v).sum();
        }
        Ok(Status::Ok)
    })
}

/// fmi3EnterConfigurationMode: no structural parameters.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    refuse(instance, "fmi3EnterConfigurationMode", NO_CONFIGURATION)
}

/// fmi3ExitConfigurationMode: no structural parameters.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3ExitConfigurationMode(instance: fmi3Instance) -> fmi3Status {
    refuse(instance, "fmi3ExitConfigurationMode", NO_CONFIGURATION)
}

const NO_CONFIGURATION: &str = "the unit has no structural parameters, so no configuration mode";
const NO_CLOCKS: &str = "the unit has no clocks";

/// fmi3GetIntervalDecimal: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetIntervalDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    intervals: *mut fmi3Float64,
    qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, intervals, qualifiers);
    refuse(instance, "fmi3GetIntervalDecimal", NO_CLOCKS)
}

/// fmi3GetIntervalFraction: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetIntervalFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *mut fmi3UInt64,
    resolutions: *mut fmi3UInt64,
    qualifiers: *mut fmi3IntervalQualifier,
) -> fmi3Status {
    let _ = (
        valueReferences,
        nValueReferences,
        counters,
        resolutions,
        qualifiers,
    );
    refuse(instance, "fmi3GetIntervalFraction", NO_CLOCKS)
}

/// fmi3GetShiftDecimal: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetShiftDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    shifts: *mut fmi3Float64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, shifts);
    refuse(instance, "fmi3GetShiftDecimal", NO_CLOCKS)
}

/// fmi3GetShiftFraction: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetShiftFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *mut fmi3UInt64,
    resolutions: *mut fmi3UInt64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, counters, resolutions);
    refuse(instance, "fmi3GetShiftFraction", NO_CLOCKS)
}

/// fmi3SetIntervalDecimal: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetIntervalDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    intervals: *const fmi3Float64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, intervals);
    refuse(instance, "fmi3SetIntervalDecimal", NO_CLOCKS)
}

/// fmi3SetIntervalFraction: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetIntervalFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *const fmi3UInt64,
    resolutions: *const fmi3UInt64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, counters, resolutions);
    refuse(instance, "fmi3SetIntervalFraction", NO_CLOCKS)
}

/// fmi3SetShiftDecimal: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetShiftDecimal(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    shifts: *const fmi3Float64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, shifts);
    refuse(instance, "fmi3SetShiftDecimal", NO_CLOCKS)
}

/// fmi3SetShiftFraction: the unit has no clocks.
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetShiftFraction(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    counters: *const fmi3UInt64,
    resolutions: *const fmi3UInt64,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, counters, resolutions);
    refuse(instance, "fmi3SetShiftFraction", NO_CLOCKS)
}

/// fmi3EvaluateDiscreteStates: the unit has no discrete states; nothing to do.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EvaluateDiscreteStates(instance: fmi3Instance) -> fmi3Status {
    with_slot(instance, "fmi3EvaluateDiscreteStates", |_| Ok(Status::Ok))
}

/// fmi3UpdateDiscreteStates (Model Exchange event mode): nothing discrete
/// changes; the next time event is the reference's next breakpoint.
///
/// # Safety
/// The flags and `nextEventTime` are null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3UpdateDiscreteStates(
    instance: fmi3Instance,
    discreteStatesNeedUpdate: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    nominalsOfContinuousStatesChanged: *mut fmi3Boolean,
    valuesOfContinuousStatesChanged: *mut fmi3Boolean,
    nextEventTimeDefined: *mut fmi3Boolean,
    nextEventTime: *mut fmi3Float64,
) -> fmi3Status {
    with_slot(instance, "fmi3UpdateDiscreteStates", |slot| {
        let flags = [
            discreteStatesNeedUpdate,
            terminateSimulation,
            nominalsOfContinuousStatesChanged,
            valuesOfContinuousStatesChanged,
            nextEventTimeDefined,
        ];
        if flags.iter().any(|f| f.is_null()) || nextEventTime.is_null() {
            return Err(CallError::InvalidArgument(
                "an output argument is a null pointer".into(),
            ));
        }
        let info = slot.instance.new_discrete_states()?;
        // SAFETY: all non-null; the caller passes valid pointers.
        unsafe {
            for flag in &flags[..4] {
                **flag = false;
            }
            *nextEventTimeDefined = info.next_event_time.is_some();
            *nextEventTime = info.next_event_time.unwrap_or(0.0);
        }
        Ok(Status::Ok)
    })
}

/// fmi3EnterContinuousTimeMode (Model Exchange).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterContinuousTimeMode(instance: fmi3Instance) -> fmi3Status {
    calls::change(instance, "fmi3EnterContinuousTimeMode", |i| {
        i.enter_continuous_time_mode().map(drop)
    })
}

/// fmi3CompletedIntegratorStep (Model Exchange): never asks for an event
/// or the end.
///
/// # Safety
/// The flags are null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3CompletedIntegratorStep(
    instance: fmi3Instance,
    noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    enterEventMode: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
) -> fmi3Status {
    let _ = noSetFMUStatePriorToCurrentPoint;
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::completed_integrator_step(
            instance,
            "fmi3CompletedIntegratorStep",
            [enterEventMode, terminateSimulation],
            false,
        )
    }
}

/// fmi3SetTime (Model Exchange).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3SetTime(instance: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    calls::change(instance, "fmi3SetTime", |i| i.set_time(time).map(drop))
}

/// fmi3SetContinuousStates (Model Exchange).
///
/// # Safety
/// `continuousStates` is null or points to `nContinuousStates` values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3SetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *const fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::set_continuous_states(
            instance,
            "fmi3SetContinuousStates",
            continuousStates,
            nContinuousStates,
        )
    }
}

/// fmi3GetContinuousStateDerivatives (Model Exchange).
///
/// # Safety
/// `derivatives` is null or points to `nContinuousStates` writable values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStateDerivatives(
    instance: fmi3Instance,
    derivatives: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let array = (derivatives, nContinuousStates);
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(
            instance,
            "fmi3GetContinuousStateDerivatives",
            array,
            |i, v| i.get_derivatives(v),
        )
    }
}

/// fmi3GetEventIndicators (Model Exchange): none.
///
/// # Safety
/// `eventIndicators` is null or points to `nEventIndicators` writable values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetEventIndicators(
    instance: fmi3Instance,
    eventIndicators: *mut fmi3Float64,
    nEventIndicators: usize,
) -> fmi3Status {
    let array = (eventIndicators, nEventIndicators);
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(instance, "fmi3GetEventIndicators", array, |i, v| {
            i.get_event_indicators(v.len())
        })
    }
}

/// fmi3GetContinuousStates (Model Exchange).
///
/// # Safety
/// `continuousStates` is null or points to `nContinuousStates` writable values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetContinuousStates(
    instance: fmi3Instance,
    continuousStates: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let array = (continuousStates, nContinuousStates);
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(instance, "fmi3GetContinuousStates", array, |i, v| {
            i.get_continuous_states(v)
        })
    }
}

/// fmi3GetNominalsOfContinuousStates (Model Exchange).
///
/// # Safety
/// `nominals` is null or points to `nContinuousStates` writable values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNominalsOfContinuousStates(
    instance: fmi3Instance,
    nominals: *mut fmi3Float64,
    nContinuousStates: usize,
) -> fmi3Status {
    let array = (nominals, nContinuousStates);
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(
            instance,
            "fmi3GetNominalsOfContinuousStates",
            array,
            |i, v| i.get_nominals(v),
        )
    }
}

/// A count for an `size_t*` argument.
///
/// # Safety
/// `out` is null or valid for writes.
unsafe fn count(
    instance: fmi3Instance,
    call: &'static str,
    out: *mut usize,
    get: impl FnOnce(&Instance) -> usize,
) -> fmi3Status {
    with_slot(instance, call, |slot| {
        if out.is_null() {
            return Err(CallError::InvalidArgument(
                "the count is a null pointer".into(),
            ));
        }
        // SAFETY: non-null; the caller passes a valid pointer.
        unsafe { *out = get(&slot.instance) };
        Ok(Status::Ok)
    })
}

/// fmi3GetNumberOfEventIndicators: none.
///
/// # Safety
/// `nEventIndicators` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfEventIndicators(
    instance: fmi3Instance,
    nEventIndicators: *mut usize,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        count(
            instance,
            "fmi3GetNumberOfEventIndicators",
            nEventIndicators,
            |_| 0,
        )
    }
}

/// fmi3GetNumberOfContinuousStates.
///
/// # Safety
/// `nContinuousStates` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetNumberOfContinuousStates(
    instance: fmi3Instance,
    nContinuousStates: *mut usize,
) -> fmi3Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        count(
            instance,
            "fmi3GetNumberOfContinuousStates",
            nContinuousStates,
            Instance::n_continuous_states,
        )
    }
}

/// fmi3EnterStepMode: Co-Simulation has no event mode here (hasEventMode = false).
#[unsafe(no_mangle)]
pub extern "C" fn fmi3EnterStepMode(instance: fmi3Instance) -> fmi3Status {
    refuse(
        instance,
        "fmi3EnterStepMode",
        "the unit has no event mode in Co-Simulation (hasEventMode = false): it is always in step mode",
    )
}

/// fmi3GetOutputDerivatives: not provided (maxOutputDerivativeOrder = 0).
///
/// # Safety
/// Any arguments: the call is refused.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3GetOutputDerivatives(
    instance: fmi3Instance,
    valueReferences: *const fmi3ValueReference,
    nValueReferences: usize,
    orders: *const fmi3Int32,
    values: *mut fmi3Float64,
    nValues: usize,
) -> fmi3Status {
    let _ = (valueReferences, nValueReferences, orders, values, nValues);
    refuse(
        instance,
        "fmi3GetOutputDerivatives",
        "output derivatives are not provided (maxOutputDerivativeOrder = 0)",
    )
}

/// fmi3DoStep: integrates with error control, inputs held; never returns
/// early or asks for event handling.
///
/// # Safety
/// The output arguments are null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi3DoStep(
    instance: fmi3Instance,
    currentCommunicationPoint: fmi3Float64,
    communicationStepSize: fmi3Float64,
    noSetFMUStatePriorToCurrentPoint: fmi3Boolean,
    eventHandlingNeeded: *mut fmi3Boolean,
    terminateSimulation: *mut fmi3Boolean,
    earlyReturn: *mut fmi3Boolean,
    lastSuccessfulTime: *mut fmi3Float64,
) -> fmi3Status {
    let _ = noSetFMUStatePriorToCurrentPoint;
    with_slot(instance, "fmi3DoStep", |slot| {
        let flags = [eventHandlingNeeded, terminateSimulation, earlyReturn];
        if flags.iter().any(|f| f.is_null()) || lastSuccessfulTime.is_null() {
            return Err(CallError::InvalidArgument(
                "an output argument is a null pointer".into(),
            ));
        }
        let outcome = slot
            .instance
            .do_step(currentCommunicationPoint, communicationStepSize);
        // SAFETY: all non-null; the caller passes valid pointers.
        unsafe {
            for flag in flags {
                *flag = false;
            }
            *lastSuccessfulTime = slot.instance.time();
        }
        outcome.map(|()| Status::Ok)
    })
}

/// fmi3ActivateModelPartition: no Scheduled Execution.
#[unsafe(no_mangle)]
pub extern "C" fn fmi3ActivateModelPartition(
    instance: fmi3Instance,
    clockReference: fmi3ValueReference,
    activationTime: fmi3Float64,
) -> fmi3Status {
    let _ = (clockReference, activationTime);
    refuse(
        instance,
        "fmi3ActivateModelPartition",
        "the unit offers no Scheduled Execution",
    )
}

//! The 44 FMI 2.0 functions (common, Model Exchange and Co-Simulation), as
//! `extern "C"` symbols. Each is a thin face over [`Instance`] through the
//! shared registry (`crate::shared`): it checks the instance pointer against
//! the set of live instances, checks the array pointers, runs the call
//! inside `catch_unwind` (a panic becomes fmi2Fatal and a log message, never
//! an unwind into the host), and reports every refusal through the
//! importer's logger. Where FMI 3.0 has the same call, the body is shared
//! (`crate::shared::calls`) and only the name differs.
#![allow(non_snake_case)] // parameter names as in the FMI 2.0 standard

use std::ffi::c_char;
use std::panic::{AssertUnwindSafe, catch_unwind};

use super::types::{
    CO_SIMULATION, MODEL_EXCHANGE, fmi2Boolean, fmi2Byte, fmi2CallbackFunctions, fmi2Component,
    fmi2EventInfo, fmi2FMUstate, fmi2Integer, fmi2Real, fmi2Status, fmi2StatusKind, fmi2String,
    fmi2Type, fmi2ValueReference, status_kind,
};
use crate::shared::c_args::{input_slice, output_slice, resource_folder, text};
use crate::shared::calls;
use crate::shared::instance::{CallError, Instance, Interface};
use crate::shared::logger::Logger;
use crate::shared::phase::Phase;
use crate::shared::registry::{self, panic_text, register, with_slot};
use crate::shared::status::Status;

/// fmi2GetTypesPlatform.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetTypesPlatform() -> *const c_char {
    c"default".as_ptr()
}

/// fmi2GetVersion.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetVersion() -> *const c_char {
    c"2.0".as_ptr()
}

/// fmi2SetDebugLogging: turns call traces on or off; categories must be declared ones.
///
/// # Safety
/// `categories` is null or points to `nCategories` strings.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetDebugLogging(
    c: fmi2Component,
    loggingOn: fmi2Boolean,
    nCategories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::set_debug_logging(
            c,
            "fmi2SetDebugLogging",
            loggingOn != 0,
            nCategories,
            categories,
        )
    }
}

fn instantiate(
    fmu_type: fmi2Type,
    guid: Option<String>,
    resources: Option<String>,
    logger: Logger,
) -> fmi2Component {
    let fail = |message: String| {
        logger.error(Status::Error, &format!("fmi2Instantiate: {message}"));
        std::ptr::null_mut()
    };
    let interface = match fmu_type {
        MODEL_EXCHANGE => Interface::ModelExchange,
        CO_SIMULATION => Interface::CoSimulation,
        other => {
            return fail(format!(
                "fmuType {other} requested; this unit offers fmi2ModelExchange (0) and \
                 fmi2CoSimulation (1)"
            ));
        }
    };
    let Some(guid) = guid else {
        return fail("fmuGUID is a null pointer".into());
    };
    let Some(uri) = resources else {
        return fail("fmuResourceLocation is a null pointer".into());
    };
    let folder = match resource_folder(&uri) {
        Ok(folder) => folder,
        Err(message) => return fail(message),
    };
    let instance = match Instance::for_interface(&folder, Some(&guid), interface) {
        Ok(instance) => instance,
        Err(error) => return fail(error.to_string()),
    };
    logger.trace(&format!("fmi2Instantiate: resources {}", folder.display()));
    register(instance, logger)
}

/// fmi2Instantiate: loads the robot and scenario from the resource folder.
/// Returns null (and logs why) on any failure.
///
/// # Safety
/// Strings are null or NUL-terminated; `functions` is null or valid for the
/// lifetime of the instance.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2Instantiate(
    instanceName: fmi2String,
    fmuType: fmi2Type,
    fmuGUID: fmi2String,
    fmuResourceLocation: fmi2String,
    functions: *const fmi2CallbackFunctions,
    visible: fmi2Boolean,
    loggingOn: fmi2Boolean,
) -> fmi2Component {
    let _ = visible; // there is no window to show
    let name = text(instanceName).unwrap_or_default();
    // SAFETY: by the caller's guarantee.
    let logger = unsafe { Logger::new(functions, &name, loggingOn != 0) };
    let guid = text(fmuGUID);
    let resources = text(fmuResourceLocation);
    let reporter = logger.clone();
    catch_unwind(AssertUnwindSafe(|| {
        instantiate(fmuType, guid, resources, logger)
    }))
    .unwrap_or_else(|payload| {
        reporter.error(
            Status::Fatal,
            &format!(
                "fmi2Instantiate: internal error ({})",
                panic_text(payload.as_ref())
            ),
        );
        std::ptr::null_mut()
    })
}

/// fmi2FreeInstance. A second call with the same pointer is detected and ignored.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2FreeInstance(c: fmi2Component) {
    registry::free(c);
}

/// fmi2SetupExperiment.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetupExperiment(
    c: fmi2Component,
    toleranceDefined: fmi2Boolean,
    tolerance: fmi2Real,
    startTime: fmi2Real,
    stopTimeDefined: fmi2Boolean,
    stopTime: fmi2Real,
) -> fmi2Status {
    with_slot(c, "fmi2SetupExperiment", |slot| {
        slot.instance.setup_experiment(
            (toleranceDefined != 0).then_some(tolerance),
            startTime,
            (stopTimeDefined != 0).then_some(stopTime),
        )?;
        Ok(Status::Ok)
    })
}

/// fmi2EnterInitializationMode.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status {
    calls::change(c, "fmi2EnterInitializationMode", |i| {
        i.enter_initialization().map(drop)
    })
}

/// fmi2ExitInitializationMode: builds the model with the parameters set.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    calls::change(c, "fmi2ExitInitializationMode", |i| {
        i.exit_initialization().map(drop)
    })
}

/// fmi2Terminate.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    calls::change(c, "fmi2Terminate", |i| i.terminate().map(drop))
}

/// fmi2Reset.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    calls::change(c, "fmi2Reset", |i| i.reset().map(drop))
}

/// fmi2GetReal.
///
/// # Safety
/// `vr` and `value` are null or point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    with_slot(c, "fmi2GetReal", |slot| {
        // SAFETY: by the caller's guarantee.
        let (vr, value) = unsafe {
            (
                input_slice(vr, nvr, "vr")?,
                output_slice(value, nvr, "value")?,
            )
        };
        slot.instance.get_real(vr, value)?;
        Ok(Status::Ok)
    })
}

/// The unit has no variables of other types: any value reference is unknown.
fn no_variables(vr: &[fmi2ValueReference], kind: &str) -> Result<Status, CallError> {
    match vr.first() {
        None => Ok(Status::Ok),
        Some(&first) => Err(CallError::InvalidArgument(format!(
            "unknown value reference {first}: this unit has no {kind} variables"
        ))),
    }
}

/// Get and set for a type the unit has no variables of.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
unsafe fn typeless_call(
    c: fmi2Component,
    call: &'static str,
    vr: *const fmi2ValueReference,
    nvr: usize,
    kind: &str,
) -> fmi2Status {
    with_slot(c, call, |_| {
        // SAFETY: by the caller's guarantee.
        let vr = unsafe { input_slice(vr, nvr, "vr") }?;
        no_variables(vr, kind)
    })
}

/// fmi2GetInteger: the unit has no Integer variables, so only an empty call succeeds.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { typeless_call(c, "fmi2GetInteger", vr, nvr, "Integer") }
}

/// fmi2GetBoolean: the unit has no Boolean variables, so only an empty call succeeds.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { typeless_call(c, "fmi2GetBoolean", vr, nvr, "Boolean") }
}

/// fmi2GetString: the unit has no String variables, so only an empty call succeeds.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { typeless_call(c, "fmi2GetString", vr, nvr, "String") }
}

/// fmi2SetInteger: the unit has no Integer variables, so only an empty call succeeds.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetInteger(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2Integer,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { typeless_call(c, "fmi2SetInteger", vr, nvr, "Integer") }
}

/// fmi2SetBoolean: the unit has no Boolean variables, so only an empty call succeeds.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetBoolean(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2Boolean,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { typeless_call(c, "fmi2SetBoolean", vr, nvr, "Boolean") }
}

/// fmi2SetString: the unit has no String variables, so only an empty call succeeds.
///
/// # Safety
/// `vr` is null or points to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetString(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    _value: *const fmi2String,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { typeless_call(c, "fmi2SetString", vr, nvr, "String") }
}

/// fmi2SetReal. A refused call changes nothing.
///
/// # Safety
/// `vr` and `value` are null or point to `nvr` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetReal(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    with_slot(c, "fmi2SetReal", |slot| {
        // SAFETY: by the caller's guarantee.
        let (vr, value) = unsafe {
            (
                input_slice(vr, nvr, "vr")?,
                input_slice(value, nvr, "value")?,
            )
        };
        slot.instance.set_real(vr, value)?;
        Ok(Status::Ok)
    })
}

/// fmi2GetFMUstate: a copy of everything that determines the future.
///
/// # Safety
/// `FMUstate` is null or valid for reads and writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::get_state(c, "fmi2GetFMUstate", FMUstate) }
}

/// fmi2SetFMUstate: rolls back (or forward) to a saved state.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    calls::set_state(c, "fmi2SetFMUstate", FMUstate)
}

/// fmi2FreeFMUstate. Freeing a state twice is detected and refused.
///
/// # Safety
/// `FMUstate` is null or valid for reads and writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2FreeFMUstate(
    c: fmi2Component,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::free_state(c, "fmi2FreeFMUstate", FMUstate) }
}

/// fmi2SerializedFMUstateSize.
///
/// # Safety
/// `size` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializedFMUstateSize(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::serialized_size(c, "fmi2SerializedFMUstateSize", FMUstate, size) }
}

/// fmi2SerializeFMUstate.
///
/// # Safety
/// `serializedState` is null or points to `size` writable bytes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SerializeFMUstate(
    c: fmi2Component,
    FMUstate: fmi2FMUstate,
    serializedState: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    let calls = ("fmi2SerializeFMUstate", "fmi2SerializedFMUstateSize");
    // SAFETY: by the caller's guarantee (fmi2Byte has the size of a byte).
    unsafe { calls::serialize(c, calls, FMUstate, serializedState.cast::<u8>(), size) }
}

/// fmi2DeSerializeFMUstate.
///
/// # Safety
/// `serializedState` is null or points to `size` bytes; `FMUstate` is null
/// or valid for reads and writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2DeSerializeFMUstate(
    c: fmi2Component,
    serializedState: *const fmi2Byte,
    size: usize,
    FMUstate: *mut fmi2FMUstate,
) -> fmi2Status {
    let bytes = (serializedState.cast::<u8>(), size);
    // SAFETY: by the caller's guarantee.
    unsafe { calls::deserialize(c, "fmi2DeSerializeFMUstate", bytes, FMUstate) }
}

/// fmi2GetDirectionalDerivative: outputs with respect to inputs, exact.
///
/// # Safety
/// The arrays are null or have the given lengths.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDirectionalDerivative(
    c: fmi2Component,
    vUnknown_ref: *const fmi2ValueReference,
    nUnknown: usize,
    vKnown_ref: *const fmi2ValueReference,
    nKnown: usize,
    dvKnown: *const fmi2Real,
    dvUnknown: *mut fmi2Real,
) -> fmi2Status {
    with_slot(c, "fmi2GetDirectionalDerivative", |slot| {
        // SAFETY: by the caller's guarantee.
        let (unknowns, knowns, seed, result) = unsafe {
            (
                input_slice(vUnknown_ref, nUnknown, "vUnknown_ref")?,
                input_slice(vKnown_ref, nKnown, "vKnown_ref")?,
                input_slice(dvKnown, nKnown, "dvKnown")?,
                output_slice(dvUnknown, nUnknown, "dvUnknown")?,
            )
        };
        slot.instance
            .directional_derivative(unknowns, knowns, seed, result)?;
        Ok(Status::Ok)
    })
}

/// fmi2SetRealInputDerivatives: refused (canInterpolateInputs is false).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetRealInputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *const fmi2Real,
) -> fmi2Status {
    with_slot(c, "fmi2SetRealInputDerivatives", |_| {
        Err(CallError::Unsupported(
            "inputs are held over each step (canInterpolateInputs = false)".into(),
        ))
    })
}

/// fmi2GetRealOutputDerivatives: refused (maxOutputDerivativeOrder is 0).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2GetRealOutputDerivatives(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    with_slot(c, "fmi2GetRealOutputDerivatives", |_| {
        Err(CallError::Unsupported(
            "output derivatives are not provided (maxOutputDerivativeOrder = 0)".into(),
        ))
    })
}

/// fmi2DoStep: integrates with error control, inputs held.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2DoStep(
    c: fmi2Component,
    currentCommunicationPoint: fmi2Real,
    communicationStepSize: fmi2Real,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
) -> fmi2Status {
    with_slot(c, "fmi2DoStep", |slot| {
        slot.instance
            .do_step(currentCommunicationPoint, communicationStepSize)?;
        Ok(Status::Ok)
    })
}

/// fmi2CancelStep: refused (steps are synchronous, never pending).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2CancelStep(c: fmi2Component) -> fmi2Status {
    with_slot(c, "fmi2CancelStep", |_| {
        Err(CallError::Unsupported(
            "no step is pending: fmi2DoStep always completes before it returns".into(),
        ))
    })
}

/// # Safety
/// `value` is null or valid for writes.
unsafe fn status_getter<T>(
    c: fmi2Component,
    call: &'static str,
    value: *mut T,
    get: impl FnOnce(&Instance) -> Option<T>,
) -> fmi2Status {
    with_slot(c, call, |slot| {
        if !matches!(
            slot.instance.phase(),
            Phase::StepComplete | Phase::StepFailed | Phase::Terminated
        ) {
            return Err(CallError::WrongPhase {
                call,
                phase: slot.instance.phase(),
            });
        }
        if value.is_null() {
            return Err(CallError::InvalidArgument("value is a null pointer".into()));
        }
        match get(&slot.instance) {
            Some(v) => {
                // SAFETY: non-null; the caller passes a valid pointer.
                unsafe { *value = v };
                Ok(Status::Ok)
            }
            None => Ok(Status::Discard),
        }
    })
}

/// fmi2GetStatus: no asynchronous steps, so no status to report (fmi2Discard).
///
/// # Safety
/// `value` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Status,
) -> fmi2Status {
    // fmi2DoStepStatus and fmi2PendingStatus only exist for asynchronous steps.
    let _ = (s, status_kind::DO_STEP_STATUS, status_kind::PENDING_STATUS);
    // SAFETY: by the caller's guarantee.
    unsafe { status_getter(c, "fmi2GetStatus", value, |_| None) }
}

/// fmi2GetRealStatus: fmi2LastSuccessfulTime is the unit's time.
///
/// # Safety
/// `value` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetRealStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Real,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        status_getter(c, "fmi2GetRealStatus", value, |instance| {
            (s == status_kind::LAST_SUCCESSFUL_TIME).then(|| instance.time())
        })
    }
}

/// fmi2GetIntegerStatus: no integer status exists (fmi2Discard).
///
/// # Safety
/// `value` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetIntegerStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    value: *mut fmi2Integer,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { status_getter(c, "fmi2GetIntegerStatus", value, |_| None) }
}

/// fmi2GetBooleanStatus: fmi2Terminated is always false (the unit never asks to stop).
///
/// # Safety
/// `value` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetBooleanStatus(
    c: fmi2Component,
    s: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        status_getter(c, "fmi2GetBooleanStatus", value, |_| {
            (s == status_kind::TERMINATED).then_some(0)
        })
    }
}

/// fmi2GetStringStatus: no string status exists (fmi2Discard).
///
/// # Safety
/// `value` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetStringStatus(
    c: fmi2Component,
    _s: fmi2StatusKind,
    value: *mut fmi2String,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { status_getter(c, "fmi2GetStringStatus", value, |_| None) }
}

/// fmi2EnterEventMode (Model Exchange).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status {
    calls::change(c, "fmi2EnterEventMode", |i| i.enter_event_mode().map(drop))
}

/// fmi2NewDiscreteStates (Model Exchange): nothing discrete changes; the
/// next time event is the reference's next breakpoint.
///
/// # Safety
/// `fmi2eventInfo` is null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2NewDiscreteStates(
    c: fmi2Component,
    fmi2eventInfo: *mut fmi2EventInfo,
) -> fmi2Status {
    with_slot(c, "fmi2NewDiscreteStates", |slot| {
        if fmi2eventInfo.is_null() {
            return Err(CallError::InvalidArgument(
                "fmi2eventInfo is a null pointer".into(),
            ));
        }
        let info = slot.instance.new_discrete_states()?;
        // SAFETY: non-null; the caller passes a valid pointer.
        unsafe {
            *fmi2eventInfo = fmi2EventInfo {
                newDiscreteStatesNeeded: 0,
                terminateSimulation: 0,
                nominalsOfContinuousStatesChanged: 0,
                valuesOfContinuousStatesChanged: 0,
                nextEventTimeDefined: fmi2Boolean::from(info.next_event_time.is_some()),
                nextEventTime: info.next_event_time.unwrap_or(0.0),
            };
        }
        Ok(Status::Ok)
    })
}

/// fmi2EnterContinuousTimeMode (Model Exchange).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status {
    calls::change(c, "fmi2EnterContinuousTimeMode", |i| {
        i.enter_continuous_time_mode().map(drop)
    })
}

/// fmi2CompletedIntegratorStep (Model Exchange): never asks for an event
/// or the end.
///
/// # Safety
/// The flags are null or valid for writes.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2CompletedIntegratorStep(
    c: fmi2Component,
    _noSetFMUStatePriorToCurrentPoint: fmi2Boolean,
    enterEventMode: *mut fmi2Boolean,
    terminateSimulation: *mut fmi2Boolean,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::completed_integrator_step(
            c,
            "fmi2CompletedIntegratorStep",
            [enterEventMode, terminateSimulation],
            0,
        )
    }
}

/// fmi2SetTime (Model Exchange).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    calls::change(c, "fmi2SetTime", |i| i.set_time(time).map(drop))
}

/// fmi2SetContinuousStates (Model Exchange).
///
/// # Safety
/// `x` is null or points to `nx` elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2SetContinuousStates(
    c: fmi2Component,
    x: *const fmi2Real,
    nx: usize,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe { calls::set_continuous_states(c, "fmi2SetContinuousStates", x, nx) }
}

/// fmi2GetDerivatives (Model Exchange): the model's own right-hand side.
///
/// # Safety
/// `derivatives` is null or points to `nx` writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetDerivatives(
    c: fmi2Component,
    derivatives: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(c, "fmi2GetDerivatives", (derivatives, nx), |i, v| {
            i.get_derivatives(v)
        })
    }
}

/// fmi2GetEventIndicators (Model Exchange): the unit has none.
///
/// # Safety
/// `eventIndicators` is null or points to `ni` writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetEventIndicators(
    c: fmi2Component,
    eventIndicators: *mut fmi2Real,
    ni: usize,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(
            c,
            "fmi2GetEventIndicators",
            (eventIndicators, ni),
            |i, v| i.get_event_indicators(v.len()),
        )
    }
}

/// fmi2GetContinuousStates (Model Exchange).
///
/// # Safety
/// `x` is null or points to `nx` writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetContinuousStates(
    c: fmi2Component,
    x: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(c, "fmi2GetContinuousStates", (x, nx), |i, v| {
            i.get_continuous_states(v)
        })
    }
}

/// fmi2GetNominalsOfContinuousStates (Model Exchange).
///
/// # Safety
/// `x_nominal` is null or points to `nx` writable elements.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn fmi2GetNominalsOfContinuousStates(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    // SAFETY: by the caller's guarantee.
    unsafe {
        calls::real_array(
            c,
            "fmi2GetNominalsOfContinuousStates",
            (x_nominal, nx),
            |i, v| i.get_nominals(v),
        )
    }
}

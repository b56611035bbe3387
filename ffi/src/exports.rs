//! The 44 FMI 2.0 functions (common, Model Exchange and Co-Simulation), as
//! `extern "C"` symbols. Each is a
//! thin face over [`Instance`]: it checks the instance pointer against the set
//! of live instances, checks the array pointers, runs the call inside
//! `catch_unwind` (a panic becomes fmi2Fatal and a log message, never an
//! unwind into the host), and reports every refusal through the importer's
//! logger.
#![allow(non_snake_case)] // parameter names as in the FMI 2.0 standard

use std::collections::{BTreeSet, VecDeque};
use std::ffi::{CStr, c_char};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use crate::instance::{CallError, Instance, Interface};
use crate::logger::{LOG_CATEGORIES, Logger};
use crate::phase::Phase;
use crate::state::Snapshot;
use crate::types::{
    CO_SIMULATION, MODEL_EXCHANGE, Status, fmi2Boolean, fmi2Byte, fmi2CallbackFunctions,
    fmi2Component, fmi2EventInfo, fmi2FMUstate, fmi2Integer, fmi2Real, fmi2Status, fmi2StatusKind,
    fmi2String, fmi2Type, fmi2ValueReference, status_kind,
};

/// An instance with its logger and the FMU states it handed out.
pub(crate) struct Slot {
    pub(crate) instance: Instance,
    pub(crate) logger: Logger,
    states: BTreeSet<usize>,
}

/// Addresses of live instances: a call with any other pointer is refused.
static LIVE: Mutex<BTreeSet<usize>> = Mutex::new(BTreeSet::new());
/// Loggers of recently freed instances, to say why a late call is refused.
static FREED: Mutex<VecDeque<(usize, Logger)>> = Mutex::new(VecDeque::new());
const FREED_REMEMBERED: usize = 64;

fn lock<T>(mutex: &Mutex<T>) -> MutexGuard<'_, T> {
    mutex
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner())
}

pub(crate) fn code(status: Status) -> fmi2Status {
    status as fmi2Status
}

pub(crate) fn panic_text(payload: &(dyn std::any::Any + Send)) -> String {
    payload
        .downcast_ref::<&str>()
        .map(|s| (*s).to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into())
}

/// Runs `body` on the instance behind `c`, if it is live and usable.
pub(crate) fn with_slot(
    c: fmi2Component,
    call: &'static str,
    body: impl FnOnce(&mut Slot) -> Result<Status, CallError>,
) -> fmi2Status {
    if c.is_null() {
        return code(Status::Error);
    }
    let address = c as usize;
    if !lock(&LIVE).contains(&address) {
        // Copy the logger out so no lock is held while the importer's code runs.
        let freed = lock(&FREED)
            .iter()
            .find(|(a, _)| *a == address)
            .map(|(_, logger)| logger.clone());
        if let Some(logger) = freed {
            logger.error(
                Status::Error,
                &format!("{call}: the instance was already freed by fmi2FreeInstance"),
            );
        }
        return code(Status::Error);
    }
    let slot = c.cast::<Slot>();
    // SAFETY: the address is live, so it is a Box<Slot> made by
    // fmi2Instantiate and not yet freed; FMI forbids concurrent calls on one instance.
    let phase = unsafe { (*slot).instance.phase() };
    if phase == Phase::Fatal {
        // SAFETY: as above.
        unsafe { &*slot }.logger.error(
            Status::Error,
            &format!("{call}: the instance had a fatal error; only fmi2FreeInstance is allowed"),
        );
        return code(Status::Error);
    }
    // SAFETY: as above; the reference does not outlive this call.
    let outcome = catch_unwind(AssertUnwindSafe(|| body(unsafe { &mut *slot })));
    // SAFETY: as above; the closure's borrow has ended.
    let slot = unsafe { &mut *slot };
    match outcome {
        Ok(Ok(status)) => {
            slot.logger.trace(&format!("{call}: ok"));
            code(status)
        }
        Ok(Err(error)) => {
            slot.logger
                .error(Status::Error, &format!("{call}: {error}"));
            code(Status::Error)
        }
        Err(payload) => {
            slot.instance.poison();
            slot.logger.error(
                Status::Fatal,
                &format!(
                    "{call}: internal error ({}); the instance is unusable",
                    panic_text(payload.as_ref())
                ),
            );
            code(Status::Fatal)
        }
    }
}

/// A slice from a C array; null is allowed only for an empty array.
///
/// # Safety
/// A non-null `pointer` points to `n` valid elements.
pub(crate) unsafe fn input_slice<'a, T>(
    pointer: *const T,
    n: usize,
    what: &str,
) -> Result<&'a [T], CallError> {
    if n == 0 {
        return Ok(&[]);
    }
    if pointer.is_null() {
        return Err(CallError::InvalidArgument(format!(
            "{what} is a null pointer for {n} values"
        )));
    }
    // SAFETY: non-null and, by the caller's guarantee, n elements long.
    Ok(unsafe { std::slice::from_raw_parts(pointer, n) })
}

/// A mutable slice from a C array; null is allowed only for an empty array.
///
/// # Safety
/// A non-null `pointer` points to `n` valid, writable elements.
pub(crate) unsafe fn output_slice<'a, T>(
    pointer: *mut T,
    n: usize,
    what: &str,
) -> Result<&'a mut [T], CallError> {
    if n == 0 {
        return Ok(&mut []);
    }
    if pointer.is_null() {
        return Err(CallError::InvalidArgument(format!(
            "{what} is a null pointer for {n} values"
        )));
    }
    // SAFETY: non-null and, by the caller's guarantee, n elements long.
    Ok(unsafe { std::slice::from_raw_parts_mut(pointer, n) })
}

pub(crate) fn text(pointer: fmi2String) -> Option<String> {
    if pointer.is_null() {
        return None;
    }
    // SAFETY: a non-null fmi2String is a NUL-terminated string by the standard.
    Some(
        unsafe { CStr::from_ptr(pointer) }
            .to_string_lossy()
            .into_owned(),
    )
}

/// The folder a `file:` URI names (FMPy passes `file:///...`).
pub(crate) fn resource_folder(uri: &str) -> Result<PathBuf, String> {
    if let Some(authority) = uri.strip_prefix("file://")
        && !authority.starts_with('/')
        && !authority.starts_with("localhost/")
    {
        return Err(format!(
            "resourceLocation \"{uri}\" names a remote host; only local file: URIs are supported"
        ));
    }
    let rest = uri
        .strip_prefix("file://localhost/")
        .map(|r| format!("/{r}"))
        .or_else(|| uri.strip_prefix("file:///").map(|r| format!("/{r}")))
        .or_else(|| uri.strip_prefix("file:/").map(|r| format!("/{r}")))
        .ok_or_else(|| format!("resourceLocation \"{uri}\" is not a file: URI"))?;
    let bytes = rest.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' && i + 2 < bytes.len() {
            let hex = std::str::from_utf8(&bytes[i + 1..i + 3]).ok();
            if let Some(byte) = hex.and_then(|h| u8::from_str_radix(h, 16).ok()) {
                decoded.push(byte);
                i += 3;
                continue;
            }
        }
        decoded.push(bytes[i]);
        i += 1;
    }
    let path = String::from_utf8(decoded)
        .map_err(|_| format!("resourceLocation \"{uri}\" is not UTF-8 after decoding"))?;
    Ok(PathBuf::from(path))
}

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
    with_slot(c, "fmi2SetDebugLogging", |slot| {
        // SAFETY: by the caller's guarantee.
        let categories = unsafe { input_slice(categories, nCategories, "categories") }?;
        let mut names = Vec::with_capacity(categories.len());
        for &category in categories {
            let name = text(category).ok_or_else(|| {
                CallError::InvalidArgument("a log category is a null pointer".into())
            })?;
            if !LOG_CATEGORIES.iter().any(|(known, _)| *known == name) {
                return Err(CallError::InvalidArgument(format!(
                    "unknown log category \"{name}\" (declared: {})",
                    LOG_CATEGORIES.map(|(n, _)| n).join(", ")
                )));
            }
            names.push(name);
        }
        // Errors are always reported; the switch concerns the call trace
        // (category logCalls), named or implied by an empty list.
        if names.is_empty() || names.iter().any(|n| n == "logCalls") {
            slot.logger.debug = loggingOn != 0;
        }
        Ok(Status::Ok)
    })
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

/// Boxes an instance with its logger and makes its address live.
pub(crate) fn register(instance: Instance, logger: Logger) -> fmi2Component {
    let slot = Box::new(Slot {
        instance,
        logger,
        states: BTreeSet::new(),
    });
    let pointer = Box::into_raw(slot);
    lock(&LIVE).insert(pointer as usize);
    lock(&FREED).retain(|(a, _)| *a != pointer as usize);
    pointer.cast()
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
    if c.is_null() || !lock(&LIVE).remove(&(c as usize)) {
        return;
    }
    // SAFETY: the address was live, so it is a Box<Slot> from fmi2Instantiate;
    // it was removed from the live set, so it is freed exactly once.
    let slot = unsafe { Box::from_raw(c.cast::<Slot>()) };
    let Slot {
        instance: _,
        logger,
        states,
    } = *slot;
    for state in states {
        // SAFETY: every live state address is a Box<Snapshot> of this instance.
        drop(unsafe { Box::from_raw(state as *mut Snapshot) });
    }
    let mut freed = lock(&FREED);
    if freed.len() == FREED_REMEMBERED {
        freed.pop_front();
    }
    freed.push_back((c as usize, logger));
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
    with_slot(c, "fmi2EnterInitializationMode", |slot| {
        slot.instance.enter_initialization()?;
        Ok(Status::Ok)
    })
}

/// fmi2ExitInitializationMode: builds the model with the parameters set.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status {
    with_slot(c, "fmi2ExitInitializationMode", |slot| {
        slot.instance.exit_initialization()?;
        Ok(Status::Ok)
    })
}

/// fmi2Terminate.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Terminate(c: fmi2Component) -> fmi2Status {
    with_slot(c, "fmi2Terminate", |slot| {
        slot.instance.terminate()?;
        Ok(Status::Ok)
    })
}

/// fmi2Reset.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2Reset(c: fmi2Component) -> fmi2Status {
    with_slot(c, "fmi2Reset", |slot| {
        slot.instance.reset()?;
        Ok(Status::Ok)
    })
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

fn live_state(slot: &Slot, state: fmi2FMUstate) -> Result<&Snapshot, CallError> {
    if state.is_null() {
        return Err(CallError::InvalidArgument(
            "FMUstate is a null pointer".into(),
        ));
    }
    if !slot.states.contains(&(state as usize)) {
        return Err(CallError::InvalidArgument(
            "FMUstate is not a live state of this instance (freed already, or from another instance)"
                .into(),
        ));
    }
    // SAFETY: live state addresses are Box<Snapshot> owned by this slot.
    Ok(unsafe { &*state.cast::<Snapshot>() })
}

/// Stores `snapshot` in `*target`: into the state it already names, or a new one.
///
/// # Safety
/// `target` is null or valid for reads and writes.
unsafe fn store_state(
    slot: &mut Slot,
    target: *mut fmi2FMUstate,
    snapshot: Snapshot,
) -> Result<Status, CallError> {
    if target.is_null() {
        return Err(CallError::InvalidArgument(
            "the FMUstate argument is a null pointer".into(),
        ));
    }
    // SAFETY: non-null, by the caller's guarantee valid.
    let existing = unsafe { *target };
    if existing.is_null() {
        let pointer = Box::into_raw(Box::new(snapshot));
        slot.states.insert(pointer as usize);
        // SAFETY: as above.
        unsafe { *target = pointer.cast() };
    } else {
        live_state(slot, existing)?;
        // SAFETY: a live state of this slot.
        unsafe { *existing.cast::<Snapshot>() = snapshot };
    }
    Ok(Status::Ok)
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
    with_slot(c, "fmi2GetFMUstate", |slot| {
        let snapshot = slot.instance.snapshot();
        // SAFETY: by the caller's guarantee.
        unsafe { store_state(slot, FMUstate, snapshot) }
    })
}

/// fmi2SetFMUstate: rolls back (or forward) to a saved state.
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetFMUstate(c: fmi2Component, FMUstate: fmi2FMUstate) -> fmi2Status {
    with_slot(c, "fmi2SetFMUstate", |slot| {
        let snapshot = live_state(slot, FMUstate)?.clone();
        slot.instance.restore(&snapshot)?;
        Ok(Status::Ok)
    })
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
    with_slot(c, "fmi2FreeFMUstate", |slot| {
        if FMUstate.is_null() {
            return Err(CallError::InvalidArgument(
                "the FMUstate argument is a null pointer".into(),
            ));
        }
        // SAFETY: non-null, by the caller's guarantee valid.
        let state = unsafe { *FMUstate };
        if state.is_null() {
            return Ok(Status::Ok);
        }
        live_state(slot, state)?;
        slot.states.remove(&(state as usize));
        // SAFETY: was a live state of this slot, now removed: freed once.
        drop(unsafe { Box::from_raw(state.cast::<Snapshot>()) });
        // SAFETY: as above.
        unsafe { *FMUstate = std::ptr::null_mut() };
        Ok(Status::Ok)
    })
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
    with_slot(c, "fmi2SerializedFMUstateSize", |slot| {
        let bytes = slot.instance.serialize(live_state(slot, FMUstate)?);
        // SAFETY: by the caller's guarantee.
        let size = unsafe { output_slice(size, 1, "size") }?;
        size[0] = bytes.len();
        Ok(Status::Ok)
    })
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
    with_slot(c, "fmi2SerializeFMUstate", |slot| {
        let bytes = slot.instance.serialize(live_state(slot, FMUstate)?);
        if size < bytes.len() {
            return Err(CallError::InvalidArgument(format!(
                "buffer of {size} bytes is too small for the state ({} bytes; ask fmi2SerializedFMUstateSize)",
                bytes.len()
            )));
        }
        // SAFETY: by the caller's guarantee.
        let out = unsafe { output_slice(serializedState, bytes.len(), "serializedState") }?;
        for (slot_byte, byte) in out.iter_mut().zip(&bytes) {
            *slot_byte = *byte as fmi2Byte;
        }
        Ok(Status::Ok)
    })
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
    with_slot(c, "fmi2DeSerializeFMUstate", |slot| {
        // SAFETY: by the caller's guarantee.
        let bytes = unsafe { input_slice(serializedState.cast::<u8>(), size, "serializedState") }?;
        let snapshot = slot.instance.deserialize(bytes)?;
        // SAFETY: by the caller's guarantee.
        unsafe { store_state(slot, FMUstate, snapshot) }
    })
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
    with_slot(c, "fmi2EnterEventMode", |slot| {
        slot.instance.enter_event_mode()?;
        Ok(Status::Ok)
    })
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
    with_slot(c, "fmi2EnterContinuousTimeMode", |slot| {
        slot.instance.enter_continuous_time_mode()?;
        Ok(Status::Ok)
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
        completed_integrator_step(
            c,
            "fmi2CompletedIntegratorStep",
            [enterEventMode, terminateSimulation],
            0,
        )
    }
}

/// fmi2/fmi3CompletedIntegratorStep: never asks for an event or the end,
/// `no` being the standard's false.
///
/// # Safety
/// The flags are null or valid for writes.
pub(crate) unsafe fn completed_integrator_step<B: Copy>(
    c: fmi2Component,
    call: &'static str,
    flags: [*mut B; 2],
    no: B,
) -> fmi2Status {
    with_slot(c, call, |slot| {
        if flags.iter().any(|f| f.is_null()) {
            return Err(CallError::InvalidArgument(
                "enterEventMode or terminateSimulation is a null pointer".into(),
            ));
        }
        slot.instance.completed_integrator_step()?;
        for flag in flags {
            // SAFETY: non-null; the caller passes valid pointers.
            unsafe { *flag = no };
        }
        Ok(Status::Ok)
    })
}

/// fmi2SetTime (Model Exchange).
#[unsafe(no_mangle)]
pub extern "C" fn fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    with_slot(c, "fmi2SetTime", |slot| {
        slot.instance.set_time(time)?;
        Ok(Status::Ok)
    })
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
    with_slot(c, "fmi2SetContinuousStates", |slot| {
        // SAFETY: by the caller's guarantee.
        let x = unsafe { input_slice(x, nx, "x") }?;
        slot.instance.set_continuous_states(x)?;
        Ok(Status::Ok)
    })
}

/// A Model Exchange getter filling an array of `n` reals.
///
/// # Safety
/// `values` is null or points to `n` writable elements.
unsafe fn real_array_getter(
    c: fmi2Component,
    call: &'static str,
    values: *mut fmi2Real,
    n: usize,
    get: impl FnOnce(&mut Instance, &mut [f64]) -> Result<(), CallError>,
) -> fmi2Status {
    with_slot(c, call, |slot| {
        // SAFETY: by the caller's guarantee.
        let values = unsafe { output_slice(values, n, "the array") }?;
        get(&mut slot.instance, values)?;
        Ok(Status::Ok)
    })
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
        real_array_getter(c, "fmi2GetDerivatives", derivatives, nx, |i, v| {
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
        real_array_getter(c, "fmi2GetEventIndicators", eventIndicators, ni, |i, v| {
            i.get_event_indicators(v.len())
        })
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
        real_array_getter(c, "fmi2GetContinuousStates", x, nx, |i, v| {
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
        real_array_getter(
            c,
            "fmi2GetNominalsOfContinuousStates",
            x_nominal,
            nx,
            |i, v| i.get_nominals(v),
        )
    }
}

//! Misuse of the C functions never crashes the host: calls out of order, null
//! pointers, unknown value references, bad step sizes, double frees, a panic
//! inside the model, Model Exchange calls in the wrong mode or interface,
//! and a long generated sequence of random calls on a Co-Simulation and a
//! Model Exchange instance. Every
//! refusal returns fmi2Error (or fmi2Fatal for the panic) and says why through
//! the logger.
//!
//! The logger here is a plain `extern "C"` function called through the
//! variadic logger pointer type: on x86-64 System V the fixed arguments of a
//! variadic call are passed exactly as for a non-variadic one, and the unit
//! never passes variadic arguments (it escapes `%`).

use std::cell::RefCell;
use std::ffi::{CStr, CString, c_char, c_int, c_void};
use std::path::{Path, PathBuf};

use rand::{Rng, SeedableRng};

use crate::exports::*;
use crate::instance::{INJECT_PANIC, Instance};
use crate::phase::Phase;
use crate::types::{fmi2CallbackFunctions, fmi2CallbackLogger, fmi2Component, fmi2FMUstate};

const OK: c_int = 0;
const DISCARD: c_int = 2;
const ERROR: c_int = 3;
const FATAL: c_int = 4;

/// Messages received: (status, category, message).
type Log = RefCell<Vec<(c_int, String, String)>>;

unsafe extern "C" fn record(
    environment: *mut c_void,
    _instance: *const c_char,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: by the logger's contract.
    unsafe { push(environment, status, category, message) }
}

/// Records one message in the `Log` behind `environment`.
///
/// # Safety
/// The environment is the `Log` of the test that made the instance; the
/// strings are valid for the duration of the call.
unsafe fn push(
    environment: *mut c_void,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: by the caller's guarantee.
    unsafe {
        let log = &*environment.cast::<Log>();
        log.borrow_mut().push((
            status,
            CStr::from_ptr(category).to_string_lossy().into_owned(),
            CStr::from_ptr(message).to_string_lossy().into_owned(),
        ));
    }
}

fn callbacks(log: &Log) -> fmi2CallbackFunctions {
    type Plain =
        unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char);
    type Variadic =
        unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char, ...);
    // SAFETY: see the module documentation (fixed arguments only, x86-64 System V).
    let logger: fmi2CallbackLogger =
        Some(unsafe { std::mem::transmute::<Plain, Variadic>(record as Plain) });
    fmi2CallbackFunctions {
        logger,
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: std::ptr::from_ref(log).cast_mut().cast(),
    }
}

/// Resources of the 1-DOF FI stage in a scratch folder: (folder URI, GUID).
fn resources(name: &str) -> (CString, CString) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let folder: PathBuf = root.join("target/fmi-tests/misuse").join(name);
    let _ = std::fs::remove_dir_all(&folder);
    std::fs::create_dir_all(&folder).expect("scratch folder");
    crate::package::write_resources(&root.join("scenarios/paper/fig05b_fi.toml"), &folder)
        .expect("resources");
    let guid = Instance::new(&folder, None)
        .expect("instance")
        .guid()
        .to_string();
    let uri = format!("file://{}", folder.canonicalize().expect("path").display());
    (
        CString::new(uri).expect("URI"),
        CString::new(guid).expect("GUID"),
    )
}

struct Unit {
    c: fmi2Component,
    _functions: Box<fmi2CallbackFunctions>,
}

fn instantiate(log: &Log, name: &str) -> Unit {
    instantiate_as(log, name, 1)
}

/// A Model Exchange instance (fmuType 0) of the misuse stage.
fn instantiate_model_exchange(log: &Log, name: &str) -> Unit {
    instantiate_as(log, name, 0)
}

/// An instance for `fmu_type` (0 Model Exchange, 1 Co-Simulation).
fn instantiate_as(log: &Log, name: &str, fmu_type: c_int) -> Unit {
    let (uri, guid) = resources(name);
    let functions = Box::new(callbacks(log));
    // SAFETY: valid strings and callbacks that outlive the instance.
    let c = unsafe {
        fmi2Instantiate(
            c"test".as_ptr(),
            fmu_type,
            guid.as_ptr(),
            uri.as_ptr(),
            &*functions,
            0,
            0,
        )
    };
    assert!(!c.is_null(), "instantiate: {:?}", log.borrow());
    Unit {
        c,
        _functions: functions,
    }
}

fn initialised(log: &Log, name: &str) -> Unit {
    let unit = instantiate(log, name);
    assert_eq!(fmi2SetupExperiment(unit.c, 0, 0.0, 0.0, 0, 0.0), OK);
    assert_eq!(fmi2EnterInitializationMode(unit.c), OK);
    assert_eq!(fmi2ExitInitializationMode(unit.c), OK);
    unit
}

/// The last message, which must report an error.
fn last_error(log: &Log) -> String {
    let log = log.borrow();
    let (status, category, message) = log.last().expect("a message was logged");
    assert!(*status >= ERROR, "status {status}: {message}");
    assert_eq!(category, "logStatusError");
    message.clone()
}

#[test]
fn calls_out_of_order_are_refused_with_a_reason() {
    let log = Log::default();
    let unit = instantiate(&log, "order");
    assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 0), ERROR);
    assert!(last_error(&log).contains("fmi2DoStep is not allowed in the instantiated state"));
    assert_eq!(fmi2ExitInitializationMode(unit.c), ERROR);
    let mut value = 0.0;
    // SAFETY: valid pointers.
    assert_eq!(unsafe { fmi2GetReal(unit.c, &0, 1, &mut value) }, ERROR);
    assert_eq!(fmi2EnterInitializationMode(unit.c), OK);
    assert_eq!(fmi2SetupExperiment(unit.c, 0, 0.0, 0.0, 0, 0.0), ERROR);
    assert!(last_error(&log).contains("fmi2SetupExperiment"));
    assert_eq!(fmi2ExitInitializationMode(unit.c), OK);
    assert_eq!(fmi2EnterInitializationMode(unit.c), ERROR);
    assert_eq!(fmi2Terminate(unit.c), OK);
    assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 0), ERROR);
    assert!(last_error(&log).contains("terminated"));
    assert_eq!(fmi2Reset(unit.c), OK);
    assert_eq!(fmi2EnterInitializationMode(unit.c), OK);
    fmi2FreeInstance(unit.c);
}

#[test]
fn null_pointers_are_refused() {
    let log = Log::default();
    let unit = initialised(&log, "null");
    let mut values = [0.0; 3];
    // SAFETY: null arrays are what is being tested; the unit checks them.
    unsafe {
        assert_eq!(
            fmi2GetReal(unit.c, std::ptr::null(), 3, values.as_mut_ptr()),
            ERROR
        );
        assert!(last_error(&log).contains("vr is a null pointer"));
        assert_eq!(
            fmi2GetReal(unit.c, [0, 1, 2].as_ptr(), 3, std::ptr::null_mut()),
            ERROR
        );
        assert_eq!(
            fmi2SetReal(unit.c, [40].as_ptr(), 1, std::ptr::null()),
            ERROR
        );
        assert_eq!(
            fmi2GetReal(std::ptr::null_mut(), [0].as_ptr(), 1, values.as_mut_ptr()),
            ERROR
        );
        assert_eq!(fmi2GetFMUstate(unit.c, std::ptr::null_mut()), ERROR);
        assert_eq!(fmi2SetFMUstate(unit.c, std::ptr::null_mut()), ERROR);
        assert_eq!(fmi2GetRealStatus(unit.c, 2, std::ptr::null_mut()), ERROR);
        // Empty arrays may be null.
        assert_eq!(
            fmi2GetReal(unit.c, std::ptr::null(), 0, std::ptr::null_mut()),
            OK
        );
        // Instantiation with missing arguments returns null and says why.
        let (uri, guid) = resources("null_instantiate");
        let functions = callbacks(&log);
        let none = fmi2Instantiate(
            c"x".as_ptr(),
            1,
            guid.as_ptr(),
            std::ptr::null(),
            &functions,
            0,
            0,
        );
        assert!(none.is_null());
        assert!(last_error(&log).contains("fmuResourceLocation is a null pointer"));
        let none = fmi2Instantiate(
            c"x".as_ptr(),
            1,
            std::ptr::null(),
            uri.as_ptr(),
            &functions,
            0,
            0,
        );
        assert!(none.is_null());
        let none = fmi2Instantiate(
            c"x".as_ptr(),
            2,
            guid.as_ptr(),
            uri.as_ptr(),
            &functions,
            0,
            0,
        );
        assert!(none.is_null());
        assert!(last_error(&log).contains("fmuType 2"));
        let none = fmi2Instantiate(
            c"x".as_ptr(),
            1,
            c"{wrong}".as_ptr(),
            uri.as_ptr(),
            &functions,
            0,
            0,
        );
        assert!(none.is_null());
        assert!(last_error(&log).contains("does not match"));
        // No callbacks at all: still no crash.
        let none = fmi2Instantiate(
            std::ptr::null(),
            1,
            guid.as_ptr(),
            c"http://x".as_ptr(),
            std::ptr::null(),
            0,
            0,
        );
        assert!(none.is_null());
    }
    fmi2FreeInstance(unit.c);
}

#[test]
fn unknown_and_unsettable_variables_are_refused_and_change_nothing() {
    let log = Log::default();
    let unit = initialised(&log, "value_references");
    let mut value = 0.0;
    // SAFETY: valid pointers throughout.
    unsafe {
        assert_eq!(fmi2GetReal(unit.c, &9999, 1, &mut value), ERROR);
        assert!(last_error(&log).contains("unknown value reference 9999"));
        // controller.k (value reference 0) is a parameter: fixed after initialisation.
        assert_eq!(fmi2SetReal(unit.c, &0, 1, &1.0), ERROR);
        assert!(last_error(&log).contains("parameters are fixed"));
        // The servo force input may be set, but not to NaN; a refused call
        // leaves the earlier entries untouched.
        let servo_force = 3 + 6 + 12 + 2;
        assert_eq!(
            fmi2SetReal(
                unit.c,
                [servo_force, servo_force].as_ptr(),
                2,
                [1.5, f64::NAN].as_ptr()
            ),
            ERROR
        );
        assert!(last_error(&log).contains("not a finite number"));
        assert_eq!(fmi2GetReal(unit.c, &servo_force, 1, &mut value), OK);
        assert_eq!(value, 0.0);
        // Outputs cannot be set.
        let output = servo_force + 2;
        assert_eq!(fmi2SetReal(unit.c, &output, 1, &1.0), ERROR);
        assert!(last_error(&log).contains("it is an output"));
        let mut integer = 0;
        assert_eq!(fmi2GetInteger(unit.c, &0, 1, &mut integer), ERROR);
        assert!(last_error(&log).contains("no Integer variables"));
        assert_eq!(fmi2SetString(unit.c, &0, 1, &c"a".as_ptr()), ERROR);
        let mut dv = 0.0;
        assert_eq!(
            fmi2GetDirectionalDerivative(unit.c, &0, 1, &output, 1, &1.0, &mut dv),
            ERROR
        );
        assert!(last_error(&log).contains("is neither an input nor a continuous state"));
        assert_eq!(
            fmi2GetDirectionalDerivative(unit.c, &0, 1, &servo_force, 1, &1.0, &mut dv),
            ERROR
        );
        assert!(last_error(&log).contains("is neither an output nor a state derivative"));
        assert_eq!(fmi2SetRealInputDerivatives(unit.c, &0, 1, &1, &1.0), ERROR);
        assert_eq!(fmi2CancelStep(unit.c), ERROR);
        let mut status = 0;
        assert_eq!(fmi2GetStatus(unit.c, 0, &mut status), DISCARD);
        let mut time = -1.0;
        assert_eq!(fmi2GetRealStatus(unit.c, 2, &mut time), OK);
        assert_eq!(time, 0.0);
    }
    fmi2FreeInstance(unit.c);
}

#[test]
fn bad_step_sizes_and_communication_points_are_refused() {
    let log = Log::default();
    let unit = initialised(&log, "steps");
    for step in [-1e-3, 0.0, f64::NAN, f64::INFINITY] {
        assert_eq!(fmi2DoStep(unit.c, 0.0, step, 0), ERROR, "step {step}");
        assert!(last_error(&log).contains("communicationStepSize must be a positive number"));
    }
    assert_eq!(fmi2DoStep(unit.c, 0.5, 1e-3, 0), ERROR);
    assert!(last_error(&log).contains("is not the unit's time"));
    assert_eq!(fmi2DoStep(unit.c, f64::NAN, 1e-3, 0), ERROR);
    // The instance is still usable after all that.
    assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 0), OK);
    fmi2FreeInstance(unit.c);
}

#[test]
fn double_frees_are_detected() {
    let log = Log::default();
    let unit = initialised(&log, "double_free");
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    // SAFETY: valid pointers; the stale copy is what is being tested.
    unsafe {
        assert_eq!(fmi2GetFMUstate(unit.c, &mut state), OK);
        let stale = state;
        assert_eq!(fmi2FreeFMUstate(unit.c, &mut state), OK);
        assert!(state.is_null());
        let mut copy = stale;
        assert_eq!(fmi2FreeFMUstate(unit.c, &mut copy), ERROR);
        assert!(last_error(&log).contains("not a live state"));
        assert_eq!(fmi2SetFMUstate(unit.c, stale), ERROR);
    }
    fmi2FreeInstance(unit.c);
    fmi2FreeInstance(unit.c);
    assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 0), ERROR);
    assert!(last_error(&log).contains("already freed"));
}

#[test]
fn a_panic_inside_the_model_becomes_fmi2fatal() {
    let log = Log::default();
    let unit = initialised(&log, "panic");
    INJECT_PANIC.with(|flag| flag.set(true));
    assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 0), FATAL);
    let message = last_error(&log);
    assert!(
        message.contains("injected fault inside the model step"),
        "{message}"
    );
    assert!(message.contains("unusable"));
    assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 0), ERROR);
    assert!(last_error(&log).contains("fatal error"));
    assert_eq!(fmi2Reset(unit.c), ERROR);
    fmi2FreeInstance(unit.c);
}

#[test]
fn logger_messages_escape_percent_signs() {
    let log = Log::default();
    let unit = initialised(&log, "percent");
    let categories = [c"%s%n".as_ptr()];
    // SAFETY: valid pointers.
    assert_eq!(
        unsafe { fmi2SetDebugLogging(unit.c, 1, 1, categories.as_ptr()) },
        ERROR
    );
    assert!(last_error(&log).contains("\"%%s%%n\""));
    fmi2FreeInstance(unit.c);
}

/// Thousands of random calls with random (often invalid) arguments: no crash,
/// statuses within the standard's set, every failure logged, and the FMU
/// still steps correctly when used properly afterwards.
#[test]
fn random_call_sequences_never_crash() {
    let log = Log::default();
    let mut rng = rand::rngs::StdRng::seed_from_u64(20261122);
    let mut units = vec![
        instantiate(&log, "random_a"),
        instantiate_model_exchange(&log, "random_b"),
    ];
    let mut states: Vec<fmi2FMUstate> = Vec::new();
    let pick_f64 = |rng: &mut rand::rngs::StdRng| -> f64 {
        match rng.random_range(0..6) {
            0 => f64::NAN,
            1 => -1e-3,
            2 => 0.0,
            3 => 1e-3,
            4 => rng.random_range(-1.0..1.0),
            _ => 1e-4,
        }
    };
    let mut calls = 0;
    for _ in 0..3000 {
        let unit = &units[rng.random_range(0..units.len())];
        let c = if rng.random_bool(0.03) {
            std::ptr::null_mut()
        } else {
            unit.c
        };
        let vr: u32 = if rng.random_bool(0.8) {
            rng.random_range(0..80)
        } else {
            rng.random()
        };
        let before = log.borrow().len();
        let mut value = 0.0;
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: all pointers are valid or null; the unit checks the rest.
        let status = unsafe {
            let n = if rng.random_bool(0.8) {
                5
            } else {
                rng.random_range(0..9)
            };
            let mut array: Vec<f64> = (0..n).map(|_| pick_f64(&mut rng)).collect();
            let pointer = if rng.random_bool(0.05) {
                std::ptr::null_mut()
            } else {
                array.as_mut_ptr()
            };
            match rng.random_range(0..30) {
                24 => crate::fmi3::exports::fmi3EnterInitializationMode(
                    c,
                    rng.random_bool(0.5),
                    pick_f64(&mut rng),
                    pick_f64(&mut rng),
                    rng.random_bool(0.5),
                    pick_f64(&mut rng),
                ),
                25 => {
                    let (mut a, mut b, mut e, mut t) = (false, false, false, 0.0);
                    crate::fmi3::exports::fmi3DoStep(
                        c,
                        pick_f64(&mut rng),
                        pick_f64(&mut rng),
                        true,
                        &mut a,
                        &mut b,
                        &mut e,
                        &mut t,
                    )
                }
                26 => crate::fmi3::exports::fmi3GetFloat64(c, &vr, 1, &mut value, 1),
                27 => crate::fmi3::exports::fmi3SetFloat64(c, &vr, 1, &pick_f64(&mut rng), 1),
                28 => {
                    let mut flags = [false; 5];
                    let mut next = 0.0;
                    let [a, b, d, e, f] = &mut flags;
                    crate::fmi3::exports::fmi3UpdateDiscreteStates(c, a, b, d, e, f, &mut next)
                }
                29 => {
                    let mut out = [0.0; 2];
                    crate::fmi3::exports::fmi3GetAdjointDerivative(
                        c,
                        &vr,
                        1,
                        [vr % 60, vr % 7].as_ptr(),
                        2,
                        &pick_f64(&mut rng),
                        1,
                        out.as_mut_ptr(),
                        2,
                    )
                }
                16 => fmi2EnterEventMode(c),
                17 => fmi2EnterContinuousTimeMode(c),
                18 => {
                    let mut info = std::mem::MaybeUninit::<crate::types::fmi2EventInfo>::zeroed();
                    fmi2NewDiscreteStates(c, info.as_mut_ptr())
                }
                19 => {
                    let (mut enter, mut terminate) = (0, 0);
                    fmi2CompletedIntegratorStep(c, 1, &mut enter, &mut terminate)
                }
                20 => fmi2SetTime(c, pick_f64(&mut rng)),
                21 => fmi2SetContinuousStates(c, pointer, n),
                22 => fmi2GetDerivatives(c, pointer, n),
                23 => fmi2GetContinuousStates(c, pointer, n),
                0 => fmi2SetupExperiment(
                    c,
                    rng.random_range(0..2),
                    pick_f64(&mut rng),
                    0.0,
                    rng.random_range(0..2),
                    pick_f64(&mut rng),
                ),
                1 => fmi2EnterInitializationMode(c),
                2 => fmi2ExitInitializationMode(c),
                3 => fmi2Terminate(c),
                4 => fmi2Reset(c),
                5 => fmi2GetReal(c, &vr, 1, &mut value),
                6 => fmi2SetReal(c, &vr, 1, &pick_f64(&mut rng)),
                7 | 8 => {
                    let mut t = 0.0;
                    fmi2GetRealStatus(c, 2, &mut t);
                    let point = if rng.random_bool(0.8) {
                        t
                    } else {
                        pick_f64(&mut rng)
                    };
                    fmi2DoStep(c, point, pick_f64(&mut rng), 0)
                }
                9 => {
                    let status = fmi2GetFMUstate(c, &mut state);
                    if !state.is_null() {
                        states.push(state);
                    }
                    status
                }
                10 => match states.len() {
                    0 => fmi2SetFMUstate(c, std::ptr::null_mut()),
                    n => fmi2SetFMUstate(c, states[rng.random_range(0..n)]),
                },
                11 => match states.len() {
                    0 => fmi2FreeFMUstate(c, &mut state),
                    n => {
                        let mut s = states[rng.random_range(0..n)];
                        fmi2FreeFMUstate(c, &mut s)
                    }
                },
                12 => {
                    let mut dv = 0.0;
                    fmi2GetDirectionalDerivative(c, &vr, 1, &(vr % 30), 1, &1.0, &mut dv)
                }
                13 => {
                    let mut size = 0usize;
                    let s = states.last().copied().unwrap_or(std::ptr::null_mut());
                    let status = fmi2SerializedFMUstateSize(c, s, &mut size);
                    let mut bytes = vec![0 as c_char; size.min(4096)];
                    if rng.random_bool(0.3) && !bytes.is_empty() {
                        bytes.pop();
                    }
                    let status2 = fmi2SerializeFMUstate(c, s, bytes.as_mut_ptr(), bytes.len());
                    if rng.random_bool(0.5) && !bytes.is_empty() {
                        let i = rng.random_range(0..bytes.len());
                        bytes[i] = bytes[i].wrapping_add(1);
                    }
                    let mut restored: fmi2FMUstate = std::ptr::null_mut();
                    let status3 =
                        fmi2DeSerializeFMUstate(c, bytes.as_ptr(), bytes.len(), &mut restored);
                    if !restored.is_null() {
                        states.push(restored);
                    }
                    status.max(status2).max(status3)
                }
                14 => {
                    let mut flag = 0;
                    fmi2GetBooleanStatus(c, rng.random_range(-1..5), &mut flag)
                }
                _ => fmi2SetDebugLogging(c, rng.random_range(0..2), 0, std::ptr::null()),
            }
        };
        calls += 1;
        assert!([OK, DISCARD, ERROR].contains(&status), "status {status}");
        if status == ERROR && !c.is_null() {
            assert!(
                log.borrow().len() > before,
                "an error without a log message"
            );
        }
    }
    assert!(calls == 3000);
    for unit in units.drain(..) {
        fmi2FreeInstance(unit.c);
    }
    // Proper use still works afterwards.
    let unit = initialised(&log, "random_after");
    let mut t = 0.0;
    for k in 1..=100 {
        let next = k as f64 * 1e-3;
        assert_eq!(fmi2DoStep(unit.c, t, next - t, 0), OK);
        t = next;
    }
    let mut time = 0.0;
    // SAFETY: valid pointer.
    assert_eq!(unsafe { fmi2GetRealStatus(unit.c, 2, &mut time) }, OK);
    assert_eq!(time, 0.1);
    fmi2FreeInstance(unit.c);
}

#[test]
fn resource_locations_in_the_forms_importers_use() {
    use crate::shared::c_args::resource_folder;
    for (uri, path) in [
        ("file:///tmp/unit/resources", "/tmp/unit/resources"),
        ("file:/tmp/unit/resources/", "/tmp/unit/resources/"),
        ("file://localhost/tmp/unit", "/tmp/unit"),
        ("file:///tmp/with%20space", "/tmp/with space"),
    ] {
        assert_eq!(resource_folder(uri), Ok(PathBuf::from(path)), "{uri}");
    }
    for uri in [
        "file://server/share/unit",
        "http://example.org/unit",
        "/tmp/unit",
    ] {
        assert!(resource_folder(uri).is_err(), "{uri}");
    }
}

/// A state saved with an integral gain (one more state) restores into an
/// instance that started without one, and both continue identically.
#[test]
fn a_state_with_another_layout_restores_after_its_parameters() {
    let log = Log::default();
    let saver = instantiate(&log, "layout_a");
    let k_i = 2; // value reference of controller.k_i
    // SAFETY: valid pointers throughout.
    unsafe {
        assert_eq!(fmi2SetReal(saver.c, &k_i, 1, &1e5), OK);
        assert_eq!(fmi2EnterInitializationMode(saver.c), OK);
        assert_eq!(fmi2ExitInitializationMode(saver.c), OK);
        for k in 0..20 {
            assert_eq!(fmi2DoStep(saver.c, k as f64 * 1e-3, 1e-3, 0), OK);
        }
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(fmi2GetFMUstate(saver.c, &mut state), OK);
        let mut size = 0usize;
        assert_eq!(fmi2SerializedFMUstateSize(saver.c, state, &mut size), OK);
        let mut bytes = vec![0 as c_char; size];
        assert_eq!(
            fmi2SerializeFMUstate(saver.c, state, bytes.as_mut_ptr(), size),
            OK
        );

        let other = initialised(&log, "layout_b");
        let mut restored: fmi2FMUstate = std::ptr::null_mut();
        assert_eq!(
            fmi2DeSerializeFMUstate(other.c, bytes.as_ptr(), size, &mut restored),
            OK
        );
        assert_eq!(
            fmi2SetFMUstate(other.c, restored),
            OK,
            "{:?}",
            log.borrow().last()
        );
        let mut gain = 0.0;
        assert_eq!(fmi2GetReal(other.c, &k_i, 1, &mut gain), OK);
        assert_eq!(gain, 1e5);
        let position = 3 + 6 + 12 + 4; // encoder.position, the first output
        for k in 20..40 {
            let t = k as f64 * 1e-3;
            assert_eq!(fmi2DoStep(saver.c, t, 1e-3, 0), OK);
            assert_eq!(fmi2DoStep(other.c, t, 1e-3, 0), OK);
        }
        let (mut a, mut b) = (0.0, 0.0);
        assert_eq!(fmi2GetReal(saver.c, &position, 1, &mut a), OK);
        assert_eq!(fmi2GetReal(other.c, &position, 1, &mut b), OK);
        assert_eq!(a.to_bits(), b.to_bits());
        assert_ne!(a, 0.0);
        fmi2FreeFMUstate(saver.c, &mut state);
        fmi2FreeInstance(other.c);
    }
    fmi2FreeInstance(saver.c);
}

/// Found while writing the `fmu_state` fuzz target, whose checksum-sealing
/// mode reaches past the CRC: states whose checksum fits but whose contents
/// no unit writes (a NaN tolerance, a time
/// outside the experiment, a negative or NaN step size, a NaN in the state
/// vector or in a parameter) were restored, and failed later, or not at all.
/// Each is refused at fmi2SetFMUstate with the reason, and changes nothing.
#[test]
fn states_that_break_the_units_rules_are_refused_even_with_a_good_checksum() {
    use crate::state::{Snapshot, decode, encode};
    let (uri, _) = resources("sealed");
    let folder = PathBuf::from(uri.to_str().expect("URI").trim_start_matches("file://"));
    let mut unit = Instance::new(&folder, None).expect("instance");
    unit.setup_experiment(None, 0.0, Some(1.0)).expect("setup");
    unit.enter_initialization().expect("enter");
    unit.exit_initialization().expect("exit");
    unit.do_step(0.0, 1e-3).expect("step");
    let good = unit.snapshot();
    let guid = unit.guid().to_string();
    type Damage = fn(&mut Snapshot);
    let cases: [(&str, Damage, &str); 12] = [
        (
            "NaN tolerance",
            |s| s.tolerance = Some(f64::NAN),
            "tolerance",
        ),
        ("tolerance 5", |s| s.tolerance = Some(5.0), "tolerance"),
        (
            "infinite start",
            |s| s.start_time = f64::INFINITY,
            "startTime",
        ),
        (
            "stop before start",
            |s| s.stop_time = Some(-1.0),
            "stopTime",
        ),
        ("NaN time", |s| checkpoint(s).t = f64::NAN, "time"),
        (
            "time past stop",
            |s| checkpoint(s).t = 2.0,
            "outside the experiment",
        ),
        ("NaN step size", |s| checkpoint(s).h = f64::NAN, "step size"),
        (
            "negative step size",
            |s| checkpoint(s).h = -1.0,
            "step size",
        ),
        ("NaN state", |s| checkpoint(s).x[0] = f64::NAN, "state 0"),
        (
            "infinite state",
            |s| checkpoint(s).x[1] = f64::INFINITY,
            "state 1",
        ),
        ("NaN gain", |s| s.values[0] = f64::NAN, "is NaN"),
        // Found by the fuzzer: step counts near 2^64 overflowed the count of
        // steps taken in a call (a panic, so fmi2Fatal).
        (
            "step counts near 2^64",
            |s| checkpoint(s).counts.steps = u64::MAX - 3,
            "step counts",
        ),
    ];
    fn checkpoint(s: &mut Snapshot) -> &mut fistage_sim::Checkpoint {
        s.checkpoint.as_mut().expect("a stepping state")
    }
    for (case, damage, reason) in cases {
        let mut damaged = good.clone();
        damage(&mut damaged);
        let sealed = decode(&guid, &encode(&guid, &damaged)).expect("the checksum fits");
        let error = unit.restore(&sealed).expect_err(case).to_string();
        assert!(
            error.contains("corrupt") && error.contains(reason),
            "{case}: {error}"
        );
        assert_eq!(
            unit.snapshot(),
            good,
            "{case}: a refused state changed the unit"
        );
    }
    unit.do_step(1e-3, 1e-3).expect("the unit still steps");
}

/// Found by the `fmu_state` fuzz target (a hang under its 10 s limit): a
/// restored state with the table 5.6 km off makes the bristle dynamics so
/// stiff that the explicit engine creeps (steps near 1e-10 s). The work is
/// bounded by the unit's limit of steps per communication step, and the
/// failure says so in the unit's terms; it used to advise raising
/// solver.max_steps, a setting an importer cannot reach.
#[test]
fn a_hopelessly_stiff_step_stops_at_the_units_limit_and_says_so() {
    let (uri, _) = resources("stiff");
    let folder = PathBuf::from(uri.to_str().expect("URI").trim_start_matches("file://"));
    let mut unit = Instance::new(&folder, None).expect("instance");
    unit.setup_experiment(None, 0.0, None).expect("setup");
    unit.enter_initialization().expect("enter");
    unit.exit_initialization().expect("exit");
    let mut far = unit.snapshot();
    far.checkpoint.as_mut().expect("stepping").x[0] = 5632.0;
    unit.restore(&far).expect("an admissible state");
    let error = unit.do_step(0.0, 1e-3).expect_err("too stiff").to_string();
    assert!(
        error.contains("the unit's limit per communication step")
            && !error.contains("solver.max_steps"),
        "{error}"
    );
    assert_eq!(unit.phase(), Phase::StepFailed);
}

/// Model Exchange misuse: its functions before initialisation, in the wrong
/// mode, on a Co-Simulation instance, with null pointers, a wrong number of
/// states and NaN states; Co-Simulation's fmi2DoStep on a Model Exchange
/// instance. Each is refused with a reason and changes nothing; the proper
/// sequence then works.
#[test]
fn model_exchange_misuse_is_refused_with_a_reason() {
    let log = Log::default();
    let unit = instantiate_model_exchange(&log, "model-exchange");
    let n = 5;
    let mut x = vec![0.0; n];
    // SAFETY: a live instance and arrays of the lengths given (or null).
    unsafe {
        assert_eq!(fmi2EnterContinuousTimeMode(unit.c), ERROR);
        assert!(last_error(&log).contains("instantiated"));
        assert_eq!(fmi2SetTime(unit.c, f64::NAN), ERROR);
        // Before initialisation, fmi2SetTime sets the start time.
        assert_eq!(fmi2SetTime(unit.c, 0.1), OK);
        assert_eq!(fmi2GetContinuousStates(unit.c, x.as_mut_ptr(), n), ERROR);
        assert_eq!(fmi2SetupExperiment(unit.c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(unit.c), OK);
        assert_eq!(fmi2ExitInitializationMode(unit.c), OK);
        // Event mode after initialisation: no integrator step yet.
        let (mut enter, mut terminate) = (0, 0);
        assert_eq!(
            fmi2CompletedIntegratorStep(unit.c, 1, &mut enter, &mut terminate),
            ERROR
        );
        assert!(last_error(&log).contains("event mode"));
        assert_eq!(fmi2DoStep(unit.c, 0.0, 1e-3, 1), ERROR);
        assert!(last_error(&log).contains("Co-Simulation function"));
        assert_eq!(fmi2NewDiscreteStates(unit.c, std::ptr::null_mut()), ERROR);
        assert!(last_error(&log).contains("null pointer"));
        assert_eq!(fmi2GetContinuousStates(unit.c, x.as_mut_ptr(), n), OK);
        let start = x.clone();
        assert_eq!(
            fmi2GetContinuousStates(unit.c, std::ptr::null_mut(), n),
            ERROR
        );
        assert!(last_error(&log).contains("null pointer"));
        assert_eq!(fmi2GetDerivatives(unit.c, x.as_mut_ptr(), n - 1), ERROR);
        assert!(last_error(&log).contains("nx = 4"));
        assert_eq!(fmi2EnterContinuousTimeMode(unit.c), OK);
        let mut bad = start.clone();
        bad[2] = f64::NAN;
        assert_eq!(fmi2SetContinuousStates(unit.c, bad.as_ptr(), n), ERROR);
        assert!(last_error(&log).contains("NaN"));
        assert_eq!(fmi2SetTime(unit.c, f64::INFINITY), ERROR);
        assert_eq!(fmi2GetEventIndicators(unit.c, x.as_mut_ptr(), 1), ERROR);
        assert!(last_error(&log).contains("no event indicators"));
        assert_eq!(fmi2GetContinuousStates(unit.c, x.as_mut_ptr(), n), OK);
        assert_eq!(x, start, "refused calls changed the state");
        // The proper sequence still works.
        assert_eq!(fmi2SetTime(unit.c, 1e-3), OK);
        assert_eq!(fmi2SetContinuousStates(unit.c, start.as_ptr(), n), OK);
        let mut dx = vec![f64::NAN; n];
        assert_eq!(fmi2GetDerivatives(unit.c, dx.as_mut_ptr(), n), OK);
        assert!(dx.iter().all(|v| v.is_finite()));
        assert_eq!(
            fmi2CompletedIntegratorStep(unit.c, 1, &mut enter, &mut terminate),
            OK
        );
        assert_eq!((enter, terminate), (0, 0));
        assert_eq!(fmi2EnterEventMode(unit.c), OK);
        fmi2FreeInstance(unit.c);
    }
    let cs = initialised(&log, "model-exchange-on-cs");
    // SAFETY: a live instance and a local array.
    unsafe {
        assert_eq!(fmi2GetDerivatives(cs.c, x.as_mut_ptr(), n), ERROR);
        assert!(last_error(&log).contains("Model Exchange function"));
        assert_eq!(fmi2EnterEventMode(cs.c), ERROR);
    }
    fmi2FreeInstance(cs.c);
}

/// The Model Exchange derivatives are the model's right-hand side, and the
/// directional derivatives of derivatives along a state equal the exact
/// Jacobian's column; the next time event is the reference's next
/// breakpoint.
#[test]
fn model_exchange_derivatives_are_the_models_own() {
    let (uri, _) = resources("model-exchange-rhs");
    let folder = PathBuf::from(uri.to_str().expect("URI").trim_start_matches("file://"));
    let mut unit =
        Instance::for_interface(&folder, None, crate::instance::Interface::ModelExchange)
            .expect("instance");
    unit.enter_initialization().expect("enter");
    unit.exit_initialization().expect("exit");
    unit.enter_continuous_time_mode().expect("continuous");
    let n = unit.model().n_states();
    let mut x = vec![0.0; n];
    unit.get_continuous_states(&mut x).expect("states");
    x[0] = 2e-6;
    x[n - 1] = 1e-7;
    unit.set_time(0.25).expect("time");
    unit.set_continuous_states(&x).expect("states");
    let mut dx = vec![0.0; n];
    unit.get_derivatives(&mut dx).expect("derivatives");
    let inputs = fistage_model::Inputs {
        platform_velocity: 0.02,
        ..Default::default()
    };
    let mut expected = vec![0.0; n];
    let model = unit.model().clone();
    model.rhs(&x, &inputs, &mut expected, &mut model.workspace());
    assert_eq!(dx, expected);
    let jacobian = model.jacobian(&x, &inputs);
    let variables = unit.variables().to_vec();
    let vr = |name: &str| {
        (variables.iter())
            .find(|v| v.name == name)
            .unwrap_or_else(|| panic!("no variable {name}"))
            .value_reference
    };
    let names = model.layout().names.clone();
    let derivatives: Vec<u32> = names
        .iter()
        .map(|s| vr(&format!("der(state.{s})")))
        .collect();
    for (column, name) in names.iter().enumerate() {
        let mut result = vec![0.0; n];
        unit.directional_derivative(
            &derivatives,
            &[vr(&format!("state.{name}"))],
            &[1.0],
            &mut result,
        )
        .expect("directional derivative");
        for row in 0..n {
            assert_eq!(
                result[row],
                jacobian[(row, column)],
                "d der({}) / d {name}",
                names[row]
            );
        }
    }
    unit.enter_event_mode().expect("event mode");
    let info = unit.new_discrete_states().expect("event info");
    assert_eq!(info.next_event_time, None, "fig05b's reference is constant");
}

/// The FMI 3.0 logger: records like [`record`].
unsafe extern "C" fn record3(
    environment: *mut c_void,
    status: c_int,
    category: *const c_char,
    message: *const c_char,
) {
    // SAFETY: as in `record`.
    unsafe { push(environment, status, category, message) }
}

/// An FMI 3.0 instance of the misuse stage (Model Exchange or Co-Simulation).
fn instantiate3(log: &Log, name: &str, model_exchange: bool) -> fmi2Component {
    use crate::fmi3::exports::*;
    let (uri, token) = resources(name);
    let path =
        CString::new(uri.to_str().expect("URI").trim_start_matches("file://")).expect("path");
    let environment = std::ptr::from_ref(log).cast_mut().cast();
    // SAFETY: valid strings; the log outlives the instance.
    let c = unsafe {
        if model_exchange {
            fmi3InstantiateModelExchange(
                c"test".as_ptr(),
                token.as_ptr(),
                path.as_ptr(),
                false,
                false,
                environment,
                Some(record3),
            )
        } else {
            fmi3InstantiateCoSimulation(
                c"test".as_ptr(),
                token.as_ptr(),
                path.as_ptr(),
                false,
                false,
                false,
                false,
                std::ptr::null(),
                0,
                environment,
                Some(record3),
                None,
            )
        }
    };
    assert!(!c.is_null(), "instantiate: {:?}", log.borrow());
    c
}

/// FMI 3.0 misuse: wrong states, null pointers, unknown and unsettable
/// references, mismatched lengths, NaN, the types and features the unit
/// leaves out; each refused with a reason naming FMI 3.0's functions, and
/// the proper sequence works afterwards.
#[test]
fn fmi3_misuse_is_refused_with_a_reason() {
    use crate::fmi3::exports::*;
    let log = Log::default();
    let cs = instantiate3(&log, "fmi3-cs", false);
    let (mut event, mut terminate, mut early, mut last) = (false, false, false, 0.0);
    // SAFETY: a live instance and local storage (or null where tested).
    unsafe {
        assert_eq!(
            fmi3DoStep(
                cs,
                0.0,
                1e-3,
                true,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last
            ),
            ERROR
        );
        let message = last_error(&log);
        assert!(
            message.contains("fmi3DoStep") && !message.contains("fmi2"),
            "{message}"
        );
        assert_eq!(
            fmi3EnterInitializationMode(cs, true, f64::NAN, 0.0, false, 0.0),
            ERROR
        );
        assert_eq!(
            fmi3EnterInitializationMode(cs, false, 0.0, 0.0, true, 5.0),
            OK
        );
        assert_eq!(fmi3ExitInitializationMode(cs), OK);
        let mut value = 0.0;
        assert_eq!(fmi3GetFloat64(cs, &100_000, 1, &mut value, 1), ERROR);
        assert!(last_error(&log).contains("unknown value reference 100000"));
        assert_eq!(fmi3GetFloat64(cs, &0, 1, &mut value, 2), ERROR);
        assert!(last_error(&log).contains("nValues = 2"));
        assert_eq!(
            fmi3GetFloat64(cs, std::ptr::null(), 1, &mut value, 1),
            ERROR
        );
        assert!(last_error(&log).contains("null pointer"));
        assert_eq!(fmi3SetFloat64(cs, &0, 1, &f64::NAN, 1), ERROR);
        let mut n = 0usize;
        assert_eq!(fmi3GetNumberOfContinuousStates(cs, &mut n), OK);
        assert_eq!(n, 5);
        let time = Instance::new(
            &PathBuf::from(
                resources("fmi3-time")
                    .0
                    .to_str()
                    .expect("URI")
                    .trim_start_matches("file://"),
            ),
            None,
        )
        .expect("instance")
        .variables()
        .len() as u32;
        assert_eq!(fmi3SetFloat64(cs, &time, 1, &1.0, 1), ERROR);
        assert!(last_error(&log).contains("independent variable"));
        let mut integer = 0i32;
        assert_eq!(fmi3GetInt32(cs, &0, 1, &mut integer, 1), ERROR);
        assert!(last_error(&log).contains("no Int32 variables"));
        assert_eq!(fmi3GetInt32(cs, std::ptr::null(), 0, &mut integer, 0), OK);
        let mut clock = false;
        assert_eq!(fmi3GetClock(cs, &0, 1, &mut clock), ERROR);
        assert_eq!(fmi3GetShiftDecimal(cs, &0, 1, &mut value), ERROR);
        assert!(last_error(&log).contains("no clocks"));
        assert_eq!(fmi3EnterConfigurationMode(cs), ERROR);
        assert_eq!(fmi3EnterStepMode(cs), ERROR);
        assert_eq!(
            fmi3DoStep(
                cs,
                0.0,
                1e-3,
                true,
                std::ptr::null_mut(),
                &mut terminate,
                &mut early,
                &mut last
            ),
            ERROR
        );
        assert_eq!(
            fmi3GetContinuousStateDerivatives(cs, [0.0; 5].as_mut_ptr(), 5),
            ERROR
        );
        assert!(last_error(&log).contains("Model Exchange function"));
        // The proper sequence works.
        assert_eq!(
            fmi3DoStep(
                cs,
                0.0,
                1e-3,
                true,
                &mut event,
                &mut terminate,
                &mut early,
                &mut last
            ),
            OK
        );
        assert_eq!((event, terminate, early, last), (false, false, false, 1e-3));
        assert_eq!(fmi3GetFloat64(cs, &time, 1, &mut value, 1), OK);
        assert_eq!(value, 1e-3);
        fmi3FreeInstance(cs);
        fmi3FreeInstance(cs);
        assert!(
            fmi3InstantiateScheduledExecution(
                c"x".as_ptr(),
                c"{token}".as_ptr(),
                c"/".as_ptr(),
                false,
                false,
                std::ptr::null_mut(),
                None,
                None,
                None,
                None
            )
            .is_null()
        );
    }
}

/// FMI 3.0 Model Exchange: the adjoint derivatives are the transpose of
/// the directional ones (both from the exact Jacobian), over states and
/// inputs to state derivatives and outputs; the event update reports no
/// next event for fig05b's constant reference.
#[test]
fn fmi3_adjoint_derivatives_are_the_transposed_directional_ones() {
    use crate::fmi3::exports::*;
    let log = Log::default();
    let me = instantiate3(&log, "fmi3-me", true);
    let (uri, _) = resources("fmi3-me-vars");
    let variables = Instance::new(
        &PathBuf::from(uri.to_str().expect("URI").trim_start_matches("file://")),
        None,
    )
    .expect("instance")
    .variables()
    .to_vec();
    let pick = |keep: &dyn Fn(&crate::variables::Binding) -> bool| -> Vec<u32> {
        (variables.iter())
            .filter(|v| keep(&v.binding))
            .map(|v| v.value_reference)
            .collect()
    };
    use crate::variables::Binding;
    let unknowns = pick(&|b| matches!(b, Binding::Derivative(_) | Binding::Output(_)));
    let knowns = pick(&|b| matches!(b, Binding::State(_) | Binding::Input(_)));
    // SAFETY: a live instance and local arrays of the lengths given.
    unsafe {
        assert_eq!(
            fmi3EnterInitializationMode(me, false, 0.0, 0.0, false, 0.0),
            OK
        );
        assert_eq!(fmi3ExitInitializationMode(me), OK);
        let flags = &mut [false; 5];
        let mut next = 0.0;
        let [a, b, c, d, e] = flags;
        assert_eq!(fmi3UpdateDiscreteStates(me, a, b, c, d, e, &mut next), OK);
        assert!(!*e, "no time event for a constant reference");
        assert_eq!(fmi3EnterContinuousTimeMode(me), OK);
        let mut x = [0.0; 5];
        assert_eq!(fmi3GetContinuousStates(me, x.as_mut_ptr(), 5), OK);
        x[0] = 3e-6;
        x[4] = -2e-7;
        assert_eq!(fmi3SetContinuousStates(me, x.as_ptr(), 5), OK);
        // The Jacobian, column by column.
        let (m, n) = (unknowns.len(), knowns.len());
        let mut jacobian = vec![vec![0.0; n]; m];
        let mut column = vec![0.0; m];
        for (j, known) in knowns.iter().enumerate() {
            assert_eq!(
                fmi3GetDirectionalDerivative(
                    me,
                    unknowns.as_ptr(),
                    m,
                    known,
                    1,
                    &1.0,
                    1,
                    column.as_mut_ptr(),
                    m
                ),
                OK,
                "{:?}",
                log.borrow().last()
            );
            for i in 0..m {
                jacobian[i][j] = column[i];
            }
        }
        let seed: Vec<f64> = (0..m).map(|i| ((i * 7 + 3) % 11) as f64 - 5.0).collect();
        let mut adjoint = vec![0.0; n];
        assert_eq!(
            fmi3GetAdjointDerivative(
                me,
                unknowns.as_ptr(),
                m,
                knowns.as_ptr(),
                n,
                seed.as_ptr(),
                m,
                adjoint.as_mut_ptr(),
                n
            ),
            OK
        );
        for j in 0..n {
            let expected: f64 = (0..m).map(|i| seed[i] * jacobian[i][j]).sum();
            let scale = (0..m)
                .map(|i| (seed[i] * jacobian[i][j]).abs())
                .sum::<f64>();
            assert!(
                (adjoint[j] - expected).abs() <= 1e-12 * scale.max(1e-300),
                "known {j}: adjoint {} against {expected}",
                adjoint[j]
            );
        }
        assert!(adjoint.iter().any(|v| *v != 0.0));
        assert_eq!(
            fmi3GetAdjointDerivative(
                me,
                unknowns.as_ptr(),
                m,
                knowns.as_ptr(),
                n,
                seed.as_ptr(),
                m - 1,
                adjoint.as_mut_ptr(),
                n
            ),
            ERROR
        );
        fmi3FreeInstance(me);
    }
}

//! What the FMU targets share: the 1-DOF FI stage's resources written once
//! into a scratch folder, a logger that remembers whether an error was
//! explained, and instances made through the C ABI.
//!
//! The logger is a plain `extern "C"` function called through the variadic
//! logger pointer type: on x86-64 System V the fixed arguments of a variadic
//! call are passed exactly as for a non-variadic one, and the unit never
//! passes variadic arguments.

use std::cell::Cell;
use std::ffi::{CString, c_char, c_int, c_void};
use std::path::Path;
use std::sync::OnceLock;

use fistage_fmi::exports::*;
use fistage_fmi::types::{fmi2CallbackFunctions, fmi2CallbackLogger, fmi2Component};

pub const OK: c_int = 0;
pub const WARNING: c_int = 1;
pub const DISCARD: c_int = 2;
pub const ERROR: c_int = 3;

thread_local! {
    /// Messages logged with status fmi2Error or worse since the last reset.
    static ERRORS_LOGGED: Cell<usize> = const { Cell::new(0) };
}

unsafe extern "C" fn remember(
    _environment: *mut c_void,
    _instance: *const c_char,
    status: c_int,
    _category: *const c_char,
    _message: *const c_char,
) {
    if status >= ERROR {
        ERRORS_LOGGED.with(|n| n.set(n.get() + 1));
    }
}

fn callbacks() -> &'static fmi2CallbackFunctions {
    struct Shared(fmi2CallbackFunctions);
    // SAFETY: the callbacks hold no data (a null environment).
    unsafe impl Sync for Shared {}
    unsafe impl Send for Shared {}
    static FUNCTIONS: OnceLock<Shared> = OnceLock::new();
    &FUNCTIONS
        .get_or_init(|| {
            type Plain = unsafe extern "C" fn(
                *mut c_void,
                *const c_char,
                c_int,
                *const c_char,
                *const c_char,
            );
            type Variadic = unsafe extern "C" fn(
                *mut c_void,
                *const c_char,
                c_int,
                *const c_char,
                *const c_char,
                ...
            );
            // SAFETY: see the module documentation.
            let logger: fmi2CallbackLogger =
                Some(unsafe { std::mem::transmute::<Plain, Variadic>(remember as Plain) });
            Shared(fmi2CallbackFunctions {
                logger,
                allocateMemory: None,
                freeMemory: None,
                stepFinished: None,
                componentEnvironment: std::ptr::null_mut(),
            })
        })
        .0
}

/// (resource URI, GUID) of the 1-DOF FI stage (paper Fig. 5b).
fn resources() -> &'static (CString, CString) {
    static RESOURCES: OnceLock<(CString, CString)> = OnceLock::new();
    RESOURCES.get_or_init(|| {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        let folder = std::env::temp_dir().join(format!("fistage-fuzz-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&folder);
        std::fs::create_dir_all(&folder).expect("scratch folder");
        fistage_fmi::package::write_resources(
            &root.join("scenarios/paper/fig05b_fi.toml"),
            &folder,
        )
        .expect("resources of the shipped scenario");
        let guid = fistage_fmi::Instance::new(&folder, None)
            .expect("instance of the shipped scenario")
            .guid()
            .to_string();
        let uri = format!("file://{}", folder.display());
        (
            CString::new(uri).expect("URI"),
            CString::new(guid).expect("GUID"),
        )
    })
}

/// A new Co-Simulation instance of the stage (never null: the resources are
/// the shipped scenario's).
pub fn instantiate() -> fmi2Component {
    instantiate_as(1)
}

/// An instance for `fmu_type` (0 Model Exchange, 1 Co-Simulation).
pub fn instantiate_as(fmu_type: i32) -> fmi2Component {
    let (uri, guid) = resources();
    // SAFETY: valid strings, and callbacks that live for the whole process.
    let c = unsafe {
        fmi2Instantiate(
            c"fuzz".as_ptr(),
            fmu_type,
            guid.as_ptr(),
            uri.as_ptr(),
            callbacks(),
            0,
            0,
        )
    };
    assert!(!c.is_null(), "the shipped scenario failed to instantiate");
    c
}

/// An instance set up and initialised from t = 0.
pub fn initialised() -> fmi2Component {
    let c = instantiate();
    assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
    assert_eq!(fmi2EnterInitializationMode(c), OK);
    assert_eq!(fmi2ExitInitializationMode(c), OK);
    c
}

/// Checks one call's status: within the standard's set and never fmi2Fatal
/// (the unit returns fmi2Fatal only for a panic it caught), and an error on a
/// live instance was explained through the logger.
pub fn check(call: &str, status: c_int, errors_before: usize, live: bool) {
    assert!(
        [OK, WARNING, DISCARD, ERROR].contains(&status),
        "{call}: status {status}"
    );
    if status == ERROR && live {
        assert!(
            errors_logged() > errors_before,
            "{call}: an error without a message"
        );
    }
}

/// Error messages logged so far.
pub fn errors_logged() -> usize {
    ERRORS_LOGGED.with(Cell::get)
}

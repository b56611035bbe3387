//! Messages to the importer through its logger callback: FMI 2.0's takes a
//! printf format, so every `%` in a message is doubled; FMI 3.0's takes the
//! text as it is, and the function names in it are FMI 3.0's. Interior NUL
//! bytes become spaces. Errors are always reported; call traces only with
//! debug logging on.

use std::ffi::{CString, c_int};

use super::status::Status;
use crate::fmi2::types::{fmi2CallbackFunctions, fmi2CallbackLogger, fmi2ComponentEnvironment};
use crate::fmi3::types::fmi3LogMessageCallback;

/// The importer's callback, of either standard.
#[derive(Clone, Copy)]
enum Sink {
    Fmi2(fmi2CallbackLogger),
    Fmi3(fmi3LogMessageCallback),
}

/// Log categories the unit declares in its model description.
pub const LOG_CATEGORIES: [(&str, &str); 2] = [
    (
        "logStatusError",
        "calls that return fmi2Error or fmi2Fatal, with the reason",
    ),
    (
        "logCalls",
        "every call of the FMI functions (debug logging)",
    ),
];

/// The importer's logger and what identifies this instance to it.
#[derive(Clone)]
pub(crate) struct Logger {
    callback: Sink,
    environment: fmi2ComponentEnvironment,
    instance_name: CString,
    /// Whether debug messages (call traces) are sent.
    pub debug: bool,
}

// SAFETY: the environment pointer is only handed back to the importer's own
// callback, on calls the importer makes for this instance.
unsafe impl Send for Logger {}

fn c_text(text: &str) -> CString {
    CString::new(text.replace('\0', " ")).unwrap_or_default()
}

impl Logger {
    /// A logger from the importer's callbacks (which may be null).
    ///
    /// # Safety
    /// `functions` is null or points to a valid `fmi2CallbackFunctions`.
    pub(crate) unsafe fn new(
        functions: *const fmi2CallbackFunctions,
        instance_name: &str,
        debug: bool,
    ) -> Self {
        // SAFETY: the caller guarantees the pointer is null or valid.
        let (callback, environment) = match unsafe { functions.as_ref() } {
            Some(f) => (f.logger, f.componentEnvironment),
            None => (None, std::ptr::null_mut()),
        };
        Self {
            callback: Sink::Fmi2(callback),
            environment,
            instance_name: c_text(instance_name),
            debug,
        }
    }

    /// A logger from an FMI 3.0 importer's callback (which may be null).
    pub(crate) fn fmi3(
        callback: fmi3LogMessageCallback,
        environment: fmi2ComponentEnvironment,
        instance_name: &str,
        debug: bool,
    ) -> Self {
        Self {
            callback: Sink::Fmi3(callback),
            environment,
            instance_name: c_text(instance_name),
            debug,
        }
    }

    /// Sends one message.
    pub(crate) fn log(&self, status: Status, category: &str, message: &str) {
        let category = c_text(category);
        match self.callback {
            Sink::Fmi2(None) | Sink::Fmi3(None) => {}
            Sink::Fmi2(Some(callback)) => {
                let message = c_text(&message.replace('%', "%%"));
                // SAFETY: the importer gave this callback for this instance; all
                // strings are valid and NUL-terminated for the duration of the call.
                unsafe {
                    callback(
                        self.environment,
                        self.instance_name.as_ptr(),
                        status as c_int,
                        category.as_ptr(),
                        message.as_ptr(),
                    );
                }
            }
            Sink::Fmi3(Some(callback)) => {
                let message = c_text(&message.replace("fmi2", "fmi3"));
                // SAFETY: as above.
                unsafe {
                    callback(
                        self.environment,
                        status as c_int,
                        category.as_ptr(),
                        message.as_ptr(),
                    );
                }
            }
        }
    }

    /// Reports a refused or failed call.
    pub(crate) fn error(&self, status: Status, message: &str) {
        self.log(status, "logStatusError", message);
    }

    /// Traces a call when debug logging is on.
    pub(crate) fn trace(&self, message: &str) {
        if self.debug {
            self.log(Status::Ok, "logCalls", message);
        }
    }
}

//! The call bodies both standards' functions run, each with the name of
//! the standard's own function (so a refusal names the function the
//! importer called): mode changes, debug logging, FMU states and the Model
//! Exchange arrays. Each runs through [`with_slot`].

use std::ffi::{c_char, c_int, c_void};

use super::c_args::{input_slice, output_slice, text};
use super::instance::{CallError, Instance};
use super::logger::LOG_CATEGORIES;
use super::registry::{live_state, store_state, with_slot};
use super::state::Snapshot;
use super::status::Status;

/// A change of the instance's mode (initialisation, event mode,
/// continuous-time mode, terminate, reset, a new time).
pub(crate) fn change(
    c: *mut c_void,
    call: &'static str,
    change: impl FnOnce(&mut Instance) -> Result<(), CallError>,
) -> c_int {
    with_slot(c, call, |slot| {
        change(&mut slot.instance)?;
        Ok(Status::Ok)
    })
}

/// Turns call traces on or off; categories must be declared ones.
///
/// # Safety
/// `categories` is null or points to `n` strings.
pub(crate) unsafe fn set_debug_logging(
    c: *mut c_void,
    call: &'static str,
    on: bool,
    n: usize,
    categories: *const *const c_char,
) -> c_int {
    with_slot(c, call, |slot| {
        // SAFETY: by the caller's guarantee.
        let categories = unsafe { input_slice(categories, n, "categories") }?;
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
            slot.logger.debug = on;
        }
        Ok(Status::Ok)
    })
}

/// A copy of everything that determines the future, into `*target`.
///
/// # Safety
/// `target` is null or valid for reads and writes.
pub(crate) unsafe fn get_state(
    c: *mut c_void,
    call: &'static str,
    target: *mut *mut c_void,
) -> c_int {
    with_slot(c, call, |slot| {
        let snapshot = slot.instance.snapshot();
        // SAFETY: by the caller's guarantee.
        unsafe { store_state(slot, target, snapshot) }
    })
}

/// Rolls back (or forward) to a saved state.
pub(crate) fn set_state(c: *mut c_void, call: &'static str, state: *mut c_void) -> c_int {
    with_slot(c, call, |slot| {
        let snapshot = live_state(slot, state)?.clone();
        slot.instance.restore(&snapshot)?;
        Ok(Status::Ok)
    })
}

/// Frees a saved state (twice is detected and refused) and nulls `*target`.
///
/// # Safety
/// `target` is null or valid for reads and writes.
pub(crate) unsafe fn free_state(
    c: *mut c_void,
    call: &'static str,
    target: *mut *mut c_void,
) -> c_int {
    with_slot(c, call, |slot| {
        if target.is_null() {
            return Err(CallError::InvalidArgument(
                "the FMUstate argument is a null pointer".into(),
            ));
        }
        // SAFETY: non-null, by the caller's guarantee valid.
        let state = unsafe { *target };
        if state.is_null() {
            return Ok(Status::Ok);
        }
        live_state(slot, state)?;
        slot.states.remove(&(state as usize));
        // SAFETY: was a live state of this slot, now removed: freed once.
        drop(unsafe { Box::from_raw(state.cast::<Snapshot>()) });
        // SAFETY: as above.
        unsafe { *target = std::ptr::null_mut() };
        Ok(Status::Ok)
    })
}

/// The size of a saved state serialized, into `*size`.
///
/// # Safety
/// `size` is null or valid for writes.
pub(crate) unsafe fn serialized_size(
    c: *mut c_void,
    call: &'static str,
    state: *mut c_void,
    size: *mut usize,
) -> c_int {
    with_slot(c, call, |slot| {
        let bytes = slot.instance.serialize(live_state(slot, state)?);
        // SAFETY: by the caller's guarantee.
        let size = unsafe { output_slice(size, 1, "size") }?;
        size[0] = bytes.len();
        Ok(Status::Ok)
    })
}

/// A saved state serialized into `out` (`size` bytes); `size_call` is the
/// function that tells the size.
///
/// # Safety
/// `out` is null or points to `size` writable bytes.
pub(crate) unsafe fn serialize(
    c: *mut c_void,
    (call, size_call): (&'static str, &'static str),
    state: *mut c_void,
    out: *mut u8,
    size: usize,
) -> c_int {
    with_slot(c, call, |slot| {
        let bytes = slot.instance.serialize(live_state(slot, state)?);
        if size < bytes.len() {
            return Err(CallError::InvalidArgument(format!(
                "buffer of {size} bytes is too small for the state ({} bytes; ask {size_call})",
                bytes.len()
            )));
        }
        // SAFETY: by the caller's guarantee.
        let out = unsafe { output_slice(out, bytes.len(), "serializedState") }?;
        out.copy_from_slice(&bytes);
        Ok(Status::Ok)
    })
}

/// A state from its serialized bytes, into `*target`.
///
/// # Safety
/// `bytes` is null or points to `size` bytes; `target` is null or valid for
/// reads and writes.
pub(crate) unsafe fn deserialize(
    c: *mut c_void,
    call: &'static str,
    (bytes, size): (*const u8, usize),
    target: *mut *mut c_void,
) -> c_int {
    with_slot(c, call, |slot| {
        // SAFETY: by the caller's guarantee.
        let bytes = unsafe { input_slice(bytes, size, "serializedState") }?;
        let snapshot = slot.instance.deserialize(bytes)?;
        // SAFETY: by the caller's guarantee.
        unsafe { store_state(slot, target, snapshot) }
    })
}

/// A completed integrator step (Model Exchange): never asks for an event
/// or the end, `no` being the standard's false.
///
/// # Safety
/// The flags are null or valid for writes.
pub(crate) unsafe fn completed_integrator_step<B: Copy>(
    c: *mut c_void,
    call: &'static str,
    flags: [*mut B; 2],
    no: B,
) -> c_int {
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

/// Sets the continuous states (Model Exchange).
///
/// # Safety
/// `x` is null or points to `n` elements.
pub(crate) unsafe fn set_continuous_states(
    c: *mut c_void,
    call: &'static str,
    x: *const f64,
    n: usize,
) -> c_int {
    with_slot(c, call, |slot| {
        // SAFETY: by the caller's guarantee.
        let x = unsafe { input_slice(x, n, "x") }?;
        slot.instance.set_continuous_states(x)?;
        Ok(Status::Ok)
    })
}

/// A Model Exchange getter filling an array of `n` reals.
///
/// # Safety
/// `values` is null or points to `n` writable elements.
pub(crate) unsafe fn real_array(
    c: *mut c_void,
    call: &'static str,
    (values, n): (*mut f64, usize),
    get: impl FnOnce(&mut Instance, &mut [f64]) -> Result<(), CallError>,
) -> c_int {
    with_slot(c, call, |slot| {
        // SAFETY: by the caller's guarantee.
        let values = unsafe { output_slice(values, n, "the array") }?;
        get(&mut slot.instance, values)?;
        Ok(Status::Ok)
    })
}

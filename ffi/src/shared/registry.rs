//! The instances both standards' functions reach: every instance lives in
//! a box whose address is in the set of live ones ([`register`]); a call
//! with any other pointer is refused, a call on an instance freed a while
//! ago says so, and every call runs inside `catch_unwind` ([`with_slot`]):
//! a panic becomes a fatal status and a log message, never an unwind into
//! the host. An instance's FMU states are boxes it owns ([`store_state`],
//! [`live_state`]), freed with it ([`free`]).

use std::collections::{BTreeSet, VecDeque};
use std::ffi::{c_int, c_void};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::{Mutex, MutexGuard};

use super::instance::{CallError, Instance};
use super::logger::Logger;
use super::phase::Phase;
use super::state::Snapshot;
use super::status::Status;

/// An instance with its logger and the FMU states it handed out.
pub(crate) struct Slot {
    pub(crate) instance: Instance,
    pub(crate) logger: Logger,
    pub(crate) states: BTreeSet<usize>,
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

pub(crate) fn code(status: Status) -> c_int {
    status as c_int
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
    c: *mut c_void,
    call: &'static str,
    body: impl FnOnce(&mut Slot) -> Result<Status, CallError>,
) -> c_int {
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
                &format!("{call}: the instance was already freed"),
            );
        }
        return code(Status::Error);
    }
    let slot = c.cast::<Slot>();
    // SAFETY: the address is live, so it is a Box<Slot> made by
    // `register` and not yet freed; FMI forbids concurrent calls on one instance.
    let phase = unsafe { (*slot).instance.phase() };
    if phase == Phase::Fatal {
        // SAFETY: as above.
        unsafe { &*slot }.logger.error(
            Status::Error,
            &format!("{call}: the instance had a fatal error; only freeing it is allowed"),
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

/// Boxes an instance with its logger and makes its address live.
pub(crate) fn register(instance: Instance, logger: Logger) -> *mut c_void {
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

/// Frees the instance behind `c` and the FMU states it handed out. A
/// second call with the same pointer is detected and ignored.
pub(crate) fn free(c: *mut c_void) {
    if c.is_null() || !lock(&LIVE).remove(&(c as usize)) {
        return;
    }
    // SAFETY: the address was live, so it is a Box<Slot> from `register`;
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

pub(crate) fn live_state(slot: &Slot, state: *mut c_void) -> Result<&Snapshot, CallError> {
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
pub(crate) unsafe fn store_state(
    slot: &mut Slot,
    target: *mut *mut c_void,
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

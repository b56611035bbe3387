//! Any bytes as a serialized FMU state (fmi2DeSerializeFMUstate), once as
//! given and once with their checksum made right, so that the fuzzer also
//! reaches what lies behind the CRC: every state is refused with a message or
//! restored, and a restored unit steps, or refuses to, without a panic and
//! without a non-finite output. The seeds are states the unit serialized.
#![no_main]

#[path = "support.rs"]
mod support;

use std::ffi::c_char;

use fistage_fmi::exports::*;
use fistage_fmi::types::fmi2FMUstate;
use libfuzzer_sys::fuzz_target;
use support::{OK, check, errors_logged};

/// Value references read back after a restore and a step (the unit has
/// fewer; the extra ones must be refused, not read out of bounds).
const READ_BACK: u32 = 40;

fn try_state(bytes: &[u8]) {
    let c = support::initialised();
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    let before = errors_logged();
    // SAFETY: a live instance, bytes valid for their length, a valid out pointer.
    let status = unsafe {
        fmi2DeSerializeFMUstate(c, bytes.as_ptr().cast::<c_char>(), bytes.len(), &mut state)
    };
    check("fmi2DeSerializeFMUstate", status, before, true);
    if status == OK {
        assert!(!state.is_null());
        let before = errors_logged();
        let restored = fmi2SetFMUstate(c, state);
        check("fmi2SetFMUstate", restored, before, true);
        if restored == OK {
            step_and_read(c);
        }
        let before = errors_logged();
        // SAFETY: a state of this instance.
        let freed = unsafe { fmi2FreeFMUstate(c, &mut state) };
        check("fmi2FreeFMUstate", freed, before, true);
    }
    fmi2FreeInstance(c);
}

/// One 1 ms step from the restored time, then every output: statuses in the
/// standard's set, and finite values after a step that succeeded.
fn step_and_read(c: fistage_fmi::types::fmi2Component) {
    let mut time = 0.0;
    let before = errors_logged();
    // SAFETY: a live instance and a valid out pointer.
    let status = unsafe { fmi2GetRealStatus(c, 2, &mut time) };
    check("fmi2GetRealStatus", status, before, true);
    let before = errors_logged();
    let stepped = fmi2DoStep(c, time, 1e-3, 1);
    check("fmi2DoStep", stepped, before, true);
    for vr in 0..READ_BACK {
        let mut value = 0.0;
        let before = errors_logged();
        // SAFETY: a live instance, one reference and one value.
        let read = unsafe { fmi2GetReal(c, &vr, 1, &mut value) };
        check("fmi2GetReal", read, before, true);
        if stepped == OK && read == OK {
            assert!(
                value.is_finite(),
                "output {vr} is {value} after a good step"
            );
        }
    }
}

fuzz_target!(|data: &[u8]| {
    try_state(data);
    if data.len() >= 4 {
        let body = &data[..data.len() - 4];
        let mut sealed = body.to_vec();
        sealed.extend_from_slice(&crc32fast::hash(body).to_le_bytes());
        if sealed != data {
            try_state(&sealed);
        }
    }
});

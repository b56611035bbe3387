//! Any bytes as a sequence of fmi2 calls on up to two instances (each Model
//! Exchange or Co-Simulation, the functions of both and FMI 3.0's called on
//! either): calls in and
//! out of order, on freed or null instances, with awkward arguments (NaN,
//! infinities, negative steps, unknown value references, damaged serialized
//! states). Every call returns a status of the standard's set, never
//! fmi2Fatal; every error on a live instance says why; a step that succeeds
//! leaves finite outputs. Steps are at most 20 ms, so that an input is a
//! sequence of calls and not one long simulation.
#![no_main]

#[path = "support.rs"]
#[allow(dead_code)] // each target uses a part
mod support;

use std::ffi::c_char;

use fistage_fmi::exports::*;
use fistage_fmi::types::{fmi2Component, fmi2EventInfo, fmi2FMUstate};
use libfuzzer_sys::fuzz_target;
use support::{OK, check, errors_logged};

/// Calls per input at most.
const MAX_CALLS: usize = 256;
/// Value references tried (a few beyond the unit's last).
const VARIABLES: u8 = 64;
/// The longest communication step a call may ask for, s.
const MAX_STEP: f64 = 0.02;

/// Instances made so far (freed ones stay, to be called after their free).
struct Session {
    units: Vec<fmi2Component>,
    live: Vec<bool>,
    states: Vec<(usize, fmi2FMUstate)>,
}

impl Session {
    fn pick(&self, bytes: &mut Bytes) -> (fmi2Component, bool) {
        let k = usize::from(bytes.u8());
        if k % 17 == 16 || self.units.is_empty() {
            return (std::ptr::null_mut(), false);
        }
        let i = k % self.units.len();
        (self.units[i], self.live[i])
    }

    fn index_of(&self, c: fmi2Component) -> Option<usize> {
        self.units.iter().position(|u| *u == c)
    }

    fn state(&self, bytes: &mut Bytes, c: fmi2Component) -> fmi2FMUstate {
        let own: Vec<_> = self
            .states
            .iter()
            .filter(|(u, _)| Some(*u) == self.index_of(c))
            .collect();
        match own.len() {
            0 => std::ptr::null_mut(),
            n => own[usize::from(bytes.u8()) % n].1,
        }
    }

    /// One call chosen by the next byte; returns its name and status.
    fn call(&mut self, bytes: &mut Bytes) -> Option<(&'static str, i32, bool)> {
        let op = bytes.u8() % 34;
        if op == 19 {
            if self.units.len() < 2 {
                self.units
                    .push(support::instantiate_as(i32::from(bytes.u8() % 2)));
                self.live.push(true);
            }
            return None;
        }
        let (c, live) = self.pick(bytes);
        let vr = if bytes.u8() < 230 {
            u32::from(bytes.u8() % VARIABLES)
        } else {
            bytes.u32()
        };
        let mut value = 0.0;
        // SAFETY: every pointer passed is null, a live or freed instance of
        // this session (the unit detects freed ones), or valid local storage.
        let status = unsafe {
            match op {
                0 => (
                    "fmi2SetupExperiment",
                    fmi2SetupExperiment(
                        c,
                        i32::from(bytes.u8() % 2),
                        bytes.real(),
                        bytes.real(),
                        i32::from(bytes.u8() % 2),
                        bytes.real(),
                    ),
                ),
                1 => (
                    "fmi2EnterInitializationMode",
                    fmi2EnterInitializationMode(c),
                ),
                2 => ("fmi2ExitInitializationMode", fmi2ExitInitializationMode(c)),
                3 => ("fmi2Terminate", fmi2Terminate(c)),
                4 => ("fmi2Reset", fmi2Reset(c)),
                5 => ("fmi2GetReal", fmi2GetReal(c, &vr, 1, &mut value)),
                6 => ("fmi2SetReal", fmi2SetReal(c, &vr, 1, &bytes.real())),
                7 | 8 => {
                    let mut t = 0.0;
                    fmi2GetRealStatus(c, 2, &mut t);
                    let point = if bytes.u8() < 220 { t } else { bytes.real() };
                    let h = match bytes.u8() % 4 {
                        0 => bytes.real(),
                        _ => f64::from(bytes.u8()) * 1e-4,
                    };
                    let h = if h.is_finite() && h > MAX_STEP {
                        MAX_STEP
                    } else {
                        h
                    };
                    let status = fmi2DoStep(c, point, h, i32::from(bytes.u8() % 2));
                    if status == OK {
                        self.outputs_are_finite(c);
                    }
                    ("fmi2DoStep", status)
                }
                9 => {
                    let mut state: fmi2FMUstate = std::ptr::null_mut();
                    let status = fmi2GetFMUstate(c, &mut state);
                    if let (false, Some(i)) = (state.is_null(), self.index_of(c)) {
                        self.states.push((i, state));
                    }
                    ("fmi2GetFMUstate", status)
                }
                10 => ("fmi2SetFMUstate", fmi2SetFMUstate(c, self.state(bytes, c))),
                11 => {
                    let mut state = self.state(bytes, c);
                    let status = fmi2FreeFMUstate(c, &mut state);
                    if status == OK {
                        self.states.retain(|(_, s)| *s != state && !state.is_null());
                    }
                    ("fmi2FreeFMUstate", status)
                }
                12 => {
                    let known = u32::from(bytes.u8() % VARIABLES);
                    let mut derivative = 0.0;
                    (
                        "fmi2GetDirectionalDerivative",
                        fmi2GetDirectionalDerivative(
                            c,
                            &vr,
                            1,
                            &known,
                            1,
                            &bytes.real(),
                            &mut derivative,
                        ),
                    )
                }
                13 => ("fmi2DeSerializeFMUstate", self.round_trip(bytes, c)),
                14 => {
                    let mut flag = 0;
                    (
                        "fmi2GetBooleanStatus",
                        fmi2GetBooleanStatus(c, i32::from(bytes.u8() % 6) - 1, &mut flag),
                    )
                }
                15 => ("fmi2CancelStep", fmi2CancelStep(c)),
                16 => (
                    "fmi2SetDebugLogging",
                    fmi2SetDebugLogging(c, i32::from(bytes.u8() % 2), 0, std::ptr::null()),
                ),
                17 => {
                    let mut status = 0;
                    (
                        "fmi2GetStatus",
                        fmi2GetStatus(c, i32::from(bytes.u8() % 6) - 1, &mut status),
                    )
                }
                20..=28 => self.model_exchange_call(op, bytes, c),
                29..=32 => fmi3_call(op, bytes, c, vr),
                _ => {
                    fmi2FreeInstance(c);
                    if let Some(i) = self.index_of(c) {
                        self.live[i] = false;
                        self.states.retain(|(u, _)| *u != i);
                    }
                    return None;
                }
            }
        };
        Some((status.0, status.1, live))
    }

    /// One Model Exchange call (`op` 20 to 28), with an array length that
    /// may not be the unit's and values that may not be finite.
    unsafe fn model_exchange_call(
        &mut self,
        op: u8,
        bytes: &mut Bytes,
        c: fmi2Component,
    ) -> (&'static str, i32) {
        let n = match bytes.u8() % 4 {
            0 => usize::from(bytes.u8() % 40),
            _ => 5,
        };
        let mut array: Vec<f64> = (0..n).map(|_| bytes.real()).collect();
        let pointer = if bytes.u8() % 16 == 0 {
            std::ptr::null_mut()
        } else {
            array.as_mut_ptr()
        };
        // SAFETY: `pointer` is null or holds `n` values; the rest as in `call`.
        unsafe {
            match op {
                20 => ("fmi2EnterEventMode", fmi2EnterEventMode(c)),
                21 => {
                    let mut info = fmi2EventInfo {
                        newDiscreteStatesNeeded: 0,
                        terminateSimulation: 0,
                        nominalsOfContinuousStatesChanged: 0,
                        valuesOfContinuousStatesChanged: 0,
                        nextEventTimeDefined: 0,
                        nextEventTime: 0.0,
                    };
                    ("fmi2NewDiscreteStates", fmi2NewDiscreteStates(c, &mut info))
                }
                22 => (
                    "fmi2EnterContinuousTimeMode",
                    fmi2EnterContinuousTimeMode(c),
                ),
                23 => {
                    let (mut enter, mut terminate) = (0, 0);
                    (
                        "fmi2CompletedIntegratorStep",
                        fmi2CompletedIntegratorStep(c, 1, &mut enter, &mut terminate),
                    )
                }
                24 => ("fmi2SetTime", fmi2SetTime(c, bytes.real())),
                25 => (
                    "fmi2SetContinuousStates",
                    fmi2SetContinuousStates(c, pointer, n),
                ),
                26 => ("fmi2GetDerivatives", fmi2GetDerivatives(c, pointer, n)),
                27 => (
                    "fmi2GetContinuousStates",
                    fmi2GetContinuousStates(c, pointer, n),
                ),
                _ => (
                    "fmi2GetNominalsOfContinuousStates",
                    fmi2GetNominalsOfContinuousStates(c, pointer, n),
                ),
            }
        }
    }

    /// Serializes a state of `c` (or none), perhaps shortens or damages the
    /// bytes, and deserializes them again.
    unsafe fn round_trip(&mut self, bytes: &mut Bytes, c: fmi2Component) -> i32 {
        let state = self.state(bytes, c);
        let mut size = 0usize;
        // SAFETY: by the caller's guarantee.
        unsafe {
            let sized = fmi2SerializedFMUstateSize(c, state, &mut size);
            let mut buffer = vec![0 as c_char; size.min(1 << 16)];
            if bytes.u8() % 4 == 0 {
                buffer.pop();
            }
            let serialized = fmi2SerializeFMUstate(c, state, buffer.as_mut_ptr(), buffer.len());
            if !buffer.is_empty() && bytes.u8() % 2 == 0 {
                let i = bytes.u32() as usize % buffer.len();
                buffer[i] ^= (1 + bytes.u8() % 255) as c_char;
            }
            let mut restored: fmi2FMUstate = std::ptr::null_mut();
            let back = fmi2DeSerializeFMUstate(c, buffer.as_ptr(), buffer.len(), &mut restored);
            if let (false, Some(i)) = (restored.is_null(), self.index_of(c)) {
                self.states.push((i, restored));
            }
            sized.max(serialized).max(back)
        }
    }

    fn outputs_are_finite(&self, c: fmi2Component) {
        for vr in 0..u32::from(VARIABLES) {
            let mut value = 0.0;
            // SAFETY: a live instance, one reference and one value.
            if unsafe { fmi2GetReal(c, &vr, 1, &mut value) } == OK {
                assert!(
                    value.is_finite(),
                    "value reference {vr} is {value} after a good step"
                );
            }
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let mut bytes = Bytes(data);
    let mut session = Session {
        units: vec![support::instantiate()],
        live: vec![true],
        states: Vec::new(),
    };
    for _ in 0..MAX_CALLS {
        if bytes.is_empty() {
            break;
        }
        let before = errors_logged();
        if let Some((name, status, live)) = session.call(&mut bytes) {
            check(name, status, before, live);
        }
    }
    for (c, live) in session.units.iter().zip(&session.live) {
        if *live {
            fmi2FreeInstance(*c);
        }
    }
});

/// One FMI 3.0 call (`op` 29 to 32) on an instance of either interface.
///
/// # Safety
/// `c` is null or an instance of this session (live or freed).
unsafe fn fmi3_call(op: u8, bytes: &mut Bytes, c: fmi2Component, vr: u32) -> (&'static str, i32) {
    use fistage_fmi::fmi3::exports::*;
    let mut value = 0.0;
    // SAFETY: local storage for every output; `c` by the caller's guarantee.
    unsafe {
        match op {
            29 => (
                "fmi3EnterInitializationMode",
                fmi3EnterInitializationMode(
                    c,
                    bytes.u8() % 2 == 0,
                    bytes.real(),
                    bytes.real(),
                    bytes.u8() % 2 == 0,
                    bytes.real(),
                ),
            ),
            30 => {
                let (mut a, mut b, mut e, mut t) = (false, false, false, 0.0);
                let h = f64::from(bytes.u8()) * 1e-4;
                let point = if bytes.u8() < 220 { 0.0 } else { bytes.real() };
                (
                    "fmi3DoStep",
                    fmi3DoStep(c, point, h.min(MAX_STEP), true, &mut a, &mut b, &mut e, &mut t),
                )
            }
            31 => (
                "fmi3GetFloat64",
                fmi3GetFloat64(c, &vr, 1, &mut value, usize::from(bytes.u8() % 3)),
            ),
            _ => {
                let mut flags = [false; 5];
                let [a, b, d, e, f] = &mut flags;
                (
                    "fmi3UpdateDiscreteStates",
                    fmi3UpdateDiscreteStates(c, a, b, d, e, f, &mut value),
                )
            }
        }
    }
}

/// The fuzzer's bytes as a stream of arguments; zeros once they run out.
struct Bytes<'a>(pub &'a [u8]);

impl Bytes<'_> {
    fn is_empty(&self) -> bool {
        self.0.is_empty()
    }
    fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((first, rest)) => {
                self.0 = rest;
                *first
            }
            None => 0,
        }
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    fn f64_bits(&mut self) -> f64 {
        let mut bits = [0u8; 8];
        bits.iter_mut().for_each(|b| *b = self.u8());
        f64::from_le_bytes(bits)
    }
    /// A real argument: the awkward values often, any bit pattern sometimes.
    fn real(&mut self) -> f64 {
        match self.u8() % 12 {
            0 => f64::NAN,
            1 => f64::INFINITY,
            2 => f64::NEG_INFINITY,
            3 => 0.0,
            4 => -0.0,
            5 => f64::MIN_POSITIVE,
            6 => 1e300,
            7 => -1.0,
            8 => 1e12,
            9 => 1e-9,
            10 => f64::from(self.u8()) * 0.1,
            _ => self.f64_bits(),
        }
    }
}

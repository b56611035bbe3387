//! Any bytes as an identification CSV file (f_ss(v) and FRF): a clear error
//! or data, never a panic.
#![no_main]

use fistage_ident::{UnitOverrides, parse_frf_csv, parse_stribeck_csv};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let units = UnitOverrides::default();
        let _ = parse_stribeck_csv("fuzz.csv", text, &units);
        let _ = parse_frf_csv("fuzz.csv", text, &units);
    }
});

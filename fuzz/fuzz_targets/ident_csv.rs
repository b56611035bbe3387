//! Any bytes as an identification file (f_ss(v) and FRF CSV, a record as
//! CSV and as a MAT-file): a clear error or data, never a panic.
#![no_main]

use fistage_ident::csv_input::parse_record_csv;
use fistage_ident::record::parse_record_mat;
use fistage_ident::{UnitOverrides, parse_frf_csv, parse_stribeck_csv};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let units = UnitOverrides::default();
    let _ = parse_record_mat("fuzz.mat", data, &units);
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_stribeck_csv("fuzz.csv", text, &units);
        let _ = parse_frf_csv("fuzz.csv", text, &units);
        let _ = parse_record_csv("fuzz.csv", text, &units);
    }
});

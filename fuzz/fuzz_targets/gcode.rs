//! Fuzzes the G-code reader (interpreter and cell splitting).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = cellseq_programs::gcode::parse("fuzz.ngc", &text);
});

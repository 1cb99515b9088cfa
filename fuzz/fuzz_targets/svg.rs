//! Fuzzes the SVG reader.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = cellseq_programs::svg::read("fuzz.svg", &text, Default::default());
});

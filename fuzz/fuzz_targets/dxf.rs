//! Fuzzes the DXF reader.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = cellseq_programs::dxf::read("fuzz.dxf", data, Default::default());
});

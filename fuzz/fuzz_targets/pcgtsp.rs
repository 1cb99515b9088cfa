//! Fuzzes the PCGTSP reader: parse, validate and, when valid, solve with greedy (validation
//! must leave nothing a solver fails on).
#![no_main]

use cellseq::formats::Format;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| cellseq_fuzz::parse_validate_solve(data, Format::Pcgtsp));

//! Fuzzes the solution reader: parse, resolve against a small instance, check.
#![no_main]

use cellseq::formats::{Format, json, parse_instance};
use libfuzzer_sys::fuzz_target;
use std::sync::OnceLock;

/// A 4-cell matrix instance with modes, precedence and fixed ends (the seed solution's).
const INSTANCE: &str = include_str!("../seeds/json/matrix-first-last.json");

fuzz_target!(|data: &[u8]| {
    static INST: OnceLock<cellseq::Instance> = OnceLock::new();
    let inst = INST.get_or_init(|| {
        parse_instance("instance", INSTANCE, Format::Json).expect("seed instance parses")
    });
    let text = String::from_utf8_lossy(data);
    let Ok(sol) = json::parse_solution("fuzz", &text) else {
        return;
    };
    if let Ok(seq) = json::from_refs(inst, &sol.sequence, "fuzz") {
        let _ = cellseq::check(inst, &seq, inst.default_objective());
    }
});

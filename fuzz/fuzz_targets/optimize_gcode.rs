//! Fuzzes the G-code pipeline: a program in, `optimize` under a time limit of half a second.
//! A program that parses is sequenced, verified and written by the pipeline; the run must end
//! within the limit plus a margin, and the output hold no non-finite number the input did not.
#![no_main]

use cellseq_fuzz::{LIMIT_S, MARGIN_S, non_finite};
use cellseq_programs::optimize::gcode::{Options, optimize};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let t0 = std::time::Instant::now();
    let Ok(parsed) = cellseq_programs::gcode::parse("fuzz.ngc", &text) else {
        return;
    };
    let opts = Options {
        time_limit: Some(LIMIT_S),
        ..Options::default()
    };
    if let Ok(out) = optimize(&parsed, &opts) {
        assert!(
            non_finite(&out.text) <= non_finite(&text),
            "the optimized program holds NaN or inf"
        );
    }
    let s = t0.elapsed().as_secs_f64();
    assert!(s <= LIMIT_S + MARGIN_S, "optimize took {s:.2} s under a {LIMIT_S} s limit");
});

//! Fuzzes the drawing pipeline: the first byte chooses SVG or DXF (and, for DXF, SVG or G-code
//! output), the rest is the drawing; it is read, sequenced by `optimize` under a time limit of
//! half a second and rendered. The run must end within the limit plus a margin, and the output
//! hold no non-finite number the input did not.
#![no_main]

use cellseq_fuzz::{LIMIT_S, MARGIN_S, non_finite};
use cellseq_programs::dxf::{self, Post};
use cellseq_programs::optimize::strokes::{self as pipe, Output};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&choice, rest)) = data.split_first() else {
        return;
    };
    let t0 = std::time::Instant::now();
    let text = String::from_utf8_lossy(rest);
    let drawing = if choice % 2 == 0 {
        cellseq_programs::svg::read("fuzz.svg", &text, Default::default())
    } else {
        dxf::read("fuzz.dxf", rest, Default::default())
    };
    let Ok(d) = drawing else {
        return;
    };
    let opts = pipe::Options {
        time_limit: Some(LIMIT_S),
        cut: choice % 2 == 1,
        ..pipe::Options::default()
    };
    let post = Post::default();
    let output = if choice % 4 == 3 {
        Output::Gcode(&post)
    } else {
        Output::Svg
    };
    if let Ok(mut out) = pipe::optimize(&d, &opts)
        && let Ok((written, _)) = pipe::render(&d, &mut out, output)
    {
        assert!(
            non_finite(&written) <= non_finite(&text),
            "the output holds NaN or inf"
        );
    }
    let s = t0.elapsed().as_secs_f64();
    assert!(s <= LIMIT_S + MARGIN_S, "optimize took {s:.2} s under a {LIMIT_S} s limit");
});

//! Issue 47 (corpus): pcb-gcode's drill files (the Eagle ULP, `mach.pp` profile, `G82`
//! canned cycles) zero each new tool on the work (`M06 T02`, `G01 Z0`, `M06`), rise to the
//! drilling height and dwell there, and go to `G00 X0 Y0` before each tool change. The touch
//! is part of the tool change (not a cut), the dwell keeps its height, and each block starts
//! from where its tool change leaves the tool. LinuxCNC's own judgment of these files is in
//! `rs274.rs` (the corpus test reads every fixture).

use cellseq_programs::gcode;
use cellseq_programs::gcode::cells::preamble_home;
use cellseq_programs::optimize::gcode::{Kept, Optimized, Options, optimize};

fn fixture(name: &str) -> String {
    crate::common::fixture_text(&format!("gcode/{name}"))
}

/// Optimizes a program and checks the written text again, independently of the run.
fn optimized(name: &str, text: &str) -> (gcode::Parsed, Optimized) {
    let p = gcode::parse(name, text).unwrap();
    let opts = Options {
        max_evals: Some(20_000),
        ..Options::default()
    };
    let out = optimize(&p, &opts).unwrap();
    let v = gcode::verify_files(name, text, "out", &out.text).unwrap();
    assert_eq!(v.cuts, out.cuts, "{name}");
    assert!(out.after.not_worse_than(&out.before), "{name}");
    (p, out)
}

#[test]
fn a_tool_zero_touch_is_part_of_its_tool_change() {
    let text = fixture("tool_zero_touch_off.ngc");
    let (p, out) = optimized("touch.ngc", &text);
    assert_eq!(p.layout.cells.len(), 10);
    assert!(p.layout.cells.iter().all(|c| c.cycle));
    assert_eq!(p.layout.blocks.len(), 2);
    // the second block's preamble holds the touch and the pause, as written
    let pre: Vec<&str> = p.layout.blocks[1]
        .preamble
        .iter()
        .map(|&g| p.program.text[g].trim())
        .collect();
    assert!(
        pre.windows(2).any(|w| w == ["G01 Z0 F100", "M06"]),
        "{pre:?}"
    );
    // the rise to the drilling height stays before the dwell after the spindle start
    let lines: Vec<&str> = out.text.lines().map(str::trim).collect();
    let rises = lines
        .windows(4)
        .filter(|w| *w == ["M06", "G00 Z2", "M03", "G04 P1"])
        .count();
    assert_eq!(rises, 2, "{}", out.text);
    // each row drilled from X0 in order: 50 + 40 + 30 + 20 + 10 mm becomes 5 × 10 mm
    assert_eq!(out.kept, Kept::Nothing, "{:?}", out.note);
    assert!(
        out.after.air_length < out.before.air_length - 150.0,
        "{} -> {}",
        out.before.air_length,
        out.after.air_length
    );
}

#[test]
fn a_touch_at_a_place_the_previous_cell_decides_is_still_refused() {
    // without `G00 X0 Y0` before the second tool change the touch happens wherever the
    // block before it ended: a new order would move it, so the program is refused as before
    let text = fixture("tool_zero_touch_off.ngc").replacen("G00 X0 Y0\nM06 T2", "M06 T2", 1);
    let e = gcode::parse("touch.ngc", &text).unwrap_err().to_string();
    assert!(
        e.contains("touch.ngc:28") && e.contains("tool change while below the safe height"),
        "{e}"
    );
}

#[test]
fn a_block_starts_where_its_tool_change_leaves_the_tool() {
    let text = fixture("tool_zero_touch_off.ngc");
    let p = gcode::parse("touch.ngc", &text).unwrap();
    // after `G00 X0 Y0`, `M06 T2` and the touch at Z0
    assert_eq!(
        preamble_home(&p.program, &p.layout.blocks[1]),
        Some([0.0, 0.0, 0.0])
    );
    // a tool change that does not say where the tool goes fixes nothing
    let text = fixture("real/pcb2gcode_d1minigsr_drill.ngc");
    let p = gcode::parse("d1.ngc", &text).unwrap();
    assert!(p.layout.blocks.len() > 1);
    assert_eq!(preamble_home(&p.program, &p.layout.blocks[1]), None);
}

#[test]
fn pcb_gcode_drill_files_save_travel_between_holes() {
    for (name, holes, tools) in [
        ("real/pcb-gcode_enabtmr_bot_drill_g82.tap", 83, 5),
        ("real/pcb-gcode_lcdi2c_top_drill_g82.tap", 61, 4),
    ] {
        let (p, out) = optimized(name, &fixture(name));
        assert_eq!(p.layout.cells.len(), holes, "{name}");
        assert!(p.layout.cells.iter().all(|c| c.cycle), "{name}");
        assert_eq!(p.layout.blocks.len(), tools, "{name}");
        // the holes of each tool start from X0 Y0, where pcb-gcode changes tools: modelled
        // from the previous block's last hole instead, every new order measured worse
        assert_ne!(out.kept, Kept::Whole, "{name}: {:?}", out.note);
        assert!(
            out.after.air_length < out.before.air_length - 5.0,
            "{name}: {} -> {}",
            out.before.air_length,
            out.after.air_length
        );
        assert_eq!(out.after.lifts, out.before.lifts, "{name}");
    }
}

//! Issue 47 (G-code): every program a shop floor has — program numbers, canned drilling cycles,
//! parameters and expressions, the spin-up dwell, moves from a position only the controller
//! knows, inch programs — and issue 50's numeric rule for coordinates. LinuxCNC's own judgment
//! of these fixtures is in `rs274.rs` (the corpus test reads every fixture).

use cellseq_programs::gcode;
use cellseq_programs::optimize::gcode::{Kept, Options, optimize};

fn fixture(name: &str) -> String {
    crate::common::fixture_text(&format!("gcode/{name}"))
}

fn opts() -> Options {
    Options {
        max_evals: Some(20_000),
        ..Options::default()
    }
}

/// Optimizes a fixture and checks the written text again, independently of the run.
fn optimized(name: &str) -> (gcode::Parsed, cellseq_programs::optimize::gcode::Optimized) {
    let text = fixture(name);
    let p = gcode::parse(name, &text).unwrap();
    let out = optimize(&p, &opts()).unwrap();
    let v = gcode::verify_files(name, &text, "out", &out.text).unwrap();
    assert_eq!(v.cuts, out.cuts, "{name}");
    assert!(out.after.not_worse_than(&out.before), "{name}");
    (p, out)
}

#[test]
fn program_numbers_are_kept_where_they_were() {
    let (_, out) = optimized("fanuc_program_number.nc");
    let lines: Vec<&str> = out.text.lines().collect();
    assert_eq!(lines[0], "%");
    assert_eq!(lines[1], "O1001 (BRACKET)");
    assert_eq!(lines.last(), Some(&"%"));
    assert_eq!(out.kept, Kept::Nothing, "{:?}", out.note);
    assert!(out.after.air_length < out.before.air_length - 100.0);
    // everything after the closing % is not part of the program (LinuxCNC ignores it)
    let text = fixture("fanuc_program_number.nc") + "G1 X500 F10\n";
    let p = gcode::parse("t.nc", &text).unwrap();
    assert!(p.program.lines.last().unwrap().cuts.is_empty());
}

#[test]
fn o_word_control_flow_is_refused_naming_the_construct_and_line() {
    for (text, says) in [
        ("G21\no100 sub\nG1 X1 F10\no100 endsub\n", "'O100 sub'"),
        ("G21\nG0 Z5\no<loop> while [1 LT 2]\n", "'O<LOOP> while'"),
        ("G21\nO1001 G0 X2\n", "followed by other words"),
    ] {
        let e = gcode::parse("p.ngc", text).unwrap_err().to_string();
        assert!(e.contains("p.ngc:") && e.contains(says), "{e}");
    }
}

#[test]
fn every_hole_of_a_canned_cycle_is_a_cell_and_drilling_saves_travel() {
    let (p, out) = optimized("real/pcb2gcode_multivibrator_nom6_drill.ngc");
    assert_eq!(p.layout.cells.len(), 52);
    assert!(p.layout.cells.iter().all(|c| c.cycle));
    assert!(
        out.after.air_length < 0.97 * out.before.air_length,
        "{} -> {}",
        out.before.air_length,
        out.after.air_length
    );
    assert_eq!(out.after.lifts, out.before.lifts);
}

#[test]
fn retract_modes_pecks_dwells_and_incremental_rows_stay_exact() {
    for name in ["fanuc_program_number.nc", "cycles_incremental.ngc"] {
        let (_, out) = optimized(name);
        assert!(
            out.after.air_length < out.before.air_length,
            "{name}: {:?}",
            out.note
        );
    }
    // a hole retracting elsewhere is another hole: G98 made G99 on a reordered program
    let text = fixture("fanuc_program_number.nc");
    let p = gcode::parse("f.nc", &text).unwrap();
    let out = optimize(&p, &opts()).unwrap();
    let tampered = out.text.replacen("G98 G81", "G99 G81", 1);
    assert!(gcode::verify_texts(&p, "t", &tampered).is_err());
    // a peck depth changed
    let tampered = out.text.replacen("Q3.", "Q2.", 1);
    assert!(gcode::verify_texts(&p, "t", &tampered).is_err());
}

#[test]
fn canned_cycles_are_read_as_linuxcnc_runs_them() {
    let p = gcode::interp::interpret(
        "G21 G90\nG0 X0 Y0 Z10\nF100\nG98 G81 X1 Y1 Z-2 R2\nX2\nG99 X3\nX4\nG80\nG0 Z0.5\n\
         G91 G81 X1 R2 Z-3 L3\nG90 G80\n",
    )
    .unwrap();
    let clear = |l: usize| match p.lines[l].cuts[0].kind {
        gcode::interp::CutKind::Cycle { clear, .. } => clear,
        _ => panic!("not a hole"),
    };
    // G98 retracts to the series' initial level, G99 to R
    assert_eq!(
        (clear(3), clear(4), clear(5)),
        (Some(10.0), Some(10.0), Some(2.0))
    );
    assert_eq!(p.lines[6].pos_before[2], Some(2.0));
    // G91: R from the level where the series started (0.5), Z from R, X steps on each repeat
    let row = &p.lines[9].cuts;
    assert_eq!(row.len(), 3);
    assert_eq!(row[2].from, [7.0, 1.0, 2.5]);
    assert_eq!(row[2].to, [7.0, 1.0, -0.5]);
    // LinuxCNC's refusals: no Z on the first hole, no R after other motion, R below Z
    for bad in [
        "G0 Z5\nF10\nG81 X1 R1\n",
        "G0 Z5\nF10\nG81 X1 Z-1 R1\nG0 Z5\nG81 X2\n",
        "G0 Z5\nF10\nG81 X1 Z-1 R-2\n",
        "G0 Z5\nF10\nG83 X1 Z-1 R1\n",
        "G0 Z5\nF10\nG84 X1 Z-1 R1\n",
    ] {
        assert!(gcode::interp::interpret(bad).is_err(), "{bad}");
    }
}

#[test]
fn parameters_are_evaluated_and_written_as_numbers() {
    let (_, out) = optimized("parameters.ngc");
    assert!(out.after.air_length < out.before.air_length);
    // the assignments stay, every line that read a parameter carries its numbers
    assert!(out.text.contains("#<depth> = -1.5"));
    assert!(out.text.contains("G1 Z-1.5 F200"), "{}", out.text);
    assert!(out.text.contains("G1 Z-2 F200"), "{}", out.text);
    for l in out.text.lines() {
        let code = l.split(['(', ';']).next().unwrap_or("");
        assert!(!code.contains('['), "a line still has an expression: {l}");
    }
}

#[test]
fn moves_before_the_first_known_position_stay_a_fixed_prefix() {
    let text = fixture("g28_prefix.gcode");
    let (p, out) = optimized("g28_prefix.gcode");
    // the feed in X/Y at the height only the controller knows is in the header, as written
    assert!(p.layout.header_end > 6);
    let head: Vec<&str> = text.lines().take(p.layout.header_end).collect();
    let out_head: Vec<&str> = out.text.lines().take(p.layout.header_end).collect();
    assert_eq!(head, out_head);
    assert!(out.after.air_length < out.before.air_length);
    // between cuts it is still refused, with the line and what to do
    let mid = "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG0 Z5\nG28 G91 Z0\nG90\nG1 X20 Y5\n\
               G0 Z5\nG0 X30\nG1 Z-1\nG1 X40\nG0 Z5\nM2\n";
    let e = gcode::parse("m.ngc", mid).unwrap_err().to_string();
    assert!(
        e.contains("m.ngc:8:") && e.contains("give X, Y and Z"),
        "{e}"
    );
}

#[test]
fn a_footer_dwell_keeps_its_height_so_the_new_order_survives() {
    // pcb2gcode's end: the last cell rises to the tool-change height, then M5 and a dwell
    let text = "G21 G90 G94\nG0 Z25\nM3 S10000\nG4 P1\nG0 Z1\n\
                G0 X0 Y0\nG1 Z-0.1 F100\nG1 X5\nG0 Z1\n\
                G0 X50 Y50\nG1 Z-0.1\nG1 X55\nG0 Z1\n\
                G0 X6 Y0\nG1 Z-0.1\nG1 X9\nG0 Z1\n\
                G0 X60 Y50\nG1 Z-0.1\nG1 X65\nG4 P0\nG0 Z25\n\
                M5\nG4 P1\nM2\n";
    let p = gcode::parse("f.ngc", text).unwrap();
    let out = optimize(&p, &opts()).unwrap();
    assert_eq!(out.kept, Kept::Nothing, "{:?}", out.note);
    assert!(out.after.air_length < out.before.air_length);
    // the cell that rises to the tool-change height stays last, the footer's dwell at Z25
    assert_eq!(out.order.last(), Some(&3));
    let tail: Vec<&str> = out.text.lines().rev().take(5).collect();
    assert_eq!(tail, ["M2", "G4 P1", "M5", "G0 Z25", "G4 P0"]);
}

#[test]
fn huge_coordinates_are_refused_by_optimize_and_import_alike() {
    let big = format!("1{}", "0".repeat(300));
    for (text, line) in [
        (format!("G21 G90\nG0 Z5\nG0 X{big}\nG1 Z-1 F100\n"), 3),
        (format!("G21 G90\nG0 Z5\nG92 X-{big}\nG1 Z-1 F100\n"), 3),
        (
            "G21 G91\nG0 Z5\nG0 X900000000\nG0 X900000000\nG1 Z-1 F100\n".into(),
            4,
        ),
        (
            format!("G21 G90\nG0 Z5\nG0 X0\nG1 Z-1 F0.{}1\n", "0".repeat(300)),
            4,
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let f = crate::common::write(dir.path(), "big.ngc", &text);
        let out = dir.path().join("o.ngc");
        let json = dir.path().join("o.json");
        for args in [
            vec![
                "optimize",
                crate::common::s(&f),
                "-o",
                crate::common::s(&out),
            ],
            vec![
                "import",
                crate::common::s(&f),
                "-o",
                crate::common::s(&json),
            ],
        ] {
            let o = crate::common::run(&args);
            let e = crate::common::stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
            assert!(e.contains(&format!("big.ngc:{line}:")), "{args:?}: {e}");
            assert!(!e.contains("NaN") && !e.contains("inf"), "{e}");
        }
    }
}

#[test]
fn inch_programs_say_their_figures_are_in_mm() {
    let f = crate::common::fixture_path("gcode/arcs_inch.ngc");
    let o = crate::common::run(&[
        "optimize",
        crate::common::s(&f),
        "--json",
        "--max-evals",
        "2000",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["units"], "mm");
    assert_eq!(v["program_units"], "inch");
    let o = crate::common::run(&["optimize", crate::common::s(&f), "--max-evals", "2000"]);
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(s.contains("the program is in inch (G20)"), "{s}");
}

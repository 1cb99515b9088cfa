//! G-code import, reordering, writing and verification on small self-written fixtures.

use cellseq_programs::gcode;
use cellseq_programs::optimize::gcode::{Options, optimize};
use proptest::prelude::*;

const FIXTURES: [&str; 3] = ["mill.ngc", "laser.gcode", "inch_plasma.ngc"];

fn fixture(name: &str) -> String {
    crate::common::fixture_text(&format!("gcode/{name}"))
}

#[test]
fn optimize_keeps_every_cut_and_never_adds_air() {
    for name in FIXTURES {
        let text = fixture(name);
        let p = gcode::parse(name, &text).unwrap();
        let out = optimize(&p, &Options::default()).unwrap();
        let mut sorted = out.order.clone();
        sorted.sort();
        assert_eq!(
            sorted,
            (0..p.layout.cells.len()).collect::<Vec<_>>(),
            "{name}"
        );
        assert!(
            out.after.air_length <= out.before.air_length + 1e-9,
            "{name}"
        );
        assert_eq!(out.after.tool_changes, out.before.tool_changes, "{name}");
        assert!(
            (out.after.cut_length - out.before.cut_length).abs() < 1e-6,
            "{name}"
        );
        // an independent re-check of the written text
        let v = gcode::verify_files(name, &text, "out", &out.text).unwrap();
        assert_eq!(v.cuts, out.cuts);
        assert!(out.cuts > 0);
    }
}

#[test]
fn mill_fixture_rules() {
    let text = fixture("mill.ngc");
    let p = gcode::parse("mill.ngc", &text).unwrap();
    assert_eq!(p.layout.blocks.len(), 2);
    // 7 milling cells, 5 holes
    assert_eq!(p.layout.cells.len(), 12);
    assert_eq!(p.layout.cells.iter().filter(|c| c.cycle).count(), 5);
    // the rules, in the instance of the milling group: inner square (line 23) before the
    // enclosing outer square (line 9), upper pass of the pocket (line 39) before the lower (43)
    let gs = gcode::groups(&p, false);
    let pl = gcode::plans(&p, false);
    let g = &gs[0];
    let (inst, dropped) = gcode::group_instance(&p, g, [0.0, 0.0, 5.0], 0.5, &pl);
    assert!(!dropped);
    let at = |line: usize| {
        g.iter()
            .position(|&c| p.program.lines[p.layout.cells[c].start].line == line)
            .unwrap()
    };
    assert!(inst.precedence.contains(&(at(23), at(9))));
    assert!(inst.precedence.contains(&(at(39), at(43))));
    // the solver's order follows them; here it is worse on lifts than the program's own
    // order, which is then kept (never worse): the rules are checked on the solver's order
    let out = optimize(&p, &Options::default()).unwrap();
    assert!(out.after.not_worse_than(&out.before));
    if out.kept == cellseq_programs::optimize::gcode::Kept::Whole {
        assert_eq!(out.text, text);
        return;
    }
    let pos = |line: usize| {
        out.order
            .iter()
            .position(|&c| p.program.lines[p.layout.cells[c].start].line == line)
            .unwrap()
    };
    // inner square (starts line 23) before the enclosing outer square (line 9)
    let first_line = |c: usize| p.program.lines[p.layout.cells[c].start].line;
    let outer = out.order.iter().position(|&c| first_line(c) == 9).unwrap();
    let inner = out.order.iter().position(|&c| first_line(c) == 23).unwrap();
    assert!(inner < outer, "inner contour must be cut first");
    // upper pass of the pocket (line 39) before the lower one (line 43)
    assert!(pos(39) < pos(43));
    // tool blocks stay in order: every T1 cell before every T2 cell
    let tools: Vec<u32> = out.order.iter().map(|&c| p.layout.cells[c].tool).collect();
    assert!(tools.windows(2).all(|w| w[0] <= w[1]), "{tools:?}");
}

#[test]
fn tampered_output_is_rejected() {
    let text = fixture("mill.ngc");
    let p = gcode::parse("mill.ngc", &text).unwrap();
    let out = optimize(&p, &Options::default()).unwrap();
    let bad = out.text.replacen("G1 X40 F600", "G1 X40.01 F600", 1);
    assert_ne!(bad, out.text);
    let e = gcode::verify_files("mill.ngc", &text, "bad.ngc", &bad).unwrap_err();
    assert!(e.to_string().contains("not equivalent"), "{e}");
    let dropped = out.text.replacen("G1 Y40\n", "", 1);
    assert!(gcode::verify_files("mill.ngc", &text, "bad.ngc", &dropped).is_err());
}

#[test]
fn unsupported_constructs_are_refused_with_line() {
    for (src, line, what) in [
        ("G21 G90\nG0 Z5\nG0 X#7\n", 3, "#7"),
        ("G21\no100 sub\n", 2, "O-word"),
        ("G21\nG33.1 Z-1 K1\n", 2, "G33.1"),
        ("G21\nG0 Z5 X0 Y0\nG1 Z-1 F100\nG2 X10 Y0 R2\n", 4, "radius"),
        (
            "G21\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG41 G1 X5\nG0 Z5\nG0 X9\nG1 Z-1\nG0 Z5\n",
            7,
            "compensation",
        ),
    ] {
        let e = gcode::parse("t.ngc", src).unwrap_err().to_string();
        assert!(e.contains(&format!("t.ngc:{line}:")), "{e}");
        assert!(e.contains(what), "{e}");
    }
}

#[test]
fn merge_tool_blocks_reduces_changes() {
    let src = "G21 G90\nT1 M6\nG0 Z5\nG0 X0 Y0\nG1 Z-1 F100\nG0 Z5\nT2 M6\nG0 X10 Y0\nG1 Z-1 F100\nG0 Z5\nT1 M6\nG0 X1 Y0\nG1 Z-1 F100\nG0 Z5\nM2\n";
    let p = gcode::parse("m.ngc", src).unwrap();
    let keep = optimize(&p, &Options::default()).unwrap();
    assert_eq!(keep.after.tool_changes, 3);
    let opts = Options {
        merge: true,
        ..Options::default()
    };
    let merged = optimize(&p, &opts).unwrap();
    assert_eq!(merged.after.tool_changes, 2);
    assert_eq!(merged.cuts, keep.cuts);
}

#[test]
fn import_gives_valid_instance() {
    let p = gcode::parse("mill.ngc", &fixture("mill.ngc")).unwrap();
    let inst = gcode::import(&p, false, 0.5, None).unwrap();
    cellseq::validate::validate(&inst, "mill.ngc").unwrap();
    assert_eq!(inst.n(), 12);
    // tool block order: each of the 7 T1 cells before each of the 5 T2 holes (the holes of
    // different cycles are groups of their own, chained)
    let mut reach = vec![vec![false; 12]; 12];
    for &(a, b) in &inst.precedence {
        reach[a][b] = true;
    }
    for k in 0..12 {
        for i in 0..12 {
            for j in 0..12 {
                reach[i][j] |= reach[i][k] && reach[k][j];
            }
        }
    }
    let t1: Vec<usize> = (0..12).filter(|&c| inst.cells[c].tool == "T1").collect();
    let t2: Vec<usize> = (0..12).filter(|&c| inst.cells[c].tool == "T2").collect();
    assert_eq!((t1.len(), t2.len()), (7, 5));
    assert!(t1.iter().all(|&a| t2.iter().all(|&b| reach[a][b])));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(p) = gcode::parse("f.ngc", &text) {
            let _ = optimize(&p, &Options::default());
        }
    }

    #[test]
    fn random_programs_never_panic_and_verify(
        toks in proptest::collection::vec(
            prop_oneof![
                Just("G0"), Just("G1"), Just("G2"), Just("G3"), Just("G90"), Just("G91"),
                Just("G20"), Just("G21"), Just("G81"), Just("G80"), Just("G98"), Just("G99"),
                Just("M3"), Just("M5"), Just("M6"), Just("T2"), Just("F100"), Just("\n"),
                Just("X1"), Just("Y-2"), Just("Z-1"), Just("Z5"), Just("R1"), Just("I1"),
                Just("J0.5"), Just("(c)"), Just(";x"), Just("S500"), Just("G17"), Just("G18"),
                Just("P2"), Just("X10.5"), Just("Y3"), Just("G28"), Just("G54"), Just("G55")
            ],
            0..120)
    ) {
        let text = toks.join(" ");
        if let Ok(p) = gcode::parse("f.ngc", &text) {
            // whatever the solver does, the written program must verify or be refused
            let _ = optimize(&p, &Options::default());
        }
    }
}

/// The modal words of a program (G and M codes, F, S, H), as written.
fn modal_words(text: &str) -> std::collections::BTreeSet<String> {
    let mut v = std::collections::BTreeSet::new();
    for l in text.lines() {
        let w = cellseq_programs::gcode::lex::tokenize(l, &mut Default::default()).unwrap();
        for (c, x) in w.words {
            let motion = c == 'G' && cellseq_programs::gcode::cells::is_motion_g(x);
            if matches!(c, 'G' | 'M' | 'H') && !motion {
                v.insert(format!("{c}{x}"));
            }
        }
    }
    v
}

#[test]
fn operator_state_stays_unset() {
    // no spindle, coolant, length offset, work offset or plane in the program: the output
    // must not set any of them, and must link at the program's own Z2, not its final Z30
    let text = fixture("operator_state.ngc");
    let p = gcode::parse("operator_state.ngc", &text).unwrap();
    let out = optimize(&p, &Options::default()).unwrap();
    assert!(!out.kept_original(), "{:?}", out.note);
    assert_ne!(out.text, text);
    assert!(
        modal_words(&out.text).is_subset(&modal_words(&text)),
        "{:?} vs {:?}",
        modal_words(&out.text),
        modal_words(&text)
    );
    for l in out.text.lines().filter(|l| l.starts_with("G0 Z")) {
        let z: f64 = l[4..].trim().parse().unwrap();
        assert!(z <= 2.0 || l == "G0 Z30", "{l}");
    }
    assert!(out.after.not_worse_than(&out.before));
    assert!(out.after.air_length < out.before.air_length);
}

#[test]
fn state_is_reestablished_only_where_the_order_changed_it() {
    // two spindle speeds and coolant switched on before the third cell: the cells before it
    // never run with coolant, the speeds are restored where needed, nothing else is added
    let src = "G21 G90\nS1000 M3\nG0 Z5\nG0 X50 Y0\nG1 Z-1 F100\nG1 X60\nG0 Z5\nG0 X0 Y0\nG1 Z-1\nG1 X10\nG0 Z5\nM8\nG0 X52 Y0\nG1 Z-1\nG1 X58\nG0 Z5\nS2000\nG0 X2 Y0\nG1 Z-1\nG1 X8\nG0 Z5\nG0 X54 Y1\nG1 Z-1\nG1 X56\nG0 Z5\nM5 M9\nM2\n";
    let p = gcode::parse("s.ngc", src).unwrap();
    let first_m8 = p.layout.cells.iter().position(|c| c.state.flood).unwrap();
    let out = optimize(&p, &Options::default()).unwrap();
    assert!(modal_words(&out.text).is_subset(&modal_words(src)));
    let pos = |c: usize| out.order.iter().position(|&x| x == c).unwrap();
    for c in 0..first_m8 {
        assert!(pos(c) < pos(first_m8), "{:?}", out.order);
    }
    // tampering with the state at a cut is caught, even with every move unchanged
    let q = out.text.replace("S2000", "S2500");
    let e = gcode::verify_files("s.ngc", src, "bad", &q).unwrap_err();
    assert!(e.to_string().contains("not equivalent"), "{e}");
    let q = out.text.replacen("M8\n", "", 1);
    assert!(gcode::verify_files("s.ngc", src, "bad", &q).is_err());
}

#[test]
fn new_motion_is_caught() {
    let text = fixture("operator_state.ngc");
    // a rapid across below the program's lowest travel height
    let low = text.replacen("G0 X0 Y0\n", "G0 Z0.5\nG0 X0 Y0\nG0 Z2\n", 1);
    let e = gcode::verify_files("o.ngc", &text, "low", &low).unwrap_err();
    assert!(e.to_string().contains("lower than the original"), "{e}");
    // a move before the program's own first motion
    let early = text.replacen("G21 G90\n", "G21 G90\nG0 X0 Y0\n", 1);
    let e = gcode::verify_files("o.ngc", &text, "early", &early).unwrap_err();
    assert!(e.to_string().contains("before the first cut"), "{e}");
    // a dwell or a pause more or less
    let dwell = text.replacen("G0 Z30\n", "G4 P1\nG0 Z30\n", 1);
    assert!(gcode::verify_files("o.ngc", &text, "dwell", &dwell).is_err());
}

#[test]
fn as_given_writes_the_program_as_it_is() {
    for name in [
        "mill.ngc",
        "laser.gcode",
        "operator_state.ngc",
        "silkscreen_z0.ngc",
        "grbl_dialect.nc",
        "mill_feed_retract.ngc",
    ] {
        let text = fixture(name);
        let p = gcode::parse(name, &text).unwrap();
        let out = optimize(
            &p,
            &Options {
                solver: cellseq::SolverKind::AsGiven,
                ..Options::default()
            },
        )
        .unwrap();
        assert_eq!(out.text, text, "{name}");
        assert_eq!(out.after, out.before, "{name}");
    }
}

#[test]
fn silkscreen_at_z0_is_sequenced_by_strokes() {
    // cuts at the travel height: cells are runs of feed moves, not single moves, and the
    // zero-length feed lines stay zero-length wherever the link ends
    let text = fixture("silkscreen_z0.ngc");
    let p = gcode::parse("silkscreen_z0.ngc", &text).unwrap();
    assert_eq!(p.layout.cells.len(), 4);
    let out = optimize(&p, &Options::default()).unwrap();
    assert!(out.after.air_length < out.before.air_length);
    assert_eq!(out.reversed.iter().filter(|&&r| r).count(), 0);
}

#[test]
fn grbl_dialect_is_carried_through_in_place() {
    let text = fixture("grbl_dialect.nc");
    let p = gcode::parse("grbl_dialect.nc", &text).unwrap();
    let out = optimize(&p, &Options::default()).unwrap();
    let keep = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| l.starts_with('$') || l.contains("G28") || l.contains("G53"))
            .map(String::from)
            .collect()
    };
    assert_eq!(keep(&out.text), keep(&text));
    // the two operations stay on their side of the G28 between them
    let lines: Vec<&str> = out.text.lines().collect();
    let g28 = lines.iter().rposition(|l| l.starts_with("G28")).unwrap();
    let after: Vec<&str> = out.text.lines().skip(g28).collect();
    assert!(after.iter().any(|l| l.contains("X20 Y20")));
    assert!(
        !after
            .iter()
            .any(|l| l.contains("X40") || l.contains("X0 Y0"))
    );
    assert!(out.after.air_length < out.before.air_length);
}

#[test]
fn unicode_whitespace_is_written_as_ascii() {
    let src = "G21 G90\u{a0}\nG0 Z5\nG0\u{2028}X0 Y0\nG1 Z-1 F100\nG1 X10\u{85}\nG0 Z5 (caf\u{e9}\u{a0})\nG0 X20 Y0\nG1 Z-1\nG1 X30\nG0 Z5\nM2\n";
    let p = gcode::parse("u.ngc", src).unwrap();
    let out = optimize(&p, &Options::default()).unwrap();
    let code: String = out
        .text
        .lines()
        .map(|l| l.split('(').next().unwrap())
        .collect();
    assert!(code.is_ascii(), "{}", out.text);
    assert!(out.text.contains("(caf\u{e9}\u{a0})"));
    let e = gcode::parse("u.ngc", "G21\nG1 X\u{e9}1\n").unwrap_err();
    assert!(e.to_string().contains("u.ngc:2:"), "{e}");
    assert!(e.to_string().contains("U+00E9"), "{e}");
}

#[test]
fn arc_tolerance_follows_linuxcnc() {
    // radii 5 and 5.02 (0.4 %, 0.02 mm): LinuxCNC runs it; 20 and 20.08 (0.4 %, 0.08 mm): not
    let ok = "G21 G90 G17\nG0 X5 Y0 Z1\nG1 Z-1 F100\nG3 X0 Y5.02 I-5 J0\nG0 Z1\nM2\n";
    gcode::parse("a.ngc", ok).unwrap();
    let bad = "G21 G90 G17\nG0 X20 Y0 Z1\nG1 Z-1 F100\nG3 X0 Y20.08 I-20 J0\nG0 Z1\nM2\n";
    let e = gcode::parse("a.ngc", bad).unwrap_err();
    assert!(e.to_string().contains("a.ngc:4:"), "{e}");
    // inch: 0.002 inch apart is accepted at radius 1
    let inch = "G20 G90 G17\nG0 X1 Y0 Z0.1\nG1 Z-0.1 F10\nG3 X0 Y1.002 I-1 J0\nG0 Z0.1\nM2\n";
    gcode::parse("i.ngc", inch).unwrap();
}

#[test]
fn never_worse_on_any_figure() {
    for name in [
        "mill.ngc",
        "laser.gcode",
        "inch_plasma.ngc",
        "operator_state.ngc",
        "silkscreen_z0.ngc",
        "grbl_dialect.nc",
        "mill_feed_retract.ngc",
        "laser_zigzag.gcode",
        "arcs_inch.ngc",
    ] {
        let text = fixture(name);
        let p = gcode::parse(name, &text).unwrap();
        let out = optimize(&p, &Options::default()).unwrap();
        assert!(
            out.after.not_worse_than(&out.before),
            "{name}: {:?} vs {:?}",
            out.after,
            out.before
        );
        if out.kept == cellseq_programs::optimize::gcode::Kept::Whole {
            assert_eq!(out.text, text, "{name}");
        }
    }
}

#[test]
fn gcode_is_never_written_into_an_svg() {
    let dir = tempfile::tempdir().unwrap();
    let o = dir.path().join("x.svg");
    let st = crate::common::cellseq()
        .args(["optimize", "tests/fixtures/gcode/mill.ngc", "-o"])
        .arg(&o)
        .current_dir(crate::common::root())
        .output()
        .unwrap();
    assert!(!st.status.success());
    assert!(String::from_utf8_lossy(&st.stderr).contains(".svg"));
    assert!(!o.exists());
}

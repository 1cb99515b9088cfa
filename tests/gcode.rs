//! G-code import, reordering, writing and verification on small self-written fixtures.

use cellseq::io::gcode::{self, Options};
use proptest::prelude::*;

const FIXTURES: [&str; 3] = ["mill.ngc", "laser.gcode", "inch_plasma.ngc"];

fn fixture(name: &str) -> String {
    std::fs::read_to_string(format!(
        "{}/tests/fixtures/gcode/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

#[test]
fn optimize_keeps_every_cut_and_never_adds_air() {
    for name in FIXTURES {
        let text = fixture(name);
        let p = gcode::parse(name, &text).unwrap();
        let out = gcode::optimize(&p, &Options::default()).unwrap();
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
    let out = gcode::optimize(&p, &Options::default()).unwrap();
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
    let out = gcode::optimize(&p, &Options::default()).unwrap();
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
        ("G21 G90\nG0 Z5\n#1 = 3\n", 3, "#"),
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
    let keep = gcode::optimize(&p, &Options::default()).unwrap();
    assert_eq!(keep.after.tool_changes, 3);
    let opts = Options {
        merge: true,
        ..Options::default()
    };
    let merged = gcode::optimize(&p, &opts).unwrap();
    assert_eq!(merged.after.tool_changes, 2);
    assert_eq!(merged.cuts, keep.cuts);
}

#[test]
fn import_gives_valid_instance() {
    let p = gcode::parse("mill.ngc", &fixture("mill.ngc")).unwrap();
    let inst = gcode::import(&p, false, 0.5, None).unwrap();
    cellseq::validate::validate(&inst, "mill.ngc").unwrap();
    assert_eq!(inst.n(), 12);
    // tool block order: 7 T1 cells × 5 T2 holes
    assert!(inst.precedence.len() >= 35);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 300, .. ProptestConfig::default() })]
    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        if let Ok(p) = gcode::parse("f.ngc", &text) {
            let _ = gcode::optimize(&p, &Options::default());
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
            let _ = gcode::optimize(&p, &Options::default());
        }
    }
}

//! Reversal of G-code cells: air saved on a laser program, arcs (IJK and R, both directions,
//! full circle, inch) reversed and verified, milling off by default and refused per cell.

use cellseq_programs::gcode::{self, interp::CutKind};
use cellseq_programs::optimize::gcode::{Options, optimize};

fn fixture(name: &str) -> String {
    crate::common::fixture_text(&format!("gcode/{name}"))
}

fn opts(reversible: Option<bool>) -> Options {
    Options {
        reversible,
        ..Options::default()
    }
}

#[test]
fn laser_reversal_reduces_air_and_verifies() {
    let text = fixture("laser_zigzag.gcode");
    let p = gcode::parse("laser_zigzag.gcode", &text).unwrap();
    let on = optimize(&p, &opts(None)).unwrap(); // 2-D: on by default
    let off = optimize(&p, &opts(Some(false))).unwrap();
    assert_eq!(off.reversible_cells, 0);
    assert!(off.reversed.iter().all(|&r| !r));
    assert!(on.reversible_cells >= 3);
    assert!(on.reversed.iter().any(|&r| r));
    assert!(
        on.after.air_length < off.after.air_length - 10.0,
        "reversal {} vs none {}",
        on.after.air_length,
        off.after.air_length
    );
    assert_eq!(on.cuts, off.cuts);
    // verify-gcode accepts the reversed program, and the moves really were turned round
    let v = gcode::verify_files("laser_zigzag.gcode", &text, "out.gcode", &on.text).unwrap();
    assert_eq!(v.cuts, on.cuts);
    assert!((v.after.air_length - on.after.air_length).abs() < 1e-9);
    let strict = gcode::verify_with(&p, "out.gcode", &on.text, false);
    assert!(
        strict.is_err(),
        "reversed program matched in the original direction"
    );
}

/// Every reversible cell cut backwards; returns the program text.
fn all_reversed(p: &gcode::Parsed) -> String {
    let plans = gcode::plans(p, true);
    let order: Vec<usize> = (0..p.layout.cells.len()).collect();
    gcode::write::write_checked(&p.program, &p.layout, &order, &plans, false).unwrap()
}

fn arcs(prog: &gcode::interp::Program) -> (usize, usize) {
    let mut cw = 0;
    let mut ccw = 0;
    for c in prog.lines.iter().flat_map(|l| l.cuts.iter()) {
        if let CutKind::Arc { cw: w, .. } = c.kind {
            if w {
                cw += 1;
            } else {
                ccw += 1;
            }
        }
    }
    (cw, ccw)
}

#[test]
fn arcs_round_trip_reversed() {
    for name in ["arcs_inch.ngc", "laser_zigzag.gcode", "inch_plasma.ngc"] {
        let text = fixture(name);
        let p = gcode::parse(name, &text).unwrap();
        let plans = gcode::plans(&p, true);
        // inch_plasma has a pierce dwell; laser_zigzag's last row is cut in G91, and a
        // reversed row is written in G90: the distance mode at its cuts would differ
        assert!(
            plans.iter().all(Option::is_some) || name != "arcs_inch.ngc",
            "{name}: {plans:?}"
        );
        assert!(plans.iter().any(Option::is_some), "{name}");
        let rev = all_reversed(&p);
        // same moves undirected, not directed
        gcode::verify_with(&p, "rev", &rev, true).unwrap_or_else(|e| panic!("{name}: {e}\n{rev}"));
        assert!(gcode::verify_with(&p, "rev", &rev, false).is_err());
        let q = gcode::parse("rev", &rev).unwrap();
        // every arc of a reversed cell turns the other way
        if plans.iter().all(Option::is_some) {
            let (cw, ccw) = arcs(&p.program);
            assert_eq!(arcs(&q.program), (ccw, cw), "{name}");
        }
        // reversing twice gives the original moves in their original direction
        let back = all_reversed(&q);
        gcode::verify_with(&p, "back", &back, false)
            .unwrap_or_else(|e| panic!("{name}: {e}\n{back}"));
    }
}

#[test]
fn arc_centres_and_feeds_kept() {
    let text = fixture("arcs_inch.ngc");
    let p = gcode::parse("arcs_inch.ngc", &text).unwrap();
    let q = gcode::parse("rev", &all_reversed(&p)).unwrap();
    let cuts = |prog: &gcode::interp::Program| {
        let mut v: Vec<_> = prog
            .lines
            .iter()
            .flat_map(|l| l.cuts.iter())
            .map(|c| gcode::verify::undirected(c, 1e-3))
            .collect();
        v.sort_by(|a, b| {
            (a.from, a.to)
                .partial_cmp(&(b.from, b.to))
                .unwrap_or(std::cmp::Ordering::Equal)
        });
        v
    };
    let (a, b) = (cuts(&p.program), cuts(&q.program));
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert!((x.feed - y.feed).abs() < 1e-9 && (x.speed - y.speed).abs() < 1e-9);
        match (x.kind, y.kind) {
            (
                CutKind::Arc {
                    center: c1, cw: w1, ..
                },
                CutKind::Arc {
                    center: c2, cw: w2, ..
                },
            ) => {
                assert_eq!(w1, w2);
                assert!(c1.iter().zip(&c2).all(|(u, v)| (u - v).abs() < 1e-4));
            }
            (CutKind::Line, CutKind::Line) => {}
            k => panic!("kinds differ: {k:?}"),
        }
    }
}

#[test]
fn milling_not_reversed_by_default_and_refused_per_cell() {
    let text = fixture("mill_feed_retract.ngc");
    let p = gcode::parse("mill_feed_retract.ngc", &text).unwrap();
    let def = optimize(&p, &opts(None)).unwrap();
    assert_eq!(def.reversible_cells, 0);
    assert!(def.reversed.iter().all(|&r| !r));
    let on = optimize(&p, &opts(Some(true))).unwrap();
    // three single-depth slots plunged and retracted at feed; the two-depth cell and the
    // rapid-retract cell stay one-mode
    assert_eq!(on.reversible_cells, 3);
    let plans = gcode::plans(&p, true);
    assert!(plans[3].is_none() && plans[4].is_none());
    assert!(on.after.air_length <= def.after.air_length + 1e-9);
    gcode::verify_files("mill_feed_retract.ngc", &text, "out", &on.text).unwrap();
    // the usual G1 plunge + G0 retract program has no reversible cell
    let mill = fixture("mill.ngc");
    let m = gcode::parse("mill.ngc", &mill).unwrap();
    assert_eq!(optimize(&m, &opts(Some(true))).unwrap().reversible_cells, 0);
}

#[test]
fn instance_cells_get_two_modes() {
    let text = fixture("laser_zigzag.gcode");
    let p = gcode::parse("laser_zigzag.gcode", &text).unwrap();
    let inst = gcode::import(&p, false, 0.5, None).unwrap();
    cellseq::validate::validate(&inst, "laser_zigzag.gcode").unwrap();
    // the last row is cut in G91: reversed moves would be absolute, so it keeps one mode
    let rev: Vec<_> = inst.cells.iter().filter(|c| c.reversible).collect();
    assert_eq!(rev.len(), inst.cells.len() - 1);
    for c in rev {
        assert_eq!(c.modes.len(), 2);
        assert_eq!(c.modes[1], c.modes[0].reversed());
    }
    let off = gcode::import(&p, false, 0.5, Some(false)).unwrap();
    assert!(
        off.cells
            .iter()
            .all(|c| !c.reversible && c.modes.len() == 1)
    );
}

mod props {
    use super::*;
    use proptest::prelude::*;

    /// A 2-D program of `cells` runs of lines and arcs (IJ or R, both directions).
    fn program(moves: &[(u8, f64, f64, f64)]) -> String {
        let mut s = String::from("G21 G90\nF600\n");
        let (mut x, mut y) = (0.0f64, 0.0f64);
        for (k, &(kind, a, b, c)) in moves.iter().enumerate() {
            if k % 3 == 0 {
                x = a * 3.0;
                y = b * 3.0;
                s.push_str(&format!("M5\nG0 X{x:.4} Y{y:.4}\nM3 S{}\n", 100 + k));
            }
            match kind % 3 {
                0 => {
                    x += a;
                    y += b;
                    s.push_str(&format!("G1 X{x:.4} Y{y:.4} F{}\n", 500 + 10 * (k % 4)));
                }
                _ => {
                    // centre at (x + a, y); end on the circle at angle c from the start
                    let (cx, cy) = (x + a.abs().max(0.5), y);
                    let r = cx - x;
                    let t = std::f64::consts::PI + c;
                    let (ex, ey) = (cx + r * t.cos(), cy + r * t.sin());
                    let g = if kind % 2 == 0 { 2 } else { 3 };
                    if kind % 3 == 1 {
                        s.push_str(&format!("G{g} X{ex:.4} Y{ey:.4} I{:.4} J0\n", cx - x));
                    } else {
                        s.push_str(&format!("G{g} X{ex:.4} Y{ey:.4} R{:.4}\n", r));
                    }
                    x = (ex * 1e4).round() / 1e4;
                    y = (ey * 1e4).round() / 1e4;
                }
            }
        }
        s.push_str("M5\nM2\n");
        s
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]
        #[test]
        fn reversed_programs_verify(moves in proptest::collection::vec(
            (0u8..6, -20.0f64..20.0, -20.0f64..20.0, 0.3f64..2.5), 1..12)) {
            let text = program(&moves);
            let p = gcode::parse("p.gcode", &text).unwrap();
            let rev = all_reversed(&p);
            gcode::verify_with(&p, "rev", &rev, true)
                .map_err(|e| TestCaseError::fail(format!("{e}\n{text}\n{rev}")))?;
            let q = gcode::parse("rev", &rev).unwrap();
            let back = all_reversed(&q);
            gcode::verify_with(&p, "back", &back, false)
                .map_err(|e| TestCaseError::fail(format!("{e}\n{text}\n{back}")))?;
            let out = optimize(&p, &opts(None)).unwrap();
            let off = optimize(&p, &opts(Some(false))).unwrap();
            prop_assert_eq!(out.cuts, off.cuts);
        }
    }
}

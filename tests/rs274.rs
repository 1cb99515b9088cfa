//! Real-interpreter check: LinuxCNC's `rs274` must read every program cellseq writes, and the
//! feed moves it reports (STRAIGHT_FEED / ARC_FEED) must equal the original's as a multiset.
//! Skipped, with a notice, when `rs274` (Debian package `linuxcnc-uspace`) is not installed.

use cellseq::io::gcode::{self, Options};
use std::process::Command;

static RS274: std::sync::Mutex<()> = std::sync::Mutex::new(());

fn rs274_available() -> bool {
    Command::new("sh")
        .args(["-c", "command -v rs274"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// A feed move in a direction-free form: `[kind, start xyz, end xyz, (centre x, y, rotation)]`
/// with the lexicographically smaller end first (on a 1e-3 grid); an arc taken the other way
/// round has its rotation negated, a full circle counts as counter-clockwise. So a move cut
/// backwards by cellseq's reversal compares equal to the original.
fn canonical(kind: f64, s: [f64; 3], e: [f64; 3], arc: Option<[f64; 3]>) -> Vec<f64> {
    let q = |p: [f64; 3]| p.map(|v| (v * 1000.0).round() as i64);
    let (mut a, mut b, mut arc) = (s, e, arc);
    if q(s) > q(e) {
        (a, b) = (e, s);
        if let Some(x) = &mut arc {
            x[2] = -x[2];
        }
    } else if q(s) == q(e)
        && let Some(x) = &mut arc
    {
        x[2] = x[2].abs();
    }
    let mut v = vec![kind];
    v.extend(a);
    v.extend(b);
    if let Some(x) = arc {
        v.extend(x);
    }
    v
}

/// Runs rs274 on a program; returns the feed moves (STRAIGHT_FEED / ARC_FEED, XY plane) in
/// the direction-free form of [`canonical`], sorted.
fn feeds(dir: &std::path::Path, name: &str, text: &str) -> Vec<Vec<f64>> {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    // rs274 runs are serialized and run in the temp dir: concurrent runs from one working
    // directory interfere (its parameter file)
    let out = {
        let _guard = RS274.lock().unwrap_or_else(|e| e.into_inner());
        Command::new("rs274")
            .arg("-g")
            .arg(&path)
            .current_dir(dir)
            .output()
            .unwrap()
    };
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        out.status.success(),
        "rs274 failed on {name}: {stderr}\n{stdout}"
    );
    for l in stdout.lines().chain(stderr.lines()) {
        assert!(
            !l.to_ascii_lowercase().contains("error"),
            "rs274 reported an error on {name}: {l}"
        );
        assert!(
            !(l.contains("CANON_PLANE_XZ") || l.contains("CANON_PLANE_YZ")),
            "{name}: only XY-plane arcs are compared here: {l}"
        );
    }
    let mut pos = [0.0f64; 3];
    let mut v: Vec<Vec<f64>> = Vec::new();
    for l in stdout.lines() {
        let Some((call, k)) = ["STRAIGHT_TRAVERSE(", "STRAIGHT_FEED(", "ARC_FEED("]
            .iter()
            .find_map(|c| l.find(c).map(|k| (*c, k)))
        else {
            continue;
        };
        let args = &l[k..];
        let (Some(a), Some(b)) = (args.find('('), args.rfind(')')) else {
            continue;
        };
        let n: Vec<f64> = args[a + 1..b]
            .split(',')
            .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN))
            .collect();
        match call {
            "STRAIGHT_TRAVERSE(" => pos = [n[0], n[1], n[2]],
            "STRAIGHT_FEED(" => {
                let e = [n[0], n[1], n[2]];
                v.push(canonical(0.0, pos, e, None));
                pos = e;
            }
            _ => {
                let e = [n[0], n[1], n[5]];
                v.push(canonical(1.0, pos, e, Some([n[2], n[3], n[4]])));
                pos = e;
            }
        }
    }
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    v
}

fn same_feeds(name: &str, a: &[Vec<f64>], b: &[Vec<f64>]) {
    assert!(!a.is_empty());
    assert_eq!(a.len(), b.len(), "{name}: feed move counts differ");
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.len(), y.len(), "{name}: {x:?} vs {y:?}");
        for (u, w) in x.iter().zip(y) {
            assert!(
                (u - w).abs() <= 2e-3,
                "{name}: feed moves differ: {x:?} vs {y:?}"
            );
        }
    }
}

fn fixture(name: &str) -> String {
    std::fs::read_to_string(format!(
        "{}/tests/fixtures/gcode/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

#[test]
fn rs274_accepts_written_programs_with_same_feeds() {
    if !rs274_available() {
        println!(
            "NOTICE: rs274 not on PATH (apt-get install linuxcnc-uspace); real-interpreter test skipped"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for name in ["mill.ngc", "laser.gcode", "inch_plasma.ngc"] {
        let text = std::fs::read_to_string(format!(
            "{}/tests/fixtures/gcode/{name}",
            env!("CARGO_MANIFEST_DIR")
        ))
        .unwrap();
        let p = gcode::parse(name, &text).unwrap();
        for merge in [false, true] {
            let out = gcode::optimize(
                &p,
                &Options {
                    merge,
                    ..Options::default()
                },
            )
            .unwrap();
            let a = feeds(dir.path(), &format!("orig_{name}"), &text);
            let b = feeds(dir.path(), &format!("out_{name}"), &out.text);
            same_feeds(name, &a, &b);
        }
    }
}

/// Reversed outputs: the optimizer's own (reversal on) and programs with every reversible
/// cell cut backwards.
#[test]
fn rs274_accepts_reversed_programs_with_same_feeds() {
    if !rs274_available() {
        println!(
            "NOTICE: rs274 not on PATH (apt-get install linuxcnc-uspace); real-interpreter test skipped"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    for name in [
        "laser_zigzag.gcode",
        "arcs_inch.ngc",
        "mill_feed_retract.ngc",
        "inch_plasma.ngc",
    ] {
        let text = fixture(name);
        let p = gcode::parse(name, &text).unwrap();
        let out = gcode::optimize(
            &p,
            &Options {
                reversible: Some(true),
                ..Options::default()
            },
        )
        .unwrap();
        let a = feeds(dir.path(), &format!("orig_{name}"), &text);
        let b = feeds(dir.path(), &format!("opt_{name}"), &out.text);
        same_feeds(name, &a, &b);
        let plans = gcode::plans(&p, true);
        assert!(
            plans.iter().any(Option::is_some),
            "{name}: nothing reversible"
        );
        let order: Vec<usize> = (0..p.layout.cells.len()).collect();
        let all = gcode::write::write(&p.program, &p.layout, &order, &plans, false);
        let c = feeds(dir.path(), &format!("rev_{name}"), &all);
        same_feeds(name, &a, &c);
    }
}

//! Real-interpreter check: LinuxCNC's `rs274` must read every program cellseq writes, and the
//! feed moves it reports (STRAIGHT_FEED / ARC_FEED) must equal the original's as a multiset.
//! Skipped, with a notice, when `rs274` (Debian package `linuxcnc-uspace`) is not installed.

use cellseq::io::gcode::{self, Options};
use std::process::Command;

fn rs274_available() -> bool {
    Command::new("sh")
        .args(["-c", "command -v rs274"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false)
}

/// Runs rs274 on a program; returns the feed canon calls (numbers only), sorted.
fn feeds(dir: &std::path::Path, name: &str, text: &str) -> Vec<Vec<f64>> {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let out = Command::new("rs274").arg("-g").arg(&path).output().unwrap();
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
    }
    let mut v: Vec<Vec<f64>> = stdout
        .lines()
        .filter_map(|l| {
            let k = l
                .find("STRAIGHT_FEED(")
                .map(|k| (k, 0.0))
                .or(l.find("ARC_FEED(").map(|k| (k, 1.0)))?;
            let args = &l[k.0..];
            let inner = &args[args.find('(')? + 1..args.rfind(')')?];
            let mut nums: Vec<f64> = vec![k.1];
            nums.extend(
                inner
                    .split(',')
                    .map(|s| s.trim().parse::<f64>().unwrap_or(f64::NAN)),
            );
            Some(nums)
        })
        .collect();
    v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
    v
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
            assert!(!a.is_empty());
            assert_eq!(a.len(), b.len(), "{name}: feed move counts differ");
            for (x, y) in a.iter().zip(&b) {
                assert_eq!(x.len(), y.len());
                for (u, w) in x.iter().zip(y) {
                    assert!(
                        (u - w).abs() <= 2e-3,
                        "{name}: feed moves differ: {x:?} vs {y:?}"
                    );
                }
            }
        }
    }
}

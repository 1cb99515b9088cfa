//! The command line refuses bad input with one clear line naming the file and the problem,
//! a non-zero exit, and never a panic.

use std::path::{Path, PathBuf};
use std::process::Output;

use crate::common::cellseq as bin;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

/// Asserts failure with every `needle` in stderr and no panic.
fn fails_with(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure, stderr: {err}");
    assert!(!err.contains("panicked"), "panic: {err}");
    assert!(!err.contains("RUST_BACKTRACE"), "backtrace hint: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks '{n}': {err}");
    }
    assert_eq!(err.trim().lines().count(), 1, "one line expected: {err}");
}

const SOP: &str = "NAME: t\nTYPE: SOP\nDIMENSION: 3\nEDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n3\n0 1 1000000\n-1 0 2\n-1 -1 0\nEOF\n";

fn geo(cells: &str, precedence: &str) -> String {
    format!(
        r#"{{"format":"cellseq-instance/1","name":"t","tools":[{{"id":"T1","diameter":6}}],
"cells":[{cells}],"precedence":[{precedence}]}}"#
    )
}

const CELL_A: &str = r#"{"id":"a","tool":"T1","modes":[{"entry":[0,0,-1],"exit":[1,0,-1]}]}"#;
const CELL_B: &str = r#"{"id":"b","tool":"T1","modes":[{"entry":[5,0,-1],"exit":[6,0,-1]}]}"#;

#[test]
fn good_files_work() {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "ok.sop", SOP);
    let out = run(&["validate", p.to_str().unwrap()]);
    assert!(out.status.success());
    assert_eq!(String::from_utf8_lossy(&out.stdout).trim(), "ok");
    let out = run(&["solve", p.to_str().unwrap(), "--solver", "exact", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for k in [
        "instance",
        "solver",
        "seed",
        "feasible",
        "cost",
        "air_length",
        "cut_length",
        "lifts",
        "tool_changes",
        "machining_time",
        "best_known",
        "gap_percent",
        "elapsed_s",
        "sequence",
    ] {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    assert_eq!(v["cost"], 3.0);
    assert_eq!(v["sequence"][0]["cell"], "1");
    let g = write(
        d.path(),
        "g.json",
        &geo(&format!("{CELL_A},{CELL_B}"), r#"["b","a"]"#),
    );
    let sol = d.path().join("s.json");
    let out = run(&["solve", g.to_str().unwrap(), "--out", sol.to_str().unwrap()]);
    assert!(out.status.success());
    let out = run(&["eval", g.to_str().unwrap(), sol.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn malformed_text_files_are_refused_with_file_and_line() {
    let d = tempfile::tempdir().unwrap();
    let cases = [
        ("empty.sop", "", "empty"),
        ("trunc.sop", &SOP[..SOP.len() - 20], "ends early"),
        (
            "dim.sop",
            &SOP.replace("DIMENSION: 3", "DIMENSION: 4"),
            "dimension",
        ),
        ("tok.sop", &SOP.replace("-1 0 2", "-1 x 2"), "'x'"),
        ("nan.sop", &SOP.replace("-1 0 2", "-1 NaN 2"), "'NaN'"),
        (
            "extra.sop",
            &SOP.replace("-1 -1 0\n", "-1 -1 0 7\n"),
            "unexpected token",
        ),
    ];
    for (name, text, needle) in cases {
        let p = write(d.path(), name, text);
        let out = run(&["validate", p.to_str().unwrap()]);
        fails_with(&out, &[name, needle]);
    }
    let p = write(d.path(), "tok.sop", &SOP.replace("-1 0 2", "-1 x 2"));
    fails_with(&run(&["info", p.to_str().unwrap()]), &["tok.sop:9:"]);
}

#[test]
fn invalid_instances_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let nan_cell = r#"{"id":"n","tool":"T1","modes":[{"entry":[0,NaN,-1],"exit":[1,0,-1]}]}"#;
    let inf_cell = r#"{"id":"n","tool":"T1","modes":[{"entry":[0,1e999,-1],"exit":[1,0,-1]}]}"#;
    let cases = [
        ("nan.json", geo(nan_cell, ""), "nan.json:"),
        ("inf.json", geo(inf_cell, ""), "inf.json:"),
        (
            "dup.json",
            geo(&format!("{CELL_A},{CELL_A}"), ""),
            "duplicate cell id 'a'",
        ),
        (
            "unk.json",
            geo(CELL_A, r#"["a","zz"]"#),
            "unknown cell 'zz'",
        ),
        (
            "cyc.json",
            geo(&format!("{CELL_A},{CELL_B}"), r#"["a","b"],["b","a"]"#),
            "cycle",
        ),
        (
            "nomode.json",
            geo(r#"{"id":"a","tool":"T1","modes":[]}"#, ""),
            "no modes",
        ),
        (
            "tool.json",
            geo(&CELL_A.replace("T1", "T9"), ""),
            "unknown tool 'T9'",
        ),
        (
            "trunc.json",
            geo(CELL_A, "")[..40].to_string(),
            "trunc.json:",
        ),
    ];
    for (name, text, needle) in cases {
        let p = write(d.path(), name, &text);
        fails_with(&run(&["validate", p.to_str().unwrap()]), &[needle]);
    }
    let p = write(
        d.path(),
        "cyc.json",
        &geo(&format!("{CELL_A},{CELL_B}"), r#"["a","b"],["b","a"]"#),
    );
    let out = run(&["validate", p.to_str().unwrap()]);
    fails_with(&out, &["'a'".trim_matches('\''), "b"]);
    fails_with(
        &run(&["validate", d.path().join("missing.sop").to_str().unwrap()]),
        &["missing.sop"],
    );
}

#[test]
fn bad_solver_and_parameters_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "ok.sop", SOP);
    let f = p.to_str().unwrap();
    fails_with(
        &run(&["solve", f, "--solver", "nope"]),
        &["unknown solver 'nope'", "greedy"],
    );
    fails_with(
        &run(&["solve", f, "--solver", "exact", "--param", "bogus=1"]),
        &["no parameter 'bogus'"],
    );
    fails_with(
        &run(&["solve", f, "--solver", "exact", "--param", "memory_mb=lots"]),
        &["memory_mb", "whole number"],
    );
    fails_with(
        &run(&["solve", f, "--param", "novalue"]),
        &["malformed parameter 'novalue'"],
    );
    fails_with(
        &run(&["solve", f, "--objective", "speed"]),
        &["unknown objective"],
    );
    fails_with(&run(&["solve", f, "--time-limit=-1"]), &["time-limit"]);
}

#[test]
fn infeasible_solution_is_reported() {
    let d = tempfile::tempdir().unwrap();
    let g = write(
        d.path(),
        "g.json",
        &geo(&format!("{CELL_A},{CELL_B}"), r#"["b","a"]"#),
    );
    let s = write(
        d.path(),
        "s.json",
        r#"{"format":"cellseq-solution/1","instance":"t","sequence":[{"cell":"a","mode":0},{"cell":"b","mode":0}]}"#,
    );
    fails_with(
        &run(&["eval", g.to_str().unwrap(), s.to_str().unwrap()]),
        &["s.json", "'b' must come before 'a'"],
    );
}

/// `cellseq solve F | head` must not panic when the reader is gone before the report is
/// written: the reading end is closed right after the start, the solve takes 0.3 s, so every
/// write meets a broken pipe.
#[test]
fn closed_stdout_ends_quietly() {
    use std::process::Stdio;
    let d = tempfile::tempdir().unwrap();
    let f = write(d.path(), "t.sop", SOP);
    let mut child = bin()
        .args(["solve", f.to_str().unwrap(), "--time-limit", "0.3"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "panic: {err}");
    assert!(
        out.status.success(),
        "status {:?}, stderr: {err}",
        out.status
    );
    assert!(err.trim().is_empty(), "unexpected stderr: {err}");
}

//! Outputs that overlap inputs: `generate -o` over a file given as a parameter, `merge --out`
//! over another run's results, `report --out` into the results directory, and a `run --out`
//! directory that is a symbolic link.

use std::os::unix::fs::symlink;
use std::path::{Path, PathBuf};

use crate::common::{root, run, s, stderr, tiny_plan};

/// A copy of a committed results directory (results, instances, summary tables).
fn results_copy(dir: &Path, name: &str) -> PathBuf {
    let src = root().join("results/reference/paper-panel");
    let dst = dir.join(name);
    std::fs::create_dir(&dst).unwrap();
    for e in std::fs::read_dir(&src).unwrap() {
        let p = e.unwrap().path();
        std::fs::copy(&p, dst.join(p.file_name().unwrap())).unwrap();
    }
    dst
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap()
}

#[test]
fn generate_refuses_to_write_over_its_tools_file() {
    let d = tempfile::tempdir().unwrap();
    let tools = d.path().join("tools.toml");
    std::fs::copy(
        root().join("crates/cellseq/src/generate/default-tools.toml"),
        &tools,
    )
    .unwrap();
    let before = read(&tools);
    let param = format!("tools={}", s(&tools));
    let args = ["generate", "panel", "--param", &param, "-o", s(&tools)];
    let o = run(&args);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--overwrite-input"), "{}", stderr(&o));
    assert_eq!(read(&tools), before, "the tools file was changed");
    // the same file by another spelling
    let other = format!("{}/./tools.toml", s(d.path()));
    let o = run(&["generate", "panel", "--param", &param, "-o", &other]);
    assert!(!o.status.success());
    assert_eq!(read(&tools), before);
    // another output is fine, and the flag allows the replacement
    let inst = d.path().join("panel.json");
    let o = run(&["generate", "panel", "--param", &param, "-o", s(&inst)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut with = args.to_vec();
    with.push("--overwrite-input");
    let o = run(&with);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        read(&tools),
        read(&inst),
        "--overwrite-input wrote the instance"
    );
}

#[test]
fn merge_refuses_an_out_directory_holding_other_results() {
    let d = tempfile::tempdir().unwrap();
    let a = results_copy(d.path(), "a");
    let b = results_copy(d.path(), "b");
    // b holds one trial fewer: results of its own that `merge a --out b` would lose
    let text = String::from_utf8(read(&b.join("results.csv"))).unwrap();
    let kept: Vec<&str> = text.lines().take(text.lines().count() - 1).collect();
    std::fs::write(b.join("results.csv"), kept.join("\n") + "\n").unwrap();
    let before = read(&b.join("results.csv"));
    let o = run(&["merge", s(&a), "--out", s(&b)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("not among the merged"),
        "{}",
        stderr(&o)
    );
    assert_eq!(read(&b.join("results.csv")), before);
    // listed among the inputs, it is merged in
    let o = run(&["merge", s(&a), s(&b), "--out", s(&b)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let merged = String::from_utf8(read(&b.join("results.csv"))).unwrap();
    assert_eq!(merged.lines().count(), text.lines().count());
    // into one of the inputs (the default): its rows are kept
    let o = run(&["merge", s(&a)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let again = String::from_utf8(read(&a.join("results.csv"))).unwrap();
    assert_eq!(again.lines().count(), text.lines().count());
    // a new directory is fine
    let c = d.path().join("c");
    let o = run(&["merge", s(&a), "--out", s(&c)]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn report_into_the_results_directory_leaves_the_results_alone() {
    let d = tempfile::tempdir().unwrap();
    let a = results_copy(d.path(), "a");
    let inputs = ["results.csv", "instances.csv"];
    let before: Vec<Vec<u8>> = inputs.iter().map(|f| read(&a.join(f))).collect();
    let o = run(&["report", s(&a), "--out", s(&a)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(a.join("report.md").is_file());
    for (f, b) in inputs.iter().zip(&before) {
        assert_eq!(&read(&a.join(f)), b, "{f} changed");
    }
    // an --out that is one of the input files is refused, and the file stays
    let res = a.join("results.csv");
    let o = run(&["report", s(&a), "--out", s(&res)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("results.csv"), "{}", stderr(&o));
    assert_eq!(read(&res), before[0]);
}

#[test]
fn run_refuses_an_out_directory_that_is_a_symbolic_link() {
    let d = tempfile::tempdir().unwrap();
    let plan = d.path().join("p.toml");
    std::fs::write(&plan, tiny_plan("t")).unwrap();
    let elsewhere = d.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let link = d.path().join("out");
    symlink(&elsewhere, &link).unwrap();
    let o = run(&["run", s(&plan), "--out", s(&link), "--threads", "1"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("symbolic link"), "{}", stderr(&o));
    assert_eq!(std::fs::read_dir(&elsewhere).unwrap().count(), 0);
    // the directory itself is fine, and so is a path through a linked parent
    let o = run(&["run", s(&plan), "--out", s(&elsewhere), "--threads", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let through = link.join("sub");
    let o = run(&["run", s(&plan), "--out", s(&through), "--threads", "1"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(elsewhere.join("sub/results.csv").is_file());
}

//! End-to-end tests of the research harness: thread-count independence, resume after kill -9,
//! shards + merge, plan checking and deterministic reports.

use cellseq_lab::plan::Plan;
use cellseq_lab::results::{Row, read_strict};
use cellseq_lab::run::{RunOptions, run_plan};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::BIN;

const PLAN: &str = r#"
name = "t"
seed = 7
replicates = 2
reference = "greedy"
[budget]
evaluations = 20000
[[instances]]
generator = "uniform"
seeds = [1, 2]
grid = { n = [8, 30], tools = 2, density = 0.05 }
[[solvers]]
name = "*"
"#;

fn write_plan(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("plan.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// results.csv with every `wall_*` column removed, as text lines.
fn without_wall(path: &Path) -> Vec<String> {
    let mut rdr = csv::Reader::from_path(path).unwrap();
    let headers = rdr.headers().unwrap().clone();
    let keep: Vec<usize> = (0..headers.len())
        .filter(|&i| !headers[i].starts_with("wall_"))
        .collect();
    let mut out = vec![
        keep.iter()
            .map(|&i| headers[i].to_string())
            .collect::<Vec<_>>()
            .join(","),
    ];
    for rec in rdr.records() {
        let rec = rec.unwrap();
        out.push(
            keep.iter()
                .map(|&i| rec[i].to_string())
                .collect::<Vec<_>>()
                .join(","),
        );
    }
    out
}

fn opts(out: &Path, threads: usize) -> RunOptions {
    RunOptions {
        threads: Some(threads),
        shard: None,
        out: out.to_path_buf(),
        progress: false,
        throttle_ms: 0,
        replace_foreign: false,
    }
}

#[test]
fn one_and_two_threads_give_identical_non_wall_columns() {
    let dir = tempfile::tempdir().unwrap();
    let plan = Plan::parse("plan.toml", PLAN, dir.path()).unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let sa = run_plan(&plan, &opts(&a, 1)).unwrap();
    let sb = run_plan(&plan, &opts(&b, 2)).unwrap();
    assert_eq!(sa.planned, plan.trials().len());
    assert_eq!(sa.ran, sa.planned);
    assert_eq!(sb.ran, sb.planned);
    let (ra, rb) = (
        without_wall(&a.join("results.csv")),
        without_wall(&b.join("results.csv")),
    );
    assert_eq!(ra.len(), plan.trials().len() + 1);
    assert_eq!(ra, rb);
    assert_eq!(
        without_wall(&a.join("traces.csv")),
        without_wall(&b.join("traces.csv"))
    );
    // a second run resumes: nothing left to do, nothing duplicated
    let again = run_plan(&plan, &opts(&a, 2)).unwrap();
    assert_eq!((again.ran, again.skipped), (0, sa.planned));
    assert_eq!(without_wall(&a.join("results.csv")), ra);
}

#[test]
fn refusals_become_infeasible_rows() {
    // exact refuses the 30-cell instance under this evaluation budget; the campaign goes on
    let dir = tempfile::tempdir().unwrap();
    let plan = Plan::parse("plan.toml", PLAN, dir.path()).unwrap();
    let out = dir.path().join("o");
    run_plan(&plan, &opts(&out, 2)).unwrap();
    let rows: Vec<Row> = read_strict(&out.join("results.csv")).unwrap();
    let bad: Vec<&Row> = rows.iter().filter(|r| !r.feasible).collect();
    assert!(!bad.is_empty());
    assert!(bad.iter().all(|r| !r.error.is_empty() && r.cost.is_none()));
    assert!(
        rows.iter()
            .filter(|r| r.solver == "greedy")
            .all(|r| r.feasible)
    );
    let asg: Vec<&Row> = rows.iter().filter(|r| r.solver == "as-given").collect();
    assert!(asg.iter().all(|r| r.reduction_pct == Some(0.0)));
}

#[test]
fn kill_dash_nine_then_resume_loses_and_duplicates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let plan_path = write_plan(dir.path(), PLAN);
    let total = Plan::load(&plan_path).unwrap().trials().len();
    let killed = dir.path().join("killed");
    let mut child = Command::new(BIN)
        .args([
            "run",
            plan_path.to_str().unwrap(),
            "--threads",
            "1",
            "--throttle-ms",
            "40",
            "--out",
        ])
        .arg(&killed)
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let results = killed.join("results.csv");
    let start = Instant::now();
    loop {
        let lines = std::fs::read_to_string(&results)
            .map(|t| t.lines().count())
            .unwrap_or(0);
        if lines >= 6 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "child made no progress"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().unwrap(); // SIGKILL on Unix
    child.wait().unwrap();
    let partial = std::fs::read_to_string(&results).unwrap().lines().count() - 1;
    assert!(partial < total, "the child finished before it was killed");
    // resume
    let st = Command::new(BIN)
        .args([
            "run",
            plan_path.to_str().unwrap(),
            "--threads",
            "2",
            "--out",
        ])
        .arg(&killed)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let clean = dir.path().join("clean");
    let st = Command::new(BIN)
        .args([
            "run",
            plan_path.to_str().unwrap(),
            "--threads",
            "1",
            "--out",
        ])
        .arg(&clean)
        .output()
        .unwrap();
    assert!(st.status.success());
    let rows: Vec<Row> = read_strict(&results).unwrap();
    let keys: BTreeSet<_> = rows.iter().map(|r| r.run_key.clone()).collect();
    assert_eq!(rows.len(), total);
    assert_eq!(keys.len(), total);
    assert_eq!(
        without_wall(&results),
        without_wall(&clean.join("results.csv"))
    );
    assert_eq!(
        without_wall(&killed.join("traces.csv")),
        without_wall(&clean.join("traces.csv"))
    );
}

#[test]
fn shards_merge_to_the_full_run() {
    let dir = tempfile::tempdir().unwrap();
    let plan_path = write_plan(dir.path(), PLAN);
    let p = plan_path.to_str().unwrap();
    let full = dir.path().join("full");
    let sh = dir.path().join("sh");
    for args in [
        vec!["run", p, "--threads", "1", "--out", full.to_str().unwrap()],
        vec!["run", p, "--shard", "1/3", "--out", sh.to_str().unwrap()],
        vec!["run", p, "--shard", "2/3", "--out", sh.to_str().unwrap()],
        vec!["run", p, "--shard", "3/3", "--out", sh.to_str().unwrap()],
        // a shard run twice into another directory: merge must drop the duplicates
        vec![
            "run",
            p,
            "--shard",
            "2/3",
            "--out",
            dir.path().join("dup").to_str().unwrap(),
        ],
    ] {
        let o = Command::new(BIN).args(&args).output().unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert!(sh.join("results.shard-2-of-3.csv").exists());
    assert!(sh.join("manifest.shard-2-of-3.json").exists());
    let merged = dir.path().join("merged");
    let o = Command::new(BIN)
        .args([
            "merge",
            sh.to_str().unwrap(),
            dir.path().join("dup").to_str().unwrap(),
            "--out",
        ])
        .arg(&merged)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        without_wall(&merged.join("results.csv")),
        without_wall(&full.join("results.csv"))
    );
    assert_eq!(
        without_wall(&merged.join("traces.csv")),
        without_wall(&full.join("traces.csv"))
    );
}

#[test]
fn check_rejects_bad_plans_before_running() {
    let dir = tempfile::tempdir().unwrap();
    for (text, want) in [
        (PLAN.replace("name = \"*\"", "name = \"nosuch\""), "unknown solver 'nosuch'"),
        (PLAN.replace("name = \"*\"", "name = \"greedy\"\nparams = { bogus = 1 }"), "no parameter 'bogus'"),
        (PLAN.replace("n = [8, 30]", "n = []"), "empty grid"),
        (PLAN.replace("generator = \"uniform\"\nseeds = [1, 2]\ngrid = { n = [8, 30], tools = 2, density = 0.05 }", "files = [\"missing.sop\"]"), "matches no file"),
        ("name = ".to_string(), "plan.toml"),
    ] {
        let p = write_plan(dir.path(), &text);
        let o = Command::new(BIN).args(["check", p.to_str().unwrap()]).output().unwrap();
        assert!(!o.status.success());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(want) && err.contains("plan.toml"), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let p = write_plan(dir.path(), PLAN);
    let o = Command::new(BIN)
        .args(["check", p.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success());
}

#[test]
fn report_is_deterministic_and_complete() {
    let dir = tempfile::tempdir().unwrap();
    let plan = Plan::parse("plan.toml", PLAN, dir.path()).unwrap();
    let out = dir.path().join("o");
    run_plan(&plan, &opts(&out, 2)).unwrap();
    let r1 = cellseq_lab::report::report(&out, &dir.path().join("r1")).unwrap();
    cellseq_lab::report::report(&out, &dir.path().join("r2")).unwrap();
    for f in ["report.md", "summary.csv", "wilcoxon.csv", "friedman.csv"] {
        let a = std::fs::read(dir.path().join("r1").join(f)).unwrap();
        let b = std::fs::read(dir.path().join("r2").join(f)).unwrap();
        assert_eq!(a, b, "{f} differs");
    }
    let md = std::fs::read_to_string(&r1.markdown).unwrap();
    for s in ["Wilcoxon", "Friedman", "performance_profile.png", "greedy"] {
        assert!(md.contains(s), "report lacks {s}");
    }
    for p in [
        "reduction_box",
        "lifts_box",
        "runtime_vs_size",
        "convergence",
        "performance_profile",
        "ecdf_time_to_target",
    ] {
        for ext in ["png", "svg"] {
            let f = dir
                .path()
                .join("r1")
                .join("plots")
                .join(format!("{p}.{ext}"));
            assert!(
                std::fs::metadata(&f)
                    .map(|m| m.len() > 1000)
                    .unwrap_or(false),
                "{}",
                f.display()
            );
        }
    }
}

#[test]
fn shipped_plans_parse_against_the_registries() {
    let root = crate::common::root();
    let demo = Plan::parse("demo", cellseq_lab::DEMO_PLAN, root).unwrap();
    assert!(demo.file.budget.evaluations.is_some() && demo.file.budget.seconds.is_none());
    assert_eq!(demo.solvers.len(), cellseq::solvers::registry().len());
    assert_eq!(
        std::fs::read_to_string(root.join("experiments/demo.toml")).unwrap(),
        cellseq_lab::DEMO_PLAN
    );
}

#[test]
fn paper_plans_are_well_formed_toml_plans() {
    // Full validation needs the casing/panel generators and tabu/sa/aco solvers; until they are
    // registered, `check` must fail only because of them.
    let root = crate::common::root();
    for f in [
        "experiments/paper-casing.toml",
        "experiments/paper-panel.toml",
    ] {
        let text = std::fs::read_to_string(root.join(f)).unwrap();
        let _: cellseq_lab::plan::PlanFile = toml::from_str(&text).unwrap();
        if let Err(e) = Plan::parse(f, &text, root) {
            let e = e.to_string();
            assert!(
                e.contains("unknown generator") || e.contains("unknown solver"),
                "{e}"
            );
        }
    }
}

#[test]
fn another_plans_results_are_never_mixed_in() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("o");
    let a = Plan::parse("plan.toml", PLAN, dir.path()).unwrap();
    run_plan(&a, &opts(&out, 2)).unwrap();
    let b = Plan::parse(
        "plan.toml",
        &PLAN.replace("seed = 7", "seed = 8"),
        dir.path(),
    )
    .unwrap();
    let e = run_plan(&b, &opts(&out, 2)).unwrap_err().to_string();
    assert!(
        e.contains("do not belong to this plan") && e.contains("results.csv"),
        "{e}"
    );
    let mut o = opts(&out, 2);
    o.replace_foreign = true;
    let s = run_plan(&b, &o).unwrap();
    assert_eq!((s.ran, s.skipped), (s.planned, 0));
}

#[test]
fn paper_sections_layers_and_tools() {
    let dir = tempfile::tempdir().unwrap();
    let text = r#"
name = "paper-t"
seed = 3
replicates = 1
objective = "time"
reference = "greedy"
[budget]
evaluations = 5000
[[instances]]
generator = "casing"
seeds = [1]
grid = { regions = 2 }
[[instances]]
files = ["ESC07.pcglns"]
[[solvers]]
name = "as-given"
[[solvers]]
name = "greedy"
[[solvers]]
name = "two-opt"
[paper]
layers = true
tools = true
source = "test"
"#;
    let root = crate::common::root();
    std::fs::copy(
        root.join("instances/pcgtsplib/ESC07.pcglns"),
        dir.path().join("ESC07.pcglns"),
    )
    .unwrap();
    let plan_path = write_plan(dir.path(), text);
    let plan = Plan::load(&plan_path).unwrap();
    let out = dir.path().join("o");
    run_plan(&plan, &opts(&out, 2)).unwrap();
    let rows: Vec<Row> = read_strict(&out.join("results.csv")).unwrap();
    let layers: Vec<cellseq_lab::results::LayerRow> = read_strict(&out.join("layers.csv")).unwrap();
    let mut casing_trials = 0;
    for r in rows.iter().filter(|r| r.feasible) {
        let mine: Vec<_> = layers.iter().filter(|l| l.run_key == r.run_key).collect();
        if r.generator == "casing" {
            casing_trials += 1;
            assert!(mine.len() >= 2, "casing has several layers");
            assert_eq!(mine.iter().map(|l| l.cells).sum::<usize>(), r.n);
            assert_eq!(mine.iter().map(|l| l.lifts).sum::<u64>(), r.lifts.unwrap());
            let path: f64 = mine.iter().map(|l| l.path_length).sum();
            // the layers hold everything but the final return home
            assert!(path <= r.path_length.unwrap() + 1e-6);
            assert!(path > 0.5 * r.path_length.unwrap());
            if r.solver == "as-given" {
                for l in &mine {
                    assert!((l.as_given_path_length.unwrap() - l.path_length).abs() < 1e-9);
                    assert_eq!(l.as_given_lifts, Some(l.lifts));
                }
            }
        } else {
            // matrix instance: no layers, and blanks rather than zeros for machine figures
            assert!(mine.is_empty());
            assert_eq!(
                (r.lifts, r.tool_changes, r.machining_time),
                (None, None, None)
            );
        }
    }
    assert_eq!(casing_trials, 3);
    let insts = std::fs::read_to_string(out.join("instances.csv")).unwrap();
    assert!(
        insts.lines().count() == 3 && insts.contains("casing"),
        "{insts}"
    );
    let rep = cellseq_lab::report::report(&out, &out.join("r")).unwrap();
    let md = std::fs::read_to_string(&rep.markdown).unwrap();
    assert!(
        md.contains("## Per layer") && md.contains("| two-opt | total |"),
        "{md}"
    );
    assert!(md.contains("## Tools and reduction per solver"), "{md}");
    let summary = std::fs::read_to_string(out.join("r").join("layers_summary.csv")).unwrap();
    assert!(summary.lines().count() > 3 * 2);
}

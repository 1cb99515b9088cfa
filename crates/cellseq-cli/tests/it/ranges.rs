//! One rule for every number a user can give (issue 50): a declared range, checked where the
//! number enters, refused naming the flag, parameter, plan key or file and line; `check`
//! refuses the plans `run` would fail on; the list in docs/bad-input.md is the one
//! `cellseq limits --markdown` prints.

use crate::common::{
    fixture_path, has_non_finite, instance_path, root, run, s, stderr, tiny_plan, write,
};
use cellseq::generate::KINDS;
use cellseq::params::{ParamKind, ParamSpec, Params};
use cellseq::registry;
use std::collections::BTreeMap;

/// Every Int and Float parameter's default lies in its declared range.
fn defaults_fit(owner: &str, specs: &[ParamSpec]) {
    for p in specs {
        if matches!(p.kind, ParamKind::Int(_) | ParamKind::Float(_)) && !p.default.is_empty() {
            let given = BTreeMap::from([(p.name.to_string(), p.default.to_string())]);
            if let Err(e) = Params::new(owner, specs, &given) {
                panic!(
                    "{owner} {}: default {} is out of range: {e}",
                    p.name, p.default
                );
            }
        }
    }
}

#[test]
fn every_default_lies_in_its_declared_range() {
    for s in registry::all() {
        defaults_fit(s.name, s.params);
    }
    for g in KINDS {
        defaults_fit(g.name, g.params);
    }
    defaults_fit("plan", cellseq_lab::plan::NUMBERS);
}

/// Runs the binary; asserts exit status 2 and that stderr names `what`; returns stderr. An
/// argument `--flag VALUE` is given as `--flag=VALUE` (so that `-1` is a value).
fn refused(args: &[&str], what: &str) -> String {
    let mut joined: Vec<String> = Vec::new();
    let mut it = args.iter().peekable();
    while let Some(a) = it.next() {
        match it.peek() {
            Some(v) if a.starts_with("--") && v.starts_with('-') && !v.starts_with("--") => {
                joined.push(format!("{a}={v}"));
                it.next();
            }
            _ => joined.push(a.to_string()),
        }
    }
    let args: Vec<&str> = joined.iter().map(String::as_str).collect();
    let args = args.as_slice();
    let o = run(args);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
    assert!(e.contains(what), "{args:?} should name {what}: {e}");
    assert!(!e.contains("panicked"), "{args:?}: {e}");
    e
}

#[test]
fn numbers_out_of_range_on_the_command_line_are_refused_by_name() {
    let sop = instance_path("tsplib-sop/ESC07.sop");
    let ngc = fixture_path("gcode/mill.ngc");
    let svg = fixture_path("svg/shapes.svg");
    let d = tempfile::tempdir().unwrap();
    let plan = write(d.path(), "p.toml", &tiny_plan("t"));
    let out = d.path().join("x.json");
    let (sop, ngc, svg, plan, out) = (s(&sop), s(&ngc), s(&svg), s(&plan), s(&out));
    for t in ["1e300", "nan", "inf", "0", "-1", "1e7"] {
        refused(&["solve", sop, "--time-limit", t], "--time-limit");
        refused(&["optimize", ngc, "--time-limit", t], "--time-limit");
    }
    refused(&["solve", sop, "--max-evals", "0"], "--max-evals");
    refused(&["optimize", ngc, "--max-evals", "-5"], "--max-evals");
    for t in ["0", "1000000", "18446744073709551616"] {
        refused(&["run", plan, "--threads", t], "--threads");
        refused(&["demo", "--threads", t], "--threads");
        refused(&["check", plan, "--threads", t], "--threads");
    }
    refused(&["check", plan, "--shards", "0"], "--shards");
    refused(&["check", plan, "--max-trials", "0"], "--max-trials");
    refused(&["run", plan, "--max-files", "1e300"], "--max-files");
    refused(&["bound", sop, "--iterations", "1e12"], "--iterations");
    for m in ["nan", "-1", "inf", "1e300"] {
        refused(&["optimize", ngc, "--margin", m], "--margin");
        refused(&["import", ngc, "-o", out, "--margin", m], "--margin");
        refused(&["optimize", svg, "--join-tol", m], "--join-tol");
        refused(&["optimize", svg, "--tolerance", m], "--tolerance");
        refused(&["optimize", svg, "--contain-tol", m], "--contain-tol");
        refused(&["optimize", svg, "--feed", m], "--feed");
        refused(&["optimize", svg, "--safe-height", m], "--safe-height");
    }
    refused(&["optimize", svg, "--max-starts", "0"], "--max-starts");
    refused(&["optimize", svg, "--max-points", "1e12"], "--max-points");
    // parameters: the solver's or generator's name and the parameter's
    refused(
        &["solve", sop, "--param", "seconds=1e300"],
        "parameter 'seconds'",
    );
    refused(
        &["solve", sop, "--solver", "ils", "--param", "k=0"],
        "parameter 'k'",
    );
    refused(
        &["solve", sop, "--solver", "sa", "--param", "alpha=1"],
        "parameter 'alpha'",
    );
    for n in [
        "1000000000000",
        "18446744073709551615",
        "18446744073709551616",
        "0",
    ] {
        let p = format!("n={n}");
        refused(
            &["generate", "uniform", "--param", &p, "-o", out],
            "parameter 'n'",
        );
    }
    refused(
        &[
            "generate",
            "uniform",
            "--param",
            "n=10000000",
            "--param",
            "preds=1000",
            "-o",
            out,
        ],
        "n x preds",
    );
    refused(
        &["generate", "panel", "--param", "ap=0.01", "-o", out],
        "roughing layers",
    );
    assert!(!d.path().join("x.json").exists());
}

/// A plan around a `[budget]` and an `[[instances]]` entry.
fn plan(budget: &str, instances: &str, extra: &str) -> String {
    format!(
        "name = \"r\"\n{extra}\n[budget]\n{budget}\n[[instances]]\n{instances}\n[[solvers]]\nname = \"greedy\"\n"
    )
}

#[test]
fn check_refuses_every_plan_run_would_fail_on() {
    let d = tempfile::tempdir().unwrap();
    let uni = "generator = \"uniform\"\ngrid = { n = 6 }";
    let cases = [
        (plan("seconds = 1e300", uni, ""), "budget.seconds"),
        (plan("seconds = nan", uni, ""), "budget.seconds"),
        (
            plan("calibration_units = 1e300", uni, ""),
            "budget.calibration_units",
        ),
        (
            plan("calibration_units = 1e9", uni, ""),
            "calibration_units",
        ),
        (plan("evaluations = 0", uni, ""), "budget.evaluations"),
        (
            plan("evaluations = 10", uni, "max_trials = 0"),
            "max_trials",
        ),
        (plan("evaluations = 10", uni, "max_files = 0"), "max_files"),
        (
            plan(
                "evaluations = 10",
                "generator = \"uniform\"\ngrid = { n = 1e12 }",
                "",
            ),
            "parameter 'n'",
        ),
        (
            plan(
                "evaluations = 10",
                "generator = \"uniform\"\ngrid = { n = [5, 1000000000000] }",
                "",
            ),
            "n=1000000000000",
        ),
        (
            plan(
                "evaluations = 10",
                "generator = \"uniform\"\ngrid = { n = 10000000, preds = 1000 }",
                "",
            ),
            "instances[0] (generator uniform, n=10000000,preds=1000)",
        ),
        (
            plan(
                "evaluations = 10",
                "generator = \"casing\"\ngrid = { width = 10 }",
                "",
            ),
            "instances[0] (generator casing, width=10)",
        ),
        (
            plan("evaluations = 10", uni, "[max_cells]\nexact = 5"),
            "max_cells.exact",
        ),
        (
            plan("evaluations = 10", uni, "[max_cells]\ngreedy = 0"),
            "max_cells.greedy",
        ),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        let p = write(d.path(), &format!("p{i}.toml"), text);
        for cmd in ["check", "run"] {
            let out = d.path().join(format!("out{i}"));
            let args = [cmd, s(&p), "--threads", "1", "--out", s(&out)];
            let args: &[&str] = if cmd == "check" { &args[..4] } else { &args };
            let e = refused(args, want);
            assert!(e.contains(&format!("p{i}.toml")), "{cmd} {i}: {e}");
            assert!(!out.join("results.csv").exists(), "{cmd} {i} wrote results");
        }
    }
    // a solver parameter out of range in a plan, an `auto` plan phase's parameter too
    let text = tiny_plan("t").replace(
        "name = \"greedy\"",
        "name = \"auto\"\nparams = { seconds = 1e300 }",
    );
    let p = write(d.path(), "auto.toml", &text);
    refused(&["check", s(&p)], "parameter 'seconds'");
    let text = tiny_plan("t").replace(
        "name = \"greedy\"",
        "name = \"auto\"\nparams = { plan = \"ils[k=0]:1\" }",
    );
    let p = write(d.path(), "phase.toml", &text);
    refused(&["check", s(&p)], "parameter 'k'");
}

#[test]
fn the_shard_estimate_of_a_plan_of_centuries_is_told_in_years() {
    let d = tempfile::tempdir().unwrap();
    let text = tiny_plan("t")
        .replace("evaluations = 1000", "seconds = 1e6")
        .replace("name = \"t\"", "name = \"t\"\nreplicates = 5000");
    let p = write(d.path(), "p.toml", &text);
    let o = run(&["check", s(&p), "--threads", "1"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(out.contains("years") && !out.contains("suggested"), "{out}");
}

#[test]
fn a_bks_value_that_is_not_a_number_is_ignored_naming_bks_csv_and_its_line() {
    let d = tempfile::tempdir().unwrap();
    std::fs::copy(
        instance_path("tsplib-sop/ESC07.sop"),
        d.path().join("ESC07.sop"),
    )
    .unwrap();
    let inst = d.path().join("ESC07.sop");
    for bad in ["NaN", "inf", "-inf", "-3", "x", ""] {
        let bks = format!("name,best_known,proven_optimal\nother,5,true\nESC07,{bad},true\n");
        std::fs::write(d.path().join("bks.csv"), bks).unwrap();
        for args in [
            vec!["solve", s(&inst), "--max-evals", "1000", "--no-bound"],
            vec!["solve", s(&inst), "--max-evals", "1000", "--json"],
            vec!["info", s(&inst)],
            vec!["bound", s(&inst), "--iterations", "5"],
        ] {
            let o = run(&args);
            let (out, e) = (String::from_utf8_lossy(&o.stdout), stderr(&o));
            assert!(o.status.success(), "{bad} {args:?}: {e}");
            assert!(
                e.contains("bks.csv:3") && e.contains("ignored"),
                "{bad}: {e}"
            );
            assert!(!has_non_finite(&out), "{bad}: {out}");
            assert!(!out.contains("best known"), "{bad}: {out}");
        }
    }
}

#[test]
fn run_refuses_a_link_out_directory_in_every_spelling() {
    use std::os::unix::fs::symlink;
    let d = tempfile::tempdir().unwrap();
    let plan = write(d.path(), "p.toml", &tiny_plan("t"));
    let target = d.path().join("target");
    std::fs::create_dir_all(target.join("sub")).unwrap();
    let link = d.path().join("link");
    symlink(&target, &link).unwrap();
    let l = s(&link);
    for form in [
        format!("{l}/"),
        format!("{l}/."),
        format!("{l}//"),
        format!("{l}/./"),
        format!("{l}/sub/.."),
        format!("{l}/.."),
    ] {
        refused(
            &["run", s(&plan), "--out", &form, "--threads", "1"],
            "symbolic link",
        );
        assert_eq!(
            std::fs::read_dir(&target).unwrap().count(),
            1,
            "{form} wrote"
        );
    }
}

#[test]
fn solvers_out_of_their_plan_range_are_not_run_and_not_counted_as_failures() {
    let d = tempfile::tempdir().unwrap();
    let text = tiny_plan("t").replace(
        "[[solvers]]\nname = \"greedy\"",
        "[max_cells]\nexact = 5\n[[solvers]]\nname = \"greedy\"\n[[solvers]]\nname = \"exact\"",
    );
    let p = write(d.path(), "p.toml", &text);
    let out = d.path().join("out");
    let o = run(&["run", s(&p), "--out", s(&out), "--threads", "1"]);
    let so = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        so.contains("0 without a feasible result, 1 not run: out of their solver's range"),
        "{so}"
    );
    let results = std::fs::read_to_string(out.join("results.csv")).unwrap();
    assert!(
        results.contains("out of range: 6 cells, more than the plan's max_cells.exact = 5"),
        "{results}"
    );
    let o = run(&["report", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let md = std::fs::read_to_string(out.join("report/report.md")).unwrap();
    assert!(
        md.contains("## Trials not run: out of their solver's range"),
        "{md}"
    );
    assert!(!md.contains("## Trials without a feasible result"), "{md}");
}

#[test]
fn bad_input_md_lists_every_range_as_limits_prints_it() {
    let o = run(&["limits", "--markdown"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let generated = String::from_utf8(o.stdout).unwrap();
    let doc = std::fs::read_to_string(root().join("docs/bad-input.md")).unwrap();
    let begin = generated.lines().next().unwrap();
    let end = generated.trim_end().lines().last().unwrap();
    let (Some(a), Some(b)) = (doc.find(begin), doc.find(end)) else {
        panic!("docs/bad-input.md has no section between {begin} and {end}");
    };
    let section = &doc[a..b + end.len()];
    assert_eq!(
        section,
        generated.trim_end(),
        "docs/bad-input.md is out of date: run scripts/update-limits.py"
    );
}

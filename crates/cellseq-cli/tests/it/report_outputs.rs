//! What `cellseq report` writes for papers (LaTeX tables, SVG figures with real text and clean
//! ticks, the right x axis for the budget) and what a run records about itself (provenance in
//! the manifest, `cellseq --version`, the time estimate of `cellseq check`).

use cellseq_lab::plan::Plan;
use cellseq_lab::run::{RunOptions, run_plan};
use std::path::Path;
use std::process::Command;

use crate::common::BIN;

fn plan(budget: &str) -> String {
    format!(
        r#"
name = "r"
seed = 3
replicates = 2
reference = "greedy"
[budget]
{budget}
[[instances]]
generator = "uniform"
seeds = [1, 2]
grid = {{ n = 20, tools = 2, density = 0.05 }}
[[solvers]]
name = "greedy"
[[solvers]]
name = "local-search"
[[solvers]]
name = "as-given"
"#
    )
}

fn run(dir: &Path, text: &str) -> std::path::PathBuf {
    let p = Plan::parse("plan.toml", text, dir).unwrap();
    let out = dir.join("o");
    run_plan(
        &p,
        &RunOptions {
            threads: Some(2),
            shard: None,
            out: out.clone(),
            progress: false,
            throttle_ms: 0,
            replace_foreign: false,
        },
    )
    .unwrap();
    cellseq_lab::report::report(&out, &out.join("r")).unwrap();
    out
}

/// The cells of each row of a tabular body (lines ending in `\\`), split at unescaped `&`.
fn row_cells(line: &str) -> usize {
    let mut n = 1;
    let mut prev = ' ';
    for c in line.chars() {
        if c == '&' && prev != '\\' {
            n += 1;
        }
        prev = c;
    }
    n
}

#[test]
fn latex_tables_are_booktabs_with_a_cell_per_column() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), &plan("evaluations = 20000"));
    let md = std::fs::read_to_string(out.join("r/report.md")).unwrap();
    for name in ["summary.tex", "solvers.tex", "wilcoxon.tex", "friedman.tex"] {
        let t = std::fs::read_to_string(out.join("r").join(name)).unwrap();
        assert!(md.contains(&format!("]({name})")), "report.md lacks {name}");
        for needle in [
            "\\toprule",
            "\\midrule",
            "\\bottomrule",
            "\\caption{",
            "\\label{tab:",
        ] {
            assert!(t.contains(needle), "{name} lacks {needle}:\n{t}");
        }
        assert!(!t.contains('|'), "{name} has vertical rules");
        assert_eq!(t.matches("\\begin{").count(), t.matches("\\end{").count());
        let spec = t
            .split("\\begin{tabular}{")
            .nth(1)
            .or_else(|| t.split("\\begin{longtable}{").nth(1))
            .and_then(|s| s.split('}').next())
            .unwrap();
        assert!(spec.chars().all(|c| c == 'l' || c == 'r'), "{spec}");
        let rows: Vec<&str> = t
            .lines()
            .filter(|l| {
                l.ends_with("\\\\")
                    && !l.starts_with("\\caption")
                    && !l.starts_with("\\multicolumn")
            })
            .collect();
        assert!(rows.len() >= 3, "{name}:\n{t}");
        for r in rows {
            assert_eq!(row_cells(r), spec.len(), "{name}: {r}");
        }
        // escaped: solver and instance ids keep their text, `_` and `%` never raw
        for l in t.lines().filter(|l| !l.starts_with('%')) {
            for (i, c) in l.char_indices() {
                if c == '%' || c == '_' {
                    assert!(
                        i > 0 && l.as_bytes()[i - 1] == b'\\',
                        "{name}: unescaped {c} in {l}"
                    );
                }
            }
        }
    }
    let s = std::fs::read_to_string(out.join("r/summary.tex")).unwrap();
    assert!(s.contains("local-search") && s.contains("\\textbf{"), "{s}");
}

/// The text elements of an SVG file.
fn svg_texts(path: &Path) -> Vec<String> {
    let svg = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&svg).unwrap();
    doc.descendants()
        .filter(|n| n.has_tag_name("text"))
        .map(|n| {
            assert!(
                n.attribute("font-family")
                    .is_some_and(|f| f.contains("DejaVu Sans")),
                "{}: text without the font family",
                path.display()
            );
            n.text().unwrap_or("").trim().to_string()
        })
        .collect()
}

#[test]
fn figures_count_evaluations_under_evaluation_budgets_with_clean_ticks() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), &plan("evaluations = 20000"));
    let plots = out.join("r/plots");
    for name in [
        "convergence",
        "convergence_facets",
        "ecdf_time_to_target",
        "performance_profile",
        "reduction_box",
        "lifts_box",
        "runtime_vs_size",
    ] {
        assert!(plots.join(format!("{name}.png")).is_file(), "{name}.png");
        let texts = svg_texts(&plots.join(format!("{name}.svg")));
        assert!(!texts.is_empty(), "{name}.svg has no text");
        for t in &texts {
            // no floating-point noise in any label
            assert!(
                !t.contains("9999") && !t.contains("0000000") && !t.contains("e-"),
                "{name}: label {t:?}"
            );
        }
    }
    let conv = svg_texts(&plots.join("convergence.svg"));
    assert!(conv.iter().any(|t| t == "evaluations"), "{conv:?}");
    assert!(!conv.iter().any(|t| t.contains("seconds")), "{conv:?}");
    // every solver appears in the legend, and decade ticks are labelled as such
    for s in ["greedy (reference)", "local-search"] {
        assert!(conv.iter().any(|t| t == s), "{s} not in {conv:?}");
    }
    assert!(
        conv.iter().any(|t| t == "1000" || t == "10⁴" || t == "100"),
        "{conv:?}"
    );
    let ecdf = svg_texts(&plots.join("ecdf_time_to_target.svg"));
    assert!(ecdf.iter().any(|t| t == "evaluations"), "{ecdf:?}");
    let prof = svg_texts(&plots.join("performance_profile.svg"));
    assert!(prof.iter().any(|t| t.starts_with("log₂ τ")), "{prof:?}");
    assert!(
        prof.iter().any(|t| t.starts_with("local-search (best on ")),
        "{prof:?}"
    );
}

#[test]
fn figures_use_wall_seconds_under_time_budgets() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), &plan("seconds = 0.05"));
    let conv = svg_texts(&out.join("r/plots/convergence.svg"));
    assert!(
        conv.iter().any(|t| t.starts_with("wall seconds")),
        "{conv:?}"
    );
    assert!(!conv.iter().any(|t| t == "evaluations"), "{conv:?}");
}

#[test]
fn manifest_records_provenance_and_the_report_repeats_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = run(dir.path(), &plan("evaluations = 5000"));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("manifest.json")).unwrap()).unwrap();
    for k in [
        "started_utc",
        "ended_utc",
        "host",
        "os",
        "kernel",
        "cpu_model",
        "cellseq_version",
        "git_commit",
        "git_dirty",
    ] {
        assert!(m[k].as_str().is_some_and(|s| !s.is_empty()), "{k}: {m}");
    }
    assert!(m["cpu_count"].as_u64().unwrap() >= 1);
    assert_eq!(m["threads"], 2);
    let (a, b) = (
        m["started_utc"].as_str().unwrap(),
        m["ended_utc"].as_str().unwrap(),
    );
    assert!(a.ends_with('Z') && a.len() == 20 && a <= b, "{a} {b}");
    assert_eq!(m["git_commit"], cellseq_lab::provenance::GIT_COMMIT);
    let md = std::fs::read_to_string(out.join("r/report.md")).unwrap();
    assert!(md.contains(&format!("started {a}, ended {b}")), "{md}");
}

#[test]
fn version_names_the_commit() {
    let o = Command::new(BIN).arg("--version").output().unwrap();
    assert!(o.status.success());
    let v = String::from_utf8(o.stdout).unwrap();
    let commit = cellseq_lab::provenance::GIT_COMMIT;
    assert!(
        v.starts_with(&format!("cellseq {} (commit ", env!("CARGO_PKG_VERSION"))),
        "{v}"
    );
    if commit == "unknown" {
        assert!(v.contains("commit unknown"), "{v}");
    } else {
        assert!(
            commit.len() == 40 && commit.chars().all(|c| c.is_ascii_hexdigit()),
            "{commit}"
        );
        assert!(v.contains(&commit[..12]), "{v}");
    }
}

#[test]
fn check_estimates_the_time_per_shard() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("plan.toml");
    std::fs::write(&p, plan("seconds = 30")).unwrap();
    let o = Command::new(BIN)
        .args([
            "check",
            p.to_str().unwrap(),
            "--shards",
            "3",
            "--threads",
            "2",
        ])
        .output()
        .unwrap();
    assert!(o.status.success());
    let s = String::from_utf8(o.stdout).unwrap();
    // 2 instances x 3 solvers x 2 replicates = 12 trials; 4 per shard, 2 rounds of 30 s
    assert!(
        s.contains("3 shard(s) of at most 4 trial(s) on 2 thread(s)"),
        "{s}"
    );
    assert!(s.contains("about 60 s") && s.contains("00:06:30"), "{s}");
}

//! `cellseq report`: tables, tests and plots from a results directory, deterministically
//! (same input files, same output bytes for the tables; plots depend on the same data only).

use super::figures;
use super::hash::stable_hash;
use super::latex;
use super::manifest::Manifest;
use super::plan::{Paper, PlanFile};
use super::results::{Row, TraceRow, read_lenient, read_strict};
use super::stats::{
    bootstrap_ci_mean, friedman, holm, mean, median, quantile, std_dev, wilcoxon_signed_rank,
};
use cellseq::error::{Error, Result};
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Bootstrap resamples for the confidence intervals.
pub const BOOTSTRAP_RESAMPLES: usize = 2000;
/// Relative gap to the best found cost that counts as reaching the target (ECDF).
pub const TARGET_GAP: f64 = figures::TARGET_GAP;

/// What the report wrote.
#[derive(Debug, Clone)]
pub struct ReportFiles {
    /// The Markdown report.
    pub markdown: PathBuf,
    /// Every file written.
    pub files: Vec<PathBuf>,
}

fn fmt(x: f64) -> String {
    if x.is_nan() {
        "–".into()
    } else if x.abs() >= 1e5 || (x != 0.0 && x.abs() < 1e-3) {
        format!("{x:.4e}")
    } else {
        format!("{x:.3}")
    }
}

fn opt(v: &[Option<f64>]) -> Vec<f64> {
    v.iter().flatten().copied().collect()
}

/// Order of first appearance.
fn ordered<'a>(it: impl Iterator<Item = &'a str>) -> Vec<String> {
    let mut seen = BTreeSet::new();
    let mut out = Vec::new();
    for s in it {
        if seen.insert(s.to_string()) {
            out.push(s.to_string());
        }
    }
    out
}

/// One line of the summary table.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SummaryRow {
    /// Instance id.
    pub instance: String,
    /// Solver id.
    pub solver: String,
    /// Trials.
    pub runs: usize,
    /// Feasible trials.
    pub feasible: usize,
    /// Mean cost.
    pub mean: f64,
    /// Median cost.
    pub median: f64,
    /// Best cost.
    pub best: f64,
    /// Standard deviation of the cost.
    pub std: f64,
    /// 95 % bootstrap CI of the mean, lower end.
    pub ci95_lo: f64,
    /// 95 % bootstrap CI of the mean, upper end.
    pub ci95_hi: f64,
    /// Mean reduction against as-given (objective), %.
    pub reduction_pct: f64,
    /// Mean air-length reduction, %.
    pub air_reduction_pct: f64,
    /// Mean total-path reduction, %.
    pub path_reduction_pct: f64,
    /// Mean machining-time reduction, %.
    pub time_reduction_pct: f64,
    /// Mean lifts.
    pub lifts: f64,
    /// Mean tool changes.
    pub tool_changes: f64,
    /// Mean machining time, s.
    pub machining_time: f64,
    /// Mean gap to best known, %.
    pub gap_bks_pct: f64,
    /// Mean wall seconds.
    pub wall_runtime_s: f64,
}

fn summarize(rows: &[&Row], instance: &str, solver: &str) -> SummaryRow {
    let ok: Vec<&&Row> = rows.iter().filter(|r| r.feasible).collect();
    let cost: Vec<f64> = ok.iter().filter_map(|r| r.cost).collect();
    let m = |f: fn(&Row) -> Option<f64>| mean(&opt(&ok.iter().map(|r| f(r)).collect::<Vec<_>>()));
    let seed = stable_hash(&[instance.as_bytes(), solver.as_bytes()]);
    let (lo, hi) = bootstrap_ci_mean(&cost, 0.95, BOOTSTRAP_RESAMPLES, seed);
    SummaryRow {
        instance: instance.into(),
        solver: solver.into(),
        runs: rows.len(),
        feasible: ok.len(),
        mean: mean(&cost),
        median: median(&cost),
        best: quantile(&cost, 0.0),
        std: std_dev(&cost),
        ci95_lo: lo,
        ci95_hi: hi,
        reduction_pct: m(|r| r.reduction_pct),
        air_reduction_pct: m(|r| r.air_reduction_pct),
        path_reduction_pct: m(|r| r.path_reduction_pct),
        time_reduction_pct: m(|r| r.time_reduction_pct),
        lifts: m(|r| r.lifts.map(|x| x as f64)),
        tool_changes: m(|r| r.tool_changes.map(|x| x as f64)),
        machining_time: m(|r| r.machining_time),
        gap_bks_pct: m(|r| r.gap_bks_pct),
        wall_runtime_s: mean(&rows.iter().map(|r| r.wall_elapsed_s).collect::<Vec<_>>()),
    }
}

fn write_csv<T: serde::Serialize>(path: &Path, rows: &[T]) -> Result<()> {
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in rows {
        w.serialize(r)
            .map_err(|e| Error::invalid(path.display().to_string(), e.to_string()))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::invalid(path.display().to_string(), e.to_string()))?;
    cellseq::files::write_atomic(path, &bytes)
}

/// One Wilcoxon comparison.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TestRow {
    /// Instance id (`ALL` for the pooled test over (instance, replicate) pairs).
    pub instance: String,
    /// Solver compared with the reference.
    pub solver: String,
    /// Reference solver.
    pub reference: String,
    /// Pairs used.
    pub pairs: usize,
    /// Mean of solver − reference cost.
    pub mean_diff: f64,
    /// V statistic.
    pub v: f64,
    /// Two-sided p-value.
    pub p: f64,
    /// Holm-adjusted p-value (over all per-instance comparisons; the pooled rows separately).
    pub p_holm: f64,
    /// `better`, `worse` or `n.s.` at the 5 % level after correction.
    pub verdict: String,
}

/// What every section reads: the trials and their grouping.
struct Data<'a> {
    /// Every trial, in file order.
    rows: &'a [Row],
    /// Instance ids in order of first appearance.
    instances: Vec<String>,
    /// Solver ids in order of first appearance.
    solvers: Vec<String>,
    /// The solver the others are tested against.
    reference: String,
    /// Trials per (instance, solver).
    by: BTreeMap<(String, String), Vec<&'a Row>>,
}

impl<'a> Data<'a> {
    fn new(rows: &'a [Row], manifest: Option<&Manifest>) -> Data<'a> {
        let instances = ordered(rows.iter().map(|r| r.instance.as_str()));
        let solvers = ordered(rows.iter().map(|r| r.solver_id.as_str()));
        let reference = manifest
            .and_then(|m| m.reference.clone())
            .filter(|r| solvers.contains(r))
            .unwrap_or_else(|| solvers[0].clone());
        let mut by: BTreeMap<(String, String), Vec<&Row>> = BTreeMap::new();
        for r in rows {
            by.entry((r.instance.clone(), r.solver_id.clone()))
                .or_default()
                .push(r);
        }
        Data {
            rows,
            instances,
            solvers,
            reference,
            by,
        }
    }

    /// The objectives of the trials, comma-separated.
    fn objective(&self) -> String {
        ordered(self.rows.iter().map(|r| r.objective.as_str())).join(", ")
    }

    /// Feasible costs of solver `s` on instance `i`, by replicate.
    fn cost_of(&self, i: &str, s: &str) -> BTreeMap<u32, f64> {
        self.by
            .get(&(i.to_string(), s.to_string()))
            .map(|g| {
                g.iter()
                    .filter(|r| r.feasible)
                    .filter_map(|r| r.cost.map(|c| (r.replicate, c)))
                    .collect()
            })
            .unwrap_or_default()
    }
}

/// The report being written: the Markdown text, the files written, the LaTeX tables to write.
struct Out<'a> {
    dir: &'a Path,
    md: String,
    files: Vec<PathBuf>,
    tex_tables: Vec<(&'static str, latex::Table)>,
}

/// Writes the report of the results in `dir` into `out`.
pub fn report(dir: &Path, out: &Path) -> Result<ReportFiles> {
    let results = dir.join("results.csv");
    if !results.exists() {
        return Err(Error::invalid(
            dir.display().to_string(),
            "no results.csv here (run `cellseq run`, or `cellseq merge` the shards first)",
        ));
    }
    let rows: Vec<Row> = read_strict(&results)?;
    if rows.is_empty() {
        return Err(Error::invalid(
            results.display().to_string(),
            "no trials in the file",
        ));
    }
    let traces: Vec<TraceRow> = read_lenient(&dir.join("traces.csv"))?.0;
    let manifest = Manifest::read(&dir.join("manifest.json"));
    let plan: Option<PlanFile> = manifest
        .as_ref()
        .and_then(|m| m.plan.as_deref())
        .and_then(|t| toml::from_str(t).ok());
    std::fs::create_dir_all(out).map_err(|e| Error::io(out.display().to_string(), e))?;
    let data = Data::new(&rows, manifest.as_ref());
    let mut o = Out {
        dir: out,
        md: String::new(),
        files: Vec::new(),
        tex_tables: Vec::new(),
    };
    let title = plan
        .as_ref()
        .map(|p| p.name.clone())
        .unwrap_or_else(|| dir.display().to_string());
    header(&mut o.md, &title, &data);
    if let Some(m) = &manifest {
        run_line(&mut o.md, m);
    }
    instances_section(&mut o.md, &data);
    failures_section(&mut o.md, &data);
    summary_section(&mut o, &data)?;
    let overview = solvers_section(&mut o.md, &data);
    wilcoxon_section(&mut o, &data, overview)?;
    friedman_section(&mut o, &data)?;
    if let Some(paper) = plan.as_ref().and_then(|p| p.paper.as_ref()) {
        paper_section(&mut o.md, &data, paper);
        if paper.layers
            && let Some((section, p)) = super::paper::layer_section(dir, out, &rows, &data.solvers)?
        {
            o.md.push_str(&section);
            o.files.push(p);
        }
        if paper.tools {
            o.md.push_str(&super::paper::tools_section(dir, &rows, &data.solvers)?);
        }
    }
    latex_section(&mut o)?;
    plots_section(&mut o, &data, &traces)?;
    let md_path = out.join("report.md");
    cellseq::files::write_atomic(&md_path, o.md.as_bytes())?;
    o.files.push(md_path.clone());
    Ok(ReportFiles {
        markdown: md_path,
        files: o.files,
    })
}

/// The title and what the numbers are.
fn header(md: &mut String, title: &str, d: &Data) {
    let _ = writeln!(md, "# Report: {title}\n");
    let _ = writeln!(
        md,
        "{} trials, {} instances, {} solvers; reference solver `{}`. Costs are the objective \
         (`{}`); reductions are against the as-given (as-programmed) order; CIs are 95 % percentile \
         bootstrap ({BOOTSTRAP_RESAMPLES} resamples, fixed seed).\n",
        d.rows.len(),
        d.instances.len(),
        d.solvers.len(),
        d.reference,
        d.objective()
    );
}

/// The provenance of the run; of merged shards: the earliest start, the latest end (when every
/// shard ended), every host.
fn run_line(md: &mut String, m: &Manifest) {
    let txt = |v: &Option<String>| v.clone().unwrap_or_else(|| "?".into());
    let dirty = if m.git_dirty.as_deref() == Some("true") {
        ", dirty tree"
    } else {
        ""
    };
    let parts = m.parts();
    let started = parts
        .iter()
        .filter_map(|p| p.started_utc.as_deref())
        .min()
        .unwrap_or("?");
    let ends: Vec<&str> = parts
        .iter()
        .filter_map(|p| p.ended_utc.as_deref())
        .collect();
    let ended = if ends.len() == parts.len() {
        ends.into_iter().max().unwrap_or("?")
    } else {
        "– (not finished)"
    };
    let hosts: BTreeSet<&str> = parts.iter().filter_map(|p| p.host.as_deref()).collect();
    let hosts = if hosts.is_empty() {
        "?".to_string()
    } else {
        hosts.into_iter().collect::<Vec<_>>().join(", ")
    };
    let shards = if parts.len() > 1 {
        format!(" ({} merged parts)", parts.len())
    } else {
        String::new()
    };
    let number = |v: Option<u64>| v.map_or_else(|| "null".to_string(), |x| x.to_string());
    let _ = writeln!(
        md,
        "Run{shards}: cellseq {} (commit {}{dirty}), plan hash `{}`, {} thread(s) on host {hosts} ({} × {}; {}, kernel {}), \
         calibration unit {} s; started {started}, ended {ended}.\n",
        txt(&m.crate_version),
        m.git_commit.as_deref().unwrap_or("unknown"),
        txt(&m.plan_hash),
        number(m.threads),
        number(m.cpu_count),
        txt(&m.cpu_model),
        txt(&m.os),
        txt(&m.kernel),
        m.calibration_seconds.map(fmt).unwrap_or_else(|| "?".into()),
    );
}

/// The instances and their features.
fn instances_section(md: &mut String, d: &Data) {
    let _ = writeln!(md, "## Instances\n");
    let _ = writeln!(
        md,
        "| instance | source | n | tools | cells per tool | precedence density | as-given cost | best known |\n|---|---|---|---|---|---|---|---|"
    );
    for i in &d.instances {
        if let Some(r) = d.rows.iter().find(|r| &r.instance == i) {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {} |",
                r.instance,
                r.generator,
                r.n,
                r.tools,
                fmt(r.n as f64 / r.tools.max(1) as f64),
                fmt(r.precedence_density),
                r.as_given_cost.map(fmt).unwrap_or_else(|| "–".into()),
                r.best_known.map(fmt).unwrap_or_else(|| "–".into())
            );
        }
    }
    let _ = writeln!(md);
}

/// Trials without a feasible result, once per (instance, solver); trials not run because the
/// instance lies beyond the solver's `[max_cells]` are listed apart, as out of range.
fn failures_section(md: &mut String, d: &Data) {
    let beyond = |r: &&Row| r.error.starts_with(super::run::OUT_OF_RANGE);
    let failed: Vec<&Row> = d
        .rows
        .iter()
        .filter(|r| !r.feasible && !beyond(r))
        .collect();
    let skipped: Vec<&Row> = d.rows.iter().filter(|r| beyond(r)).collect();
    for (rows, title) in [
        (&failed, "Trials without a feasible result"),
        (
            &skipped,
            "Trials not run: out of their solver's range (the plan's max_cells)",
        ),
    ] {
        if rows.is_empty() {
            continue;
        }
        let _ = writeln!(md, "## {title} ({})\n", rows.len());
        let mut seen = BTreeSet::new();
        for r in rows {
            if seen.insert((r.instance.clone(), r.solver_id.clone())) {
                let _ = writeln!(md, "- `{}` on `{}`: {}", r.solver_id, r.instance, r.error);
            }
        }
        let _ = writeln!(md);
    }
}

/// The table per instance and solver (`summary.csv`, `summary.tex`).
fn summary_section(o: &mut Out, d: &Data) -> Result<()> {
    let mut summary = Vec::new();
    for i in &d.instances {
        for s in &d.solvers {
            if let Some(g) = d.by.get(&(i.clone(), s.clone())) {
                summary.push(summarize(g, i, s));
            }
        }
    }
    let sum_csv = o.dir.join("summary.csv");
    write_csv(&sum_csv, &summary)?;
    o.tex_tables.push((
        "summary.tex",
        latex::summary_table(&summary, &d.objective()),
    ));
    o.files.push(sum_csv);
    let md = &mut o.md;
    let _ = writeln!(md, "## Per instance and solver\n");
    let _ = writeln!(
        md,
        "| instance | solver | ok/runs | mean | median | best | std | 95 % CI | red. % | air red. % | path red. % | time red. % | lifts | tool ch. | mach. time s | gap bks % | wall s |"
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for s in &summary {
        let _ = writeln!(
            md,
            "| {} | {} | {}/{} | {} | {} | {} | {} | [{}, {}] | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            s.instance,
            s.solver,
            s.feasible,
            s.runs,
            fmt(s.mean),
            fmt(s.median),
            fmt(s.best),
            fmt(s.std),
            fmt(s.ci95_lo),
            fmt(s.ci95_hi),
            fmt(s.reduction_pct),
            fmt(s.air_reduction_pct),
            fmt(s.path_reduction_pct),
            fmt(s.time_reduction_pct),
            fmt(s.lifts),
            fmt(s.tool_changes),
            fmt(s.machining_time),
            fmt(s.gap_bks_pct),
            fmt(s.wall_runtime_s)
        );
    }
    let _ = writeln!(md);
    Ok(())
}

/// The overview per solver over all instances; returns its lines for `solvers.tex`.
fn solvers_section(md: &mut String, d: &Data) -> Vec<latex::SolverLine> {
    let _ = writeln!(md, "## Per solver (all instances)\n");
    let _ = writeln!(
        md,
        "| solver | ok/runs | mean red. % | median red. % | mean lifts | mean tool ch. | mean wall s |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    let mut overview = Vec::new();
    for s in &d.solvers {
        let g: Vec<&Row> = d.rows.iter().filter(|r| &r.solver_id == s).collect();
        let ok: Vec<&&Row> = g.iter().filter(|r| r.feasible).collect();
        let red = opt(&ok.iter().map(|r| r.reduction_pct).collect::<Vec<_>>());
        let lifts: Vec<f64> = ok
            .iter()
            .filter_map(|r| r.lifts.map(|x| x as f64))
            .collect();
        let tc: Vec<f64> = ok
            .iter()
            .filter_map(|r| r.tool_changes.map(|x| x as f64))
            .collect();
        let wall: Vec<f64> = g.iter().map(|r| r.wall_elapsed_s).collect();
        let _ = writeln!(
            md,
            "| {s} | {}/{} | {} | {} | {} | {} | {} |",
            ok.len(),
            g.len(),
            fmt(mean(&red)),
            fmt(median(&red)),
            fmt(mean(&lifts)),
            fmt(mean(&tc)),
            fmt(mean(&wall))
        );
        overview.push(latex::SolverLine {
            solver: s.clone(),
            ok: ok.len(),
            runs: g.len(),
            mean_red: mean(&red),
            median_red: median(&red),
            lifts: mean(&lifts),
            tool_changes: mean(&tc),
            wall: mean(&wall),
        });
    }
    let _ = writeln!(md);
    overview
}

/// One paired comparison of `x` (solver) with `y` (reference); the Holm columns are filled later.
fn test_row(instance: &str, solver: &str, reference: &str, x: &[f64], y: &[f64]) -> TestRow {
    let w = wilcoxon_signed_rank(x, y);
    let diff: Vec<f64> = x.iter().zip(y).map(|(a, b)| a - b).collect();
    TestRow {
        instance: instance.into(),
        solver: solver.into(),
        reference: reference.into(),
        pairs: x.len(),
        mean_diff: mean(&diff),
        v: w.v,
        p: w.p,
        p_holm: f64::NAN,
        verdict: String::new(),
    }
}

/// Paired Wilcoxon tests of every solver against the reference, per instance and pooled
/// (`wilcoxon.csv`, `wilcoxon.tex`; `solvers.tex` from `overview`).
fn wilcoxon_section(o: &mut Out, d: &Data, overview: Vec<latex::SolverLine>) -> Result<()> {
    let reference = &d.reference;
    let mut tests: Vec<TestRow> = Vec::new();
    let mut pooled: Vec<TestRow> = Vec::new();
    for s in d.solvers.iter().filter(|s| *s != reference) {
        let (mut px, mut py) = (Vec::new(), Vec::new());
        for i in &d.instances {
            let a = d.cost_of(i, s);
            let b = d.cost_of(i, reference);
            let (mut x, mut y) = (Vec::new(), Vec::new());
            for (rep, c) in &a {
                if let Some(r) = b.get(rep) {
                    x.push(*c);
                    y.push(*r);
                }
            }
            px.extend(&x);
            py.extend(&y);
            if !x.is_empty() {
                tests.push(test_row(i, s, reference, &x, &y));
            }
        }
        if !px.is_empty() {
            pooled.push(test_row("ALL", s, reference, &px, &py));
        }
    }
    for group in [&mut tests, &mut pooled] {
        let adj = holm(&group.iter().map(|t| t.p).collect::<Vec<_>>());
        for (t, a) in group.iter_mut().zip(adj) {
            t.p_holm = a;
            t.verdict = if a < 0.05 {
                if t.mean_diff < 0.0 { "better" } else { "worse" }.into()
            } else {
                "n.s.".into()
            };
        }
    }
    let md = &mut o.md;
    let _ = writeln!(
        md,
        "## Paired Wilcoxon signed-rank tests against `{reference}`\n\nPairs are replicates of the same \
         instance; two-sided; Holm correction over all per-instance comparisons (pooled rows corrected \
         among themselves). `better` = lower cost than the reference at the 5 % level.\n"
    );
    let _ = writeln!(
        md,
        "| instance | solver | pairs | mean diff | V | p | p (Holm) | verdict |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for t in pooled.iter().chain(&tests) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            t.instance,
            t.solver,
            t.pairs,
            fmt(t.mean_diff),
            t.v,
            fmt(t.p),
            fmt(t.p_holm),
            t.verdict
        );
    }
    let _ = writeln!(md);
    let tests_csv = o.dir.join("wilcoxon.csv");
    write_csv(
        &tests_csv,
        &pooled.iter().chain(&tests).cloned().collect::<Vec<_>>(),
    )?;
    o.tex_tables
        .push(("solvers.tex", latex::solver_table(&overview)));
    o.tex_tables.push((
        "wilcoxon.tex",
        latex::wilcoxon_table(&pooled, &tests, reference),
    ));
    o.files.push(tests_csv);
    Ok(())
}

/// The Friedman test over instances (blocks) with the solvers feasible on every instance
/// (`friedman.csv`, `friedman.tex`).
fn friedman_section(o: &mut Out, d: &Data) -> Result<()> {
    let complete: Vec<&String> = d
        .solvers
        .iter()
        .filter(|s| d.instances.iter().all(|i| !d.cost_of(i, s).is_empty()))
        .collect();
    let _ = writeln!(o.md, "## Friedman test over instances\n");
    let blocks: Vec<Vec<f64>> = d
        .instances
        .iter()
        .map(|i| {
            complete
                .iter()
                .map(|s| mean(&d.cost_of(i, s).values().copied().collect::<Vec<_>>()))
                .collect()
        })
        .collect();
    let Some(f) = friedman(&blocks) else {
        let _ = writeln!(
            o.md,
            "Not enough data (needs at least 2 instances and 2 solvers feasible on all of them)."
        );
        let _ = writeln!(o.md);
        return Ok(());
    };
    let _ = writeln!(
        o.md,
        "Blocks: {} instances (mean cost per instance); treatments: {} solvers with a feasible result on \
         every instance. Friedman chi-squared = {}, df = {}, p = {}.\n",
        blocks.len(),
        complete.len(),
        fmt(f.statistic),
        f.df,
        fmt(f.p)
    );
    let mut order: Vec<usize> = (0..complete.len()).collect();
    order.sort_by(|&a, &b| f.avg_ranks[a].total_cmp(&f.avg_ranks[b]));
    let _ = writeln!(o.md, "| solver | average rank (1 = best) |\n|---|---|");
    let mut csv_rows = Vec::new();
    for k in order.iter().copied() {
        let _ = writeln!(o.md, "| {} | {} |", complete[k], fmt(f.avg_ranks[k]));
        csv_rows.push((complete[k].clone(), f.avg_ranks[k]));
    }
    let p = o.dir.join("friedman.csv");
    let mut w = csv::Writer::from_writer(Vec::new());
    let _ = w.write_record(["solver", "average_rank", "statistic", "df", "p"]);
    o.tex_tables.push((
        "friedman.tex",
        latex::friedman_table(&csv_rows, f.statistic, f.df, f.p, blocks.len()),
    ));
    for (s, r) in csv_rows {
        let _ = w.write_record([
            s,
            r.to_string(),
            f.statistic.to_string(),
            f.df.to_string(),
            f.p.to_string(),
        ]);
    }
    cellseq::files::write_atomic(&p, &w.into_inner().unwrap_or_default())?;
    o.files.push(p);
    let _ = writeln!(o.md);
    Ok(())
}

/// The value of a paper figure's metric in one trial.
fn metric(r: &Row, metric: &str) -> Option<f64> {
    match metric {
        "reduction_pct" => r.reduction_pct,
        "air_reduction_pct" => r.air_reduction_pct,
        "path_reduction_pct" => r.path_reduction_pct,
        "time_reduction_pct" => r.time_reduction_pct,
        "lifts" => r.lifts.map(|x| x as f64),
        "tool_changes" => r.tool_changes.map(|x| x as f64),
        "machining_time" => r.machining_time,
        "air_length" => r.air_length,
        _ => None,
    }
}

/// The paper's figures beside ours: each figure's solver, else the solver with the largest
/// mean reduction.
fn paper_section(md: &mut String, d: &Data, paper: &Paper) {
    let _ = writeln!(
        md,
        "## Paper figures beside ours\n\nSource: {}\n",
        paper.source
    );
    let _ = writeln!(md, "| figure | paper | ours | solver |\n|---|---|---|---|");
    let best_solver = d
        .solvers
        .iter()
        .filter(|s| **s != "as-given")
        .map(|s| {
            let red: Vec<f64> = d
                .rows
                .iter()
                .filter(|r| &r.solver_id == s)
                .filter_map(|r| r.reduction_pct)
                .collect();
            (s.clone(), mean(&red))
        })
        .filter(|(_, m)| m.is_finite())
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|x| x.0);
    for f in &paper.figures {
        let solver = f
            .solver
            .clone()
            .or_else(|| best_solver.clone())
            .unwrap_or_default();
        let vals: Vec<f64> = d
            .rows
            .iter()
            .filter(|r| r.solver_id == solver && r.feasible && super::paper::in_figures(r))
            .filter_map(|r| metric(r, &f.metric))
            .collect();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            f.label,
            f.value,
            fmt(mean(&vals)),
            solver
        );
    }
    let _ = writeln!(md);
}

/// Writes the LaTeX (booktabs) versions of the tables and links them.
fn latex_section(o: &mut Out) -> Result<()> {
    for (name, t) in &o.tex_tables {
        let p = o.dir.join(name);
        cellseq::files::write_atomic(&p, latex::render(t).as_bytes())?;
        o.files.push(p);
    }
    let _ = writeln!(
        o.md,
        "LaTeX (booktabs) versions of the tables: {}.\n",
        o.tex_tables
            .iter()
            .map(|(n, _)| format!("[{n}]({n})"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Ok(())
}

/// Draws the figures into `plots/` and shows them.
fn plots_section(o: &mut Out, d: &Data, traces: &[TraceRow]) -> Result<()> {
    let plot_dir = o.dir.join("plots");
    std::fs::create_dir_all(&plot_dir).map_err(|e| Error::io(plot_dir.display().to_string(), e))?;
    let plots_written = figures::write_figures(
        &plot_dir,
        &figures::FigureData {
            rows: d.rows,
            traces,
            instances: &d.instances,
            solvers: &d.solvers,
            reference: &d.reference,
        },
    )
    .map_err(|e| {
        Error::invalid(
            plot_dir.display().to_string(),
            format!("plotting failed: {e}"),
        )
    })?;
    let _ = writeln!(
        o.md,
        "## Plots\n\nEach figure is written as PNG (shown), SVG (text kept as text) and PDF (text in \
         DejaVu Sans, the font embedded: for papers).\n"
    );
    for p in plots_written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "png"))
    {
        let name = p.file_name().and_then(|s| s.to_str()).unwrap_or("");
        let svg = name.replace(".png", ".svg");
        let pdf = name.replace(".png", ".pdf");
        let _ = writeln!(
            o.md,
            "![{name}](plots/{name})  \n[SVG](plots/{svg}) · [PDF](plots/{pdf})\n"
        );
    }
    o.files.extend(plots_written);
    Ok(())
}

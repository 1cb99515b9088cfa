//! `check`, `run`, `merge`, `report`: the research harness (see `cellseq_lab`).

use anyhow::{Context as _, Result, bail};
use cellseq_lab::plan::{Limits, Plan};
use cellseq_lab::run::{RunOptions, run_plan};
use cellseq_lab::{report, results};
use clap::Args;
use std::path::{Path, PathBuf};

/// Caps on the size of a plan (the same for `check` and `run`).
#[derive(Args, Debug, Clone, Copy)]
pub struct LimitArgs {
    /// Refuse plans with more trials than this (default 100000, or the plan's `max_trials`).
    #[arg(long, value_name = "N", value_parser = super::ranges::max_trials)]
    max_trials: Option<u64>,
    /// Stop a file pattern that looks at more directory entries than this (default 100000, or
    /// the plan's `max_files`).
    #[arg(long, value_name = "N", value_parser = super::ranges::max_files)]
    max_files: Option<u64>,
}

impl LimitArgs {
    fn limits(self) -> Limits {
        Limits {
            max_trials: self.max_trials,
            max_files: self.max_files,
        }
    }
}

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Experiment plan (TOML), or a portfolio file of the `auto` solver (one with `[[rule]]`).
    plan: PathBuf,
    /// Shards the plan will run as (for the time-per-shard estimate).
    #[arg(long, default_value_t = 1, value_parser = super::ranges::shards)]
    shards: usize,
    /// Threads per shard (for the estimate; default: all cores here).
    #[arg(long, value_parser = super::ranges::threads)]
    threads: Option<usize>,
    #[command(flatten)]
    limits: LimitArgs,
}

#[derive(Args, Debug)]
pub struct RunArgs {
    /// Experiment plan (TOML).
    plan: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = super::ranges::threads)]
    threads: Option<usize>,
    /// Run only shard I of N (1-based), e.g. `--shard 2/8`.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Output directory (default: results/<plan name>).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Testing hook: sleep this many milliseconds after each trial.
    #[arg(long, hide = true, default_value_t = 0, value_parser = super::ranges::throttle_ms)]
    throttle_ms: u64,
    #[command(flatten)]
    limits: LimitArgs,
}

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Directories holding results*.csv / traces*.csv / manifest*.json.
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output directory (default: the first directory).
    #[arg(long)]
    out: Option<PathBuf>,
}

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Results directory (results.csv, traces.csv, manifest.json).
    dir: PathBuf,
    /// Report directory (default: DIR/report).
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Parses `I/N`.
pub fn parse_shard(s: &str) -> Result<(usize, usize)> {
    let Some((i, n)) = s.split_once('/') else {
        bail!("--shard '{s}': expected I/N, e.g. 1/4");
    };
    let (Ok(i), Ok(n)) = (i.trim().parse::<usize>(), n.trim().parse::<usize>()) else {
        bail!("--shard '{s}': expected I/N with whole numbers, e.g. 1/4");
    };
    if n == 0 || i == 0 || i > n {
        bail!("--shard '{s}': I must lie in 1..=N");
    }
    Ok((i, n))
}

pub fn check(a: CheckArgs) -> Result<()> {
    if cellseq::registry::is_portfolio_file(&a.plan) {
        return check_portfolio(&a.plan);
    }
    let plan = Plan::load_with(&a.plan, a.limits.limits())?;
    say!(
        "ok: {} instances x {} solvers x {} replicates = {} trials (reference {})",
        plan.instances.len(),
        plan.solvers.len(),
        plan.file.replicates,
        plan.trial_count(),
        plan.reference
    );
    let threads = a.threads.unwrap_or_else(rayon::current_num_threads);
    let e = cellseq_lab::estimate::estimate(&plan, a.shards, threads, || {
        cellseq_lab::run::calibrate()
    })?;
    say!("{e}");
    Ok(())
}

/// `check` on a portfolio file of the `auto` solver: validated as `solve` and `run` would.
fn check_portfolio(path: &Path) -> Result<()> {
    let text = path
        .to_str()
        .with_context(|| format!("{}: the path is not UTF-8", path.display()))?;
    let names = cellseq::registry::validate_portfolio(text)?;
    say!(
        "ok: portfolio with {} rules ({})",
        names.len(),
        names.join(", ")
    );
    Ok(())
}

/// Runs a plan and prints a summary.
pub fn execute(plan: &Plan, opts: &RunOptions) -> Result<()> {
    let s = run_plan(plan, opts)?;
    let beyond = if s.out_of_range > 0 {
        format!(
            ", {} not run: out of their solver's range (the plan's max_cells)",
            s.out_of_range
        )
    } else {
        String::new()
    };
    say!(
        "{} trials: {} run now, {} already done, {} without a feasible result{beyond}",
        s.planned,
        s.ran,
        s.skipped,
        s.failed
    );
    say!("results   {}", s.files.results.display());
    say!("traces    {}", s.files.traces.display());
    say!("manifest  {}", s.files.manifest.display());
    Ok(())
}

pub fn run(a: RunArgs) -> Result<()> {
    let plan = Plan::load_with(&a.plan, a.limits.limits())?;
    let shard = a.shard.as_deref().map(parse_shard).transpose()?;
    let out = a
        .out
        .unwrap_or_else(|| Path::new("results").join(&plan.file.name));
    let opts = RunOptions {
        threads: a.threads,
        shard,
        out,
        progress: true,
        throttle_ms: a.throttle_ms,
        replace_foreign: false,
    };
    execute(&plan, &opts)
}

pub fn merge(a: MergeArgs) -> Result<()> {
    for d in &a.dirs {
        if !d.is_dir() {
            bail!("{}: not a directory", d.display());
        }
    }
    let out = a.out.unwrap_or_else(|| a.dirs[0].clone());
    refuse_foreign_results(&out, &a.dirs)?;
    let (rows, dups) = results::merge(&a.dirs, &out)?;
    say!(
        "merged {rows} trials ({dups} duplicates dropped) into {}",
        out.join("results.csv").display()
    );
    Ok(())
}

/// Tables `merge` writes (and reads, with any suffix after the stem).
const MERGED_TABLES: [&str; 5] = [
    "results.csv",
    "traces.csv",
    "layers.csv",
    "instances.csv",
    "manifest.json",
];

/// Refuses a `merge --out` directory that holds results of its own without being one of the
/// merged directories: its tables would be replaced by tables that do not hold its rows.
/// One of the inputs (the default: the first) is fine: its rows are read first and kept.
fn refuse_foreign_results(out: &Path, dirs: &[PathBuf]) -> Result<()> {
    if dirs.iter().any(|d| cellseq::files::same_file(d, out)) {
        return Ok(());
    }
    if let Some(t) = MERGED_TABLES
        .iter()
        .find(|t| std::fs::symlink_metadata(out.join(t)).is_ok())
    {
        bail!(
            "{}: holds results of its own ({t}) and is not among the merged directories; its \
             tables would be replaced without its rows: list it among the directories to merge \
             it too, or choose another --out",
            out.display()
        );
    }
    Ok(())
}

pub fn report(a: ReportArgs) -> Result<()> {
    let out = a.out.unwrap_or_else(|| a.dir.join("report"));
    let r = report::report(&a.dir, &out)?;
    say!("report    {}", r.markdown.display());
    say!("plots     {}", out.join("plots").display());
    Ok(())
}

//! Running a plan: instance preparation, machine calibration, parallel seeded trials with
//! crash-safe appending and resume, and the manifest.

use super::layers::{Breakdown, breakdown};
use super::plan::{Plan, Source, Trial};
use super::results::{
    Appender, InstanceRow, LayerRow, OutFiles, Row, TraceRow, read_lenient, write_table,
};
use cellseq::error::{Error, Result};
use cellseq::formats::load_instance;
use cellseq::model::{Instance, Objective};
use cellseq::{Budget, Solve, SolverKind, Trace};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Most worker threads a run may use: each holds a solver's memory, and more threads than
/// cores only add memory (`--threads`).
pub const MAX_THREADS: usize = 1024;

/// The start of the `error` of a trial that was not run because the instance lies beyond the
/// solver's `[max_cells]` (its row is not counted as a failure).
pub const OUT_OF_RANGE: &str = "out of range:";

/// How to run a plan.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Worker threads (default: all cores).
    pub threads: Option<usize>,
    /// `(I, N)`: run only shard I (1-based) of N.
    pub shard: Option<(usize, usize)>,
    /// Output directory.
    pub out: PathBuf,
    /// Show a progress bar (only drawn on a terminal).
    pub progress: bool,
    /// Sleep this long after each trial (testing hook for interruption tests).
    pub throttle_ms: u64,
    /// When the output already holds trials of another plan: discard them (true, used by the
    /// demo) or refuse to run (false), so results are never mixed or silently lost.
    pub replace_foreign: bool,
}

/// What a run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// Trials of this shard.
    pub planned: usize,
    /// Trials skipped because their key was already in the results.
    pub skipped: usize,
    /// Trials run now.
    pub ran: usize,
    /// Trials that ended infeasible or in an error.
    pub failed: usize,
    /// Trials not run because the instance lies beyond the solver's `[max_cells]` (not
    /// counted in `failed`).
    pub out_of_range: usize,
    /// Files written.
    pub files: OutFiles,
}

/// An instance ready for trials.
pub struct Prepared {
    /// The instance.
    pub instance: Instance,
    /// Its objective.
    pub objective: Objective,
    /// as-given report: (cost, air length, machining time, path length).
    pub as_given: Option<(f64, f64, f64, f64)>,
    /// Best-known value and whether proven optimal.
    pub bks: Option<(f64, bool)>,
    /// Precedence density.
    pub density: f64,
    /// Per-layer breakdown of the as-given order (geometric instances).
    pub as_given_layers: Option<Breakdown>,
}

/// Loads or generates an instance of the plan and computes its baseline and features.
pub fn prepare(plan: &Plan, idx: usize) -> Result<Prepared> {
    let r = &plan.instances[idx];
    let (instance, bks) = match &r.source {
        Source::File(p) => (load_instance(p)?, checked_best_known(p)),
        Source::Generated { kind, params, seed } => {
            let inst = cellseq::generate::generate(kind, params, *seed).map_err(|e| {
                Error::invalid(
                    &plan.path,
                    format!(
                        "instance {} (generator {kind}, {}, seed {seed}): {e}",
                        r.id,
                        super::plan::grid_point(params)
                    ),
                )
            })?;
            (inst, None)
        }
    };
    let objective = match plan.objective {
        _ if instance.is_matrix() => Objective::Matrix,
        Some(Objective::Matrix) | None => instance.default_objective(),
        Some(o) => o,
    };
    let as_given = Solve::new(SolverKind::AsGiven)
        .seed(0)
        .objective(objective)
        .run(&instance)
        .ok();
    let as_given_layers = as_given
        .as_ref()
        .and_then(|r| breakdown(&instance, &r.sequence));
    let as_given = as_given.map(|r| {
        (
            r.report.cost,
            r.report.air_length,
            r.report.machining_time,
            r.report.path_length,
        )
    });
    let density = instance.precedence_density();
    Ok(Prepared {
        instance,
        objective,
        as_given,
        bks,
        density,
        as_given_layers,
    })
}

/// The best-known value beside instance file `p`; a bad `bks.csv` row is ignored with a
/// warning naming the file and line.
fn checked_best_known(p: &Path) -> Option<(f64, bool)> {
    cellseq::formats::best_known_checked(p).unwrap_or_else(|e| {
        eprintln!("warning: {e}; the best-known value is ignored");
        None
    })
}

/// How much less `x` is than `base`, in percent; none when not finite.
fn pct_less(base: Option<f64>, x: Option<f64>) -> Option<f64> {
    match (base, x) {
        (Some(b), Some(x)) if b.abs() > 0.0 => Some(100.0 * (b - x) / b).filter(|v| v.is_finite()),
        _ => None,
    }
}

/// The gap of `x` above `reference` in percent; none when not finite (a best-known value of
/// 1e-320 would make it infinite).
fn gap(x: Option<f64>, reference: Option<f64>) -> Option<f64> {
    match (x, reference) {
        (Some(x), Some(r)) if r.abs() > 0.0 => Some(100.0 * (x - r) / r).filter(|v| v.is_finite()),
        _ => None,
    }
}

fn kv(m: &BTreeMap<String, String>) -> String {
    m.iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(";")
}

/// The `instances.csv` row of a prepared instance.
pub fn instance_row(id: &str, inst: &Instance) -> InstanceRow {
    let mut order: Vec<String> = inst.tools.iter().map(|t| t.id.clone()).collect();
    for c in &inst.cells {
        if !order.contains(&c.tool) {
            order.push(c.tool.clone());
        }
    }
    let per_tool: Vec<String> = order
        .iter()
        .filter_map(|t| {
            let k = inst.cells.iter().filter(|c| &c.tool == t).count();
            (k > 0).then(|| format!("{}:{k}", if t.is_empty() { "-" } else { t }))
        })
        .collect();
    let layers: BTreeSet<u32> = inst.cells.iter().map(|c| c.layer).collect();
    InstanceRow {
        instance: id.to_string(),
        generator: inst.meta.generator.clone().unwrap_or_else(|| "file".into()),
        n: inst.n(),
        tools: inst.used_tools().len(),
        cells_per_tool: per_tool.join(" "),
        layers: layers.len(),
        comment: inst.meta.comment.clone().unwrap_or_default(),
    }
}

/// What one trial produced: its result row, its anytime trace and its per-layer rows.
pub type TrialOutput = (Row, Vec<TraceRow>, Vec<LayerRow>);

/// Runs one trial; never fails: errors, refusals and panics become an infeasible row.
pub fn run_trial(plan: &Plan, prep: &Prepared, t: &Trial, calib_s: f64) -> TrialOutput {
    let iref = &plan.instances[t.instance];
    let sref = &plan.solvers[t.solver];
    let inst = &prep.instance;
    let b = &plan.file.budget;
    // checked against the calibration when the run started (`run_plan`)
    let time_limit = super::plan::trial_seconds(b, calib_s).unwrap_or(b.seconds);
    let budget = Budget {
        time_limit: time_limit.map(Duration::from_secs_f64),
        max_evals: b.evaluations,
    };
    let mut trace = Trace::default();
    let start = Instant::now();
    let beyond = plan.max_cells(&sref.name).filter(|&m| inst.n() as u64 > m);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if let Some(m) = beyond {
            return Err(cellseq::Error::Param(format!(
                "{OUT_OF_RANGE} {} cells, more than the plan's max_cells.{} = {m}; not run",
                inst.n(),
                sref.name
            )));
        }
        sref.name.parse::<SolverKind>().and_then(|kind| {
            Solve::new(kind)
                .params_text(&sref.params)
                .seed(t.seed)
                .budget(budget)
                .objective(prep.objective)
                .observe(&mut trace)
                .run(inst)
        })
    }));
    let wall = start.elapsed().as_secs_f64();
    let full_params = cellseq::registry::find(&sref.name)
        .and_then(|info| info.check_params(&sref.params))
        .map(|p| kv(p.values()))
        .unwrap_or_else(|_| kv(&sref.params));
    let mut row = Row {
        run_key: t.key.clone(),
        trial: t.index,
        instance: iref.id.clone(),
        generator: inst.meta.generator.clone().unwrap_or_else(|| "file".into()),
        gen_params: kv(&inst.meta.params),
        n: inst.n(),
        tools: inst.used_tools().len(),
        precedence_density: prep.density,
        solver: sref.name.clone(),
        solver_id: sref.id.clone(),
        params: full_params,
        replicate: t.replicate,
        seed: t.seed,
        budget: b.label(),
        objective: prep.objective.name().into(),
        as_given_cost: prep.as_given.map(|a| a.0),
        best_known: prep.bks.map(|b| b.0),
        wall_elapsed_s: wall,
        ..Row::default()
    };
    let mut layer_rows = Vec::new();
    match result {
        Ok(Ok(r)) => {
            if let Some(b) = breakdown(inst, &r.sequence) {
                for l in &b.layers {
                    let base = prep
                        .as_given_layers
                        .as_ref()
                        .and_then(|a| a.layers.iter().find(|x| x.layer == l.layer));
                    layer_rows.push(LayerRow {
                        run_key: t.key.clone(),
                        trial: t.index,
                        instance: iref.id.clone(),
                        solver_id: sref.id.clone(),
                        replicate: t.replicate,
                        layer: l.layer,
                        cells: l.cells,
                        cut_length: l.cut_length,
                        air_length: l.air_length,
                        path_length: l.cut_length + l.air_length,
                        lifts: l.lifts,
                        tool_changes: l.tool_changes,
                        machining_time: l.machining_time,
                        as_given_path_length: base.map(|a| a.cut_length + a.air_length),
                        as_given_lifts: base.map(|a| a.lifts),
                        as_given_machining_time: base.map(|a| a.machining_time),
                    });
                }
            }
            let rep = r.report;
            row.feasible = true;
            row.cost = Some(rep.cost);
            row.air_length = Some(rep.air_length);
            row.path_length = Some(rep.path_length);
            // matrix instances have no lifts, tools or machine: blanks, not zeros
            if !inst.is_matrix() {
                row.lifts = Some(rep.lifts);
                row.tool_changes = Some(rep.tool_changes);
                row.machining_time = Some(rep.machining_time);
            }
            row.reduction_pct = pct_less(row.as_given_cost, row.cost);
            if !inst.is_matrix() {
                row.air_reduction_pct = pct_less(prep.as_given.map(|a| a.1), row.air_length);
                row.path_reduction_pct = pct_less(prep.as_given.map(|a| a.3), row.path_length);
                row.time_reduction_pct = pct_less(prep.as_given.map(|a| a.2), row.machining_time);
            }
            row.gap_bks_pct = gap(row.cost, row.best_known);
            let proven_bks = prep.bks.filter(|b| b.1).map(|b| b.0);
            row.lower_bound = match (r.lower_bound, proven_bks) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            if r.proven_optimal {
                row.lower_bound = Some(rep.cost);
            }
            row.gap_lb_pct = gap(row.cost, row.lower_bound);
            row.proven_optimal = r.proven_optimal;
            row.evaluations = r.evaluations;
        }
        Ok(Err(e)) => row.error = e.to_string(),
        Err(p) => {
            let msg = p
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            row.error = format!("solver '{}' panicked: {msg}", sref.name);
        }
    }
    let traces = trace
        .points
        .iter()
        .map(|p| TraceRow {
            run_key: t.key.clone(),
            trial: t.index,
            instance: iref.id.clone(),
            solver_id: sref.id.clone(),
            replicate: t.replicate,
            evaluations: p.evaluations,
            wall_elapsed_s: p.elapsed_s,
            best: p.best,
        })
        .collect();
    (row, traces, layer_rows)
}

/// Seconds of the calibration kernel: the median of 5 greedy solves of a fixed generated
/// instance (uniform, n = 2000, 3 tools). Budgets in calibration units scale with it.
pub fn calibrate() -> Result<f64> {
    let params: BTreeMap<String, String> = [("n", "2000"), ("tools", "3")]
        .into_iter()
        .map(|(k, v)| (k.into(), v.into()))
        .collect();
    let inst = cellseq::generate::generate("uniform", &params, 12345)?;
    let mut times = Vec::new();
    for _ in 0..5 {
        let t = Instant::now();
        Solve::new(SolverKind::Greedy)
            .objective(Objective::Time)
            .run(&inst)?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok(times[2])
}

fn command_output(cmd: &str, args: &[&str], dir: &Path) -> Option<String> {
    let out = std::process::Command::new(cmd)
        .args(args)
        .current_dir(dir)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string())
}

/// Writes the manifest of a run.
pub fn write_manifest(
    plan: &Plan,
    opts: &RunOptions,
    files: &OutFiles,
    threads: usize,
    calib: f64,
    summary: Option<&RunSummary>,
) -> Result<()> {
    let dir = std::env::current_dir().unwrap_or_else(|_| PathBuf::from("."));
    let mut m = serde_json::json!({
        "format": "cellseq-manifest/1",
        "crate_version": env!("CARGO_PKG_VERSION"),
        "git_commit": command_output("git", &["rev-parse", "HEAD"], &dir)
            .or_else(|| command_output("git", &["rev-parse", "HEAD"], Path::new(env!("CARGO_MANIFEST_DIR")))),
        "plan_name": plan.file.name,
        "plan_hash": plan.hash,
        "plan": plan.text,
        "reference": plan.reference,
        "rustc_version": command_output("rustc", &["--version"], &dir),
        "cpu_model": cpu_model(),
        "threads": threads,
        "calibration_seconds": calib,
        "shard": opts.shard.map(|(i, n)| format!("{i}/{n}")),
        "trials_planned": summary.map(|s| s.planned),
        "trials_ran": summary.map(|s| s.ran),
        "trials_skipped": summary.map(|s| s.skipped),
        "trials_failed": summary.map(|s| s.failed),
        "trials_out_of_range": summary.map(|s| s.out_of_range),
        "complete": summary.is_some(),
    });
    super::provenance::stamp(&mut m, &files.manifest, summary.is_some());
    cellseq::files::write_atomic(
        &files.manifest,
        serde_json::to_string_pretty(&m)
            .unwrap_or_default()
            .as_bytes(),
    )
}

/// Resume: keeps the complete rows of this plan (`order`: run key -> trial), once each, and
/// drops torn lines and the traces and layer rows of unfinished trials. Returns the run keys of
/// the trials done. Rows of another plan are refused unless `replace_foreign`.
fn resume(
    files: &OutFiles,
    order: &HashMap<String, usize>,
    replace_foreign: bool,
) -> Result<BTreeSet<String>> {
    let (mut done_rows, torn) = read_lenient::<Row>(&files.results)?;
    let before = done_rows.len();
    let foreign = done_rows
        .iter()
        .filter(|r| !order.contains_key(&r.run_key))
        .count();
    if foreign > 0 && !replace_foreign {
        return Err(Error::invalid(
            files.results.display().to_string(),
            format!(
                "{foreign} of its {before} trials do not belong to this plan (another plan, seed, \
                 budget or shard wrote them); choose another --out directory"
            ),
        ));
    }
    let mut seen = BTreeSet::new();
    done_rows.retain(|r| order.contains_key(&r.run_key) && seen.insert(r.run_key.clone()));
    let (mut done_traces, torn_t) = read_lenient::<TraceRow>(&files.traces)?;
    let before_t = done_traces.len();
    done_traces.retain(|t| seen.contains(&t.run_key));
    if torn || done_rows.len() != before {
        write_table(&files.results, &done_rows)?;
    }
    if torn_t || done_traces.len() != before_t {
        write_table(&files.traces, &done_traces)?;
    }
    let (mut done_layers, torn_l) = read_lenient::<LayerRow>(&files.layers)?;
    let before_l = done_layers.len();
    done_layers.retain(|l| seen.contains(&l.run_key));
    if torn_l || done_layers.len() != before_l {
        write_table(&files.layers, &done_layers)?;
    }
    Ok(seen)
}

/// The instance table: the old one plus the instances prepared now, in plan order.
fn write_instance_table(
    plan: &Plan,
    files: &OutFiles,
    prepared: &HashMap<usize, Prepared>,
) -> Result<()> {
    let (mut rows, _) = read_lenient::<InstanceRow>(&files.instances)?;
    for (&i, p) in prepared {
        let id = &plan.instances[i].id;
        if !rows.iter().any(|r| &r.instance == id) {
            rows.push(instance_row(id, &p.instance));
        }
    }
    let pos: HashMap<&str, usize> = plan
        .instances
        .iter()
        .enumerate()
        .map(|(i, r)| (r.id.as_str(), i))
        .collect();
    rows.retain(|r| pos.contains_key(r.instance.as_str()));
    rows.sort_by_key(|r| pos[r.instance.as_str()]);
    write_table(&files.instances, &rows)
}

/// Runs `trials` in parallel (inside the caller's thread pool), appending each trial's traces,
/// layer rows and result row as it completes. Returns the numbers of infeasible trials and of
/// trials out of their solver's range.
fn run_trials(
    plan: &Plan,
    opts: &RunOptions,
    files: &OutFiles,
    trials: &[Trial],
    prepared: &HashMap<usize, Prepared>,
    calib: f64,
) -> Result<(usize, usize)> {
    let writer = Mutex::new((
        Appender::open::<Row>(&files.results)?,
        Appender::open::<TraceRow>(&files.traces)?,
        Appender::open::<LayerRow>(&files.layers)?,
    ));
    let bar = if opts.progress && std::io::stderr().is_terminal() {
        ProgressBar::new(trials.len() as u64)
    } else {
        ProgressBar::with_draw_target(Some(trials.len() as u64), ProgressDrawTarget::hidden())
    };
    bar.set_style(
        ProgressStyle::with_template(
            "{bar:40} {pos}/{len} trials  {elapsed_precise} elapsed, ETA {eta_precise}  {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let failed = std::sync::atomic::AtomicUsize::new(0);
    let out_of_range = std::sync::atomic::AtomicUsize::new(0);
    let res: Result<()> = trials.par_iter().try_for_each(|t| {
        let prep = &prepared[&t.instance];
        let (row, traces, layers) = run_trial(plan, prep, t, calib);
        if row.error.starts_with(OUT_OF_RANGE) {
            out_of_range.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        } else if !row.feasible {
            failed.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        }
        {
            let mut w = writer
                .lock()
                .map_err(|_| Error::Param("writer lock poisoned".into()))?;
            // traces first: a trial counts as done only once its result row is there
            w.1.append(&traces)?;
            w.2.append(&layers)?;
            w.0.append(&[row])?;
        }
        bar.inc(1);
        if opts.throttle_ms > 0 {
            std::thread::sleep(Duration::from_millis(opts.throttle_ms));
        }
        Ok(())
    });
    bar.finish_and_clear();
    res?;
    drop(writer);
    Ok((failed.into_inner(), out_of_range.into_inner()))
}

/// Rewrites the tables in plan order (one row per trial), so that the files do not depend on
/// thread scheduling.
fn finalise(files: &OutFiles) -> Result<()> {
    let (mut rows, _) = read_lenient::<Row>(&files.results)?;
    let mut seen = BTreeSet::new();
    rows.retain(|r| seen.insert(r.run_key.clone()));
    rows.sort_by_key(|r| r.trial);
    write_table(&files.results, &rows)?;
    let (mut traces, _) = read_lenient::<TraceRow>(&files.traces)?;
    traces.sort_by_key(|t| t.trial);
    write_table(&files.traces, &traces)?;
    let (mut layers, _) = read_lenient::<LayerRow>(&files.layers)?;
    let mut seen_layer = BTreeSet::new();
    layers.retain(|l| seen.contains(&l.run_key) && seen_layer.insert((l.run_key.clone(), l.layer)));
    layers.sort_by_key(|l| (l.trial, l.layer));
    write_table(&files.layers, &layers)
}

/// Runs (or resumes) a plan into `opts.out`.
pub fn run_plan(plan: &Plan, opts: &RunOptions) -> Result<RunSummary> {
    if let Some((i, n)) = opts.shard
        && (n == 0 || i == 0 || i > n)
    {
        return Err(Error::Param(format!(
            "--shard {i}/{n}: expected I/N with 1 <= I <= N"
        )));
    }
    if let Some(t) = opts.threads
        && !(1..=MAX_THREADS).contains(&t)
    {
        return Err(Error::Param(format!(
            "--threads must be a whole number in [1, {MAX_THREADS}], got {t}"
        )));
    }
    let out = &opts.out;
    cellseq::files::ensure_not_link_dir(out)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out.display().to_string(), e))?;
    let files = OutFiles::new(out, opts.shard);
    files.refuse_links()?;
    let threads = opts
        .threads
        .unwrap_or_else(rayon::current_num_threads)
        .clamp(1, MAX_THREADS);
    let calib = calibrate()?;
    super::plan::trial_seconds(&plan.file.budget, calib)
        .map_err(|e| Error::invalid(&plan.path, e))?;
    write_manifest(plan, opts, &files, threads, calib, None)?;

    let mut trials = plan.trials();
    if let Some((i, n)) = opts.shard {
        trials.retain(|t| t.index % n == i - 1);
    }
    let planned = trials.len();
    let order: HashMap<String, usize> = trials.iter().map(|t| (t.key.clone(), t.index)).collect();

    let seen = resume(&files, &order, opts.replace_foreign)?;
    let skipped = seen.len();
    trials.retain(|t| !seen.contains(&t.key));

    // instances needed by the remaining trials
    let needed: BTreeSet<usize> = trials.iter().map(|t| t.instance).collect();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Param(format!("thread pool: {e}")))?;
    let prepared: HashMap<usize, Prepared> = pool.install(|| {
        needed
            .par_iter()
            .map(|&i| prepare(plan, i).map(|p| (i, p)))
            .collect::<Result<HashMap<_, _>>>()
    })?;
    write_instance_table(plan, &files, &prepared)?;
    let (failed, out_of_range) =
        pool.install(|| run_trials(plan, opts, &files, &trials, &prepared, calib))?;
    finalise(&files)?;
    let summary = RunSummary {
        planned,
        skipped,
        ran: trials.len(),
        failed,
        out_of_range,
        files: files.clone(),
    };
    write_manifest(plan, opts, &files, threads, calib, Some(&summary))?;
    Ok(summary)
}

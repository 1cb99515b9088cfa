//! `info`, `validate`, `solve`, `eval`, `solvers`, `generate`.

use anyhow::{Context as _, Result, bail};
use cellseq::formats::json::{self, SOLUTION_FORMAT, SolutionFile};
use cellseq::formats::{self, best_known};
use cellseq::model::{Instance, Objective};
use cellseq::search::Deadline;
use cellseq::solvers::{self, Budget, NoObserver, RunResult, parse_kv};
use clap::Args;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Instance file (.json, .sop, .pcglns).
    file: PathBuf,
}

#[derive(Args, Debug)]
pub struct ValidateArgs {
    /// Instance file.
    file: PathBuf,
}

#[derive(Args, Debug)]
pub struct SolveArgs {
    /// Instance file.
    pub file: PathBuf,
    /// Solver name (see `cellseq solvers`).
    #[arg(long, default_value = solvers::DEFAULT_SOLVER)]
    pub solver: String,
    /// Solver parameter KEY=VALUE (repeatable).
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Wall-clock limit of the whole command in seconds: reading the file, solving, the lower
    /// bound after the solve (at most a twentieth of the time; `--no-bound` gives it to the
    /// solver) and the report end within it plus a small margin (docs/bad-input.md, "Time
    /// limits"). Experiments (`cellseq run`) give each solver its full budget instead.
    #[arg(long, value_name = "SECONDS")]
    pub time_limit: Option<f64>,
    /// Evaluation budget (deterministic runs): an integer, `200_000_000` or `2e8`.
    #[arg(long, value_name = "N", value_parser = super::parse_count)]
    pub max_evals: Option<u64>,
    /// Objective: time (default), air, or matrix.
    #[arg(long)]
    pub objective: Option<String>,
    /// Write the solution here (cellseq-solution/1 JSON).
    #[arg(long, value_name = "SOLUTION.json")]
    pub out: Option<PathBuf>,
    /// Allow `--out` to be the instance file itself (by any path or link).
    #[arg(long)]
    pub overwrite_input: bool,
    /// Print one JSON object instead of the human-readable report.
    #[arg(long)]
    pub json: bool,
    /// Skip the lower bound computed after solving (`lower_bound`, `certified_gap_percent`).
    #[arg(long)]
    pub no_bound: bool,
    /// Portfolio file of the `auto` solver (TOML, docs/portfolio.md); the same as
    /// `--param portfolio=FILE`.
    #[arg(long, value_name = "FILE")]
    pub portfolio: Option<PathBuf>,
    /// Print the instance's features and the portfolio rule `auto` chooses, with its plan,
    /// before solving (with `--json`: an `explain` object).
    #[arg(long)]
    pub explain: bool,
}

#[derive(Args, Debug)]
pub struct EvalArgs {
    /// Instance file.
    file: PathBuf,
    /// Solution file (cellseq-solution/1 JSON).
    solution: PathBuf,
    /// Objective: time (default), air, or matrix.
    #[arg(long)]
    objective: Option<String>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Args, Debug)]
pub struct GenerateArgs {
    /// Generator kind (see the list in the error for unknown kinds).
    kind: String,
    /// Generator parameter KEY=VALUE (repeatable).
    #[arg(long = "param", value_name = "KEY=VALUE")]
    params: Vec<String>,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output instance file: `cellseq-instance/1` JSON, or TSPLIB SOP when it ends in `.sop`
    /// (SOP-shaped matrix families).
    #[arg(short, long)]
    out: PathBuf,
    /// Allow the output to replace a file given as a parameter (e.g. `tools=PATH`).
    #[arg(long)]
    overwrite_input: bool,
}

/// Loads an instance, with the file named in any error.
pub fn load(path: &Path) -> Result<Instance> {
    Ok(formats::load_instance(path)?)
}

/// Parses an objective name, or the instance's default.
pub fn objective_of(inst: &Instance, name: Option<&str>) -> Result<Objective> {
    match name {
        None => Ok(inst.default_objective()),
        Some(s) => match Objective::parse(s) {
            Some(Objective::Matrix) if !inst.is_matrix() => {
                bail!("objective 'matrix' needs a matrix instance (TSPLIB SOP or PCGTSP)")
            }
            Some(o) if inst.is_matrix() && o != Objective::Matrix => {
                bail!("matrix instances are scored by their matrix; objective '{s}' does not apply")
            }
            Some(o) => Ok(o),
            None => bail!("unknown objective '{s}' (known: time, air, matrix)"),
        },
    }
}

pub fn info(a: InfoArgs) -> Result<()> {
    let inst = load(&a.file)?;
    say!("instance        {}", inst.name);
    say!(
        "kind            {}",
        if inst.is_matrix() {
            "matrix"
        } else {
            "geometric"
        }
    );
    say!("cells           {}", inst.n());
    say!("modes           {}", inst.total_modes());
    say!("tools           {}", inst.used_tools().len());
    say!("precedence      {} edges", inst.precedence.len());
    say!("density         {:.4}", inst.precedence_density());
    if let Some(g) = &inst.meta.generator {
        say!("source          {g}");
    }
    say!(
        "as-programmed   {}",
        if inst.as_given.is_some() { "yes" } else { "no" }
    );
    if let Some((bk, proven)) = best_known(&a.file) {
        say!(
            "best known      {bk}{}",
            if proven { " (optimal)" } else { "" }
        );
    }
    Ok(())
}

pub fn validate(a: ValidateArgs) -> Result<()> {
    load(&a.file)?;
    say!("ok");
    Ok(())
}

/// Share of a `solve` time limit (of what reading left) kept for the lower bound after the
/// solve, unless `--no-bound`.
pub const BOUND_SHARE: f64 = 0.05;

pub fn solve(a: SolveArgs) -> Result<()> {
    let clock = Instant::now();
    // the limit covers the whole command: it is checked, and its deadline set, first
    let deadline = match a.time_limit {
        None => Deadline::NONE,
        Some(t) => {
            if !(t.is_finite() && t > 0.0) {
                bail!("--time-limit must be a positive number of seconds, got {t}");
            }
            let limit = Duration::try_from_secs_f64(t)
                .ok()
                .and_then(|d| clock.checked_add(d).map(|_| d))
                .with_context(|| format!("--time-limit {t}: too large a number of seconds"))?;
            Deadline::from(clock, Some(limit))
        }
    };
    if let Some(out) = &a.out {
        formats::write::ensure_not_input(&a.file, out, a.overwrite_input)?;
    }
    let mut params = parse_kv(&a.params)?;
    if let Some(p) = &a.portfolio {
        if a.solver != solvers::auto::INFO.name {
            bail!("--portfolio applies to the auto solver, not '{}'", a.solver);
        }
        if params.contains_key("portfolio") {
            bail!("give the portfolio once: --portfolio or --param portfolio=FILE");
        }
        let p = p
            .to_str()
            .with_context(|| format!("--portfolio {}: the path is not UTF-8", p.display()))?;
        params.insert("portfolio".to_string(), p.to_string());
    }
    if a.explain && a.solver != solvers::auto::INFO.name {
        bail!(
            "--explain describes the auto solver's choice; '{}' has none",
            a.solver
        );
    }
    // the solver and its parameters (an auto portfolio file) are checked before the instance
    // is read
    solvers::find(&a.solver)?.build(&params)?;
    let inst = load(&a.file)?;
    let objective = objective_of(&inst, a.objective.as_deref())?;
    let explained = if a.explain {
        Some(solvers::auto::explain(&inst, objective, &params)?)
    } else {
        None
    };
    if let (Some(e), false) = (&explained, a.json) {
        for l in &e.lines {
            say!("{l}");
        }
    }
    // the solver gets what reading left, less the bound's share
    let budget = Budget {
        time_limit: deadline.remaining().map(|left| {
            if a.no_bound {
                left
            } else {
                left.mul_f64(1.0 - BOUND_SHARE)
            }
        }),
        max_evals: a.max_evals,
    };
    let mut r = solvers::run(
        &a.solver,
        &inst,
        objective,
        &params,
        a.seed,
        budget,
        &mut NoObserver,
    )?;
    if !a.no_bound {
        attach_bound(&inst, &mut r, deadline);
    }
    let bk = best_known(&a.file).map(|b| b.0);
    if let Some(out) = &a.out {
        let sol = solution_file(&inst, &a.solver, a.seed, &r);
        formats::write_atomic(out, json::solution_to_json(&sol).as_bytes())
            .with_context(|| format!("writing {}", out.display()))?;
    }
    if a.json {
        let mut v = result_json(&inst, &a.solver, a.seed, &r, bk);
        if let (Some(e), Some(o)) = (&explained, v.as_object_mut()) {
            o.insert("explain".to_string(), serde_json::to_value(e)?);
        }
        say!("{}", serde_json::to_string(&v)?);
    } else {
        print_report(&inst, &a.solver, &r, bk);
    }
    Ok(())
}

/// Largest instance for which `solve` computes a lower bound after solving.
pub const SOLVE_BOUND_MAX_CELLS: usize = 200_000;

/// Raises the run's lower bound with [`cellseq::bound::compute`] (cheap settings), within
/// `deadline` (a bound not done by then is left out).
pub fn attach_bound(inst: &Instance, r: &mut RunResult, deadline: Deadline) {
    if inst.n() > SOLVE_BOUND_MAX_CELLS || r.outcome.proven_optimal || deadline.passed() {
        return;
    }
    let model = cellseq::cost::CostModel::new(inst, r.objective);
    let opts = cellseq::bound::BoundOptions {
        lagrangian_iterations: 100,
        lagrangian_max_cells: 200,
        assignment_max_cells: 1000,
        upper: Some(r.report.cost),
        deadline,
        ..Default::default()
    };
    let b = cellseq::bound::compute(&model, &opts).best;
    r.outcome.lower_bound = Some(r.outcome.lower_bound.map_or(b, |x| x.max(b)));
}

/// The solution file of a run.
pub fn solution_file(inst: &Instance, solver: &str, seed: u64, r: &RunResult) -> SolutionFile {
    SolutionFile {
        format: SOLUTION_FORMAT.into(),
        instance: inst.name.clone(),
        solver: solver.into(),
        seed,
        objective: r.objective.name().into(),
        sequence: json::to_refs(inst, &r.outcome.sequence),
        report: Some(r.report),
    }
}

fn gap(cost: f64, bk: Option<f64>) -> Option<f64> {
    bk.filter(|&b| b > 0.0).map(|b| 100.0 * (cost - b) / b)
}

/// The `--json` object of a run.
pub fn result_json(
    inst: &Instance,
    solver: &str,
    seed: u64,
    r: &RunResult,
    bk: Option<f64>,
) -> serde_json::Value {
    let rep = &r.report;
    json!({
        "instance": inst.name,
        "solver": solver,
        "seed": seed,
        "objective": r.objective.name(),
        "feasible": true,
        "cost": rep.cost,
        "air_length": rep.air_length,
        "cut_length": rep.cut_length,
        "path_length": rep.path_length,
        "lifts": rep.lifts,
        "tool_changes": rep.tool_changes,
        "machining_time": rep.machining_time,
        "best_known": bk,
        "gap_percent": gap(rep.cost, bk),
        "proven_optimal": r.outcome.proven_optimal,
        "lower_bound": r.outcome.lower_bound,
        "certified_gap_percent": r.outcome.lower_bound
            .and_then(|lb| cellseq::bound::certified_gap_percent(rep.cost, lb)),
        "evaluations": r.evaluations,
        "elapsed_s": r.elapsed_s,
        "sequence": json::to_refs(inst, &r.outcome.sequence),
    })
}

fn print_report(inst: &Instance, solver: &str, r: &RunResult, bk: Option<f64>) {
    let rep = &r.report;
    say!("instance        {} ({} cells)", inst.name, inst.n());
    say!("solver          {solver}");
    say!("objective       {}", r.objective.name());
    say!("cost            {}", fmt_num(rep.cost));
    if !inst.is_matrix() {
        say!("cut length      {:.3} mm", rep.cut_length);
        say!("air length      {:.3} mm", rep.air_length);
        say!("path length     {:.3} mm", rep.path_length);
        say!("lifts           {}", rep.lifts);
        say!("tool changes    {}", rep.tool_changes);
        say!("machining time  {:.3} s", rep.machining_time);
    }
    if let Some(b) = bk {
        say!(
            "best known      {}  (gap {:.3} %)",
            fmt_num(b),
            gap(rep.cost, Some(b)).unwrap_or(0.0)
        );
    }
    if r.outcome.proven_optimal {
        say!("proven optimal  yes");
    }
    if let Some(lb) = r.outcome.lower_bound {
        say!("lower bound     {}", fmt_num(lb));
        if let Some(g) = cellseq::bound::certified_gap_percent(rep.cost, lb) {
            say!("certified gap   {g:.3} %");
        }
    }
    say!("feasible        yes (independent checker)");
    say!("evaluations     {}", r.evaluations);
    say!("elapsed         {:.3} s", r.elapsed_s);
}

fn fmt_num(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{x:.0}")
    } else {
        format!("{x:.3}")
    }
}

pub fn eval(a: EvalArgs) -> Result<()> {
    let inst = load(&a.file)?;
    let objective = objective_of(&inst, a.objective.as_deref())?;
    let spath = a.solution.display().to_string();
    let text = formats::read_text(&a.solution)?;
    let sol = json::parse_solution(&spath, &text)?;
    let seq = json::from_refs(&inst, &sol.sequence, &spath)?;
    let rep = cellseq::check(&inst, &seq, objective)
        .map_err(|v| anyhow::anyhow!("{spath}: infeasible: {v}"))?;
    let bk = best_known(&a.file).map(|b| b.0);
    if a.json {
        say!(
            "{}",
            json!({"instance": inst.name, "feasible": true, "objective": objective.name(),
                   "report": rep, "best_known": bk, "gap_percent": gap(rep.cost, bk)})
        );
    } else {
        say!("feasible        yes");
        say!("cost            {}", fmt_num(rep.cost));
        if !inst.is_matrix() {
            say!("air length      {:.3} mm", rep.air_length);
            say!("lifts           {}", rep.lifts);
            say!("tool changes    {}", rep.tool_changes);
            say!("machining time  {:.3} s", rep.machining_time);
        }
        if let Some(b) = bk {
            say!(
                "best known      {}  (gap {:.3} %)",
                fmt_num(b),
                gap(rep.cost, Some(b)).unwrap_or(0.0)
            );
        }
    }
    Ok(())
}

#[derive(Args, Debug)]
pub struct SolversArgs {
    /// Print `docs/solvers.md` instead (Markdown: every solver's description and parameters).
    #[arg(long)]
    markdown: bool,
}

pub fn solvers(a: SolversArgs) -> Result<()> {
    if a.markdown {
        say!("{}", solvers::docs::markdown().trim_end());
        return Ok(());
    }
    for s in solvers::registry() {
        let default = if s.name == solvers::DEFAULT_SOLVER {
            "  (default)"
        } else {
            ""
        };
        say!("{}{default}\n    {}", s.name, s.summary);
        for p in s.params {
            let kind = solvers::docs::kind_label(&p.kind);
            say!("    --param {}={}  [{kind}]  {}", p.name, p.default, p.help);
        }
    }
    Ok(())
}

pub fn generate(a: GenerateArgs) -> Result<()> {
    let params = parse_kv(&a.params)?;
    // a parameter naming a file (tools=PATH) is an input: never written over silently
    for v in params.values().map(Path::new).filter(|p| p.is_file()) {
        formats::write::ensure_not_input(v, &a.out, a.overwrite_input)?;
    }
    let inst = cellseq::generate::generate(&a.kind, &params, a.seed)?;
    let sop = a
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("sop"));
    if sop {
        let text = cellseq::generate::families::sop::to_sop_text(&inst)?;
        formats::write_atomic(&a.out, text.as_bytes())?;
    } else {
        formats::save_instance(&a.out, &inst)?;
    }
    say!("wrote {} ({} cells)", a.out.display(), inst.n());
    Ok(())
}

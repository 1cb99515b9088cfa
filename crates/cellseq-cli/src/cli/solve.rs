//! `info`, `validate`, `solve`, `eval`, `solvers`, `generate`.

use anyhow::{Context as _, Result, bail};
use cellseq::formats;
use cellseq::formats::json;
use cellseq::model::{Instance, Objective};
use cellseq::params::parse_kv;
use cellseq::registry::{self, DEFAULT_SOLVER};
use cellseq::{Solve, Solved, SolverKind};
use clap::Args;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    #[arg(long, default_value = DEFAULT_SOLVER)]
    pub solver: String,
    /// Solver parameter KEY=VALUE (repeatable).
    #[arg(long = "param", value_name = "KEY=VALUE")]
    pub params: Vec<String>,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Wall-clock limit of the whole command in seconds: reading the file, solving, the lower
    /// bound after the solve (at most a twentieth of the time, a tenth for geometric instances
    /// above 50 000 cells; `--no-bound` gives it to the solver) and the report end within it plus a small margin (docs/bad-input.md, "Time
    /// limits"). Experiments (`cellseq run`) give each solver its full budget instead.
    #[arg(long, value_name = "SECONDS", value_parser = super::ranges::time_limit)]
    pub time_limit: Option<f64>,
    /// Evaluation budget (deterministic runs): an integer, `200_000_000` or `2e8`.
    #[arg(long, value_name = "N", value_parser = super::ranges::max_evals)]
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

/// The best-known value and proof flag from a `bks.csv` beside `file`; a row whose value is
/// not a finite number ≥ 0 is ignored with a warning naming `bks.csv` and its line.
pub fn best_known(file: &Path) -> Option<(f64, bool)> {
    formats::best_known_checked(file).unwrap_or_else(|e| {
        eprintln!("warning: {e}; the best-known value is ignored");
        None
    })
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

pub fn solve(a: SolveArgs) -> Result<()> {
    let clock = Instant::now();
    // the limit covers the whole command: it is checked, and its clock started, first
    let limit = a
        .time_limit
        .map(|t| {
            cellseq::solve::checked_seconds("--time-limit", t).map_err(|_| {
                anyhow::anyhow!(
                    "--time-limit must be a positive number of seconds (at most {:e}), got {t}",
                    cellseq::solve::MAX_SECONDS
                )
            })
        })
        .transpose()?;
    if let Some(out) = &a.out {
        cellseq::files::ensure_not_input(&a.file, out, a.overwrite_input)?;
    }
    let kind: SolverKind = a.solver.parse()?;
    let mut params = parse_kv(&a.params)?;
    if let Some(p) = &a.portfolio {
        if kind != SolverKind::Auto {
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
    if a.explain && kind != SolverKind::Auto {
        bail!(
            "--explain describes the auto solver's choice; '{}' has none",
            a.solver
        );
    }
    let mut solve = Solve::new(kind)
        .params_text(&params)
        .seed(a.seed)
        .lower_bound(!a.no_bound);
    if let Some(n) = a.max_evals {
        solve = solve.max_evals(n);
    }
    // the solver and its parameters (an auto portfolio file) are checked before the instance
    // is read
    solve.validated_params()?;
    let inst = load(&a.file)?;
    let objective = objective_of(&inst, a.objective.as_deref())?;
    let explained = if a.explain {
        Some(registry::explain(&inst, objective, &params)?)
    } else {
        None
    };
    if let (Some(e), false) = (&explained, a.json) {
        for l in &e.lines {
            say!("{l}");
        }
    }
    // the solver (and the bound after it) get what reading left; the solver sizes its plan
    // by the whole limit
    if let Some(limit) = limit {
        solve = solve.time_limit(limit).started(clock);
    }
    let r = solve.objective(objective).run(&inst)?;
    let bk = best_known(&a.file).map(|b| b.0);
    if let Some(out) = &a.out {
        r.save(&inst, out)
            .with_context(|| format!("writing {}", out.display()))?;
    }
    if a.json {
        let mut v = r.to_json(&inst, bk);
        if let (Some(e), Some(o)) = (&explained, v.as_object_mut()) {
            o.insert("explain".to_string(), serde_json::to_value(e)?);
        }
        say!("{}", serde_json::to_string(&v)?);
    } else {
        print_report(&inst, &r, bk);
    }
    Ok(())
}

/// The gap to the best-known value in percent; none without one, or when it is not finite
/// (a best-known value of 1e-320 would make it infinite).
fn gap(cost: f64, bk: Option<f64>) -> Option<f64> {
    bk.filter(|&b| b > 0.0)
        .map(|b| 100.0 * (cost - b) / b)
        .filter(|g| g.is_finite())
}

fn print_report(inst: &Instance, r: &Solved, bk: Option<f64>) {
    let rep = &r.report;
    say!("instance        {} ({} cells)", inst.name, inst.n());
    say!("solver          {}", r.solver);
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
        say_best_known(b, rep.cost);
    }
    if r.proven_optimal {
        say!("proven optimal  yes");
    }
    if let Some(lb) = r.lower_bound {
        say!("lower bound     {}", fmt_num(lb));
        if let Some(g) = r.certified_gap_percent() {
            say!("certified gap   {g:.3} %");
        }
    }
    say!("feasible        yes (independent checker)");
    say!("evaluations     {}", r.evaluations);
    say!("elapsed         {:.3} s", r.elapsed_s);
}

/// The best-known line: the value, and the gap when it is defined (not for a best known of 0).
fn say_best_known(b: f64, cost: f64) {
    match gap(cost, Some(b)) {
        Some(g) => say!("best known      {}  (gap {g:.3} %)", fmt_num(b)),
        None => say!("best known      {}", fmt_num(b)),
    }
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
    let text = cellseq::files::read_text(&a.solution)?;
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
            say_best_known(b, rep.cost);
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
        say!("{}", registry::markdown().trim_end());
        return Ok(());
    }
    for s in registry::all() {
        let default = if s.name == DEFAULT_SOLVER {
            "  (default)"
        } else {
            ""
        };
        say!("{}{default}\n    {}", s.name, s.summary);
        for p in s.params {
            let kind = registry::kind_label(&p.kind);
            say!("    --param {}={}  [{kind}]  {}", p.name, p.default, p.help);
        }
    }
    Ok(())
}

pub fn generate(a: GenerateArgs) -> Result<()> {
    let params = parse_kv(&a.params)?;
    // a parameter naming a file (tools=PATH) is an input: never written over silently
    for v in params.values().map(Path::new).filter(|p| p.is_file()) {
        cellseq::files::ensure_not_input(v, &a.out, a.overwrite_input)?;
    }
    let inst = cellseq::generate::generate(&a.kind, &params, a.seed)?;
    let sop = a
        .out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("sop"));
    if sop {
        let text = cellseq::generate::families::sop::to_sop_text(&inst)?;
        cellseq::files::write_atomic(&a.out, text.as_bytes())?;
    } else {
        formats::save_instance(&a.out, &inst)?;
    }
    say!("wrote {} ({} cells)", a.out.display(), inst.n());
    Ok(())
}

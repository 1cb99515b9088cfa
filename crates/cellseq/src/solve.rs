//! Solving an instance, from a typed choice to a verified result you can save: [`Solve`]
//! (solver, budget, seed, parameters, objective, lower bound) and [`Solved`] (the sequence, the
//! independent checker's [`Report`], the bound, the anytime trace).
//!
//! ```
//! use cellseq::prelude::*;
//!
//! // five cells with explicit costs, cell 1 before cell 3
//! let costs = vec![
//!     0.0, 4.0, 1.0, 9.0, 9.0,
//!     9.0, 0.0, 3.0, 2.0, 8.0,
//!     9.0, 1.0, 0.0, 9.0, 6.0,
//!     9.0, 9.0, 1.0, 0.0, 1.0,
//!     9.0, 9.0, 9.0, 9.0, 0.0,
//! ];
//! let inst = Instance::from_matrix("tiny", 5, costs, &[(1, 3)])?;
//! let solved = Solve::new(SolverKind::Exact).max_evals(1_000_000).run(&inst)?;
//! assert!(solved.proven_optimal);
//! assert_eq!(solved.cost(), solved.report.cost);
//! # Ok::<(), cellseq::Error>(())
//! ```

use crate::bound::{self, BoundOptions};
use crate::checker::Report;
use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::files::write_atomic;
use crate::formats::json::{self, SOLUTION_FORMAT, SolutionFile};
use crate::model::{Instance, Objective, Sequence};
use crate::params::{ParamValue, Params};
use crate::solvers::{self, SolverKind};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

pub use crate::context::{Budget, NoObserver, Observer, Progress, Trace};

/// Share of a time limit kept for the lower bound when [`Solve::lower_bound`] is on: the
/// solver gets the rest, so the limit covers the whole solve. Geometric instances of more
/// than [`BOUND_LARGE_CELLS`] cells keep [`BOUND_SHARE_LARGE`] instead ([`bound_share`]).
pub const BOUND_SHARE: f64 = 0.05;

/// Share of a time limit kept for the lower bound on instances of more than
/// [`BOUND_LARGE_CELLS`] cells (geometric): the sparse assignment bound's time grows with n (about
/// 0.45 s at 10⁵ cells on one core, notes/bounds-scale.md), and what is left after the
/// solver's end and the bound's cost model is less than the share, so 5 % of a 10 s limit
/// does not hold it there.
pub const BOUND_SHARE_LARGE: f64 = 0.10;

/// Size (cells) above which [`BOUND_SHARE_LARGE`] applies to a geometric instance.
pub const BOUND_LARGE_CELLS: usize = 50_000;

/// The share of a time limit kept for the lower bound of `inst`: [`BOUND_SHARE_LARGE`] for a
/// geometric instance of more than [`BOUND_LARGE_CELLS`] cells (where the sparse assignment
/// bound runs), [`BOUND_SHARE`] otherwise.
pub fn bound_share(inst: &Instance) -> f64 {
    if !inst.is_matrix() && inst.n() > BOUND_LARGE_CELLS {
        BOUND_SHARE_LARGE
    } else {
        BOUND_SHARE
    }
}

/// Largest instance (cells) for which [`Solve::lower_bound`] computes a bound after solving.
pub const BOUND_MAX_CELLS: usize = 200_000;

pub use crate::params::MAX_SECONDS;

impl Budget {
    /// A wall-clock budget of `seconds`; refused unless `0 < seconds ≤` [`MAX_SECONDS`].
    pub fn seconds(seconds: f64) -> Result<Budget> {
        Ok(Budget {
            time_limit: Some(checked_seconds("time limit", seconds)?),
            max_evals: None,
        })
    }
    /// An evaluation budget of `n` evaluations: deterministic on any machine.
    pub fn evaluations(n: u64) -> Budget {
        Budget {
            time_limit: None,
            max_evals: Some(n),
        }
    }
    /// The share `frac` of this budget: its time limit and its evaluations scaled.
    pub fn scaled(self, frac: f64) -> Budget {
        Budget {
            time_limit: self.time_limit.map(|t| t.mul_f64(frac)),
            max_evals: self.max_evals.map(|e| (e as f64 * frac) as u64),
        }
    }
}

/// `seconds` as a duration when `0 < seconds ≤` [`MAX_SECONDS`]; otherwise an error naming
/// `what` and the accepted range.
pub fn checked_seconds(what: &str, seconds: f64) -> Result<Duration> {
    if seconds.is_finite() && seconds > 0.0 && seconds <= MAX_SECONDS {
        Ok(Duration::from_secs_f64(seconds))
    } else {
        Err(Error::Param(format!(
            "{what} must be a number of seconds in (0, {MAX_SECONDS:e}], got {seconds}"
        )))
    }
}

/// A solve to run: which solver, with what budget, seed and parameters. Build it with
/// [`Solve::new`] and the setters, run it on an instance with [`Solve::run`].
///
/// Defaults: seed 1, no budget (each solver's own stopping rule), the solver's default
/// parameters, the instance's default objective, no lower bound after the solve.
pub struct Solve<'o> {
    solver: SolverKind,
    params: Vec<(String, ParamValue)>,
    seed: u64,
    budget: Budget,
    objective: Option<Objective>,
    lower_bound: bool,
    observer: Option<&'o mut dyn Observer>,
    stop: Option<&'o AtomicBool>,
    started: Option<Instant>,
}

impl Default for Solve<'_> {
    fn default() -> Self {
        Solve::new(SolverKind::default())
    }
}

impl<'o> Solve<'o> {
    /// A solve with `solver` and the defaults above.
    pub fn new(solver: SolverKind) -> Self {
        Solve {
            solver,
            params: Vec::new(),
            seed: 1,
            budget: Budget::default(),
            objective: None,
            lower_bound: false,
            observer: None,
            stop: None,
            started: None,
        }
    }
    /// The random seed.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// The whole budget (time limit and evaluations together; the first reached stops).
    pub fn budget(mut self, budget: Budget) -> Self {
        self.budget = budget;
        self
    }
    /// A wall-clock limit on the solve (solver and lower bound), counted from [`Solve::run`] or
    /// from [`Solve::started`].
    pub fn time_limit(mut self, limit: Duration) -> Self {
        self.budget.time_limit = Some(limit);
        self
    }
    /// An evaluation budget: the same result on any machine and thread count.
    pub fn max_evals(mut self, n: u64) -> Self {
        self.budget.max_evals = Some(n);
        self
    }
    /// Sets a solver parameter; [`Solve::run`] refuses a name the solver does not declare or a
    /// value of the wrong type, listing the known names.
    pub fn param(mut self, name: &str, value: impl Into<ParamValue>) -> Self {
        self.params.retain(|(k, _)| k != name);
        self.params.push((name.to_string(), value.into()));
        self
    }
    /// Sets parameters given as text (`--param KEY=VALUE`, a plan's table).
    pub fn params_text(mut self, given: &BTreeMap<String, String>) -> Self {
        for (k, v) in given {
            self = self.param(k, v.as_str());
        }
        self
    }
    /// The objective (`time` or `air` for geometric instances; matrix instances are scored by
    /// their matrix).
    pub fn objective(mut self, objective: Objective) -> Self {
        self.objective = Some(objective);
        self
    }
    /// Computes a lower bound after the solve (instances of up to [`BOUND_MAX_CELLS`] cells,
    /// cheap settings) and keeps the better of it and the solver's own.
    pub fn lower_bound(mut self, on: bool) -> Self {
        self.lower_bound = on;
        self
    }
    /// Receives every improvement of the best cost while the solver runs.
    pub fn observe(mut self, observer: &'o mut dyn Observer) -> Self {
        self.observer = Some(observer);
        self
    }
    /// Stops the solver as soon as `stop` is set (from another thread: a user's Ctrl-C, a
    /// caller's cancel); it returns the best sequence found so far, checked as always.
    pub fn stop_when(mut self, stop: &'o AtomicBool) -> Self {
        self.stop = Some(stop);
        self
    }
    /// Counts the time limit from `at` rather than from [`Solve::run`]: a command that read
    /// its input since `at` gives its whole `--time-limit` and this start. The run ends at
    /// `at` + limit; a solver that sizes its plan by the limit (`auto`) sees the whole limit
    /// (`Context::nominal_limit`), not what reading left of it.
    pub fn started(mut self, at: Instant) -> Self {
        self.started = Some(at);
        self
    }
    /// The solver chosen.
    pub fn solver(&self) -> SolverKind {
        self.solver
    }
    /// The parameters validated against the solver's declaration, defaults filled in.
    pub fn validated_params(&self) -> Result<Params> {
        let info = self.solver.info();
        let params = Params::typed(info.name, info.params, &self.params)?;
        info.check_params(params.values())
    }

    /// Runs the solver on `inst`, then checks its sequence with the independent checker.
    ///
    /// Fails when the parameters do not fit the solver, the objective does not apply to the
    /// instance, the precedence admits no order, the solver errs, or the checker finds the
    /// sequence infeasible or costed otherwise than the solver claims.
    pub fn run(self, inst: &Instance) -> Result<Solved> {
        let info = self.solver.info();
        let params = self.validated_params()?;
        let objective = objective_for(inst, self.objective)?;
        let mut trace = Trace::default();
        let mut tee = Tee {
            trace: &mut trace,
            user: self.observer,
        };
        // the limit covers the bound too: the solver gets all but the bound's share of what is
        // left; it sizes its plan by the whole limit
        let nominal = self.budget.time_limit;
        let deadline = Deadline::from(self.started.unwrap_or_else(Instant::now), nominal);
        let mut budget = self.budget;
        // (a limit beyond the clock's range has no deadline: the budget keeps it)
        budget.time_limit = deadline.remaining().or(nominal);
        if self.lower_bound {
            let share = bound_share(inst);
            budget.time_limit = budget.time_limit.map(|t| t.mul_f64(1.0 - share));
        }
        let opts = solvers::RunOptions {
            stop: self.stop,
            nominal,
        };
        let r = solvers::run_until(
            info.name,
            inst,
            objective,
            params.values(),
            self.seed,
            budget,
            &mut tee,
            opts,
        )?;
        let mut solved = Solved {
            solver: self.solver,
            seed: self.seed,
            params,
            objective: r.objective,
            sequence: r.outcome.sequence,
            report: r.report,
            proven_optimal: r.outcome.proven_optimal,
            lower_bound: r.outcome.lower_bound,
            evaluations: r.evaluations,
            elapsed_s: r.elapsed_s,
            trace: trace.points,
        };
        if self.lower_bound {
            solved.attach_bound_within(inst, deadline);
        }
        Ok(solved)
    }
}

/// The objective `asked` for `inst`, or its default; an objective that does not apply is an
/// error.
pub fn objective_for(inst: &Instance, asked: Option<Objective>) -> Result<Objective> {
    match asked {
        None => Ok(inst.default_objective()),
        Some(Objective::Matrix) if !inst.is_matrix() => Err(Error::invalid(
            &inst.name,
            "objective 'matrix' needs a matrix instance (TSPLIB SOP or PCGTSP)",
        )),
        Some(o) if inst.is_matrix() && o != Objective::Matrix => Err(Error::invalid(
            &inst.name,
            format!(
                "matrix instances are scored by their matrix; objective '{}' does not apply",
                o.name()
            ),
        )),
        Some(o) => Ok(o),
    }
}

/// Records every point and passes it on to the caller's observer.
struct Tee<'a, 'o> {
    trace: &'a mut Trace,
    user: Option<&'o mut dyn Observer>,
}

impl Observer for Tee<'_, '_> {
    fn improved(&mut self, p: Progress) {
        self.trace.improved(p);
        if let Some(u) = self.user.as_deref_mut() {
            u.improved(p);
        }
    }
}

/// A verified result: the sequence with the independent checker's report (the authoritative
/// figures), the lower bound and whether the solver proved optimality, and how it was found.
#[derive(Debug, Clone)]
pub struct Solved {
    /// The solver that ran.
    pub solver: SolverKind,
    /// Its seed.
    pub seed: u64,
    /// Its parameters, defaults filled in.
    pub params: Params,
    /// The objective the sequence was scored by.
    pub objective: Objective,
    /// The order of cells, each with its mode.
    pub sequence: Sequence,
    /// The independent checker's figures of the sequence.
    pub report: Report,
    /// True when the solver proved the sequence optimal.
    pub proven_optimal: bool,
    /// A valid lower bound on the optimum, when one is known.
    pub lower_bound: Option<f64>,
    /// Evaluations counted.
    pub evaluations: u64,
    /// Seconds the solver ran.
    pub elapsed_s: f64,
    /// Every improvement of the best cost: evaluations, seconds, cost.
    pub trace: Vec<Progress>,
}

impl Solved {
    /// The cost of the sequence, by the checker.
    pub fn cost(&self) -> f64 {
        self.report.cost
    }
    /// The gap between the cost and the lower bound, in percent of the bound.
    pub fn certified_gap_percent(&self) -> Option<f64> {
        self.lower_bound
            .and_then(|lb| bound::certified_gap_percent(self.report.cost, lb))
    }
    /// The gap to a best-known value, in percent of it; none when it is 0 or the gap is not
    /// finite.
    pub fn gap_percent(&self, best_known: f64) -> Option<f64> {
        (best_known > 0.0)
            .then(|| 100.0 * (self.report.cost - best_known) / best_known)
            .filter(|g| g.is_finite())
    }
    /// Raises the lower bound with `bound::compute` at cheap settings (instances of up to
    /// [`BOUND_MAX_CELLS`] cells; nothing when the result is proven optimal).
    pub fn attach_bound(&mut self, inst: &Instance) {
        self.attach_bound_within(inst, Deadline::NONE);
    }
    /// [`Solved::attach_bound`] within `deadline`: a bound not done by then is left out.
    pub fn attach_bound_within(&mut self, inst: &Instance, deadline: Deadline) {
        if inst.n() > BOUND_MAX_CELLS || self.proven_optimal || deadline.passed() {
            return;
        }
        let model = CostModel::new(inst, self.objective);
        let opts = BoundOptions {
            lagrangian_iterations: 100,
            lagrangian_max_cells: 200,
            assignment_max_cells: 1000,
            upper: Some(self.report.cost),
            deadline,
            ..Default::default()
        };
        let b = bound::compute(&model, &opts).best;
        self.lower_bound = Some(self.lower_bound.map_or(b, |x| x.max(b)));
    }
    /// The solution file (`cellseq-solution/1`) of this result on `inst`.
    pub fn solution_file(&self, inst: &Instance) -> SolutionFile {
        SolutionFile {
            format: SOLUTION_FORMAT.into(),
            instance: inst.name.clone(),
            solver: self.solver.name().into(),
            seed: self.seed,
            objective: self.objective.name().into(),
            sequence: json::to_refs(inst, &self.sequence),
            report: Some(self.report),
        }
    }
    /// Writes the solution file to `path`, safely ([`crate::files::write_atomic`]).
    pub fn save(&self, inst: &Instance, path: &Path) -> Result<()> {
        write_atomic(
            path,
            json::solution_to_json(&self.solution_file(inst)).as_bytes(),
        )
    }
    /// The result as the JSON object `cellseq solve --json` prints: `instance, solver, seed,
    /// objective, feasible, cost, air_length, cut_length, path_length, lifts, tool_changes,
    /// machining_time, best_known, gap_percent, proven_optimal, lower_bound,
    /// certified_gap_percent, evaluations, elapsed_s, sequence`.
    pub fn to_json(&self, inst: &Instance, best_known: Option<f64>) -> serde_json::Value {
        let rep = &self.report;
        serde_json::json!({
            "instance": inst.name,
            "solver": self.solver.name(),
            "seed": self.seed,
            "objective": self.objective.name(),
            "feasible": true,
            "cost": rep.cost,
            "air_length": rep.air_length,
            "cut_length": rep.cut_length,
            "path_length": rep.path_length,
            "lifts": rep.lifts,
            "tool_changes": rep.tool_changes,
            "machining_time": rep.machining_time,
            "best_known": best_known,
            "gap_percent": best_known.and_then(|b| self.gap_percent(b)),
            "proven_optimal": self.proven_optimal,
            "lower_bound": self.lower_bound,
            "certified_gap_percent": self.certified_gap_percent(),
            "evaluations": self.evaluations,
            "elapsed_s": self.elapsed_s,
            "sequence": json::to_refs(inst, &self.sequence),
        })
    }
}

/// Saves `solved` as a solution file of `inst` at `path` ([`Solved::save`]): a
/// `cellseq-solution/1` JSON file that `cellseq eval` re-checks, written atomically.
///
/// ```
/// use cellseq::prelude::*;
///
/// let inst = cellseq::generate::generate("uniform", &[("n".to_string(), "12".to_string())].into(), 3)?;
/// let solved = Solve::new(SolverKind::Greedy).run(&inst)?;
/// let dir = std::env::temp_dir().join(format!("cellseq-doc-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// let path = dir.join("solution.json");
/// cellseq::save_solution(&path, &inst, &solved)?;
/// let text = cellseq::files::read_text(&path)?;
/// let file = cellseq::formats::json::parse_solution("solution.json", &text)?;
/// let back = cellseq::formats::json::from_refs(&inst, &file.sequence, "solution.json")?;
/// assert_eq!(back, solved.sequence);
/// # std::fs::remove_dir_all(&dir).unwrap();
/// # Ok::<(), cellseq::Error>(())
/// ```
pub fn save_solution(path: &Path, inst: &Instance, solved: &Solved) -> Result<()> {
    solved.save(inst, path)
}

/// Lower bounds on the optimum of `inst` under `objective` (every bound the options afford,
/// each with its time, and the best).
///
/// ```
/// use cellseq::prelude::*;
/// use cellseq::{BoundOptions, lower_bounds};
///
/// let text = "TYPE: SOP\nDIMENSION: 4\nEDGE_WEIGHT_SECTION\n4\n0 5 2 9\n-1 0 1 3\n-1 4 0 3\n-1 -1 -1 0\nEOF\n";
/// let inst = cellseq::parse("four.sop", text, Format::Sop)?;
/// let bounds = lower_bounds(&inst, inst.default_objective(), &BoundOptions::default())?;
/// let best = Solve::new(SolverKind::Exact).max_evals(100_000).run(&inst)?;
/// assert!(bounds.best <= best.cost());
/// # Ok::<(), cellseq::Error>(())
/// ```
pub fn lower_bounds(
    inst: &Instance,
    objective: Objective,
    opts: &BoundOptions,
) -> Result<bound::Bounds> {
    let objective = objective_for(inst, Some(objective))?;
    let model = CostModel::new(inst, objective);
    if !model.acyclic() {
        return Err(Error::invalid(
            &inst.name,
            "no order satisfies the precedence with the fixed first and last cells",
        ));
    }
    Ok(bound::compute(&model, opts))
}

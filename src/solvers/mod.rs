//! Solvers: one [`Solver`] trait, parameters, budgets, progress observers and a registry.
//!
//! To add a solver: write a module here with a type implementing [`Solver`], give it a
//! [`SolverInfo`] (name, summary, parameters with defaults, constructor) and list it in
//! [`registry`]. The conformance tests in `tests/conformance.rs` then cover it automatically.

pub mod aco;
pub mod as_given;
pub mod atsp;
pub mod auto;
pub mod beam;
pub mod drawing;
pub mod eacs;
pub mod edge;
pub mod exact;
pub mod greedy;
pub mod ils;
pub mod insertion;
pub mod local_search;
pub mod process;
pub mod reopt;
pub mod rules;
pub mod sa;
pub mod start;
pub mod tabu;
pub mod two_opt;

use crate::check::{Report, check};
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::model::{Instance, Objective, Sequence};
use std::collections::BTreeMap;

pub use crate::params::{ParamKind, ParamSpec, Params, parse_kv};
use std::time::{Duration, Instant};

/// How much work a solver may do. Evaluation budgets make runs deterministic.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Budget {
    /// Wall-clock limit.
    pub time_limit: Option<Duration>,
    /// Limit on counted evaluations (move evaluations, arc lookups in construction).
    pub max_evals: Option<u64>,
}

/// One point of an anytime trace.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Evaluations so far.
    pub evaluations: u64,
    /// Seconds since the start.
    pub elapsed_s: f64,
    /// Best cost so far.
    pub best: f64,
}

/// Receives progress when a solver finds a better solution.
pub trait Observer {
    /// Called on every improvement of the best cost.
    fn improved(&mut self, p: Progress);
}

/// An observer that records every improvement.
#[derive(Debug, Default, Clone)]
pub struct Trace {
    /// The recorded points.
    pub points: Vec<Progress>,
}

impl Observer for Trace {
    fn improved(&mut self, p: Progress) {
        self.points.push(p);
    }
}

/// An observer that ignores everything.
pub struct NoObserver;

impl Observer for NoObserver {
    fn improved(&mut self, _p: Progress) {}
}

/// What a solver sees while it runs: the instance, its cost model, parameters, seed, budget.
pub struct Context<'a> {
    /// The instance.
    pub instance: &'a Instance,
    /// Arc costs and precedence.
    pub model: &'a CostModel,
    /// Validated parameters.
    pub params: &'a Params,
    /// Random seed.
    pub seed: u64,
    /// Budget.
    pub budget: Budget,
    observer: &'a mut dyn Observer,
    start: Instant,
    evaluations: u64,
    best: f64,
}

impl<'a> Context<'a> {
    /// Builds a context; the clock starts now.
    pub fn new(
        instance: &'a Instance,
        model: &'a CostModel,
        params: &'a Params,
        seed: u64,
        budget: Budget,
        observer: &'a mut dyn Observer,
    ) -> Self {
        Context {
            instance,
            model,
            params,
            seed,
            budget,
            observer,
            start: Instant::now(),
            evaluations: 0,
            best: f64::INFINITY,
        }
    }
    /// A context for a sub-solver run inside this one (portfolio phases, warm starts): the same
    /// instance, model and seed, its own parameters, budget and observer; its clock starts now.
    /// The caller adds the sub-run's evaluations back with [`Context::count`].
    pub fn sub<'b>(
        &self,
        params: &'b Params,
        budget: Budget,
        observer: &'b mut dyn Observer,
    ) -> Context<'b>
    where
        'a: 'b,
    {
        Context::new(
            self.instance,
            self.model,
            params,
            self.seed,
            budget,
            observer,
        )
    }
    /// Counts `k` evaluations.
    #[inline]
    pub fn count(&mut self, k: u64) {
        self.evaluations += k;
    }
    /// Evaluations counted so far.
    pub fn evaluations(&self) -> u64 {
        self.evaluations
    }
    /// Seconds since the start.
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
    /// True when the budget is used up.
    pub fn exhausted(&self) -> bool {
        if let Some(m) = self.budget.max_evals
            && self.evaluations >= m
        {
            return true;
        }
        if let Some(t) = self.budget.time_limit
            && self.start.elapsed() >= t
        {
            return true;
        }
        false
    }
    /// Reports a solution cost; the observer hears of it when it improves the best.
    pub fn report(&mut self, cost: f64) {
        if cost < self.best - 1e-9 * cost.abs().max(1.0) {
            self.best = cost;
            let p = Progress {
                evaluations: self.evaluations,
                elapsed_s: self.elapsed(),
                best: cost,
            };
            self.observer.improved(p);
        }
    }
    /// Best cost reported so far.
    pub fn best(&self) -> f64 {
        self.best
    }
}

/// What a solver returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The best sequence found.
    pub sequence: Sequence,
    /// Its cost by the solver's own evaluation.
    pub cost: f64,
    /// True when the solver proved the sequence optimal.
    pub proven_optimal: bool,
    /// A valid lower bound on the optimum, when the solver has one.
    pub lower_bound: Option<f64>,
}

/// A sequencing algorithm.
pub trait Solver: Send + Sync {
    /// Runs the algorithm.
    fn solve(&self, ctx: &mut Context) -> Result<Outcome>;
}

/// A registry entry.
pub struct SolverInfo {
    /// Registry name.
    pub name: &'static str,
    /// One-line description.
    pub summary: &'static str,
    /// Parameters with defaults.
    pub params: &'static [ParamSpec],
    /// Builds the solver from validated parameters.
    pub make: fn(&Params) -> Box<dyn Solver>,
}

/// True when the environment asks the solvers for their diagnostic trace on standard error:
/// `CELLSEQ_TRACE` (any value; `CELLSEQ_BEAM_TRACE`, the beam's older name, is read as well).
pub fn trace_enabled() -> bool {
    std::env::var_os("CELLSEQ_TRACE").is_some() || std::env::var_os("CELLSEQ_BEAM_TRACE").is_some()
}

/// Every registered solver, in display order.
pub fn registry() -> Vec<&'static SolverInfo> {
    vec![
        &auto::INFO,
        &as_given::INFO,
        &greedy::INFO,
        &edge::INFO,
        &insertion::INFO,
        &ils::INFO,
        &atsp::INFO,
        &exact::INFO,
        &beam::INFO,
        &reopt::INFO,
        &two_opt::INFO,
        &local_search::INFO,
        &sa::INFO,
        &tabu::INFO,
        &aco::INFO,
        &eacs::INFO,
        &process::INFO,
        &rules::INFO,
        &drawing::INFO,
    ]
}

/// Name of the solver `cellseq solve` uses when none is named.
pub const DEFAULT_SOLVER: &str = "auto";

/// Looks a solver up by name.
pub fn find(name: &str) -> Result<&'static SolverInfo> {
    registry()
        .into_iter()
        .find(|s| s.name == name)
        .ok_or_else(|| Error::UnknownSolver {
            name: name.to_string(),
            known: registry()
                .iter()
                .map(|s| s.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

/// The result of [`run`]: the solver's outcome and the independent checker's report.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Solver output.
    pub outcome: Outcome,
    /// Checker report (the authoritative figures).
    pub report: Report,
    /// Evaluations counted.
    pub evaluations: u64,
    /// Seconds spent.
    pub elapsed_s: f64,
    /// Objective used.
    pub objective: Objective,
}

/// Runs a solver by name, then verifies its sequence with the independent checker.
///
/// Fails when the solver errs, when the checker finds the sequence infeasible, or when the
/// solver's own cost disagrees with the checker's.
pub fn run(
    name: &str,
    inst: &Instance,
    objective: Objective,
    given: &BTreeMap<String, String>,
    seed: u64,
    budget: Budget,
    observer: &mut dyn Observer,
) -> Result<RunResult> {
    let info = find(name)?;
    let params = Params::new(name, info.params, given)?;
    let solver = (info.make)(&params);
    let model = CostModel::new(inst, objective);
    if !model.acyclic() {
        return Err(Error::invalid(
            &inst.name,
            "no order satisfies the precedence with the fixed first and last cells (see `cellseq validate`)",
        ));
    }
    let objective = model.objective();
    let mut ctx = Context::new(inst, &model, &params, seed, budget, observer);
    let outcome = solver.solve(&mut ctx)?;
    let elapsed_s = ctx.elapsed();
    let evaluations = ctx.evaluations();
    let report = check(inst, &outcome.sequence, objective).map_err(|v| Error::Solver {
        solver: name.to_string(),
        msg: format!("returned an infeasible sequence: {v}"),
    })?;
    if !report.cost.is_finite() {
        return Err(Error::Solver {
            solver: name.to_string(),
            msg: format!(
                "the checker computes a cost of {} (see `cellseq validate`)",
                report.cost
            ),
        });
    }
    let tol = 1e-6 * report.cost.abs().max(1.0);
    if (report.cost - outcome.cost).abs() > tol {
        return Err(Error::Solver {
            solver: name.to_string(),
            msg: format!(
                "claims cost {} but the checker computes {}",
                outcome.cost, report.cost
            ),
        });
    }
    Ok(RunResult {
        outcome,
        report,
        evaluations,
        elapsed_s,
        objective,
    })
}

/// A ready-made outcome for a sequence scored by the model.
pub fn outcome_of(model: &CostModel, sequence: Sequence) -> Outcome {
    let cost = model.evaluate(&sequence);
    Outcome {
        sequence,
        cost,
        proven_optimal: false,
        lower_bound: None,
    }
}

//! Solvers: one [`Solver`] trait, parameters, budgets, progress observers and a registry.
//!
//! To add a solver: write a module here with a type implementing [`Solver`], give it a
//! [`SolverInfo`] (name, summary, parameters with defaults, constructor) and list it in
//! [`registry`]. The conformance tests in `tests/it/conformance.rs` then cover it automatically.

pub mod aco;
pub mod as_given;
pub mod atsp;
pub mod auto;
pub mod beam;
pub mod docs;
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
pub use crate::search::{
    Budget, Context, NoObserver, Observer, Outcome, Progress, Trace, outcome_of,
};

/// A sequencing algorithm.
pub trait Solver: Send + Sync {
    /// Runs the algorithm.
    fn solve(&self, ctx: &mut Context) -> Result<Outcome>;
    /// Runs the algorithm from `start` when one is given: solvers whose [`Caps`] declare
    /// `starts_from` search from it, those that declare `warm_start` take it as their first
    /// incumbent; the others run [`Solver::solve`] and are never handed a start by
    /// [`sub_run`]. Without a start this is [`Solver::solve`].
    fn solve_from(&self, ctx: &mut Context, start: Option<&Sequence>) -> Result<Outcome> {
        let _ = start;
        self.solve(ctx)
    }
}

/// The instances a solver needs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Needs {
    /// Any instance, geometric or matrix.
    Any,
    /// Instances with geometry (cells with points).
    Geometric,
    /// Instances given by a cost matrix.
    Matrix,
}

/// What a solver can do, declared in its registry entry; sub-runs, plans and tests read it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Caps {
    /// Never ends worse than `greedy` and keeps to an evaluation budget up to one pass or
    /// construction (the local-search family).
    pub improves: bool,
    /// Searches from a given sequence and returns one no worse ([`Solver::solve_from`]); a
    /// plan phase may start it from an earlier sequence (`*`, `+`).
    pub starts_from: bool,
    /// Takes a given sequence as its first incumbent (an upper bound to prune with) instead of
    /// its own warm start; the result is never worse.
    pub warm_start: bool,
    /// Proves its result optimal when it finishes within the budget and its limits.
    pub exact: bool,
    /// The instances it runs on.
    pub needs: Needs,
}

impl Caps {
    /// No capability, any instance: the base of every declaration
    /// (`Caps { exact: true, ..Caps::NONE }`).
    pub const NONE: Caps = Caps {
        improves: false,
        starts_from: false,
        warm_start: false,
        exact: false,
        needs: Needs::Any,
    };
    /// True when a start sequence can be handed to the solver.
    pub fn takes_start(&self) -> bool {
        self.starts_from || self.warm_start
    }
}

/// A registry entry.
pub struct SolverInfo {
    /// Registry name.
    pub name: &'static str,
    /// One-line description.
    pub summary: &'static str,
    /// Parameters with defaults.
    pub params: &'static [ParamSpec],
    /// What it can do.
    pub caps: Caps,
    /// Builds the solver from validated parameters; fails when they do not make a solver
    /// (for instance a malformed `auto` plan).
    pub make: fn(&Params) -> Result<Box<dyn Solver>>,
}

impl SolverInfo {
    /// Validates `given` against the declared parameters and builds the solver.
    pub fn build(&self, given: &BTreeMap<String, String>) -> Result<(Params, Box<dyn Solver>)> {
        let params = Params::new(self.name, self.params, given)?;
        let solver = (self.make)(&params)?;
        Ok((params, solver))
    }
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

/// A solver run inside another (a portfolio phase, a warm start, a window, a fallback): which
/// solver, its parameters, its share of the budget, its seed, an optional start, and the
/// instance it runs on when not the caller's.
pub struct Sub<'s> {
    /// Registry name.
    pub name: &'s str,
    /// Its parameters as given (validated against its declaration).
    pub params: &'s BTreeMap<String, String>,
    /// Its budget (a share of the caller's).
    pub budget: Budget,
    /// Its seed.
    pub seed: u64,
    /// The sequence it starts from (solvers whose [`Caps::takes_start`]).
    pub start: Option<&'s Sequence>,
    /// Another instance and its cost model (a backwards twin, a window); `None`: the caller's.
    pub on: Option<(&'s Instance, &'s CostModel)>,
}

impl<'s> Sub<'s> {
    /// A sub-run of `name` with its default parameters, on the caller's instance.
    pub fn new(name: &'s str, budget: Budget, seed: u64) -> Self {
        static NONE: BTreeMap<String, String> = BTreeMap::new();
        Sub {
            name,
            params: &NONE,
            budget,
            seed,
            start: None,
            on: None,
        }
    }
}

/// Runs a sub-solver: builds it from the registry (refusing a start it cannot take), runs it
/// in a context of its own (its clock starts now; no observer), and adds its evaluations to
/// `ctx` when it succeeds. The caller decides whether to [`Context::report`] its cost.
///
/// The sub-run never outlives the caller's deadline: its time limit is the smaller of its own
/// and what is left of the caller's (a sub-run without a time limit gets the caller's rest).
pub fn sub_run(ctx: &mut Context, sub: Sub) -> Result<Outcome> {
    let info = find(sub.name)?;
    let (params, solver) = info.build(sub.params)?;
    if sub.start.is_some() && !info.caps.takes_start() {
        return Err(Error::Solver {
            solver: info.name.to_string(),
            msg: "cannot start from a given sequence".to_string(),
        });
    }
    let (instance, model) = sub.on.unwrap_or((ctx.instance, ctx.model));
    let mut quiet = NoObserver;
    let mut budget = sub.budget;
    if let Some(left) = ctx.remaining() {
        budget.time_limit = Some(budget.time_limit.map_or(left, |t| t.min(left)));
    }
    let mut inner = Context::new(instance, model, &params, sub.seed, budget, &mut quiet);
    let out = solver.solve_from(&mut inner, sub.start)?;
    ctx.count(inner.evaluations());
    Ok(out)
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
    let (params, solver) = info.build(given)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formats::{Format, parse_instance};

    fn tiny() -> Instance {
        // 5 nodes, node 1 first and node 5 last, 2 before 4
        let text = "TYPE: SOP\nDIMENSION: 5\nEDGE_WEIGHT_SECTION\n5\n\
                    0 4 1 9 9\n-1 0 3 2 8\n-1 1 0 -1 6\n-1 -1 1 0 1\n-1 -1 -1 -1 0\nEOF\n";
        parse_instance("tiny.sop", text, Format::Sop).unwrap()
    }

    #[test]
    fn building_auto_refuses_a_malformed_plan() {
        let info = find("auto").unwrap();
        let kv = |v: &str| BTreeMap::from([("plan".to_string(), v.to_string())]);
        assert!(info.build(&kv("local-search:0.5,ils*:1")).is_ok());
        let e = info.build(&kv("nosuch:1")).err().unwrap().to_string();
        assert!(e.contains("nosuch"), "{e}");
        let e = info.build(&kv("greedy*:1")).err().unwrap().to_string();
        assert!(
            e.contains("only ils, eacs and reopt can start from an earlier sequence"),
            "{e}"
        );
    }

    #[test]
    fn sub_runs_start_only_solvers_that_take_a_start() {
        let inst = tiny();
        let model = CostModel::new(&inst, inst.default_objective());
        let params = Params::new("as-given", &[], &BTreeMap::new()).unwrap();
        let mut obs = NoObserver;
        let budget = Budget {
            time_limit: None,
            max_evals: Some(5_000),
        };
        let mut ctx = Context::new(&inst, &model, &params, 3, budget, &mut obs);
        let start = sub_run(&mut ctx, Sub::new("as-given", budget, 3)).unwrap();
        let used = ctx.evaluations();
        for info in registry() {
            let sub = Sub {
                start: Some(&start.sequence),
                ..Sub::new(info.name, budget, 3)
            };
            let out = sub_run(&mut ctx, sub);
            if info.caps.takes_start() {
                let out = out.unwrap_or_else(|e| panic!("{}: {e}", info.name));
                assert!(out.cost <= start.cost, "{} worse than its start", info.name);
                assert!(ctx.evaluations() >= used, "{}", info.name);
            } else {
                assert!(out.is_err(), "{} took a start it cannot use", info.name);
            }
        }
    }
}

//! Solvers: one [`SolverKind`] per registry entry, what each declares ([`SolverInfo`]: name,
//! summary, description, parameters, capabilities), and how they are run.
//!
//! To add a solver: write `src/solvers/<name>.rs` with a type implementing [`Solver`] (or
//! [`StartsFrom`], which makes it one, or [`WarmStart`] when it can take a start sequence) and a
//! `pub static INFO: SolverInfo` that declares everything about it, then add one line to the
//! `registry!` list below. The [`SolverKind`] variant, [`registry`], `docs/solvers.md`
//! ([`markdown`]) and the conformance tests (which iterate [`SolverKind::ALL`]) follow from it.

/// Declares the solver modules and derives [`SolverKind`] from them: one line per solver,
/// `Variant => module`, in display order. The module's `INFO` says everything else.
macro_rules! registry {
    ($($variant:ident => $module:ident),* $(,)?) => {
        $(pub mod $module;)*

        /// A solver of the registry, chosen by type: `SolverKind::Ils`, or by its registry name
        /// with [`str::parse`] (`"ils".parse::<SolverKind>()`, an unknown name is an
        /// [`Error::UnknownSolver`] listing the known ones). [`SolverKind::info`] tells its
        /// name, summary, description, parameters and capabilities.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        #[non_exhaustive]
        pub enum SolverKind {
            $(
                #[doc = concat!("The solver declared in `src/solvers/", stringify!($module),
                                "` (see [`SolverKind::info`]).")]
                $variant,
            )*
        }

        impl SolverKind {
            /// Every registry solver, in display order.
            pub const ALL: &'static [SolverKind] = &[$(SolverKind::$variant),*];

            /// What the solver declares: name, summary, description, parameters, capabilities.
            pub fn info(self) -> &'static SolverInfo {
                match self {
                    $(SolverKind::$variant => &$module::INFO,)*
                }
            }
        }
    };
}

registry! {
    Auto => auto,
    AsGiven => as_given,
    Greedy => greedy,
    GreedyEdge => edge,
    Insertion => insertion,
    Ils => ils,
    Gls => gls,
    Atsp => atsp,
    Exact => exact,
    Beam => beam,
    Reopt => reopt,
    Corridor => corridor,
    TwoOpt => two_opt,
    LocalSearch => local_search,
    Sa => sa,
    Tabu => tabu,
    Aco => aco,
    Eacs => eacs,
    Process => process,
    Rules => rules,
    Drawing => drawing,
}

pub mod docs;
pub mod start;

pub use auto::{
    BUILT_IN_PORTFOLIO, Explanation, Features, explain, is_portfolio_file, validate_portfolio,
};
pub use docs::{kind_label, markdown};

use crate::checker::{Report, check};
use crate::cost::CostModel;
use crate::engine::{Costs, Solution};
use crate::error::{Error, Result};
use crate::model::{Instance, Objective, Sequence};
use std::collections::BTreeMap;
use std::sync::atomic::AtomicBool;

pub use crate::context::{
    Budget, Context, NoObserver, Observer, Outcome, outcome_of,
};
pub use crate::params::{ParamKind, ParamSpec, Params};
#[cfg(feature = "internals")]
pub use crate::{context::{Progress, Trace}, params::parse_kv};

/// A sequencing algorithm (crate-internal: users choose a [`SolverKind`] and run it through
/// [`crate::Solve`]).
pub trait Solver: Send + Sync {
    /// Runs the algorithm.
    fn solve(&self, ctx: &mut Context) -> Result<Outcome>;
}

/// A solver that searches from a given sequence and returns one no worse (a plan phase may
/// start it from an earlier phase's sequence: `*`, `+`), or from a start of its own; every
/// such type is a [`Solver`] that runs from its own start.
pub trait StartsFrom: Send + Sync {
    /// Runs the algorithm from `start`, a feasible sequence of the context's instance
    /// evaluated with open-loop costs, or from the solver's own start when `None`.
    fn run_from(&self, ctx: &mut Context, start: Option<Solution>) -> Result<Outcome>;
}

impl<T: StartsFrom> Solver for T {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        self.run_from(ctx, None)
    }
}

/// A solver that takes a given sequence as its first incumbent (an upper bound to prune with)
/// instead of its own warm start; the result is never worse.
pub trait WarmStart: Solver {
    /// Runs the algorithm with `incumbent`, a feasible sequence, as its first upper bound.
    fn warm_start(&self, ctx: &mut Context, incumbent: &Sequence) -> Result<Outcome>;
}

/// How a registry entry builds its solver from validated parameters; which start the solver
/// can take is part of the type, so the compiler holds the declaration and the code together.
/// A constructor fails when the parameters do not make a solver (a malformed `auto` plan).
#[derive(Clone, Copy)]
pub enum Build {
    /// A solver that runs from scratch only.
    Fresh(fn(&Params) -> Result<Box<dyn Solver>>),
    /// A solver that can search from a given sequence ([`StartsFrom`]).
    StartsFrom(fn(&Params) -> Result<Box<dyn StartsFrom>>),
    /// A solver that can take a given sequence as its first incumbent ([`WarmStart`]).
    WarmStart(fn(&Params) -> Result<Box<dyn WarmStart>>),
}

/// A solver built from a registry entry, with the start it can take.
pub enum Built {
    /// Runs from scratch only.
    Fresh(Box<dyn Solver>),
    /// Can search from a given sequence.
    StartsFrom(Box<dyn StartsFrom>),
    /// Can take a given sequence as its first incumbent.
    WarmStart(Box<dyn WarmStart>),
}

impl Built {
    /// Runs the solver, from `start` when one is given; a solver that cannot take a start is
    /// refused one (an error naming `name`).
    pub fn run(&self, ctx: &mut Context, start: Option<&Sequence>, name: &str) -> Result<Outcome> {
        match (self, start) {
            (Built::Fresh(s), None) => s.solve(ctx),
            (Built::StartsFrom(s), None) => s.run_from(ctx, None),
            (Built::WarmStart(s), None) => s.solve(ctx),
            (Built::StartsFrom(s), Some(q)) => {
                let start = Solution::new(&Costs::open(ctx.model), q);
                s.run_from(ctx, Some(start))
            }
            (Built::WarmStart(s), Some(q)) => s.warm_start(ctx, q),
            (Built::Fresh(_), Some(_)) => Err(Error::Solver {
                solver: name.to_string(),
                msg: "cannot start from a given sequence".to_string(),
            }),
        }
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

/// What a solver promises about its results, declared in its registry entry; sub-runs, plans
/// and tests read it. (Which start it can take is not a flag: it is the `Build` variant.)
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Caps {
    /// Never ends worse than `greedy` and keeps to an evaluation budget up to one pass or
    /// construction (the local-search family).
    pub improves: bool,
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
        exact: false,
        needs: Needs::Any,
    };
}

/// A registry entry: everything a solver declares about itself, in its own file.
pub struct SolverInfo {
    /// Registry name (`--solver NAME`).
    pub name: &'static str,
    /// One-line description.
    pub summary: &'static str,
    /// The longer description (Markdown) of `docs/solvers.md`.
    pub description: &'static str,
    /// Parameters with defaults.
    pub params: &'static [ParamSpec],
    /// What it promises.
    pub caps: Caps,
    /// How it is built, and which start it can take.
    pub(crate) build: Build,
}

impl std::fmt::Debug for SolverInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolverInfo")
            .field("name", &self.name)
            .field("caps", &self.caps)
            .finish_non_exhaustive()
    }
}

impl SolverInfo {
    /// Validates `given` against the declared parameters and builds the solver.
    pub(crate) fn build(&self, given: &BTreeMap<String, String>) -> Result<(Params, Built)> {
        let params = Params::new(self.name, self.params, given)?;
        let built = match self.build {
            Build::Fresh(f) => Built::Fresh(f(&params)?),
            Build::StartsFrom(f) => Built::StartsFrom(f(&params)?),
            Build::WarmStart(f) => Built::WarmStart(f(&params)?),
        };
        Ok((params, built))
    }
    /// Validates `given` against the declared parameters and tries the constructor (a
    /// malformed `auto` plan or portfolio fails here): the parameters with defaults filled in.
    pub fn check_params(&self, given: &BTreeMap<String, String>) -> Result<Params> {
        self.build(given).map(|(p, _)| p)
    }
    /// True when the solver searches from a given sequence (`StartsFrom`).
    pub fn starts_from(&self) -> bool {
        matches!(self.build, Build::StartsFrom(_))
    }
    /// True when the solver takes a given sequence as its first incumbent (`WarmStart`).
    pub fn warm_start(&self) -> bool {
        matches!(self.build, Build::WarmStart(_))
    }
    /// True when a start sequence can be handed to the solver.
    pub fn takes_start(&self) -> bool {
        !matches!(self.build, Build::Fresh(_))
    }
}

/// True when the environment asks the solvers for their diagnostic trace on standard error:
/// `CELLSEQ_TRACE` (any value; `CELLSEQ_BEAM_TRACE`, the beam's older name, is read as well).
pub fn trace_enabled() -> bool {
    std::env::var_os("CELLSEQ_TRACE").is_some() || std::env::var_os("CELLSEQ_BEAM_TRACE").is_some()
}

/// Every registered solver, in display order.
pub fn registry() -> Vec<&'static SolverInfo> {
    SolverKind::ALL.iter().map(|k| k.info()).collect()
}

/// Name of the solver `cellseq solve` uses when none is named.
pub const DEFAULT_SOLVER: &str = "auto";

/// Looks a solver up by name.
pub fn find(name: &str) -> Result<&'static SolverInfo> {
    name.parse::<SolverKind>().map(SolverKind::info)
}

impl std::str::FromStr for SolverKind {
    type Err = Error;
    /// The solver of registry name `name`; an unknown name is an [`Error::UnknownSolver`]
    /// listing the known ones.
    fn from_str(name: &str) -> Result<SolverKind> {
        SolverKind::ALL
            .iter()
            .copied()
            .find(|k| k.info().name == name)
            .ok_or_else(|| Error::UnknownSolver {
                name: name.to_string(),
                known: SolverKind::ALL
                    .iter()
                    .map(|k| k.info().name)
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }
}

impl SolverKind {
    /// Its registry name (`ils`, `greedy-edge`, ...).
    pub fn name(self) -> &'static str {
        self.info().name
    }
}

impl Default for SolverKind {
    /// `auto`, the solver `cellseq solve` uses when none is named.
    fn default() -> Self {
        SolverKind::Auto
    }
}

impl std::fmt::Display for SolverKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
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
    /// The sequence it starts from (solvers that [`SolverInfo::takes_start`]).
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
    let (_, solver) = info.build(sub.params)?;
    let (instance, model) = sub.on.unwrap_or((ctx.instance, ctx.model));
    let mut quiet = NoObserver;
    let mut budget = sub.budget;
    if let Some(left) = ctx.remaining() {
        budget.time_limit = Some(budget.time_limit.map_or(left, |t| t.min(left)));
    }
    let mut inner = Context::new(instance, model, sub.seed, budget, &mut quiet)
        .with_stop(ctx.stop_flag());
    let out = solver.run(&mut inner, sub.start, info.name)?;
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
    let opts = RunOptions::default();
    run_until(name, inst, objective, given, seed, budget, observer, opts)
}

/// What [`run_until`] takes beyond [`run`]'s arguments.
#[derive(Debug, Clone, Copy, Default)]
pub struct RunOptions<'a> {
    /// Stops the run (with the best found so far) as soon as it is set.
    pub stop: Option<&'a AtomicBool>,
    /// The time limit the caller stated for the whole solve, when the budget's is what is
    /// left of it ([`Context::nominal_limit`]).
    pub nominal: Option<std::time::Duration>,
}

/// [`run`] with [`RunOptions`]: also stopped as soon as `opts.stop` is set, its plan sized
/// by `opts.nominal`.
#[allow(clippy::too_many_arguments)]
pub fn run_until(
    name: &str,
    inst: &Instance,
    objective: Objective,
    given: &BTreeMap<String, String>,
    seed: u64,
    budget: Budget,
    observer: &mut dyn Observer,
    opts: RunOptions<'_>,
) -> Result<RunResult> {
    let info = find(name)?;
    let (_, solver) = info.build(given)?;
    let model = CostModel::new(inst, objective);
    if !model.acyclic() {
        return Err(Error::invalid(
            &inst.name,
            "no order satisfies the precedence with the fixed first and last cells (see `cellseq validate`)",
        ));
    }
    let objective = model.objective();
    let mut ctx = Context::new(inst, &model, seed, budget, observer)
        .with_stop(opts.stop)
        .with_nominal(opts.nominal);
    let outcome = solver.run(&mut ctx, None, name)?;
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
    // a result at the model's floor (a lower bound on every sequence) is optimal, whichever
    // solver found it (a search stops there without a proof of its own)
    let mut outcome = outcome;
    let floor = ctx.floor();
    if !outcome.proven_optimal && crate::context::meets_floor(report.cost, floor) {
        outcome.proven_optimal = true;
        outcome.lower_bound = Some(outcome.lower_bound.map_or(floor, |b| b.max(floor)));
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

    /// A result at the model's floor is reported as proven optimal with the floor as its
    /// lower bound, whichever solver found it; one above it is not.
    #[test]
    fn a_result_at_the_floor_is_proven() {
        let zeros = "TYPE: SOP\nDIMENSION: 4\nEDGE_WEIGHT_SECTION\n4\n\
                     0 0 0 0\n-1 0 0 0\n-1 0 0 0\n-1 -1 -1 0\nEOF\n";
        let inst = parse_instance("zeros.sop", zeros, Format::Sop).unwrap();
        let go = |inst: &Instance| {
            let obj = inst.default_objective();
            run("greedy", inst, obj, &BTreeMap::new(), 1, Budget::default(), &mut NoObserver)
                .unwrap()
        };
        let r = go(&inst);
        assert_eq!(r.report.cost, 0.0);
        assert!(r.outcome.proven_optimal);
        assert_eq!(r.outcome.lower_bound, Some(0.0));
        let r = go(&tiny());
        let floor = crate::context::floor(&CostModel::new(&tiny(), tiny().default_objective()));
        assert!(r.report.cost > floor, "the tiny instance's optimum is above its floor");
        assert!(!r.outcome.proven_optimal);
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
            e.contains("only gls, ils, eacs, reopt and corridor can start from an earlier sequence"),
            "{e}"
        );
    }

    #[test]
    fn sub_runs_start_only_solvers_that_take_a_start() {
        let inst = tiny();
        let model = CostModel::new(&inst, inst.default_objective());
        let mut obs = NoObserver;
        let budget = Budget {
            time_limit: None,
            max_evals: Some(5_000),
        };
        let mut ctx = Context::new(&inst, &model, 3, budget, &mut obs);
        let start = sub_run(&mut ctx, Sub::new("as-given", budget, 3)).unwrap();
        let used = ctx.evaluations();
        for info in registry() {
            let sub = Sub {
                start: Some(&start.sequence),
                ..Sub::new(info.name, budget, 3)
            };
            let out = sub_run(&mut ctx, sub);
            if info.takes_start() {
                let out = out.unwrap_or_else(|e| panic!("{}: {e}", info.name));
                assert!(out.cost <= start.cost, "{} worse than its start", info.name);
                assert!(ctx.evaluations() >= used, "{}", info.name);
            } else {
                assert!(out.is_err(), "{} took a start it cannot use", info.name);
            }
        }
    }
}

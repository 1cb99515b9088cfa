//! What a run needs, shared by the move engine and the solvers: the budget (time and
//! evaluations), the evaluation counter and clock ([`Context`]), progress observers and traces,
//! and what a run returns ([`Outcome`]). Nothing here knows any solver: the engine's searches
//! take a [`Context`] for their budget and counter, and the solvers receive one from
//! [`crate::solvers::run`] or from a sub-run ([`crate::solvers::sub_run`]).

pub use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::model::{Instance, Sequence};
use std::sync::atomic::{AtomicBool, Ordering};
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

/// What a solver sees while it runs: the instance, its cost model, seed and budget (its
/// parameters were read when it was built).
pub struct Context<'a> {
    /// The instance.
    pub instance: &'a Instance,
    /// Arc costs and precedence.
    pub model: &'a CostModel,
    /// Random seed.
    pub seed: u64,
    /// Budget.
    pub budget: Budget,
    observer: &'a mut dyn Observer,
    stop: Option<&'a AtomicBool>,
    /// The time limit as the caller stated it ([`Context::nominal_limit`]), when it differs
    /// from the budget's.
    nominal: Option<Duration>,
    start: Instant,
    evaluations: u64,
    best: f64,
    /// A cheap lower bound on the optimum ([`floor`]), computed on the first report: a run
    /// whose best meets it is done.
    floor: Option<f64>,
    /// Calls of [`Context::exhausted_polled`] and the evaluation count when it last read
    /// the clock.
    polls: u32,
    polled_at: u64,
}

/// [`Context::exhausted_polled`] reads the clock at least every this many calls …
const POLL_CALLS: u32 = 16;
/// … and after this many counted evaluations.
const POLL_EVALS: u64 = 4096;

impl<'a> Context<'a> {
    /// Builds a context; the clock starts now.
    pub fn new(
        instance: &'a Instance,
        model: &'a CostModel,
        seed: u64,
        budget: Budget,
        observer: &'a mut dyn Observer,
    ) -> Self {
        Context {
            instance,
            model,
            seed,
            budget,
            observer,
            stop: None,
            nominal: None,
            start: Instant::now(),
            evaluations: 0,
            best: f64::INFINITY,
            floor: None,
            polls: 0,
            polled_at: 0,
        }
    }
    /// The same context, also stopped as soon as `stop` is set (from another thread: a user's
    /// Ctrl-C, a caller's cancel); the solver ends as at the end of its budget.
    pub fn with_stop(mut self, stop: Option<&'a AtomicBool>) -> Self {
        self.stop = stop;
        self
    }
    /// The same context, its plan sized by `limit` ([`Context::nominal_limit`]); `None` keeps
    /// the budget's time limit.
    pub fn with_nominal(mut self, limit: Option<Duration>) -> Self {
        self.nominal = limit;
        self
    }
    /// The time limit a solver sizes its plan by: the limit its caller stated for the whole
    /// solve (a command's `--time-limit`, before reading the input and the lower bound's share
    /// took their part of it), or else the budget's own. A solver that picks its phases by
    /// budget (`auto`'s beam and long plans) compares this with its thresholds, so that
    /// `--time-limit 5` means 5 s to it; the budget and the clock still end the run.
    pub fn nominal_limit(&self) -> Option<Duration> {
        self.nominal.or(self.budget.time_limit)
    }
    /// The stop flag this context honours, for the contexts of sub-runs.
    pub fn stop_flag(&self) -> Option<&'a AtomicBool> {
        self.stop
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
    /// The share of the budget used: of the evaluation budget when one is set (so that a run
    /// under an evaluation budget stays deterministic), else of the time limit, else none.
    pub fn used_share(&self) -> f64 {
        if let Some(m) = self.budget.max_evals {
            self.evaluations as f64 / m.max(1) as f64
        } else if let Some(t) = self.budget.time_limit {
            self.elapsed() / t.as_secs_f64().max(1e-9)
        } else {
            0.0
        }
    }
    /// The end of the wall-clock budget (none without a time limit): what long computations
    /// below the solvers (bounds, tables, constructions) check.
    pub fn deadline(&self) -> Deadline {
        Deadline::from(self.start, self.budget.time_limit)
    }
    /// The wall-clock time left, or `None` without a time limit.
    pub fn remaining(&self) -> Option<Duration> {
        self.budget
            .time_limit
            .map(|t| t.saturating_sub(self.start.elapsed()))
    }
    /// True when the budget is used up, the stop flag is set, or when the best reported cost meets the model's
    /// [`floor`] (it is optimal: nothing is left to search for).
    pub fn exhausted(&self) -> bool {
        if self.exhausted_but_the_clock() {
            return true;
        }
        if let Some(t) = self.budget.time_limit
            && self.start.elapsed() >= t
        {
            return true;
        }
        false
    }
    /// The checks of [`Context::exhausted`] that do not read the clock: the stop flag, the
    /// floor and the evaluation budget.
    #[inline]
    fn exhausted_but_the_clock(&self) -> bool {
        self.stop.is_some_and(|s| s.load(Ordering::Relaxed))
            || self.solved()
            || self.budget.max_evals.is_some_and(|m| self.evaluations >= m)
    }
    /// [`Context::exhausted`] for the hot loops of the local search, where every call does a
    /// little counted work (one cell looked at): the clock is read only every
    /// [`POLL_CALLS`] calls or [`POLL_EVALS`] counted evaluations, whichever comes first, since
    /// a clock read costs as much as dozens of move evaluations. The budget, the stop flag
    /// and the floor are checked on every call; the time limit is overrun by at most that
    /// much work.
    #[inline]
    pub fn exhausted_polled(&mut self) -> bool {
        if self.budget.time_limit.is_some() {
            self.polls += 1;
            if self.polls < POLL_CALLS && self.evaluations.saturating_sub(self.polled_at) < POLL_EVALS {
                return self.exhausted_but_the_clock();
            }
            self.polls = 0;
            self.polled_at = self.evaluations;
        }
        self.exhausted()
    }
    /// True when the best reported cost meets the model's [`floor`]: it is optimal.
    #[inline]
    pub fn solved(&self) -> bool {
        self.floor.is_some_and(|f| meets_floor(self.best, f))
    }
    /// The model's [`floor`], computed once per run (on the first report or here).
    pub fn floor(&mut self) -> f64 {
        *self.floor.get_or_insert_with(|| floor(self.model))
    }
    /// Reports a solution cost; the observer hears of it when it improves the best.
    pub fn report(&mut self, cost: f64) {
        if cost < self.best - 1e-9 * cost.abs().max(1.0) {
            self.floor();
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
    #[cfg(any(test, feature = "internals"))]
    pub fn best(&self) -> f64 {
        self.best
    }
}

/// True when `cost` meets the floor `f` (within 10⁻⁹ of it): a sequence of that cost is
/// optimal.
#[inline]
pub fn meets_floor(cost: f64, f: f64) -> bool {
    cost <= f + 1e-9 * f.abs().max(1.0)
}

/// A lower bound on the cost of every sequence that costs O(nodes) given the model's cheapest
/// arcs ([`CostModel::least_arcs`], built once per model; without them the arcs count as 0):
/// the constant, the cheapest start and finish, and every cell but one entered by its
/// cheapest arc (in its cheapest mode), the dearest of those left out. Exact with one cell,
/// with all-zero arcs and with all costs equal: a run that meets it can stop.
pub fn floor(m: &CostModel) -> f64 {
    let n = m.n();
    let nodes = |c: usize| (0..m.modes(c)).map(move |md| (md, m.node(c, md)));
    let least = |it: &mut dyn Iterator<Item = f64>| it.fold(f64::INFINITY, f64::min);
    if n == 0 {
        return m.constant();
    }
    if n == 1 {
        let only = least(&mut nodes(0).map(|(md, _)| m.start(0, md) + m.finish(0, md)));
        return m.constant() + only;
    }
    let start = least(&mut (0..n).flat_map(|c| nodes(c).map(move |(md, _)| m.start(c, md))));
    let finish = least(&mut (0..n).flat_map(|c| nodes(c).map(move |(md, _)| m.finish(c, md))));
    let entered = m.least_arcs().map_or(0.0, |la| {
        let per: Vec<f64> = (0..n)
            .map(|c| least(&mut nodes(c).map(|(_, nd)| la.inn[nd])))
            .collect();
        let top = per.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        per.iter().sum::<f64>() - top
    });
    let f = m.constant() + start + finish + entered;
    if f.is_finite() { f } else { m.constant() }
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::Objective;

    fn instance() -> (Instance, CostModel) {
        let kv = [("n", "20")]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let inst = crate::generate::generate("random-sop", &kv, 1).expect("generated");
        let m = CostModel::new(&inst, Objective::Matrix);
        (inst, m)
    }

    /// The polled check reads the clock within `POLL_CALLS` calls (a spent time limit ends
    /// the loop that soon) and sees the evaluation budget and the stop flag at once.
    #[test]
    fn polled_check_ends_as_the_plain_one() {
        let (inst, m) = instance();
        let mut obs = NoObserver;
        let spent = Budget {
            time_limit: Some(Duration::ZERO),
            max_evals: None,
        };
        let mut ctx = Context::new(&inst, &m, 1, spent, &mut obs);
        assert!(ctx.exhausted());
        let calls = (1..=POLL_CALLS).find(|_| ctx.exhausted_polled());
        assert!(calls.is_some(), "the clock was not read in {POLL_CALLS} calls");
        // counted work makes it read the clock on the next call
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, spent, &mut obs);
        ctx.count(POLL_EVALS);
        assert!(ctx.exhausted_polled());

        let budget = Budget {
            time_limit: Some(Duration::from_secs(3600)),
            max_evals: Some(10),
        };
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, budget, &mut obs);
        assert!(!ctx.exhausted_polled());
        ctx.count(10);
        assert!(ctx.exhausted_polled());

        let stop = AtomicBool::new(false);
        let budget = Budget {
            time_limit: Some(Duration::from_secs(3600)),
            max_evals: None,
        };
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, budget, &mut obs).with_stop(Some(&stop));
        assert!(!ctx.exhausted_polled());
        stop.store(true, Ordering::Relaxed);
        assert!(ctx.exhausted_polled());
    }
}

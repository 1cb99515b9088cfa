//! What a run needs, shared by the move engine and the solvers: the budget (time and
//! evaluations), the evaluation counter and clock ([`Context`]), progress observers and traces,
//! and what a run returns ([`Outcome`]). Nothing here knows any solver: the engine's searches
//! take a [`Context`] for their budget and counter, and the solvers receive one from
//! [`crate::solvers::run`] or from a sub-run ([`crate::solvers::sub_run`]).

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
    start: Instant,
    evaluations: u64,
    best: f64,
}

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
            start: Instant::now(),
            evaluations: 0,
            best: f64::INFINITY,
        }
    }
    /// The same context, also stopped as soon as `stop` is set (from another thread: a user's
    /// Ctrl-C, a caller's cancel); the solver ends as at the end of its budget.
    pub fn with_stop(mut self, stop: Option<&'a AtomicBool>) -> Self {
        self.stop = stop;
        self
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
    /// True when the budget is used up or the stop flag is set.
    pub fn exhausted(&self) -> bool {
        if self.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            return true;
        }
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
    #[cfg(any(test, feature = "internals"))]
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

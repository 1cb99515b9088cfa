//! The optimisation pipeline shared by G-code and drawings: groups in their required order →
//! instance → solver → keep the original where it is not worse → verify → write atomically.
//!
//! File codecs (`io::gcode`, `io::svg`, `io::dxf`) read, interpret, write and verify files and
//! never call a solver; the pipeline does. This module holds the steps every input kind shares:
//! the budget of the whole command ([`Allowance`]: one time limit or evaluation budget covering
//! parse, solve, verify and write, shared among groups by size), solving one group with its
//! share and keeping the group's original order unless the solver's order is strictly better
//! ([`solve_group`]), and where the time went ([`Timings`]). [`gcode`] is the G-code pipeline,
//! [`strokes`] the pipeline of SVG and DXF drawings.

pub mod gcode;
pub mod strokes;

use cellseq::error::{Error, Result};
use cellseq::model::{Instance, Objective, Sequence, Visit};
use cellseq::{Budget, Solve, SolverKind};
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// Seconds spent in each step of a command (also printed in `--json` reports).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Timings {
    /// Reading and interpreting the input.
    pub parse_s: f64,
    /// Building instances and running the solver on every group.
    pub solve_s: f64,
    /// Checking the output against the input.
    pub verify_s: f64,
    /// Producing the output text and writing it.
    pub write_s: f64,
}

impl Timings {
    /// Sum of the steps.
    pub fn total_s(&self) -> f64 {
        self.parse_s + self.solve_s + self.verify_s + self.write_s
    }
}

/// The budget of a whole command: a wall-clock limit counted from `started` (the moment the
/// command began, so parsing counts) and/or an evaluation budget for the solver. Without
/// either, a deterministic evaluation budget is derived from each group's size.
#[derive(Debug, Clone, Copy)]
pub struct Allowance {
    /// When the command started.
    pub started: Instant,
    /// Time limit of the whole command (s).
    pub time_limit: Option<f64>,
    /// Evaluations for all groups together.
    pub max_evals: Option<u64>,
}

impl Allowance {
    /// An allowance starting now. The time limit must lie in (0, [`cellseq::solve::MAX_SECONDS`]]
    /// seconds and the evaluation budget be at least 1; other values are refused, naming
    /// `--time-limit` or `--max-evals`.
    pub fn new(time_limit: Option<f64>, max_evals: Option<u64>) -> Result<Self> {
        if let Some(t) = time_limit {
            cellseq::solve::checked_seconds("--time-limit", t)?;
        }
        if max_evals == Some(0) {
            return Err(Error::Param("--max-evals must be at least 1".into()));
        }
        Ok(Allowance {
            started: Instant::now(),
            time_limit,
            max_evals,
        })
    }

    /// Seconds left of the time limit (none without one); never negative.
    pub fn remaining_s(&self) -> Option<f64> {
        self.time_limit
            .map(|t| (t - self.started.elapsed().as_secs_f64()).max(0.0))
    }

    /// The solver budget of a group of `size` items when `left` items (this group included)
    /// are still to be solved, keeping `reserve_s` seconds for verifying and writing. Time is
    /// shared by size among what is left, so a group that finishes early leaves its time to
    /// the next; evaluations are shared by size of the whole (`total` items), deterministically.
    pub fn share(&self, size: usize, left: usize, total: usize, reserve_s: f64) -> Budget {
        let default = (size as u64 * 20_000).clamp(100_000, 10_000_000);
        self.share_or(size, left, total, reserve_s, default)
    }

    /// [`share`](Self::share) with the evaluation budget a group gets when the command has
    /// neither a time limit nor an evaluation budget (`default_evals`: each input kind has its
    /// own, deterministic and linear in the group's size).
    pub fn share_or(
        &self,
        size: usize,
        left: usize,
        total: usize,
        reserve_s: f64,
        default_evals: u64,
    ) -> Budget {
        let frac = |part: usize, whole: usize| part as f64 / whole.max(1) as f64;
        let time_limit = self.remaining_s().map(|r| {
            let usable = (r - reserve_s).max(0.0);
            Duration::from_secs_f64(usable * frac(size, left))
        });
        let max_evals = match (self.max_evals, self.time_limit) {
            (Some(n), _) => Some(((n as f64) * frac(size, total)).ceil().max(1.0) as u64),
            // without a time limit: an evaluation budget, so the output is deterministic
            (None, None) => Some(default_evals),
            (None, Some(_)) => None,
        };
        Budget {
            time_limit,
            max_evals,
        }
    }
}

/// The outcome of [`solve_group`].
#[derive(Debug, Clone)]
pub struct GroupSolve {
    /// The order kept (the solver's, or the group's original order).
    pub sequence: Sequence,
    /// True when the original order was kept because the solver's order was not better.
    pub kept_original: bool,
    /// Cost of the original order (checker's objective).
    pub original_cost: f64,
    /// Cost of the solver's order.
    pub solver_cost: f64,
    /// Seconds spent in the solver.
    pub elapsed_s: f64,
}

/// The instance's original order: its `as_given` sequence, else cells in file order.
pub fn original_order(inst: &Instance) -> Sequence {
    inst.as_given
        .clone()
        .unwrap_or_else(|| (0..inst.cells.len()).map(|i| Visit::new(i, 0)).collect())
}

/// Runs `solver` on one group's instance with `budget`, and keeps the group's original order
/// unless the solver's order is strictly better on `objective` (by the independent checker).
/// `as-given` keeps the original order without running anything.
pub fn solve_group(
    inst: &Instance,
    objective: Objective,
    solver: SolverKind,
    params: &BTreeMap<String, String>,
    seed: u64,
    budget: Budget,
) -> Result<GroupSolve> {
    cellseq::validate::validate(inst, &inst.name)?;
    let original = original_order(inst);
    // the original order is what the program does, even where it breaks a derived rule
    // (inner contours first): its cost is measured without precedence then
    let original_cost = match cellseq::check(inst, &original, objective) {
        Ok(r) => r.cost,
        Err(_) => {
            let mut free = inst.clone();
            free.precedence.clear();
            cellseq::check(&free, &original, objective)
                .map_err(|v| {
                    Error::invalid(&inst.name, format!("the original order is invalid: {v}"))
                })?
                .cost
        }
    };
    if solver == SolverKind::AsGiven {
        return Ok(GroupSolve {
            sequence: original,
            kept_original: true,
            original_cost,
            solver_cost: original_cost,
            elapsed_s: 0.0,
        });
    }
    let r = Solve::new(solver)
        .params_text(params)
        .seed(seed)
        .budget(budget)
        .objective(objective)
        .run(inst)?;
    let better = r.report.cost < original_cost - 1e-9 * original_cost.abs().max(1.0);
    Ok(GroupSolve {
        kept_original: !better,
        sequence: if better { r.sequence } else { original },
        original_cost,
        solver_cost: r.report.cost,
        elapsed_s: r.elapsed_s,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evaluation_shares_follow_size_and_are_deterministic() {
        let a = Allowance::new(None, Some(1000)).unwrap();
        assert_eq!(a.share(250, 1000, 1000, 0.0).max_evals, Some(250));
        assert_eq!(a.share(250, 250, 1000, 0.0).max_evals, Some(250));
        let b = Allowance::new(None, None).unwrap();
        assert_eq!(b.share(10, 10, 10, 0.0).max_evals, Some(200_000));
        assert!(b.share(10, 10, 10, 0.0).time_limit.is_none());
    }

    #[test]
    fn time_shares_leave_the_reserve() {
        let a = Allowance::new(Some(10.0), None).unwrap();
        let b = a.share(1, 2, 2, 2.0);
        let t = b.time_limit.unwrap().as_secs_f64();
        assert!(t <= 4.0 && t > 3.5, "{t}");
        assert!(b.max_evals.is_none());
    }
}

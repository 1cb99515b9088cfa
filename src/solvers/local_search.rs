//! `local-search`: greedy start (or the greedy matching start where it applies and is
//! cheaper, see [`super::edge`]), on large instances without precedence a first Or-opt pass
//! on a linked list (O(1) moves), then variable neighbourhood descent over every move of the
//! engine (Or-opt, 2-opt with mode flip, single-cell mode change, SOP-3-exchange, mode DP).
//! After the first descent it iterates: kick the best with a few random feasible Or-opt moves,
//! descend again, keep the result when better (until the budget, or `kicks` failures in a row).

use super::start::{best_start, outcome};
use super::{Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::engine::moves::{apply_segment, segment_delta, window};
use crate::engine::search::Search;
use crate::engine::{Costs, linked};
use crate::error::Result;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "local-search",
    summary: "greedy, then (iterated) VND over Or-opt, 2-opt with mode flip, mode change, SOP-3-exchange and the mode DP",
    params: &[
        ParamSpec {
            name: "k",
            default: "10",
            kind: ParamKind::Int,
            help: "candidate neighbours per cell",
        },
        ParamSpec {
            name: "kicks",
            default: "30",
            kind: ParamKind::Int,
            help: "iterated VND: stop after this many non-improving kicks (runs until the budget when one is set; 0 = plain VND)",
        },
        ParamSpec {
            name: "strength",
            default: "3",
            kind: ParamKind::Int,
            help: "random feasible Or-opt moves per kick",
        },
        ParamSpec {
            name: "vnd",
            default: "true",
            kind: ParamKind::Bool,
            help: "false = stop after the start and the linked-list Or-opt pass (where it applies): greedy plus one O(1)-per-move improvement pass",
        },
        ParamSpec {
            name: "max-block",
            default: "0",
            kind: ParamKind::Int,
            help: "longest block of SOP-3-exchange (0 = n up to 120 cells, 64 up to 5000, else 8)",
        },
    ],
    make: |p: &Params| {
        let kicks = p.int("kicks");
        let strength = p.int("strength").max(1) as usize;
        Box::new(LocalSearch {
            kicks,
            strength,
            k: p.int("k").max(1) as usize,
            max_block: p.int("max-block") as usize,
            vnd: p.bool("vnd"),
        })
    },
};

/// From this many cells on, instances without precedence get a first Or-opt pass on a linked
/// list ([`linked::or_opt`]) before the VND. At 10^5 cells it does not pay (the VND's 2-opt
/// gains more per second: 0.825 against 0.837 × greedy's air after 10 s); at 10^6 it is the
/// only pass that finishes within a minute.
pub const LINKED_CELLS: usize = 200_000;

/// The VND solver.
pub struct LocalSearch {
    /// Candidate neighbours per cell.
    pub k: usize,
    /// SOP-3-exchange block limit (0 = automatic).
    pub max_block: usize,
    /// Non-improving kicks before stopping when no budget is set.
    pub kicks: u64,
    /// Random Or-opt moves per kick.
    pub strength: usize,
    /// Run the VND (false: only the start and the linked-list Or-opt pass).
    pub vnd: bool,
}

impl Solver for LocalSearch {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs::open(m);
        let mut s = best_start(ctx, &c, 8);
        if ctx.exhausted() {
            return Ok(outcome(m, &s));
        }
        let mut search = Search::new(c, self.k);
        if self.max_block > 0 {
            search.max_block = self.max_block;
        }
        if s.n() >= LINKED_CELLS && linked::applies(&c) {
            // O(1) Or-opt moves first: on the array every move shifts the cells in between
            linked::or_opt(&c, &search.nb, &mut s, ctx);
            ctx.report(s.cost + m.constant());
        }
        if !self.vnd {
            return Ok(outcome(m, &s));
        }
        search.vnd(&mut s, ctx);
        ctx.report(s.cost + m.constant());
        // iterated VND: kick the best with random feasible Or-opt moves, descend, keep if better
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        let budgeted = ctx.budget.max_evals.is_some() || ctx.budget.time_limit.is_some();
        let mut best = s.clone();
        let mut fails = 0u64;
        let n = best.n();
        while n >= 4 && self.kicks > 0 && !ctx.exhausted() && (budgeted || fails < self.kicks) {
            s.clone_from(&best);
            for _ in 0..self.strength {
                let len = rng.random_range(1..=3usize).min(n - 1);
                let i = rng.random_range(0..=n - len);
                let (lo, hi) = window(m, &s, i, len);
                if hi <= lo {
                    continue;
                }
                let p = rng.random_range(lo as i64..hi as i64) as isize;
                if p >= i as isize - 1 && p < (i + len) as isize {
                    continue;
                }
                let d = segment_delta(&c, &s, i, len, p, false);
                apply_segment(m, &mut s, i, len, p, false, d);
            }
            ctx.count(self.strength as u64);
            search.vnd(&mut s, ctx);
            if s.cost < best.cost - 1e-9 * best.cost.abs().max(1.0) {
                best.clone_from(&s);
                ctx.report(best.cost + m.constant());
                fails = 0;
            } else {
                fails += 1;
            }
        }
        Ok(outcome(m, &best))
    }
}

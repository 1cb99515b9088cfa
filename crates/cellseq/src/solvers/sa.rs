//! `sa`: simulated annealing as in paper 000 (process-based sequencing of machining cells):
//! Metropolis acceptance, Markov chains of length L per temperature, geometric cooling, stop
//! when the best has not changed over a number of chains (or the budget ends); open-loop
//! (path) or closed-loop (tour: return to home) evaluation.
//!
//! Random moves come from the engine: Or-opt (segment of 1–3 cells to a random position of its
//! precedence window, kept or reversed with mode flip), reversal with mode flip of a short
//! precedence-free segment, single-cell mode change. [`Anneal`] can confine moves to fixed
//! blocks of positions (the `process` solver anneals inside its level-4 groups).

use super::Build;
use super::start::{greedy_start, outcome, true_cost};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::engine::moves::{
    apply_segment, reverse_delta_direct, reversible_segment, segment_delta, window,
};
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution, cheaper};
use crate::error::Result;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "sa",
    summary: "simulated annealing (paper 000): Metropolis, chains of length L, geometric cooling, stagnation stop",
    description: "Simulated annealing as in paper 000: Metropolis acceptance over Markov chains of length \
`chain` × n per temperature, geometric cooling by `alpha` from a temperature at which an \
average worsening move is accepted with probability `accept0`, a stop after `stall` chains \
without a new best, re-annealing from the best (`reheats`), open- or closed-loop evaluation \
(`eval`), and a VND polish of the best (`polish`).",
    params: SPECS,
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Sa {
            anneal: Anneal::from_params(p),
            polish: p.bool("polish"),
        }))
    }),
};

/// The parameters shared by `sa` and `process`.
pub static SPECS: &[ParamSpec] = &[
    ParamSpec {
        name: "chain",
        default: "20",
        kind: ParamKind::float(0.01, 1e6),
        help: "Markov chain length L per temperature, times n",
    },
    ParamSpec {
        name: "alpha",
        default: "0.97",
        kind: ParamKind::float_open(0.0, 1.0),
        help: "geometric cooling factor per chain",
    },
    ParamSpec {
        name: "accept0",
        default: "0.3",
        kind: ParamKind::float_open(0.0, 1.0),
        help: "initial acceptance probability of an average worsening move",
    },
    ParamSpec {
        name: "stall",
        default: "40",
        kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
        help: "stop a run after this many chains without a new best",
    },
    ParamSpec {
        name: "max-chains",
        default: "2000",
        kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
        help: "chains per run at most",
    },
    ParamSpec {
        name: "reheats",
        default: "3",
        kind: ParamKind::int(0, crate::params::MAX_ITERATIONS),
        help: "re-annealing runs from the best after a run stops (unlimited while a budget is set)",
    },
    ParamSpec {
        name: "eval",
        default: "open",
        kind: ParamKind::Choice(&["open", "closed"]),
        help: "open-loop (path) or closed-loop (return to home) evaluation",
    },
    ParamSpec {
        name: "polish",
        default: "true",
        kind: ParamKind::Bool,
        help: "finish with the engine's VND on the best",
    },
];

/// The SA solver.
pub struct Sa {
    /// Annealing schedule.
    pub anneal: Anneal,
    /// VND at the end.
    pub polish: bool,
}

/// An annealing schedule and its move generator.
#[derive(Debug, Clone)]
pub struct Anneal {
    /// Chain length factor (L = chain · n).
    pub chain: f64,
    /// Cooling factor.
    pub alpha: f64,
    /// Initial acceptance probability.
    pub accept0: f64,
    /// Chains without a new best before a run stops.
    pub stall: u64,
    /// Chain limit per run.
    pub max_chains: u64,
    /// Re-annealing runs.
    pub reheats: u64,
    /// Closed-loop evaluation.
    pub closed: bool,
}

impl Anneal {
    /// Reads the [`SPECS`] parameters.
    pub fn from_params(p: &Params) -> Self {
        Anneal {
            chain: p.float("chain"),
            alpha: p.float("alpha"),
            accept0: p.float("accept0"),
            stall: p.int("stall"),
            max_chains: p.int("max-chains"),
            reheats: p.int("reheats"),
            closed: p.word("eval") == "closed",
        }
    }

    /// Anneals `s` in place (it ends as the best solution found). `block[p]` = (first, last)
    /// position of the block that position p belongs to, when moves are confined to blocks.
    pub fn run(
        &self,
        ctx: &mut Context,
        c: &Costs,
        s: &mut Solution,
        block: Option<&[(u32, u32)]>,
        rng: &mut ChaCha8Rng,
    ) {
        let n = s.n();
        if n < 2 {
            return;
        }
        let m = c.m;
        let multi = m.multimode();
        // initial temperature from the median of sampled worsening moves (robust to the huge
        // "forbidden" arc costs of some matrix instances)
        let mut ups: Vec<f64> = Vec::new();
        for _ in 0..200 {
            if let Some((d, _)) = self.propose(c, s, block, rng, multi)
                && d > 0.0
            {
                ups.push(d);
            }
        }
        ctx.count(200);
        if ups.is_empty() {
            return;
        }
        ups.sort_by(f64::total_cmp);
        let t0 = -ups[ups.len() / 2] / self.accept0.ln();
        let len = ((self.chain * n as f64) as u64).max(1);
        let mut best = s.clone();
        let budgeted = ctx.budget.max_evals.is_some() || ctx.budget.time_limit.is_some();
        let mut run = 0u64;
        'runs: loop {
            let mut t = if run == 0 { t0 } else { t0 * 0.05 };
            let mut stall = 0u64;
            for _ in 0..self.max_chains {
                let before = best.cost;
                for step in 0..len {
                    if step % 256 == 0 && ctx.exhausted() {
                        break 'runs;
                    }
                    ctx.count(1);
                    let Some((d, mv)) = self.propose(c, s, block, rng, multi) else {
                        continue;
                    };
                    if d <= 0.0 || rng.random::<f64>() < (-d / t).exp() {
                        mv.apply(m, s, d);
                        if cheaper(s.cost, best.cost) {
                            best.clone_from(s);
                            ctx.report(true_cost(c, &best));
                        }
                    }
                }
                s.cost = s.evaluate(c);
                t *= self.alpha;
                if cheaper(best.cost, before) {
                    stall = 0;
                } else {
                    stall += 1;
                    if stall >= self.stall {
                        break;
                    }
                }
            }
            run += 1;
            if !budgeted && run > self.reheats {
                break;
            }
            s.clone_from(&best);
        }
        s.clone_from(&best);
        s.cost = s.evaluate(c);
    }

    fn propose(
        &self,
        c: &Costs,
        s: &Solution,
        block: Option<&[(u32, u32)]>,
        rng: &mut ChaCha8Rng,
        multi: bool,
    ) -> Option<(f64, Move)> {
        let m = c.m;
        let n = s.n();
        let i = rng.random_range(0..n);
        let (bs, be) = block
            .map(|b| (b[i].0 as usize, b[i].1 as usize))
            .unwrap_or((0, n - 1));
        let r = rng.random::<f64>();
        if multi && r < 0.15 {
            let cell = s.order[i] as usize;
            let k = m.modes(cell);
            if k < 2 {
                return None;
            }
            let md = rng.random_range(0..k);
            if md == s.mode[cell] as usize {
                return None;
            }
            let d = crate::engine::moves::mode_delta(c, s, i, md);
            return Some((d, Move::Mode(cell, md)));
        }
        if r < 0.4 {
            let j = (i + rng.random_range(1..=30usize)).min(be);
            if j <= i || !reversible_segment(m, s, i, j - i + 1) {
                return None;
            }
            return Some((reverse_delta_direct(c, s, i, j), Move::Reverse(i, j)));
        }
        let len = rng.random_range(1..=3usize).min(be + 1 - i);
        let (lo, hi) = window(m, s, i, len);
        let lo = lo.max(bs as isize - 1);
        let hi = hi.min(be as isize + 1);
        if hi - 1 < lo {
            return None;
        }
        let p = rng.random_range(lo as i64..hi as i64) as isize;
        if p >= i as isize - 1 && p < (i + len) as isize {
            return None;
        }
        let rev = len > 1 && rng.random_bool(0.5) && reversible_segment(m, s, i, len);
        Some((
            segment_delta(c, s, i, len, p, rev),
            Move::Segment(i, len, p, rev),
        ))
    }
}

/// A proposed move.
enum Move {
    Mode(usize, usize),
    Reverse(usize, usize),
    Segment(usize, usize, isize, bool),
}

impl Move {
    fn apply(&self, m: &crate::cost::CostModel, s: &mut Solution, d: f64) {
        match *self {
            Move::Mode(cell, md) => s.set_mode(cell, md, d),
            Move::Reverse(i, j) => s.reverse(m, i, j, d),
            Move::Segment(i, len, p, r) => apply_segment(m, s, i, len, p, r, d),
        }
    }
}

impl Solver for Sa {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs {
            m,
            closed: self.anneal.closed,
        };
        let seq = greedy_start(ctx);
        let mut s = Solution::new(&c, &seq);
        let start_cost = m.evaluate(&seq);
        ctx.report(start_cost);
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        self.anneal.run(ctx, &c, &mut s, None, &mut rng);
        let open = Costs::open(m);
        let mut s = Solution::new(&open, &s.sequence());
        if self.polish && !ctx.deadline().passed() {
            let mut search = Search::new_until(open, 10, ctx.deadline());
            search.vnd(&mut s, ctx);
        }
        // never end worse than the start under the true objective
        let out = outcome(m, &s);
        let out = if out.cost <= start_cost {
            out
        } else {
            super::outcome_of(m, seq)
        };
        ctx.report(out.cost);
        Ok(out)
    }
}

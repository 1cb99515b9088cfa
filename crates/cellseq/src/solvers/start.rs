//! Shared pieces of the improvement solvers: start solutions and result reporting.

use super::{Context, Outcome, ParamKind, ParamSpec, outcome_of};
use crate::clock::Ticker;
use crate::construct::{edge, greedy, insertion};
use crate::cost::CostModel;
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution};
use crate::model::{Sequence, Visit};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// The deterministic greedy start (the `greedy` solver's sequence).
/// Once the run's deadline passes, the rest of the cells follow in a quick feasible order.
pub fn greedy_start(ctx: &mut Context) -> Sequence {
    let m = ctx.model;
    let deadline = ctx.deadline();
    if m.is_geometric() {
        greedy::geometric_until(m, &mut |k| ctx.count(k), deadline)
    } else {
        greedy::matrix_until(m, &mut |k| ctx.count(k), deadline)
    }
}

/// The greedy start as an engine solution (evaluated with `c`), reported to the observer.
pub fn greedy_solution(ctx: &mut Context, c: &Costs) -> Solution {
    let seq = greedy_start(ctx);
    let s = Solution::new(c, &seq);
    ctx.report(s.cost + c.m.constant());
    s
}

/// The `k` parameter of a solver whose start comes from [`given_or_polished`] and whose gains
/// the VND polishes.
pub const POLISH_K: ParamSpec = ParamSpec {
    name: "k",
    default: "12",
    kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
    help: "candidate neighbours per cell of the VND that polishes a gain",
};

/// The start of an improvement solver that may be given one: `start`, or else the greedy
/// sequence polished by the VND with `k` candidates, reported to the observer; with the
/// search to go on with, or `None` when the time limit passed before it was built (the start
/// is then the answer).
pub fn given_or_polished<'a>(
    ctx: &mut Context,
    c: Costs<'a>,
    start: Option<Solution>,
    k: usize,
) -> (Solution, Option<Search<'a>>) {
    let fresh = start.is_none();
    let mut s = match start {
        Some(s) => s,
        None => greedy_solution(ctx, &c),
    };
    if ctx.deadline().passed() {
        return (s, None);
    }
    let mut search = Search::new_until(c, k, ctx.deadline());
    if fresh {
        search.vnd(&mut s, ctx);
    }
    ctx.report(s.cost + c.m.constant());
    (s, Some(search))
}

/// The best of the greedy start; on geometric instances with precedence (up to
/// [`INSERTION_MAX_CELLS`] cells) the cheapest-insertion start of [`super::insertion`] with `k`
/// places per cell, seeded with the run's seed; and, where it applies (geometric, no
/// precedence, one tool), the greedy matching start of [`super::edge`] with `k` candidates
/// per item end. Above
/// [`EDGE_ONLY_CELLS`] cells only the greedy matching is built where it applies (on uniform
/// strokes it is 0.91–0.93 × greedy's air from 10^4 cells on, and the nearest-neighbour walk
/// costs seconds there).
pub fn best_start(ctx: &mut Context, c: &Costs, k: usize) -> Solution {
    if c.m.n() > EDGE_ONLY_CELLS && edge::applicable(c.m) {
        let deadline = ctx.deadline();
        let seq = edge::sequence_until(c.m, k, &mut |k| ctx.count(k), deadline);
        let s = Solution::new(c, &seq);
        ctx.report(s.cost + c.m.constant());
        return s;
    }
    let mut s = greedy_solution(ctx, c);
    if c.m.is_geometric()
        && !c.m.dag.is_empty()
        && c.m.n() <= INSERTION_MAX_CELLS
        && !ctx.exhausted()
    {
        let seed = ctx.seed;
        let deadline = ctx.deadline();
        let seq = insertion::sequence_until(c.m, k, seed, &mut |k| ctx.count(k), deadline);
        let t = Solution::new(c, &seq);
        if t.cost < s.cost {
            ctx.report(t.cost + c.m.constant());
            s = t;
        }
    }
    if edge::applicable(c.m) && !ctx.exhausted() {
        let deadline = ctx.deadline();
        let seq = edge::sequence_until(c.m, k, &mut |k| ctx.count(k), deadline);
        let t = Solution::new(c, &seq);
        if t.cost < s.cost {
            ctx.report(t.cost + c.m.constant());
            s = t;
        }
    }
    s
}

/// See [`best_start`].
pub const EDGE_ONLY_CELLS: usize = 50_000;

/// Up to this many cells [`best_start`] also builds the [`super::insertion`] sequence on
/// geometric instances with precedence. Insertion touches cells in random places of memory:
/// 0.9 s at 10^5 `uniform` cells, 8 s at 4·10^5, 39 s at 10^6, where greedy takes 0.5–5 s.
pub const INSERTION_MAX_CELLS: usize = 200_000;

/// A randomized fringe construction, O(n²): at each step the cheapest ready (cell, mode) is
/// taken with probability `1 − noise`, otherwise one of the three cheapest at random. With
/// `first` set, that ready cell starts the path.
pub fn random_start(
    ctx: &mut Context,
    rng: &mut ChaCha8Rng,
    noise: f64,
    first: Option<(usize, usize)>,
) -> Sequence {
    let m = ctx.model;
    let n = m.n();
    let mut missing: Vec<u32> = m.dag.preds.iter().map(|p| p.len() as u32).collect();
    let mut ready: Vec<usize> = (0..n).filter(|&c| missing[c] == 0).collect();
    let mut seq: Sequence = Vec::with_capacity(n);
    let mut clock = Ticker::new(ctx.deadline(), 16);
    while !ready.is_empty() {
        if clock.passed() {
            crate::construct::complete(m, &mut seq);
            return seq;
        }
        let mut top: Vec<(f64, usize, usize, usize)> = Vec::with_capacity(4);
        for (idx, &c) in ready.iter().enumerate() {
            for md in 0..m.modes(c) {
                let cost = match seq.last() {
                    None => m.start(c, md),
                    Some(p) => m.arc(p.cell, p.mode, c, md),
                };
                top.push((cost, c, md, idx));
                top.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
                top.truncate(3);
            }
        }
        ctx.count(ready.len() as u64);
        let mut pick = if rng.random_bool(noise.clamp(0.0, 1.0)) {
            top[rng.random_range(0..top.len())]
        } else {
            top[0]
        };
        if seq.is_empty()
            && let Some((c, md)) = first
            && let Some(idx) = ready.iter().position(|&r| r == c)
        {
            pick = (0.0, c, md, idx);
        }
        let (_, c, md, idx) = pick;
        ready.swap_remove(idx);
        seq.push(Visit::new(c, md));
        for &s in &m.dag.succs[c] {
            missing[s as usize] -= 1;
            if missing[s as usize] == 0 {
                ready.push(s as usize);
            }
        }
    }
    seq
}

/// The outcome of a solution, scored by the true (open-loop) objective.
pub fn outcome(m: &CostModel, s: &Solution) -> Outcome {
    outcome_of(m, s.sequence())
}

/// True cost (with the order-independent constant) of a solution evaluated with `c`.
pub fn true_cost(c: &Costs, s: &Solution) -> f64 {
    if c.closed {
        c.m.evaluate(&s.sequence())
    } else {
        s.cost + c.m.constant()
    }
}

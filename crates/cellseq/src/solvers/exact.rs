//! `exact`: dynamic programming over precedence-closed subsets (Held–Karp over order ideals)
//! with the mode in the state.
//!
//! A state is (ideal S, last node u) with the cheapest cost of a path that visits exactly the
//! cells of S and ends in u. Only order ideals (predecessor-closed sets) are reachable, so dense
//! precedence shrinks the state space from 2ⁿ to far less. Levels are processed by |S|; the
//! memory in use is tracked and the solver refuses once it would pass `memory_mb`. Every state
//! keeps the node it was reached from, so the optimal path is read back exactly; it used to be
//! found again by recomputing costs within a tolerance, which failed ("broken DP
//! back-pointer") once costs overflowed to infinity (∞ − ∞ is NaN).

use super::Build;
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::clock::Ticker;
use crate::error::{Error, Result};
use crate::model::Visit;
use rustc_hash::FxHashMap;
use std::time::Instant;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "exact",
    summary: "Held-Karp DP over precedence-closed subsets with modes; proves optimality",
    description: "Held–Karp dynamic programming over precedence-closed subsets of cells, with modes: the \
optimum, proven. The number of precedence-closed subsets decides its memory; an instance \
whose tables would pass `memory_mb`, or with more than `max_cells` cells, is refused with an \
error rather than started.",
    params: &[
        ParamSpec {
            name: "memory_mb",
            default: "4096",
            kind: ParamKind::int(1, crate::params::MAX_MEMORY_MB),
            help: "refuse when the DP tables would need more than this many MiB",
        },
        ParamSpec {
            name: "max_cells",
            default: "128",
            kind: ParamKind::int(1, 128),
            help: "refuse instances with more cells (the subset bitset holds at most 128)",
        },
    ],
    caps: Caps {
        exact: true,
        ..Caps::NONE
    },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Exact {
            memory_mb: p.int("memory_mb"),
            max_cells: p.int("max_cells") as usize,
        }))
    }),
};

/// The exact DP solver.
pub struct Exact {
    /// Memory limit (MiB).
    pub memory_mb: u64,
    /// Largest instance accepted.
    pub max_cells: usize,
}

/// A DP state: the ideal (cells visited, as bits) and its last node.
type Key = (u128, u32);
/// Per state: the node before the last (`NO_PRED` at the start) and the cheapest cost.
type Level = FxHashMap<Key, (u32, f64)>;

/// The predecessor of a path's first node.
const NO_PRED: u32 = u32::MAX;

/// Memory of one state in a level's table (key, value and the table's control byte, at its
/// load factor). The states of all levels live in flat tables: no allocation per ideal, so a
/// run cut off by its deadline frees millions of them at once rather than one by one.
const BYTES_PER_STATE: u64 = 56;

impl Solver for Exact {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        if n > self.max_cells {
            return Err(err(format!(
                "instance has {n} cells; the exact DP accepts at most {} (use another solver)",
                self.max_cells
            )));
        }
        let pred_mask: Vec<u128> = (0..n)
            .map(|c| m.dag.preds[c].iter().fold(0u128, |a, &p| a | 1u128 << p))
            .collect();
        let mut dp = Dp {
            limit: self.memory_mb.saturating_mul(1 << 20),
            memory_mb: self.memory_mb,
            used: 0,
            levels: Vec::with_capacity(n),
            pred_mask,
            sort_per_key: 0.0,
            grow_per_key: 0.0,
        };
        let mut first = Level::default();
        let mut ideals = 0u64;
        for v in 0..n {
            if dp.pred_mask[v] == 0 {
                ideals += 1;
                for md in 0..m.modes(v) {
                    first.insert(
                        (1u128 << v, m.node(v, md) as u32),
                        (NO_PRED, m.start(v, md)),
                    );
                }
            }
        }
        dp.used += BYTES_PER_STATE * first.len() as u64;
        ctx.count(ideals);
        dp.levels.push(first);
        // the clock is read between subsets too: one level can hold millions of them
        let mut clock = Ticker::new(ctx.deadline(), 4);
        for k in 1..n {
            dp.next_level(ctx, k, &mut clock)?;
        }
        let seq = dp.read_back(ctx, n)?;
        let cost = m.evaluate(&seq);
        ctx.report(cost);
        Ok(Outcome {
            sequence: seq,
            cost,
            proven_optimal: true,
            lower_bound: Some(cost),
        })
    }
}

/// An error of the `exact` solver.
fn err(msg: String) -> Error {
    Error::Solver {
        solver: "exact".into(),
        msg,
    }
}

/// The refusal when the budget ends at subset size `k + 1` of `n`.
fn out_of_budget(k: usize, n: usize) -> Error {
    err(format!(
        "budget exhausted at subset size {} of {n} before optimality was proven",
        k + 1
    ))
}

/// Whether the time left covers `seconds`, the estimate of a step that cannot stop halfway
/// (a level's sort or a table's rehash); always without a deadline.
fn time_covers(ctx: &Context, seconds: f64) -> bool {
    ctx.deadline()
        .remaining()
        .is_none_or(|left| left.as_secs_f64() >= seconds)
}

/// Doubles the capacity of level `k`'s full table `next`, unless the time left would not cover
/// the rehash, estimated at twice the last growth's time per state (`per_key`, updated here):
/// the cost per state rises as the table outgrows the caches.
fn grow(ctx: &Context, next: &mut Level, k: usize, per_key: &mut f64) -> Result<()> {
    let len = next.len();
    if !time_covers(ctx, 2.0 * *per_key * len as f64) {
        return Err(out_of_budget(k, ctx.model.n()));
    }
    let growing = Instant::now();
    next.reserve(len.max(16));
    *per_key = growing.elapsed().as_secs_f64() / len.max(1) as f64;
    Ok(())
}

/// The DP's tables and memory account.
struct Dp {
    limit: u64,
    memory_mb: u64,
    used: u64,
    levels: Vec<Level>,
    pred_mask: Vec<u128>,
    /// Seconds per state of the last level's sort: the next sort is not started when the
    /// time left would not cover it (a sort cannot stop halfway; a level holds millions).
    sort_per_key: f64,
    /// Seconds per state of the last growth of a level's table: the same for the next growth
    /// (a rehash of every state, which cannot stop halfway either).
    grow_per_key: f64,
}

impl Dp {
    /// Level `k` (ideals of k + 1 cells) from level `k − 1`.
    fn next_level(&mut self, ctx: &mut Context, k: usize, clock: &mut Ticker) -> Result<()> {
        let m = ctx.model;
        let n = m.n();
        let prev = &self.levels[k - 1];
        let mut next = Level::default();
        let mut evals = 0u64;
        // deterministic iteration: the states of the previous level sorted (grouped by ideal)
        if !time_covers(ctx, self.sort_per_key * prev.len() as f64) {
            return Err(out_of_budget(k, n));
        }
        let sorting = Instant::now();
        let mut keys: Vec<Key> = prev.keys().copied().collect();
        keys.sort_unstable();
        self.sort_per_key = sorting.elapsed().as_secs_f64() / keys.len().max(1) as f64;
        // one ideal's entries (last node, cost), in the order ties were always broken in:
        // last cell from the highest index down, modes in order
        let mut entries: Vec<(u32, f64)> = Vec::new();
        let mut i = 0;
        while i < keys.len() {
            if clock.passed() {
                return Err(out_of_budget(k, n));
            }
            let s = keys[i].0;
            let j = i + keys[i..].iter().take_while(|key| key.0 == s).count();
            entries.clear();
            entries.extend(keys[i..j].iter().map(|key| (key.1, prev[key].1)));
            entries.sort_by_key(|e| {
                let (c, md) = m.cell_mode(e.0 as usize);
                (std::cmp::Reverse(c), md)
            });
            i = j;
            for v in 0..n {
                if s >> v & 1 == 1 || self.pred_mask[v] & !s != 0 {
                    continue;
                }
                let t = s | 1u128 << v;
                for mv in 0..m.modes(v) {
                    // the cheapest way in, and where from (the first of equal costs)
                    let mut best = (f64::INFINITY, NO_PRED);
                    for &(u, cu) in &entries {
                        let (cu_cell, cu_mode) = m.cell_mode(u as usize);
                        let c = cu + m.arc(cu_cell, cu_mode, v, mv);
                        if c < best.0 {
                            best = (c, u);
                        }
                    }
                    evals += entries.len() as u64;
                    let key = (t, m.node(v, mv) as u32);
                    match next.get_mut(&key) {
                        Some(e) => {
                            if best.0 < e.1 {
                                *e = (best.1, best.0);
                            }
                        }
                        None => {
                            if next.len() == next.capacity() {
                                grow(ctx, &mut next, k, &mut self.grow_per_key)?;
                            }
                            self.used += BYTES_PER_STATE;
                            next.insert(key, (best.1, best.0));
                        }
                    }
                }
            }
            if self.used > self.limit {
                return Err(err(format!(
                    "memory estimate passed the limit of {} MiB at subset size {} of {n} \
                     ({} states so far); raise memory_mb or use another solver",
                    self.memory_mb,
                    k + 1,
                    next.len()
                )));
            }
        }
        ctx.count(evals);
        if ctx.exhausted() {
            return Err(out_of_budget(k, n));
        }
        self.levels.push(next);
        Ok(())
    }

    /// The optimal sequence: the cheapest complete state with its finish, then back along
    /// the stored predecessors (exact, no re-evaluation of costs).
    fn read_back(&self, ctx: &Context, n: usize) -> Result<Vec<Visit>> {
        let m = ctx.model;
        let full = &self.levels[n - 1];
        let mut best = (f64::INFINITY, NO_PRED, 0u128);
        for (&(all, u), &(_, cu)) in full {
            let (c, md) = m.cell_mode(u as usize);
            let total = cu + m.finish(c, md);
            if total < best.0 || (total == best.0 && u < best.1) {
                best = (total, u, all);
            }
        }
        if full.is_empty() {
            return Err(err("no feasible order".into()));
        }
        if best.1 == NO_PRED {
            // only when every complete path costs infinity or NaN, which validation rules out
            return Err(err("no complete order has a finite cost".into()));
        }
        let mut seq = Vec::with_capacity(n);
        let (mut s, mut u) = (best.2, best.1);
        for k in (0..n).rev() {
            let (c, md) = m.cell_mode(u as usize);
            seq.push(Visit::new(c, md));
            let pred = self.levels[k]
                .get(&(s, u))
                .map(|e| e.0)
                .ok_or_else(|| err("internal error: DP state missing on the way back".into()))?;
            if k == 0 {
                break;
            }
            if pred == NO_PRED {
                return Err(err("internal error: DP path ends early".into()));
            }
            s &= !(1u128 << c);
            u = pred;
        }
        seq.reverse();
        Ok(seq)
    }
}

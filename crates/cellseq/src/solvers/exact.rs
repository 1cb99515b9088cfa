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
use crate::error::{Error, Result};
use crate::model::Visit;
use rustc_hash::FxHashMap;

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

/// One DP entry: the last node, the node before it (`NO_PRED` at the start) and the cost.
type Entry = (u32, u32, f64);
type Level = FxHashMap<u128, Vec<Entry>>;

/// The predecessor of a path's first node.
const NO_PRED: u32 = u32::MAX;

const BYTES_PER_IDEAL: u64 = 80;
const BYTES_PER_ENTRY: u64 = 16;

impl Solver for Exact {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        let err = |msg: String| Error::Solver {
            solver: "exact".into(),
            msg,
        };
        if n > self.max_cells {
            return Err(err(format!(
                "instance has {n} cells; the exact DP accepts at most {} (use another solver)",
                self.max_cells
            )));
        }
        let pred_mask: Vec<u128> = (0..n)
            .map(|c| m.dag.preds[c].iter().fold(0u128, |a, &p| a | 1u128 << p))
            .collect();
        let limit = self.memory_mb.saturating_mul(1 << 20);
        let mut used: u64 = 0;
        let mut levels: Vec<Level> = Vec::with_capacity(n);
        let mut first = Level::default();
        for v in 0..n {
            if pred_mask[v] == 0 {
                let e: Vec<Entry> = (0..m.modes(v))
                    .map(|md| (m.node(v, md) as u32, NO_PRED, m.start(v, md)))
                    .collect();
                used += BYTES_PER_IDEAL + BYTES_PER_ENTRY * e.len() as u64;
                first.insert(1u128 << v, e);
            }
        }
        ctx.count(first.len() as u64);
        levels.push(first);
        for k in 1..n {
            let prev = &levels[k - 1];
            let mut next = Level::default();
            let mut evals = 0u64;
            // deterministic iteration: sort the ideals of the previous level
            let mut keys: Vec<&u128> = prev.keys().collect();
            keys.sort_unstable();
            for &s in keys {
                let entries = &prev[&s];
                for v in 0..n {
                    if s >> v & 1 == 1 || pred_mask[v] & !s != 0 {
                        continue;
                    }
                    let t = s | 1u128 << v;
                    let slot = next.entry(t).or_insert_with(|| {
                        used += BYTES_PER_IDEAL;
                        Vec::new()
                    });
                    for mv in 0..m.modes(v) {
                        let nv = m.node(v, mv) as u32;
                        // the cheapest way in, and where from (the first of equal costs)
                        let mut best = (f64::INFINITY, NO_PRED);
                        for &(u, _, cu) in entries {
                            let (cu_cell, cu_mode) = m.cell_mode(u as usize);
                            let c = cu + m.arc(cu_cell, cu_mode, v, mv);
                            if c < best.0 {
                                best = (c, u);
                            }
                        }
                        evals += entries.len() as u64;
                        match slot.iter_mut().find(|e| e.0 == nv) {
                            Some(e) => {
                                if best.0 < e.2 {
                                    (e.1, e.2) = (best.1, best.0);
                                }
                            }
                            None => {
                                used += BYTES_PER_ENTRY;
                                slot.push((nv, best.1, best.0));
                            }
                        }
                    }
                }
                if used > limit {
                    return Err(err(format!(
                        "memory estimate passed the limit of {} MiB at subset size {} of {n} \
                         ({} subsets so far); raise memory_mb or use another solver",
                        self.memory_mb,
                        k + 1,
                        next.len()
                    )));
                }
            }
            ctx.count(evals);
            if ctx.exhausted() {
                return Err(err(format!(
                    "budget exhausted at subset size {} of {n} before optimality was proven",
                    k + 1
                )));
            }
            levels.push(next);
        }
        // close the path
        let full = &levels[n - 1];
        let (&all, entries) = full
            .iter()
            .next()
            .ok_or_else(|| err("no feasible order".into()))?;
        let mut best = (f64::INFINITY, NO_PRED);
        for &(u, _, cu) in entries {
            let (c, md) = m.cell_mode(u as usize);
            let total = cu + m.finish(c, md);
            if total < best.0 || (total == best.0 && u < best.1) {
                best = (total, u);
            }
        }
        if best.1 == NO_PRED {
            // only when every complete path costs infinity or NaN, which validation rules out
            return Err(err("no complete order has a finite cost".into()));
        }
        // walk back along the stored predecessors: exact, no re-evaluation of costs
        let mut seq = Vec::with_capacity(n);
        let mut s = all;
        let mut u = best.1;
        for k in (0..n).rev() {
            let (c, md) = m.cell_mode(u as usize);
            seq.push(Visit::new(c, md));
            let pred = levels[k]
                .get(&s)
                .and_then(|es| es.iter().find(|e| e.0 == u))
                .map(|e| e.1)
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

//! `reopt`: window re-optimization — the exact tree search of [`super::beam`] run on short
//! stretches of the best sequence, each as an instance of its own.
//!
//! The cells at positions `lo..hi` of a sequence, between the fixed slot before them and the
//! fixed slot after them, form a sub-instance: an anchor cell forced first (its links into
//! the window are the links out of the slot before it: a cell in its mode, or the path start),
//! the window's cells with all their modes and the precedence pairs among them, and an anchor
//! forced last (the links into the slot after it: a cell in its mode, the path end, or a
//! closed tour's return). Every precedence pair with a cell outside the window holds whatever
//! order the window takes: no chain of pairs can leave the window and come back, since the
//! cell outside would have to lie both before and after it. So any sequence of the
//! sub-instance maps back to a feasible sequence, and its cost differs from the window's
//! links by exactly the difference of the sub-instance's costs.
//!
//! `beam` searches each window from the window's current order as its incumbent, so a window
//! never gets worse; where its passes end without a width cut the window is optimal. This is
//! the POPMUSIC scheme (Taillard and Voss) with an exact sub-solver. On dense precedence
//! (TSPLIB's rbg instances) windows of 80 cells are proven in 0.1–3 s, and a window holds
//! what the local searches miss: on rbg323a a 3141 sequence of `auto` had one window of
//! 80 cells whose optimum is one lower, which makes 3140, the proven optimum
//! (notes/lab/sopq9.md).
//!
//! The first sweep covers the sequence with windows of `window` cells, `step` apart, from a
//! random offset. Each later sweep has windows a quarter larger, centred on the windows of
//! the sweep before that the search could not prove optimal (where the order is loose and
//! the gains lie), or covering the whole sequence again when every window was proven. After
//! a gain the sequence is polished by the VND before the next window.

use super::Build;
use super::StartsFrom;
use super::start::{POLISH_K, given_or_polished, outcome};
use super::{
    Budget, Caps, Context, Outcome, ParamKind, ParamSpec, Params, SolverInfo, Sub,
};
use crate::cost::CostModel;
use crate::engine::{Costs, Slot, Solution};
use crate::error::Result;
use crate::model::{Cell, CostMatrix, Instance, Mode, Objective, Sequence, Visit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Duration;

/// Largest window: a window with the fixed cells either side is an instance `beam` takes
/// ([`super::beam::MAX_CELLS`] cells).
const MAX_WINDOW: u64 = super::beam::MAX_CELLS as u64 - 2;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "reopt",
    summary: "window re-optimization: the exact tree search (beam) on windows of the sequence, each solved as an instance of its own, from the window's order",
    description: "Window re-optimization (POPMUSIC with an exact sub-solver). Windows of `window` \
consecutive cells, `step` apart, are each made an instance of their own between the fixed \
cells either side and searched by `beam` from the window's order, so a window never gets \
worse. A later sweep has windows a quarter larger, centred where the last sweep could not \
prove its windows optimal, up to `max-window`; one window gets at most `window-share` of the \
budget, and a gain is polished by the VND. Alone it starts from `greedy`; in `auto` it ends \
the built-in portfolio's `sparse` rule, from the best so far. On rbg323a it turns `ils`'s 3141 into the optimum 3140.",
    params: &[
        ParamSpec {
            name: "window",
            default: "40",
            kind: ParamKind::int(2, MAX_WINDOW),
            help: "cells per window at the first sweep (windows grow by a quarter after a sweep without a gain)",
        },
        ParamSpec {
            name: "step",
            default: "0",
            kind: ParamKind::int(0, crate::params::MAX_CELLS),
            help: "positions between the starts of two windows of a sweep (0: a quarter of a window)",
        },
        ParamSpec {
            name: "window-share",
            default: "0.1",
            kind: ParamKind::float_above(0.0, 1.0),
            help: "most of the budget that one window's search may use",
        },
        ParamSpec {
            name: "max-window",
            default: "200",
            kind: ParamKind::int(2, MAX_WINDOW),
            help: "windows grow up to this many cells; a sweep at this size without a gain ends the run",
        },
        POLISH_K,
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::StartsFrom(|p: &Params| Ok(Box::new(from_params(p)))),
};

/// Builds the solver from validated parameters.
pub fn from_params(p: &Params) -> Reopt {
    Reopt {
        window: p.int("window") as usize,
        step: p.int("step") as usize,
        window_share: p.float("window-share"),
        max_window: p.int("max-window") as usize,
        k: p.int("k") as usize,
    }
}

/// Window re-optimization.
pub struct Reopt {
    /// Cells per window at the first sweep.
    pub window: usize,
    /// Positions between two window starts (0: a quarter of a window).
    pub step: usize,
    /// Largest share of the budget for one window.
    pub window_share: f64,
    /// Largest window (cells).
    pub max_window: usize,
    /// Candidate neighbours of the polishing VND.
    pub k: usize,
}

/// The sub-instance of the cells at positions `lo..hi` of `s` between their fixed neighbours
/// (see the module documentation), with the cell of the whole instance behind each of its
/// cells (`None` for the two anchors). Cell 0 is the left anchor, cell `hi − lo + 1` the
/// right one; a window cell keeps its modes in their order.
pub fn window_instance(c: &Costs, s: &Solution, lo: usize, hi: usize) -> (Instance, Vec<u32>) {
    let m = c.m;
    let len = hi - lo;
    let k = len + 2;
    let cells: Vec<u32> = s.order[lo..hi].to_vec();
    let modes = |i: usize| {
        if i == 0 || i == k - 1 {
            1
        } else {
            m.modes(cells[i - 1] as usize)
        }
    };
    let mut off = vec![0usize; k + 1];
    for i in 0..k {
        off[i + 1] = off[i] + modes(i);
    }
    let size = off[k];
    let left: Slot = s.at(lo as isize - 1);
    let right: Slot = s.at(hi as isize);
    let mut costs = vec![0.0; size * size];
    for a in 1..k - 1 {
        let ca = cells[a - 1] as usize;
        for ma in 0..modes(a) {
            let na = off[a] + ma;
            costs[na] = c.link(left, Some((ca, ma)));
            costs[na * size + off[k - 1]] = c.link(Some((ca, ma)), right);
            for b in 1..k - 1 {
                if a == b {
                    continue;
                }
                let cb = cells[b - 1] as usize;
                for mb in 0..modes(b) {
                    costs[na * size + off[b] + mb] = m.arc(ca, ma, cb, mb);
                }
            }
        }
    }
    let mut precedence = Vec::new();
    for i in 1..k - 1 {
        precedence.push((0, i));
        precedence.push((i, k - 1));
        for &q in &m.dag.succs[cells[i - 1] as usize] {
            let pq = s.pos[q as usize] as usize;
            if pq >= lo && pq < hi {
                precedence.push((i, pq - lo + 1));
            }
        }
    }
    let sub_cells = (0..k)
        .map(|i| Cell::new(i.to_string(), "", vec![Mode::default(); modes(i)]))
        .collect();
    let inst = Instance {
        name: format!("window {lo}..{hi}"),
        cells: sub_cells,
        precedence,
        matrix: Some(CostMatrix { size, costs }),
        first: Some(0),
        last: Some(k - 1),
        ..Instance::default()
    };
    (inst, cells)
}

/// One window's budget: a share `frac` of the whole budget `b`, but no more than what is left
/// of it after `used_evals` evaluations and `used_s` seconds.
fn window_budget(b: Budget, used_evals: u64, used_s: f64, frac: f64) -> Budget {
    Budget {
        time_limit: b.time_limit.map(|t| {
            let t = t.as_secs_f64();
            Duration::from_secs_f64((t * frac).min((t - used_s).max(0.0)))
        }),
        max_evals: b.max_evals.map(|e| {
            ((e as f64 * frac) as u64)
                .min(e.saturating_sub(used_evals))
                .max(1)
        }),
    }
}

impl Reopt {
    /// The best reorder of window `lo..hi` of `s` by the tree search, applied when it is
    /// cheaper. Returns (gain applied, window proven optimal).
    pub fn window(
        &self,
        c: &Costs,
        s: &mut Solution,
        ctx: &mut Context,
        lo: usize,
        hi: usize,
    ) -> Result<(bool, bool)> {
        let (sub, cells) = window_instance(c, s, lo, hi);
        let sm = CostModel::new(&sub, Objective::Matrix);
        let len = hi - lo;
        let mut current: Sequence = Vec::with_capacity(len + 2);
        current.push(Visit::new(0, 0));
        for (i, &x) in cells.iter().enumerate() {
            current.push(Visit::new(i + 1, s.mode[x as usize] as usize));
        }
        current.push(Visit::new(len + 1, 0));
        let budget = window_budget(
            ctx.budget,
            ctx.evaluations(),
            ctx.elapsed(),
            self.window_share,
        );
        let job = Sub {
            start: Some(&current),
            on: Some((&sub, &sm)),
            ..Sub::new("beam", budget, ctx.seed)
        };
        let out = super::sub_run(ctx, job)?;
        // the window's share of `s`: the links from position lo − 1 to position hi
        let before = s.links(c, lo as isize - 1, hi as isize);
        let now = sm.evaluate(&current);
        // the sub-instance's costs are the window's links (computed by the same calls)
        debug_assert!((now - before).abs() <= 1e-6 * before.abs().max(1.0));
        let gain = now - out.cost;
        if gain <= 1e-9 * s.cost.abs().max(1.0) {
            return Ok((false, out.proven_optimal));
        }
        let seq = &out.sequence;
        debug_assert_eq!(seq.len(), len + 2);
        let order: Vec<u32> = seq[1..=len].iter().map(|v| cells[v.cell - 1]).collect();
        let modes: Vec<u32> = seq[1..=len].iter().map(|v| v.mode as u32).collect();
        s.rewrite_with_modes(lo, &order, &modes, 0.0);
        // the exact change, whatever rounding the sub-instance's sums carried
        s.cost += s.links(c, lo as isize - 1, hi as isize) - before;
        Ok((true, out.proven_optimal))
    }

}

impl StartsFrom for Reopt {
    /// Runs the sweeps from `start` (evaluated with open-loop costs), or from the greedy
    /// sequence polished by the VND when `start` is `None`.
    fn run_from(&self, ctx: &mut Context, start: Option<Solution>) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        let c = Costs::open(m);
        let (mut s, search) = given_or_polished(ctx, c, start, self.k);
        let Some(mut search) = search else {
            return Ok(outcome(m, &s));
        };
        if n < 2 {
            return Ok(outcome(m, &s));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed ^ 0x4e0f_7a11);
        let cap = self.max_window.min(n);
        let mut w = self.window.min(cap);
        // centres of the windows of the last sweep that the search could not prove optimal:
        // the next sweep, with larger windows, looks only there (none: every window)
        let mut focus: Vec<usize> = Vec::new();
        let (mut windows, mut gains, mut proofs) = (0u64, 0u64, 0u64);
        'sweeps: while !ctx.exhausted() {
            let step = if self.step > 0 {
                self.step
            } else {
                (w / 4).max(1)
            };
            let starts = if focus.is_empty() {
                let first = if n > w {
                    rng.random_range(0..step.min(n - w + 1))
                } else {
                    0
                };
                let mut v: Vec<usize> = (first..n.saturating_sub(w)).step_by(step).collect();
                v.push(n.saturating_sub(w));
                v
            } else {
                let mut v: Vec<usize> = focus
                    .iter()
                    .map(|&centre| centre.saturating_sub(w / 2).min(n.saturating_sub(w)))
                    .collect();
                v.sort_unstable();
                v.dedup_by(|b, a| *b < *a + step.div_ceil(2));
                v
            };
            let mut unproven = Vec::new();
            let mut gained = false;
            for lo in starts {
                if ctx.exhausted() {
                    break 'sweeps;
                }
                let hi = (lo + w).min(n);
                let (g, proven) = self.window(&c, &mut s, ctx, lo, hi)?;
                windows += 1;
                proofs += proven as u64;
                if !proven {
                    unproven.push((lo + hi) / 2);
                }
                if g {
                    gains += 1;
                    gained = true;
                    search.vnd(&mut s, ctx);
                    ctx.report(s.cost + m.constant());
                }
            }
            if w >= cap && !gained {
                // the largest windows found nothing: searching them again finds nothing new
                break;
            }
            focus = unproven;
            w = (w + w.div_ceil(4)).min(cap);
        }
        if super::trace_enabled() {
            eprintln!("reopt: {windows} windows, {proofs} proven, {gains} gains, last window {w}");
        }
        Ok(outcome(m, &s))
    }
}

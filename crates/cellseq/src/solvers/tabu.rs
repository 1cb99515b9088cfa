//! `tabu`: multi-start tabu search as in paper 004 (cutting-sequence optimisation by tabu
//! search): a move takes one cell out together with its entry/exit pair and re-inserts it
//! elsewhere, possibly with the pair swapped (any mode of the cell); the moved cell is tabu for
//! `tenure` iterations unless the move beats the best (aspiration). Starts: one from every
//! ready start cell and mode (greedy completion), plus randomized greedy starts.
//! Insertion positions come from the K-nearest candidate lists inside the cell's precedence
//! window, so an iteration costs O(n·K·k).

use super::Build;
use super::start::{greedy_start, outcome, random_start};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::engine::moves::{apply_segment, mode_delta, window};
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution, cheaper};
use crate::error::Result;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "tabu",
    summary: "multi-start tabu search (paper 004): relocate a cell with its entry/exit pair, tenure, aspiration",
    description: "Multi-start tabu search as in paper 004: each iteration takes one cell out with its \
entry/exit pair and re-inserts it at the best non-tabu place, possibly with the pair swapped \
(any mode of the cell), among places next to its `k` candidate neighbours inside its \
precedence window; a move that beats the best is allowed even when tabu (aspiration), and a \
moved cell stays tabu for `tenure` iterations. Starts: every ready start cell and mode first, then randomized greedy, up to \
`starts`.",
    params: &[
        ParamSpec {
            name: "tenure",
            default: "0",
            kind: ParamKind::int(0, crate::params::MAX_CELLS),
            help: "iterations a moved cell stays tabu (0 = 5 + n/20)",
        },
        ParamSpec {
            name: "iters",
            default: "3000",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "iterations per start at most",
        },
        ParamSpec {
            name: "stall",
            default: "400",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "stop a start after this many iterations without a new best",
        },
        ParamSpec {
            name: "starts",
            default: "8",
            kind: ParamKind::int(1, 1_000_000),
            help: "starts at most (every ready start cell/mode first, then randomized greedy)",
        },
        ParamSpec {
            name: "k",
            default: "10",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate neighbours per cell",
        },
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Tabu {
            tenure: p.int("tenure") as usize,
            iters: p.int("iters"),
            stall: p.int("stall"),
            starts: p.int("starts") as usize,
            k: p.int("k") as usize,
        }))
    }),
};

/// The tabu solver.
pub struct Tabu {
    /// Tenure (0 = automatic).
    pub tenure: usize,
    /// Iterations per start.
    pub iters: u64,
    /// Stagnation limit per start.
    pub stall: u64,
    /// Number of starts.
    pub starts: usize,
    /// Candidate neighbours.
    pub k: usize,
}

/// The tabu list: per cell, the iteration until which it may not move.
#[derive(Debug, Clone)]
pub struct TabuList {
    /// `until[c]`: first iteration at which c may move again.
    pub until: Vec<u64>,
    /// Current iteration.
    pub iter: u64,
    /// Tenure.
    pub tenure: u64,
}

/// One tabu iteration: finds the best admissible relocation (or mode swap) and applies it.
/// Returns false when no admissible move exists.
pub fn tabu_step(
    c: &Costs,
    search: &Search,
    s: &mut Solution,
    tabu: &mut TabuList,
    best_cost: f64,
    ctx: &mut Context,
) -> bool {
    let m = c.m;
    let n = s.n();
    let mut best: Option<(f64, usize, isize, usize)> = None; // delta, cell, p (or -2 = mode only), mode
    let mut evals = 0u64;
    for x in 0..n {
        let i = s.pos[x] as usize;
        let ii = i as isize;
        let is_tabu = tabu.until[x] > tabu.iter;
        let (lo, hi) = window(m, s, i, 1);
        let removal = s.link(c, ii - 1, ii + 1) - s.link(c, ii - 1, ii) - s.link(c, ii, ii + 1);
        let mut consider = |d: f64, p: isize, md: usize| {
            if is_tabu && !cheaper(s.cost + d, best_cost) {
                return;
            }
            if best.is_none_or(|b| d < b.0) {
                best = Some((d, x, p, md));
            }
        };
        let k = m.modes(x);
        for md in 0..k {
            if md != s.mode[x] as usize {
                evals += 1;
                consider(mode_delta(c, s, i, md), -2, md);
            }
        }
        let cands = search.nb.inn[x]
            .iter()
            .map(|&v| s.pos[v as usize] as isize)
            .chain(
                search.nb.out[x]
                    .iter()
                    .map(|&w| s.pos[w as usize] as isize - 1),
            );
        for p in cands {
            if p == ii - 1 || p == ii || p < lo || p >= hi {
                continue;
            }
            let (a, b) = (s.at(p), s.at(p + 1));
            let base = removal - c.link(a, b);
            for md in 0..k {
                evals += 1;
                let xm = Some((x, md));
                consider(base + c.link(a, xm) + c.link(xm, b), p, md);
            }
        }
    }
    ctx.count(evals);
    let Some((d, x, p, md)) = best else {
        return false;
    };
    if p == -2 {
        s.set_mode(x, md, d);
    } else {
        s.mode[x] = md as u32;
        apply_segment(m, s, s.pos[x] as usize, 1, p, false, d);
    }
    tabu.until[x] = tabu.iter + tabu.tenure;
    true
}

impl Solver for Tabu {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        let c = Costs::open(m);
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        let greedy = greedy_start(ctx);
        let mut best = Solution::new(&c, &greedy);
        ctx.report(best.cost + m.constant());
        if ctx.deadline().passed() {
            return Ok(outcome(m, &best));
        }
        let search = Search::new_until(c, self.k, ctx.deadline());
        let tenure = if self.tenure == 0 {
            5 + n / 20
        } else {
            self.tenure
        } as u64;
        // start list: every ready start (cell, mode), then randomized starts
        let mut firsts: Vec<(usize, usize)> = (0..n)
            .filter(|&x| m.dag.preds[x].is_empty())
            .flat_map(|x| (0..m.modes(x)).map(move |md| (x, md)))
            .collect();
        firsts.truncate(self.starts);
        let mut polish = Search::new_until(c, self.k, ctx.deadline());
        for start in 0..self.starts {
            if ctx.exhausted() {
                break;
            }
            let seq = if start == 0 {
                greedy.clone()
            } else if start < firsts.len() {
                random_start(ctx, &mut rng, 0.0, Some(firsts[start]))
            } else {
                random_start(ctx, &mut rng, 0.3, None)
            };
            let mut s = Solution::new(&c, &seq);
            let mut local_best = s.clone();
            let mut tabu = TabuList {
                until: vec![0u64; n],
                iter: 0,
                tenure,
            };
            let mut last_improve = 0u64;
            for iter in 1..=self.iters {
                if ctx.exhausted() || iter - last_improve > self.stall {
                    break;
                }
                tabu.iter = iter;
                if !tabu_step(&c, &search, &mut s, &mut tabu, local_best.cost, ctx) {
                    break;
                }
                if iter % 64 == 0 {
                    s.cost = s.evaluate(&c);
                }
                if cheaper(s.cost, local_best.cost) {
                    local_best.clone_from(&s);
                    last_improve = iter;
                    if local_best.cost < best.cost {
                        ctx.report(local_best.cost + m.constant());
                    }
                }
            }
            local_best.cost = local_best.evaluate(&c);
            polish.vnd(&mut local_best, ctx);
            if local_best.cost < best.cost {
                best = local_best;
                ctx.report(best.cost + m.constant());
            }
        }
        Ok(outcome(m, &best))
    }
}

//! `aco`: the improved ant colony of patent 003, in the ant colony system form of HAS-SOP:
//! pheromone on cell → cell transitions, heuristic 1/(travel cost) where the travel cost
//! includes the tool-change detour (the cost model's arc), candidates restricted to the
//! precedence fringe (cells whose predecessors are all placed), pseudo-random proportional
//! rule, local and global pheromone updates, the engine's local search (SOP-3-exchange VND) on
//! the ants, and the mode DP (the greedy pass over contact points) on every tour.

use super::Build;
use super::start::{greedy_solution, outcome};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::clock::Ticker;
use crate::engine::modes::mode_dp;
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution, cheaper};
use crate::error::Result;
use crate::model::{Sequence, Visit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustc_hash::FxHashMap;

/// The colony parameters `aco` and `eacs` share: ants, beta, s, rho, phi.
pub(crate) const COLONY: [ParamSpec; 5] = [
    ParamSpec {
        name: "ants",
        default: "10",
        kind: ParamKind::int(1, 10_000),
        help: "ants per iteration",
    },
    ParamSpec {
        name: "beta",
        default: "2",
        kind: ParamKind::float(0.0, 20.0),
        help: "heuristic exponent",
    },
    ParamSpec {
        name: "s",
        default: "10",
        kind: ParamKind::float(0.0, 1e7),
        help: "exploitation: q0 = 1 - s/n (about s random choices per tour)",
    },
    ParamSpec {
        name: "rho",
        default: "0.1",
        kind: ParamKind::float(0.0, 1.0),
        help: "global evaporation",
    },
    ParamSpec {
        name: "phi",
        default: "0.01",
        kind: ParamKind::float(0.0, 1.0),
        help: "local evaporation",
    },
];

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "aco",
    summary: "ant colony system (patent 003 / HAS-SOP): fringe construction, tool-change-aware heuristic, local search, mode DP",
    description: "Ant colony system after patent 003 and HAS-SOP: ants build sequences over the \
precedence fringe with a heuristic that charges tool changes, local and global pheromone \
updates on cell → cell arcs, local search on every ant, the iteration best or none (`ls`), \
and the mode DP.",
    params: &[
        COLONY[0],
        COLONY[1],
        COLONY[2],
        COLONY[3],
        COLONY[4],
        ParamSpec {
            name: "iters",
            default: "300",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "iterations at most",
        },
        ParamSpec {
            name: "stall",
            default: "25",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "stop after this many iterations without a new best",
        },
        ParamSpec {
            name: "ls",
            default: "all",
            kind: ParamKind::Choice(&["all", "best", "none"]),
            help: "local search on every ant, on the iteration best, or none",
        },
        ParamSpec {
            name: "k",
            default: "10",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate neighbours per cell (local search)",
        },
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Aco {
            ants: p.int("ants") as usize,
            beta: p.float("beta"),
            s: p.float("s"),
            rho: p.float("rho"),
            phi: p.float("phi"),
            iters: p.int("iters"),
            stall: p.int("stall"),
            ls: p.word("ls").to_string(),
            k: p.int("k") as usize,
        }))
    }),
};

/// The ant colony solver.
pub struct Aco {
    /// Ants per iteration.
    pub ants: usize,
    /// Heuristic exponent.
    pub beta: f64,
    /// Expected random choices per tour.
    pub s: f64,
    /// Global evaporation.
    pub rho: f64,
    /// Local evaporation.
    pub phi: f64,
    /// Iteration limit.
    pub iters: u64,
    /// Stagnation limit.
    pub stall: u64,
    /// Which ants get local search.
    pub ls: String,
    /// Candidate neighbours.
    pub k: usize,
}

/// Pheromone on cell → cell transitions (row n = from home): dense up to 3000 cells, sparse
/// (default τ0 for untouched arcs) above.
pub struct Pheromone {
    n: usize,
    tau0: f64,
    dense: Vec<f64>,
    sparse: FxHashMap<u64, f64>,
}

impl Pheromone {
    /// All arcs at `tau0`.
    pub fn new(n: usize, tau0: f64) -> Self {
        let dense = if n <= 3000 {
            vec![tau0; (n + 1) * n]
        } else {
            Vec::new()
        };
        Pheromone {
            n,
            tau0,
            dense,
            sparse: FxHashMap::default(),
        }
    }
    #[inline]
    fn key(&self, a: Option<usize>, b: usize) -> usize {
        a.unwrap_or(self.n) * self.n + b
    }
    /// Pheromone on a → b (`None` = home).
    #[inline]
    pub fn get(&self, a: Option<usize>, b: usize) -> f64 {
        let k = self.key(a, b);
        if self.dense.is_empty() {
            *self.sparse.get(&(k as u64)).unwrap_or(&self.tau0)
        } else {
            self.dense[k]
        }
    }
    /// The initial pheromone level.
    #[inline]
    pub fn tau0(&self) -> f64 {
        self.tau0
    }
    /// Sets pheromone on a → b.
    #[inline]
    pub fn set(&mut self, a: Option<usize>, b: usize, v: f64) {
        let k = self.key(a, b);
        if self.dense.is_empty() {
            self.sparse.insert(k as u64, v);
        } else {
            self.dense[k] = v;
        }
    }
}

impl Aco {
    /// Builds one ant's tour from the fringe of ready cells.
    pub fn construct(
        &self,
        ctx: &mut Context,
        tau: &mut Pheromone,
        eps: f64,
        rng: &mut ChaCha8Rng,
    ) -> Sequence {
        let m = ctx.model;
        let n = m.n();
        let q0 = (1.0 - self.s / n as f64).clamp(0.0, 1.0);
        let mut missing: Vec<u32> = m.dag.preds.iter().map(|p| p.len() as u32).collect();
        let mut ready: Vec<usize> = (0..n).filter(|&c| missing[c] == 0).collect();
        let mut seq: Sequence = Vec::with_capacity(n);
        let mut w: Vec<(f64, usize)> = Vec::new();
        // O(n) per step: past the deadline the ant ends with a quick feasible completion
        let mut clock = Ticker::new(ctx.deadline(), 16);
        while !ready.is_empty() {
            if clock.passed() {
                crate::construct::complete(m, &mut seq);
                break;
            }
            let cur = seq.last().map(|v| (v.cell, v.mode));
            w.clear();
            let mut total = 0.0;
            let mut arg = (f64::NEG_INFINITY, 0usize);
            for (idx, &r) in ready.iter().enumerate() {
                let (cost, md) = match cur {
                    Some((a, ma)) => m.best_arc_into(a, ma, r),
                    None => (0..m.modes(r))
                        .map(|k| (m.start(r, k), k))
                        .fold((f64::INFINITY, 0), |b, x| if x.0 < b.0 { x } else { b }),
                };
                let eta = 1.0 / (cost.max(0.0) + eps);
                let v = tau.get(cur.map(|x| x.0), r) * eta.powf(self.beta);
                total += v;
                w.push((v, md));
                if v > arg.0 {
                    arg = (v, idx);
                }
            }
            ctx.count(ready.len() as u64);
            let idx = if rng.random::<f64>() < q0 || total <= 0.0 || !total.is_finite() {
                arg.1
            } else {
                let mut x = rng.random::<f64>() * total;
                let mut pick = w.len() - 1;
                for (i, &(v, _)) in w.iter().enumerate() {
                    x -= v;
                    if x <= 0.0 {
                        pick = i;
                        break;
                    }
                }
                pick
            };
            let r = ready[idx];
            let md = w[idx].1;
            let a = cur.map(|x| x.0);
            let t = tau.get(a, r);
            tau.set(a, r, (1.0 - self.phi) * t + self.phi * tau.tau0);
            ready.swap_remove(idx);
            seq.push(Visit::new(r, md));
            for &s in &m.dag.succs[r] {
                missing[s as usize] -= 1;
                if missing[s as usize] == 0 {
                    ready.push(s as usize);
                }
            }
        }
        seq
    }
}

impl Solver for Aco {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        let c = Costs::open(m);
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        let mut best = greedy_solution(ctx, &c);
        if n < 2 || ctx.deadline().passed() {
            return Ok(outcome(m, &best));
        }
        let scale = best.cost.abs().max(1e-9);
        let mut tau = Pheromone::new(n, 1.0 / (n as f64 * scale));
        let eps = 1e-3 * scale / n as f64;
        let mut search = Search::new_until(c, self.k, ctx.deadline());
        let mut last_improve = 0u64;
        for iter in 1..=self.iters {
            if ctx.exhausted() || iter - last_improve > self.stall {
                break;
            }
            let mut it_best: Option<Solution> = None;
            for _ in 0..self.ants {
                if ctx.exhausted() {
                    break;
                }
                let seq = self.construct(ctx, &mut tau, eps, &mut rng);
                let mut s = Solution::new(&c, &seq);
                let e = mode_dp(&c, &mut s);
                ctx.count(e);
                if self.ls == "all" {
                    search.vnd(&mut s, ctx);
                }
                if it_best.as_ref().is_none_or(|b| s.cost < b.cost) {
                    it_best = Some(s);
                }
            }
            let Some(mut ib) = it_best else { break };
            if self.ls == "best" {
                search.vnd(&mut ib, ctx);
            }
            if cheaper(ib.cost, best.cost) {
                best = ib;
                last_improve = iter;
                ctx.report(best.cost + m.constant());
            }
            // global update on the best-so-far tour
            let dep = 1.0 / best.cost.abs().max(1e-9);
            let mut prev: Option<usize> = None;
            for &x in &best.order {
                let x = x as usize;
                let t = tau.get(prev, x);
                tau.set(prev, x, (1.0 - self.rho) * t + self.rho * dep);
                prev = Some(x);
            }
        }
        Ok(outcome(m, &best))
    }
}

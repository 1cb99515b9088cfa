//! `eacs`: enhanced ant colony system with SOP-3-exchange (after Gambardella, Montemanni and
//! Weyland, EJOR 2012, which builds on HAS-SOP, Gambardella and Dorigo 2000).
//!
//! Differences from the plain ant colony (`aco`):
//! - **Exploitation copies the best solution**: with probability q0 an ant moves to the cell
//!   that follows its current cell in the best-so-far solution when that cell is ready (all
//!   predecessors placed); when it is not, the ant takes the ready cell with the largest
//!   τ·η^β. Otherwise (probability 1 − q0) it draws a ready cell in proportion to τ·η^β.
//!   With q0 = 1 − s/n an ant deviates from the best about s times per tour, so tours are
//!   built in O(n) for the copied steps.
//! - **Focused local search**: only ants whose constructed cost lies within `ls-band` of the
//!   best get local search, and it starts only from the cells whose predecessor or successor
//!   differs from the best solution (the don't-push stack seeded with the new arcs): Or-opt,
//!   SOP-3-exchange with labelling searched forward and backward ([`crate::engine::sop3x`]),
//!   optionally 2-opt, then the mode DP. The default band is wide: on instances where one
//!   deviating arc costs a large share of the tour (prob.100, ESC47) a narrow band starves
//!   the search.
//! - Local pheromone update on every step, global update on the best-so-far solution; after
//!   `reset` iterations without a new best the pheromone is reset (the best is kept).
//!
//! The start is the greedy sequence after a full VND. Every construction step and every move
//! evaluation is counted, so a run under an evaluation budget is deterministic.

use super::Build;
use super::StartsFrom;
use super::aco::{COLONY, Pheromone};
use super::start::{greedy_solution, outcome};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, SolverInfo};
use crate::clock::Ticker;
use crate::engine::crossover::Crossover;
use crate::engine::lk::Lk;
use crate::engine::modes::mode_dp;
use crate::engine::sop3x::{TwoWay, sop3_two_way};
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution, cheaper};
use crate::error::Result;
use crate::model::{Sequence, Visit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "eacs",
    summary: "enhanced ant colony system (EACS): best-guided construction, focused SOP-3-exchange/Or-opt on near-best ants, mode DP",
    description: "The enhanced ant colony system of Gambardella, Montemanni and Weyland: ants copy the \
best solution's successor with probability q0 = 1 − `s`/n; the local search (Or-opt, \
SOP-3-exchange searched forward and backward, 2-opt, the mode DP) runs only on ants within \
`ls-band` of the best and starts only from the cells whose neighbours differ from the best \
solution. Each ant's local optimum is recombined with the best by partition crossover \
(`cross`).",
    params: &[
        COLONY[0],
        COLONY[1],
        COLONY[2],
        COLONY[3],
        COLONY[4],
        ParamSpec {
            name: "ls-band",
            default: "10",
            kind: ParamKind::float(0.0, 1000.0),
            help: "local search on ants whose constructed cost is within this relative band above the best",
        },
        ParamSpec {
            name: "reset",
            default: "0",
            kind: ParamKind::int(0, crate::params::MAX_ITERATIONS),
            help: "reset the pheromone after this many iterations without a new best (0 = never)",
        },
        ParamSpec {
            name: "stall",
            default: "2000",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "stop after this many iterations without a new best when no budget is set",
        },
        ParamSpec {
            name: "two-way",
            default: "true",
            kind: ParamKind::Bool,
            help: "SOP-3-exchange searches backward as well as forward",
        },
        ParamSpec {
            name: "two-opt",
            default: "true",
            kind: ParamKind::Bool,
            help: "include 2-opt with mode flip in the ants' local search",
        },
        ParamSpec {
            name: "k",
            default: "12",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate neighbours per cell (Or-opt)",
        },
        ParamSpec {
            name: "cross",
            default: "true",
            kind: ParamKind::Bool,
            help: "partition crossover of every improved ant with the best (engine::crossover): segments that hold the same cells in both are taken from the cheaper one",
        },
        ParamSpec {
            name: "lk",
            default: "false",
            kind: ParamKind::Choice(&["auto", "true", "false"]),
            help: "the ants' local search also runs Lin-Kernighan chains of feasible reversals (engine::lk); auto = when costs are symmetric (off by default: slower per ant and worse in auto on prob.100)",
        },
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::StartsFrom(|p: &Params| Ok(Box::new(from_params(p)))),
};

/// Builds the solver from validated parameters.
pub fn from_params(p: &Params) -> Eacs {
    Eacs {
        ants: p.int("ants") as usize,
        beta: p.float("beta"),
        s: p.float("s"),
        rho: p.float("rho"),
        phi: p.float("phi"),
        ls_band: p.float("ls-band"),
        reset: p.int("reset"),
        stall: p.int("stall"),
        k: p.int("k") as usize,
        two_opt: p.bool("two-opt"),
        two_way: p.bool("two-way"),
        lk: p.switch("lk"),
        cross: p.bool("cross"),
    }
}

/// The enhanced ant colony system.
pub struct Eacs {
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
    /// Relative band above the best for local search.
    pub ls_band: f64,
    /// Iterations without a new best before a pheromone reset (0 = never).
    pub reset: u64,
    /// Iterations without a new best before stopping (no budget).
    pub stall: u64,
    /// Candidate neighbours.
    pub k: usize,
    /// 2-opt in the ants' local search.
    pub two_opt: bool,
    /// Backward as well as forward SOP-3-exchange.
    pub two_way: bool,
    /// Lin-Kernighan chains in the ants' local search (`None`: when costs are symmetric).
    pub lk: Option<bool>,
    /// Partition crossover of every improved ant with the best.
    pub cross: bool,
}

/// Scratch space of one construction.
struct Ant {
    missing: Vec<u32>,
    ready: Vec<usize>,
    /// index of a cell in `ready` (usize::MAX when not ready)
    slot: Vec<usize>,
    w: Vec<(f64, usize)>,
}

impl Ant {
    fn new(n: usize) -> Self {
        Ant {
            missing: vec![0; n],
            ready: Vec::with_capacity(n),
            slot: vec![usize::MAX; n],
            w: Vec::with_capacity(n),
        }
    }
    fn take(&mut self, idx: usize) -> usize {
        let r = self.ready.swap_remove(idx);
        self.slot[r] = usize::MAX;
        if idx < self.ready.len() {
            self.slot[self.ready[idx]] = idx;
        }
        r
    }
    fn push(&mut self, c: usize) {
        self.slot[c] = self.ready.len();
        self.ready.push(c);
    }
}

impl Eacs {
    /// Builds one ant's sequence, guided by the best solution `best`.
    #[allow(clippy::too_many_arguments)]
    fn construct(
        &self,
        ctx: &mut Context,
        tau: &mut Pheromone,
        eta_eps: f64,
        q0: f64,
        best: &Solution,
        ant: &mut Ant,
        rng: &mut ChaCha8Rng,
    ) -> Sequence {
        let m = ctx.model;
        let n = m.n();
        for (c, p) in m.dag.preds.iter().enumerate() {
            ant.missing[c] = p.len() as u32;
        }
        ant.ready.clear();
        ant.slot.iter_mut().for_each(|v| *v = usize::MAX);
        for c in 0..n {
            if ant.missing[c] == 0 {
                ant.push(c);
            }
        }
        let mut seq: Sequence = Vec::with_capacity(n);
        let mut evals = 0u64;
        // O(n) per step: the clock is read every few steps, and past the deadline the ant
        // ends with a quick feasible completion
        let mut clock = Ticker::new(ctx.deadline(), 16);
        while !ant.ready.is_empty() {
            if clock.passed() {
                crate::construct::complete(m, &mut seq);
                break;
            }
            let cur = seq.last().map(|v: &Visit| (v.cell, v.mode));
            let exploit = rng.random::<f64>() < q0;
            // the successor of the current cell in the best solution
            let follow = if exploit {
                let p = match cur {
                    Some((a, _)) => best.pos[a] as usize + 1,
                    None => 0,
                };
                (p < n)
                    .then(|| best.order[p] as usize)
                    .filter(|&x| ant.slot[x] != usize::MAX)
            } else {
                None
            };
            let (idx, md) = if let Some(x) = follow {
                evals += 1;
                let md = match cur {
                    Some((a, ma)) => m.best_arc_into(a, ma, x).1,
                    None => best.mode[x] as usize,
                };
                (ant.slot[x], md)
            } else {
                ant.w.clear();
                let mut total = 0.0;
                let mut arg = (f64::NEG_INFINITY, 0usize);
                for (i, &r) in ant.ready.iter().enumerate() {
                    let (cost, md) = match cur {
                        Some((a, ma)) => m.best_arc_into(a, ma, r),
                        None => (0..m.modes(r))
                            .map(|k| (m.start(r, k), k))
                            .fold((f64::INFINITY, 0), |b, x| if x.0 < b.0 { x } else { b }),
                    };
                    let eta = 1.0 / (cost.max(0.0) + eta_eps);
                    let h = if self.beta == 2.0 {
                        eta * eta
                    } else {
                        eta.powf(self.beta)
                    };
                    let v = tau.get(cur.map(|x| x.0), r) * h;
                    total += v;
                    ant.w.push((v, md));
                    if v > arg.0 {
                        arg = (v, i);
                    }
                }
                evals += ant.ready.len() as u64;
                let i = if exploit || total <= 0.0 || !total.is_finite() {
                    arg.1
                } else {
                    let mut x = rng.random::<f64>() * total;
                    let mut pick = ant.w.len() - 1;
                    for (i, &(v, _)) in ant.w.iter().enumerate() {
                        x -= v;
                        if x <= 0.0 {
                            pick = i;
                            break;
                        }
                    }
                    pick
                };
                (i, ant.w[i].1)
            };
            let r = ant.take(idx);
            let a = cur.map(|x| x.0);
            let t = tau.get(a, r);
            tau.set(a, r, (1.0 - self.phi) * t + self.phi * tau.tau0());
            seq.push(Visit::new(r, md));
            for &s in &m.dag.succs[r] {
                ant.missing[s as usize] -= 1;
                if ant.missing[s as usize] == 0 {
                    ant.push(s as usize);
                }
            }
        }
        ctx.count(evals);
        seq
    }
}

/// Cells of `s` whose predecessor or successor differs from those in `best`.
pub fn changed_cells(s: &Solution, best: &Solution, out: &mut Vec<u32>) {
    let n = s.n();
    out.clear();
    let nb = |o: &Solution, c: usize| {
        let p = o.pos[c] as usize;
        let pred = if p == 0 { u32::MAX } else { o.order[p - 1] };
        let succ = if p + 1 == n { u32::MAX } else { o.order[p + 1] };
        (pred, succ)
    };
    for c in 0..n {
        if nb(s, c) != nb(best, c) {
            out.push(c as u32);
        }
    }
}

/// Focused descent from `seeds`: Or-opt and SOP-3-exchange (and, with `two_opt`, a 2-opt
/// pass) until none improves, then the mode DP when some cell has several modes.
#[allow(clippy::too_many_arguments)]
pub fn focused_descent(
    search: &mut Search,
    w: &mut TwoWay,
    s: &mut Solution,
    ctx: &mut Context,
    seeds: &[u32],
    multimode: bool,
    two_opt: bool,
    two_way: bool,
) {
    loop {
        let a = search.or_opt_seeded(s, ctx, seeds);
        let b = if two_way {
            sop3_two_way(search, w, s, ctx, seeds)
        } else {
            search.sop3_seeded(s, ctx, seeds)
        };
        let c = two_opt && search.two_opt(s, ctx);
        if !(a || b || c) || ctx.exhausted() {
            break;
        }
    }
    if multimode {
        search.modes(s, ctx);
    }
}

impl StartsFrom for Eacs {
    /// Runs the colony from `start` (evaluated with open-loop costs), or from the greedy
    /// sequence when `start` is `None`.
    fn run_from(&self, ctx: &mut Context, start: Option<Solution>) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        let c = Costs::open(m);
        let mut best = match start {
            Some(s) => s,
            None => greedy_solution(ctx, &c),
        };
        if ctx.deadline().passed() {
            return Ok(outcome(m, &best));
        }
        let mut search = Search::new_until(c, self.k, ctx.deadline());
        let mut lk = Lk::when(self.lk, &c, 12, 3);
        Lk::full_descent(lk.as_mut(), &mut search, &mut best, ctx);
        ctx.report(best.cost + m.constant());
        if n < 3 {
            return Ok(outcome(m, &best));
        }
        let multimode = m.multimode();
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed ^ 0xeac5);
        let scale = best.cost.abs().max(1e-9);
        let tau0 = 1.0 / (n as f64 * scale);
        let mut tau = Pheromone::new(n, tau0);
        let eta_eps = 1e-3 * scale / n as f64;
        let q0 = (1.0 - self.s / n as f64).clamp(0.0, 1.0);
        let bounded = ctx.budget.max_evals.is_some() || ctx.budget.time_limit.is_some();
        let mut ant = Ant::new(n);
        let mut w = TwoWay::default();
        let mut seeds = Vec::new();
        let mut since_best = 0u64;
        let mut since_reset = 0u64;
        let mut px = Crossover::default();
        let mut crosses = 0u64;
        while !ctx.exhausted() && (bounded || since_best < self.stall) {
            let mut improved = false;
            for _ in 0..self.ants {
                if ctx.exhausted() {
                    break;
                }
                let seq = self.construct(ctx, &mut tau, eta_eps, q0, &best, &mut ant, &mut rng);
                let mut s = Solution::new(&c, &seq);
                ctx.count(n as u64);
                if multimode {
                    let e = mode_dp(&c, &mut s);
                    ctx.count(e);
                }
                if s.cost > best.cost + self.ls_band * best.cost.abs() {
                    continue;
                }
                changed_cells(&s, &best, &mut seeds);
                if seeds.is_empty() {
                    continue;
                }
                focused_descent(
                    &mut search,
                    &mut w,
                    &mut s,
                    ctx,
                    &seeds,
                    multimode,
                    self.two_opt,
                    self.two_way,
                );
                if let Some(lk) = lk.as_mut() {
                    while lk.improve(&c, &search.nb, &mut s, ctx, &seeds) && !ctx.exhausted() {
                        focused_descent(
                            &mut search,
                            &mut w,
                            &mut s,
                            ctx,
                            &seeds,
                            multimode,
                            self.two_opt,
                            self.two_way,
                        );
                    }
                }
                // an ant that does not beat the best may still hold better segments: the
                // partition crossover takes each segment from the cheaper of the two
                if self.cross && !cheaper(s.cost, best.cost) {
                    // every attempt is charged its O(n), whether it gives a child or not
                    ctx.count(n as u64);
                    if let Some(child) = px.cross(&c, &s, &best) {
                        crosses += 1;
                        s = child;
                    }
                }
                if cheaper(s.cost, best.cost) {
                    Lk::full_descent(lk.as_mut(), &mut search, &mut s, ctx);
                    best = s;
                    ctx.report(best.cost + m.constant());
                    improved = true;
                }
            }
            if improved {
                since_best = 0;
                since_reset = 0;
            } else {
                since_best += 1;
                since_reset += 1;
            }
            if self.reset > 0 && since_reset >= self.reset {
                tau = Pheromone::new(n, tau0);
                since_reset = 0;
            }
            // global update on the best-so-far solution
            let dep = 1.0 / best.cost.abs().max(1e-9);
            let mut prev: Option<usize> = None;
            for &x in &best.order {
                let x = x as usize;
                let t = tau.get(prev, x);
                tau.set(prev, x, (1.0 - self.rho) * t + self.rho * dep);
                prev = Some(x);
            }
            ctx.count(n as u64);
        }
        if super::trace_enabled() {
            eprintln!("eacs: {crosses} crossovers gave a new best");
        }
        Ok(outcome(m, &best))
    }
}

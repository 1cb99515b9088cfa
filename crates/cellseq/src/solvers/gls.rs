//! `gls`: guided local search (Voudouris and Tsang, "Guided local search and its application
//! to the traveling salesman problem", EJOR 113, 1999) over the moves of `ils`'s repair.
//!
//! The search descends to a local optimum, then repeats until the budget ends:
//!
//! 1. **Penalise.** Of the links between consecutive cells of the current sequence, the `top`
//!    with the highest utility `cost / (1 + penalty)` get one more penalty each (on costs that
//!    read the same backwards, the link's reverse too). A penalised link costs
//!    `cost + λ · penalty`, with `λ = alpha ×` the mean link cost of the first local optimum.
//! 2. **Descend on the penalised costs** from the current sequence: Or-opt, SOP-3-exchange and
//!    (on costs that read the same backwards) Lin–Kernighan chains, started at the ends of the
//!    links just penalised (the other cells' "don't look" bits stay set), to a local optimum
//!    of the penalised costs. The candidate lists stay those of the true costs.
//! 3. **Keep the best true cost.** A sequence whose true cost beats the best is polished by
//!    the full descent on the true costs (VND and Lin–Kernighan) and kept.
//!
//! The penalties pull the walk out of each local optimum through its dearest links, and the
//! walk comes back to cheap structure the penalties have not touched: no random kicks, so a
//! run is the same for every seed. The penalised costs live in a copy of the cost model whose
//! arcs are raised in place; the closure and the cheapest arcs it caches stay those of the true
//! costs, which are lower bounds of the penalised ones, so every pruning the moves make stays
//! exact.
//!
//! Penalties apply to matrix instances with one mode per cell and at most [`MAX_NODES`] nodes
//! (the copy of the matrix); elsewhere `gls` is the descent alone.

use super::Build;
use super::start::{greedy_solution, outcome};
use super::{
    Caps, Context, Outcome, ParamKind, ParamSpec, Params, SolverInfo, StartsFrom,
};
use crate::cost::CostModel;
use crate::engine::lk::Lk;
use crate::engine::neighbours::Neighbours;
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution, cheaper};
use crate::error::Result;
use rustc_hash::FxHashMap;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "gls",
    summary: "guided local search: penalties on the dearest links of each local optimum, descent on the penalised costs, the best true cost kept",
    description: "Guided local search (Voudouris and Tsang). From a local optimum, the `top` links with \
the highest `cost / (1 + penalty)` get one more penalty each, and the search descends again \
on costs raised by `λ × penalty` (λ = `alpha` × the first optimum's mean link cost) with \
Or-opt, SOP-3-exchange and, on costs that read the same backwards, Lin–Kernighan chains, \
started at the penalised links. Every sequence whose true cost beats the best is polished on \
the true costs and kept. No random kicks: the result does not depend on the seed. Penalties \
apply to matrix instances with one mode per cell and at most 4096 nodes; elsewhere it is the \
descent alone. In `auto` it is the walk of the built-in portfolio's `symmetric` rule, after \
its short local search or its beam, the whole plan of its `symmetric-medium` rule \
(symmetric matrices of 401-1000 cells), and the long-budget plan of its `dense-ties` rule \
(dense precedence with many zero-cost links).",
    params: &[
        ParamSpec {
            name: "alpha",
            default: "3",
            kind: ParamKind::float(0.0, 100.0),
            help: "penalty weight λ as a multiple of the first local optimum's mean link cost",
        },
        ParamSpec {
            name: "top",
            default: "2",
            kind: ParamKind::int(1, 1000),
            help: "links penalised after each local optimum (those of the highest utility)",
        },
        ParamSpec {
            name: "k",
            default: "12",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate neighbours per cell (from the true costs)",
        },
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::StartsFrom(|p: &Params| {
        Ok(Box::new(Gls {
            alpha: p.float("alpha"),
            top: p.int("top") as usize,
            k: p.int("k") as usize,
        }))
    }),
};

/// Most nodes whose cost matrix `gls` copies for its penalised costs (128 MiB of `f64`).
pub const MAX_NODES: usize = 4096;

/// Longest Lin–Kernighan chain and first steps per cell (the `ils` defaults).
const LK_DEPTH: usize = 12;
const LK_BREADTH: usize = 3;

/// The guided local search.
pub struct Gls {
    /// Penalty weight, as a multiple of the first local optimum's mean link cost.
    pub alpha: f64,
    /// Links penalised per local optimum.
    pub top: usize,
    /// Candidate neighbours per cell.
    pub k: usize,
}

/// Whether penalties apply to this model (see the module documentation).
pub fn applies(m: &CostModel) -> bool {
    !m.is_geometric() && m.one_mode() && m.nodes() <= MAX_NODES && m.n() >= 3
}

/// The penalties of the links, and the rule that picks the next ones.
pub struct Penalties {
    /// λ: the cost one penalty adds to a link.
    pub lambda: f64,
    /// Penalise a link's reverse with it (costs that read the same backwards).
    pub symmetric: bool,
    count: FxHashMap<(u32, u32), u32>,
    util: Vec<(f64, u32, u32)>,
}

impl Penalties {
    /// No penalties yet.
    pub fn new(lambda: f64, symmetric: bool) -> Self {
        Penalties {
            lambda,
            symmetric,
            count: FxHashMap::default(),
            util: Vec::new(),
        }
    }

    /// Penalties on the link from cell `a` to cell `b`.
    pub fn of(&self, a: u32, b: u32) -> u32 {
        self.count.get(&(a, b)).copied().unwrap_or(0)
    }

    /// Gives the `top` links of `s` with the highest utility `cost / (1 + penalty)` (true
    /// costs `c`; ties to the earlier cell pair) one more penalty each, raises them in `pm` by
    /// λ, and puts their end cells in `seeds`.
    pub fn penalise(
        &mut self,
        c: &Costs,
        s: &Solution,
        pm: &mut CostModel,
        top: usize,
        seeds: &mut Vec<u32>,
    ) {
        self.util.clear();
        for p in 0..s.n().saturating_sub(1) {
            let (a, b) = (s.order[p], s.order[p + 1]);
            let cost = c.link(s.at(p as isize), s.at(p as isize + 1));
            self.util
                .push((cost / (1.0 + self.of(a, b) as f64), a, b));
        }
        let order = |x: &(f64, u32, u32), y: &(f64, u32, u32)| {
            y.0.total_cmp(&x.0).then((x.1, x.2).cmp(&(y.1, y.2)))
        };
        let top = top.min(self.util.len());
        if top < self.util.len() && top > 0 {
            self.util.select_nth_unstable_by(top - 1, order);
        }
        seeds.clear();
        for i in 0..top {
            let (_, a, b) = self.util[i];
            let mut raise = |x: u32, y: u32| {
                *self.count.entry((x, y)).or_insert(0) += 1;
                pm.add_to_arc(x as usize, y as usize, self.lambda);
            };
            raise(a, b);
            if self.symmetric {
                raise(b, a);
            }
            seeds.push(a);
            seeds.push(b);
        }
    }
}

/// The full descent on `c` (VND, then Lin–Kernighan alternating with it); gives back the
/// candidate lists it borrowed.
fn descend(
    c: Costs,
    nb: Neighbours,
    lk: &mut Option<Lk>,
    s: &mut Solution,
    ctx: &mut Context,
) -> Neighbours {
    let mut search = Search::with_neighbours(c, nb);
    Lk::full_descent(lk.as_mut(), &mut search, s, ctx);
    search.nb
}

/// The descent on `c` from the cells `seeds`: Or-opt, SOP-3-exchange and Lin–Kernighan until
/// none improves; gives back the candidate lists it borrowed.
fn repair(
    c: Costs,
    nb: Neighbours,
    lk: &mut Option<Lk>,
    s: &mut Solution,
    ctx: &mut Context,
    seeds: &[u32],
) -> Neighbours {
    let mut search = Search::with_neighbours(c, nb);
    loop {
        let a = search.or_opt_seeded(s, ctx, seeds);
        let b = search.sop3_seeded(s, ctx, seeds);
        let l = match lk.as_mut() {
            Some(lk) => lk.improve(&c, &search.nb, s, ctx, seeds),
            None => false,
        };
        if !(a || b || l) || ctx.exhausted() {
            break;
        }
    }
    search.nb
}

impl StartsFrom for Gls {
    fn run_from(&self, ctx: &mut Context, start: Option<Solution>) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs::open(m);
        let mut s = match start {
            Some(s) => s,
            None => greedy_solution(ctx, &c),
        };
        if ctx.deadline().passed() {
            return Ok(outcome(m, &s));
        }
        let mut lk = Lk::when(None, &c, LK_DEPTH, LK_BREADTH);
        let mut nb = Neighbours::new_until(m, self.k, ctx.deadline());
        nb = descend(c, nb, &mut lk, &mut s, ctx);
        let mut best = s.clone();
        ctx.report(best.cost + m.constant());
        if !applies(m) {
            return Ok(outcome(m, &best));
        }
        let symmetric = lk.as_ref().is_some_and(|l| l.symmetric);
        let lambda = self.alpha * s.cost.max(0.0) / (m.n() as f64 + 1.0);
        let mut pen = Penalties::new(lambda, symmetric);
        let mut pm = m.clone();
        let mut seeds = Vec::new();
        let (mut rounds, mut gains) = (0u64, 0u64);
        // `exhausted` is also true once the best meets the model's floor (an optimum)
        while !ctx.exhausted() {
            rounds += 1;
            pen.penalise(&c, &s, &mut pm, self.top, &mut seeds);
            ctx.count(m.n() as u64);
            let pc = Costs::open(&pm);
            s.cost = s.evaluate(&pc);
            nb = repair(pc, nb, &mut lk, &mut s, ctx, &seeds);
            let real = s.evaluate(&c);
            if cheaper(real, best.cost) {
                let mut t = s.clone();
                t.cost = real;
                nb = descend(c, nb, &mut lk, &mut t, ctx);
                if t.cost < best.cost {
                    best = t;
                    gains += 1;
                    ctx.report(best.cost + m.constant());
                }
            }
        }
        if super::trace_enabled() {
            eprintln!("gls: {rounds} rounds, {gains} new bests, lambda {lambda:.4}");
        }
        Ok(outcome(m, &best))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::NoObserver;
    use crate::engine::atsp::random_matrix_instance;
    use crate::model::{CostMatrix, Objective, Sequence};
    use crate::solvers::Solver;
    use crate::solvers::Budget;

    /// The links of highest `cost / (1 + penalty)` get the penalties, ties to the earlier
    /// pair, their reverses too on symmetric costs, and the model's arcs rise by λ each time.
    #[test]
    fn penalises_the_links_of_highest_utility() {
        let inst = random_matrix_instance(8, 3, 100, &[]);
        let m = CostModel::new(&inst, Objective::Matrix);
        let c = Costs::open(&m);
        let seq: Sequence = (0..8).map(|i| crate::model::Visit::new(i, 0)).collect();
        let s = Solution::new(&c, &seq);
        let link = |p: usize| m.arc(p, 0, p + 1, 0);
        let mut by_util: Vec<(f64, usize)> = (0..7).map(|p| (link(p), p)).collect();
        by_util.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let mut pm = m.clone();
        let mut pen = Penalties::new(5.0, true);
        let mut seeds = Vec::new();
        pen.penalise(&c, &s, &mut pm, 2, &mut seeds);
        for (i, &(_, p)) in by_util.iter().enumerate() {
            let (a, b) = (p as u32, p as u32 + 1);
            let want = u32::from(i < 2);
            assert_eq!(pen.of(a, b), want, "link {p}");
            assert_eq!(pen.of(b, a), want, "reverse of link {p}");
            assert_eq!(pm.arc(p, 0, p + 1, 0), m.arc(p, 0, p + 1, 0) + 5.0 * want as f64);
        }
        assert_eq!(seeds.len(), 4);
        // the dearest link now has utility cost / 2: penalised again only while that stays
        // above the third link's cost
        let (top, p0) = by_util[0];
        pen.penalise(&c, &s, &mut pm, 1, &mut seeds);
        let again = top / 2.0 > by_util[2].0
            || (top / 2.0 == by_util[2].0 && p0 < by_util[2].1);
        assert_eq!(pen.of(p0 as u32, p0 as u32 + 1), 1 + u32::from(again));
    }

    /// A best at the model's floor ends the rounds at once (here every link costs 0, so λ is
    /// 0 and no penalty could lead anywhere), not at the end of a large evaluation budget.
    #[test]
    fn stops_at_the_floor() {
        let mut inst = random_matrix_instance(30, 5, 100, &[]);
        if let Some(mx) = inst.matrix.as_mut() {
            for x in mx.costs.iter_mut().filter(|x| **x < CostMatrix::FORBIDDEN) {
                *x = 0.0;
            }
        }
        let m = CostModel::new(&inst, Objective::Matrix);
        let budget = Budget {
            time_limit: None,
            max_evals: Some(1_000_000_000),
        };
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, budget, &mut obs);
        let g = Gls {
            alpha: 3.0,
            top: 2,
            k: 12,
        };
        let o = g.solve(&mut ctx).unwrap();
        assert_eq!(Solution::new(&Costs::open(&m), &o.sequence).cost, 0.0);
        assert!(ctx.evaluations() < 1_000_000, "{}", ctx.evaluations());
    }

    /// On a 60-cell random instance with precedence the search ends feasible, no worse than
    /// its descent, and the same for two seeds (no random kicks).
    #[test]
    fn never_worse_than_its_descent_and_seed_free() {
        let pairs: Vec<(usize, usize)> = (0..20).map(|i| (i, i + 30)).collect();
        let inst = random_matrix_instance(60, 11, 1000, &pairs);
        let m = CostModel::new(&inst, Objective::Matrix);
        let budget = Budget {
            time_limit: None,
            max_evals: Some(3_000_000),
        };
        let g = Gls {
            alpha: 3.0,
            top: 2,
            k: 12,
        };
        let mut costs = Vec::new();
        for seed in [1, 2] {
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, seed, budget, &mut obs);
            let c = Costs::open(&m);
            let mut d = greedy_solution(&mut ctx, &c);
            let nb = Neighbours::new(&m, 12);
            let mut lk = Lk::when(None, &c, LK_DEPTH, LK_BREADTH);
            descend(c, nb, &mut lk, &mut d, &mut ctx);
            let mut ctx = Context::new(&inst, &m, seed, budget, &mut obs);
            let o = g.solve(&mut ctx).unwrap();
            let s = Solution::new(&c, &o.sequence);
            assert!(s.feasible(&m));
            assert!(s.cost <= d.cost + 1e-9, "{} > descent {}", s.cost, d.cost);
            costs.push((s.cost, o.sequence));
        }
        assert_eq!(costs[0], costs[1]);
    }
}

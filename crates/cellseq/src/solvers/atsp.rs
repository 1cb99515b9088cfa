//! `atsp`: for asymmetric costs with little or no precedence — the assignment problem's cycles
//! patched into a path, candidate lists from its reduced costs, an iterated Or-3opt search with
//! block-swap kicks, then depth-first branch and bound on the assignment relaxation
//! ([`crate::engine::atsp`]).

use super::Build;
use super::start::{greedy_solution, outcome};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::bound::assignment::Assignment;
use crate::engine::atsp::bnb::{ApState, Bnb, End};
use crate::engine::atsp::cands::{Rank, candidates};
use crate::engine::atsp::or3::Or3;
use crate::engine::atsp::patch::{ApGraph, construct_until};
use crate::engine::modes::mode_dp;
use crate::engine::{Costs, Neighbours, Solution};
use crate::error::Result;
use crate::model::Visit;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "atsp",
    summary: "asymmetric costs with little or no precedence: assignment cycles patched into a path, reduced-cost candidates, iterated Or-3opt with block-swap kicks, then branch and bound on the assignment",
    description: "For asymmetric costs with little or no precedence (an asymmetric TSP as an open path).

- **Start**: the better of `greedy` and the assignment problem's solution (a dummy node \
closes the path) whose cycles are patched into one path (`patch=greedy`: the cheapest join of \
any two cycles first; `karp`: into the largest cycle); arcs no feasible order can use are left \
out, and a patched path that breaks the precedence is repaired by a topological sort that \
follows it. Above `ap-max-cells` no assignment is solved.
- **Search**: iterated Or-3opt (two adjacent blocks swap places, no reversal) on candidate \
lists ranked by the assignment's reduced costs (`cand=reduced`, ties by raw cost; `k` per \
cell), precedence checked on every move; kicks swap two blocks across a third (`kick=far`) \
or two adjacent blocks (`near`), of up to `kick-len` cells; equal-or-better results are \
accepted.
- **Branch and bound**: once `bnb-after` kicks per cell in a row bring no improvement (or no \
kick is allowed), an instance with one mode per cell and no precedence apart from a fixed \
start and end turns to a depth-first branch and bound on \
the assignment relaxation (Carpaneto and Toth's subtour elimination: the smallest cycle's arcs \
are excluded one per child, the ones before it forced; each child is one augmenting path from \
its parent, lowest bound first; children at or above the best tour are pruned). Every node's \
cycles are also patched into a tour, descended by Or-3opt when within `polish` of the best. \
When the tree is exhausted the result is reported as proven optimal, with the optimum as its \
lower bound.
- `auto` runs it (the built-in portfolio's `free` rule) on asymmetric matrix instances whose \
`free_density` (the closure density apart from cells ordered against every other: a fixed \
start and end) is at most 0.001; notes/atsp.md has the measurements.",
    params: &[
        ParamSpec {
            name: "k",
            default: "8",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate successors and predecessors per cell",
        },
        ParamSpec {
            name: "cand",
            default: "reduced",
            kind: ParamKind::Choice(&["reduced", "raw"]),
            help: "rank candidates by the assignment's reduced costs (ties by raw cost) or by raw cost",
        },
        ParamSpec {
            name: "kick-len",
            default: "10",
            kind: ParamKind::int(1, crate::params::MAX_CELLS),
            help: "longest block of a kick (two adjacent blocks of 1..kick-len cells swap places)",
        },
        ParamSpec {
            name: "kick",
            default: "far",
            kind: ParamKind::Choice(&["far", "near"]),
            help: "far: two blocks swap places across a third (A B C D E -> A D C B E); near: two adjacent blocks swap (A B C D -> A C B D)",
        },
        ParamSpec {
            name: "patch",
            default: "greedy",
            kind: ParamKind::Choice(&["greedy", "karp"]),
            help: "greedy: the cheapest join of any two assignment cycles first; karp: cycles joined into the largest one, largest first",
        },
        ParamSpec {
            name: "bnb-after",
            default: "1",
            kind: ParamKind::int(0, 1_000_000),
            help: "after this many kicks per cell without improvement the search turns to branch and bound on the assignment (0: never)",
        },
        ParamSpec {
            name: "polish",
            default: "0.05",
            kind: ParamKind::float(0.0, 10.0),
            help: "branch and bound: a patched tour is descended by Or-3opt when at most this fraction above the best",
        },
        ParamSpec {
            name: "ap-max-cells",
            default: "3000",
            kind: ParamKind::int(0, 20_000),
            help: "above this many cells no assignment is solved (its graph is an (n + 1)² table): greedy start and nearest-cost candidates",
        },
    ],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Atsp {
            k: p.int("k") as usize,
            rank: if p.word("cand") == "raw" {
                Rank::Raw
            } else {
                Rank::Reduced
            },
            kick_len: p.int("kick-len") as usize,
            ap_max_cells: p.int("ap-max-cells") as usize,
            far: p.word("kick") == "far",
            greedy_patch: p.word("patch") == "greedy",
            bnb_after: p.int("bnb-after") as usize,
            polish: p.float("polish"),
        }))
    }),
};

/// The solver.
pub struct Atsp {
    /// Candidates per cell.
    pub k: usize,
    /// How candidates are ranked.
    pub rank: Rank,
    /// Longest kick block.
    pub kick_len: usize,
    /// Largest instance that gets the assignment.
    pub ap_max_cells: usize,
    /// Kicks across a third block (else adjacent blocks).
    pub far: bool,
    /// Greedy patching (else Karp's order).
    pub greedy_patch: bool,
    /// Kicks per cell without improvement before branch and bound (0: never).
    pub bnb_after: usize,
    /// Patched tours within this fraction of the best are descended.
    pub polish: f64,
}

impl Atsp {
    /// The start and the candidate lists: the patched assignment with reduced-cost lists
    /// (when it applies), else greedy with nearest-cost lists. Where the precedence made the
    /// patched path be repaired, greedy is descended as well and the cheaper local optimum
    /// wins (the repair moves every cell that must wait for a predecessor next to it, across
    /// arcs the assignment did not choose).
    fn start(&self, ctx: &mut Context, c: &Costs) -> (Solution, Neighbours, Option<Relaxation>) {
        let m = ctx.model;
        let greedy = greedy_solution(ctx, c);
        if ctx.deadline().passed() {
            let none = vec![Vec::new(); m.n()];
            let nb = Neighbours {
                out: none.clone(),
                inn: none,
            };
            return (greedy, nb, None);
        }
        if m.n() < 2 || m.n() > self.ap_max_cells || ctx.exhausted() {
            return (greedy, Neighbours::new_until(m, self.k, ctx.deadline()), None);
        }
        let modes: Vec<u32> = (0..m.n()).map(|c| greedy.mode[c]).collect();
        let g = ApGraph::new(m, &modes);
        let Some((order, ap, evals)) = construct_until(m, &g, self.greedy_patch, ctx.deadline())
        else {
            return (greedy, Neighbours::new_until(m, self.k, ctx.deadline()), None);
        };
        ctx.count(evals);
        let seq: Vec<Visit> = order
            .iter()
            .map(|&x| Visit::new(x as usize, modes[x as usize] as usize))
            .collect();
        let patched = Solution::new(c, &seq);
        let nb = candidates(&g, &ap, self.k, self.rank);
        if super::trace_enabled() {
            eprintln!(
                "atsp: assignment {}, patched {}, greedy {}",
                ap.value, patched.cost, greedy.cost
            );
        }
        ctx.report(patched.cost.min(greedy.cost) + m.constant());
        if m.dag.succs.iter().all(|s| s.is_empty()) {
            return (patched, nb, Some((g, ap)));
        }
        let descended = |mut s: Solution, ctx: &mut Context| {
            let mut or3 = Or3::new(*c, &nb);
            or3.push_all(&s);
            or3.descend(&mut s, ctx);
            s
        };
        let a = descended(patched, ctx);
        let b = descended(greedy, ctx);
        let s = if a.cost <= b.cost { a } else { b };
        (s, nb, Some((g, ap)))
    }
}

/// The assignment graph and its optimal assignment, when the start solved one.
type Relaxation = (ApGraph, Assignment);

impl Atsp {
    /// Depth-first branch and bound on the assignment relaxation ([`Bnb`]) from the best
    /// order `best`, until the budget runs out or the tree is exhausted; every tour it meets
    /// is descended by Or-3opt (a patched one only when within `polish` of the best) and
    /// replaces `best` when cheaper. True when the tree was exhausted and every one-cycle
    /// leaf kept the precedence: then `best` is optimal for the cells' fixed modes.
    fn branch_and_bound(
        &self,
        ctx: &mut Context,
        c: &Costs,
        nb: &Neighbours,
        g: &ApGraph,
        ap: &Assignment,
        best: &mut Solution,
    ) -> bool {
        let m = ctx.model;
        let tol = 1e-9 * best.cost.abs().max(1.0);
        let mut bnb = Bnb::new(g);
        let mut or3 = Or3::new(*c, nb);
        let mut counted = 0u64;
        let polish = self.polish;
        let mut leaves = 0u64;
        let mut rejected = false;
        let ub = best.cost;
        // both callbacks count and report through the context
        let ctx_cell = std::cell::RefCell::new(ctx);
        let end = bnb.search(
            ApState::of(ap),
            ub,
            tol,
            |order, value| {
                let mut ctx = ctx_cell.borrow_mut();
                let leaf = value.is_some();
                leaves += u64::from(leaf);
                let mut s = best.reordered(c, order);
                if !s.feasible(m) {
                    rejected |= leaf;
                    return best.cost;
                }
                if !leaf && s.cost > best.cost * (1.0 + polish) + tol {
                    return best.cost;
                }
                or3.push_all(&s);
                or3.descend(&mut s, &mut ctx);
                if s.cost < best.cost - tol {
                    best.clone_from(&s);
                    ctx.report(best.cost + m.constant());
                    if super::trace_enabled() {
                        eprintln!("atsp: branch and bound {} after {:.2} s", best.cost, ctx.elapsed());
                    }
                }
                best.cost
            },
            |work| {
                let mut ctx = ctx_cell.borrow_mut();
                let d = (g.n + 1) as u64;
                ctx.count((work - counted) / d + 1);
                counted = work;
                ctx.exhausted()
            },
        );
        if super::trace_enabled() {
            eprintln!(
                "atsp: branch and bound {end:?}, {} nodes, {leaves} one-cycle leaves",
                bnb.nodes
            );
        }
        end == End::Exhausted && !rejected
    }
}

impl Solver for Atsp {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs::open(m);
        let (mut s, nb, relax) = self.start(ctx, &c);
        if ctx.deadline().passed() {
            return Ok(outcome(m, &s));
        }
        let mut or3 = Or3::new(c, &nb);
        or3.push_all(&s);
        or3.descend(&mut s, ctx);
        ctx.report(s.cost + m.constant());
        let mut best = s.clone();
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed ^ 0xa75b);
        let max_len = self.kick_len.min(s.n() / 3).max(1);
        // branch and bound where every tour of the assignment graph is a feasible order of
        // the instance: one mode per cell (else the graph holds the start's modes) and no
        // precedence apart from cells ordered against every other (a fixed start and end,
        // whose arcs the graph leaves out). With other pairs most one-cycle leaves break one
        // (random-sop p = 1 %: half the nodes), and the tree wastes the time.
        let bnb = self.bnb_after > 0
            && relax.is_some()
            && !m.multimode()
            && crate::engine::atsp::free_density(m) == 0.0;
        let mut stalled = 0usize;
        while !ctx.exhausted() {
            ctx.count(1);
            if !or3.kick(&mut s, &mut rng, max_len, 20, self.far) {
                break;
            }
            or3.descend(&mut s, ctx);
            let tol = 1e-9 * best.cost.abs().max(1.0);
            stalled += 1;
            if s.cost < best.cost - tol {
                best.clone_from(&s);
                ctx.report(best.cost + m.constant());
                stalled = 0;
            } else if s.cost > best.cost + tol {
                s.clone_from(&best);
            }
            if bnb && stalled >= self.bnb_after * s.n() {
                break;
            }
        }
        let mut proven = false;
        if let Some((g, ap)) = relax.as_ref().filter(|_| bnb)
            && !ctx.exhausted()
        {
            proven = self.branch_and_bound(ctx, &c, &nb, g, ap, &mut best);
        }
        if m.multimode() {
            ctx.count(mode_dp(&c, &mut best));
            proven = false;
        }
        let mut out = outcome(m, &best);
        if proven {
            out.proven_optimal = true;
            out.lower_bound = Some(out.cost);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use crate::cost::CostModel;
    use crate::engine::atsp::patch::{self, ApGraph, construct};
    use crate::engine::atsp::random_matrix_instance;
    use crate::engine::{Costs, Solution};
    use crate::model::{Instance, Objective, Visit};
    use crate::solvers::{Budget, NoObserver, run};
    use std::collections::BTreeMap;

    /// A random matrix instance with costs in 0..10 (many ties), SOP-like fixed ends on odd
    /// seeds and one precedence pair on seeds divisible by 3.
    fn tiny(n: usize, seed: u64) -> Instance {
        let prec = if seed.is_multiple_of(3) {
            vec![(2, 1)]
        } else {
            vec![]
        };
        let ends = seed % 2 == 1;
        Instance {
            name: format!("tiny{seed}"),
            first: ends.then_some(0),
            last: ends.then_some(n - 1),
            ..random_matrix_instance(n, seed, 10, &prec)
        }
    }

    fn solve(name: &str, inst: &Instance, evals: Option<u64>) -> (f64, Vec<Visit>) {
        let budget = Budget {
            time_limit: None,
            max_evals: evals,
        };
        let r = run(
            name,
            inst,
            Objective::Matrix,
            &BTreeMap::new(),
            7,
            budget,
            &mut NoObserver,
        )
        .unwrap();
        (r.report.cost, r.outcome.sequence)
    }

    /// The assignment is a lower bound on the exact optimum, the patched path a feasible
    /// upper bound, equal to the optimum when the assignment is one cycle whose path keeps the
    /// precedence; `atsp` reaches the exact optimum on every tiny instance.
    #[test]
    fn patching_against_the_exact_solver() {
        let mut one_cycle = 0;
        for seed in 0..24u64 {
            let n = 5 + (seed as usize % 4);
            let inst = tiny(n, seed);
            let m = CostModel::new(&inst, Objective::Matrix);
            let (opt, _) = solve("exact", &inst, None);
            let g = ApGraph::new(&m, &vec![0; n]);
            let (order, ap, _) = construct(&m, &g, seed % 2 == 0).unwrap();
            let seq: Vec<Visit> = order.iter().map(|&x| Visit::new(x as usize, 0)).collect();
            let s = Solution::new(&Costs::open(&m), &seq);
            assert!(
                s.feasible(&m),
                "seed {seed}: patched path breaks the precedence"
            );
            assert!(
                ap.value <= opt + 1e-9,
                "seed {seed}: AP {} > opt {opt}",
                ap.value
            );
            assert!(
                s.cost >= opt - 1e-9,
                "seed {seed}: patched {} < opt {opt}",
                s.cost
            );
            // one assignment cycle that needed no repair is an optimal path
            if patch::cycles(&ap.col).len() == 1 && patch::path_of(&ap.col) == order {
                one_cycle += 1;
                assert_eq!(s.cost, ap.value, "seed {seed}: the path is the assignment");
                assert_eq!(s.cost, opt, "seed {seed}: one AP cycle is the optimum");
            }
            let (cost, _) = solve("atsp", &inst, Some(20_000));
            assert_eq!(cost, opt, "seed {seed}: atsp {cost}, exact {opt}");
        }
        assert!(one_cycle > 0, "no instance had a one-cycle assignment");
    }

    /// Where `atsp`'s branch and bound exhausts its tree it claims optimality, with the
    /// optimum as its lower bound; the claim agrees with the DP on every instance that makes
    /// it, and it is made on every instance without precedence.
    #[test]
    fn exhausted_branch_and_bound_proves_the_optimum() {
        let mut proofs = 0;
        for seed in 0..40u64 {
            let n = 6 + (seed as usize % 5);
            let inst = tiny(n, 1000 + seed);
            let (opt, _) = solve("exact", &inst, None);
            let r = run(
                "atsp",
                &inst,
                Objective::Matrix,
                &BTreeMap::new(),
                seed,
                Budget {
                    time_limit: None,
                    max_evals: Some(1_000_000),
                },
                &mut NoObserver,
            )
            .unwrap();
            if inst.precedence.is_empty() && inst.first.is_none() {
                assert!(r.outcome.proven_optimal, "seed {seed}: no proof");
            }
            if r.outcome.proven_optimal {
                proofs += 1;
                assert_eq!(r.report.cost, opt, "seed {seed}");
                assert_eq!(r.outcome.lower_bound, Some(r.outcome.cost), "seed {seed}");
            }
        }
        assert!(proofs > 0);
    }

    /// The same seed and evaluation budget give the same sequence.
    #[test]
    fn deterministic_under_an_evaluation_budget() {
        let inst = tiny(40, 5);
        let a = solve("atsp", &inst, Some(200_000));
        let b = solve("atsp", &inst, Some(200_000));
        assert_eq!(a, b);
    }
}

//! Depth-first branch and bound on the assignment relaxation (Carpaneto and Toth's subtour
//! elimination, searched depth first as in Zhang's truncated branch and bound).
//!
//! A node is the assignment problem of the [`ApGraph`] with some arcs excluded and some
//! forced. Its optimal value bounds every tour that keeps those choices. A node whose
//! assignment is one cycle (through the dummy node) is a tour. Otherwise the cycle with the
//! fewest free arcs `a_1 … a_k` is broken: child `t` excludes `a_t` and forces
//! `a_1 … a_{t−1}`, so the children split the node's tours without overlap. Children are
//! searched depth first, the lowest bound first, and a child whose bound reaches the best tour
//! known is pruned.
//!
//! Each child's assignment is its parent's with one row freed (the excluded arc's tail) and
//! matched again by one shortest augmenting path on reduced costs (the parent's potentials
//! stay feasible: one cost only grew), O(d²) on the dense graph. Forced arcs keep their row
//! and column to each other.
//!
//! The search is a heuristic under a budget: every node also patches its cycles into a tour
//! ([`super::patch::patch`]), and every tour found goes to a caller's callback (which may
//! improve it) whose result tightens the pruning bound. When the tree is exhausted within the
//! budget and every tour found kept the precedence, the best tour is optimal up to the
//! pruning tolerance the caller gives (`atsp`: 10⁻⁹ of the best cost, the engine's measure of
//! an improvement).

use super::patch::{ApGraph, cycles, patch, path_of};
use crate::bound::assignment::Assignment;

const NONE: u32 = u32::MAX;

/// An assignment with its potentials, as the search keeps it per node.
#[derive(Debug, Clone, Default)]
pub struct ApState {
    /// Column of each row.
    col: Vec<u32>,
    /// Row of each column.
    row: Vec<u32>,
    /// Row potentials.
    u: Vec<f64>,
    /// Column potentials.
    v: Vec<f64>,
    /// The assignment's value.
    value: f64,
}

impl ApState {
    /// The state of an optimal assignment `ap` of order `d`.
    pub fn of(ap: &Assignment) -> ApState {
        let d = ap.col.len();
        let mut row = vec![NONE; d];
        for (i, &j) in ap.col.iter().enumerate() {
            row[j] = i as u32;
        }
        ApState {
            col: ap.col.iter().map(|&j| j as u32).collect(),
            row,
            u: ap.u.clone(),
            v: ap.v.clone(),
            value: ap.value,
        }
    }

    fn succ(&self) -> Vec<usize> {
        self.col.iter().map(|&j| j as usize).collect()
    }
}

/// Why a search ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    /// Every node was searched or pruned.
    Exhausted,
    /// The caller's stop condition held.
    Stopped,
}

/// A child of a node: its bound, the index of the arc it excludes, its assignment.
struct Child {
    bound: f64,
    t: usize,
    state: ApState,
}

/// A node being searched: the free arcs of the cycle it breaks, its children by bound and the
/// child entered last.
struct Frame {
    arcs: Vec<(u32, u32)>,
    children: Vec<Child>,
    next: usize,
    entered: Option<usize>,
}

/// The search: the graph's costs with the current exclusions, the forced arcs and the
/// scratch of the shortest-path searches.
pub struct Bnb<'a> {
    g: &'a ApGraph,
    d: usize,
    cost: Vec<f64>,
    force_row: Vec<u32>,
    force_col: Vec<u32>,
    dist: Vec<f64>,
    pred: Vec<u32>,
    done: Vec<bool>,
    scanned: Vec<u32>,
    /// Arc costs looked at so far.
    pub work: u64,
    /// Nodes searched so far.
    pub nodes: u64,
    /// Augmenting-path searches so far.
    pub augments: u64,
}

impl<'a> Bnb<'a> {
    /// A search on `g` with nothing excluded or forced.
    pub fn new(g: &'a ApGraph) -> Bnb<'a> {
        let d = g.n + 1;
        let mut cost = Vec::with_capacity(d * d);
        for i in 0..d {
            cost.extend((0..d).map(|j| g.c(i, j)));
        }
        Bnb {
            g,
            d,
            cost,
            force_row: vec![NONE; d],
            force_col: vec![NONE; d],
            dist: vec![f64::INFINITY; d],
            pred: vec![NONE; d],
            done: vec![false; d],
            scanned: Vec::with_capacity(d),
            work: 0,
            nodes: 0,
            augments: 0,
        }
    }

    /// Matches the free row `r0` again by one shortest augmenting path on reduced costs and
    /// updates the potentials; false when no finite path exists (then `s` is unusable).
    fn augment(&mut self, s: &mut ApState, r0: usize) -> bool {
        let d = self.d;
        self.augments += 1;
        self.dist.fill(f64::INFINITY);
        self.done.fill(false);
        self.scanned.clear();
        let mut r = r0;
        let mut base = 0.0;
        let sink = loop {
            let fr = self.force_row[r];
            let cols = if fr == NONE {
                0..d
            } else {
                fr as usize..fr as usize + 1
            };
            self.work += cols.len() as u64;
            let row = &self.cost[r * d..(r + 1) * d];
            for j in cols {
                if self.done[j] {
                    continue;
                }
                let fc = self.force_col[j];
                if fc != NONE && fc as usize != r {
                    continue;
                }
                let c = row[j];
                if !c.is_finite() {
                    continue;
                }
                let nd = base + c - s.u[r] - s.v[j];
                if nd < self.dist[j] {
                    self.dist[j] = nd;
                    self.pred[j] = r as u32;
                }
            }
            let mut best = f64::INFINITY;
            let mut jmin = NONE;
            for j in 0..d {
                if !self.done[j] && self.dist[j] < best {
                    best = self.dist[j];
                    jmin = j as u32;
                }
            }
            if jmin == NONE {
                return false;
            }
            let jmin = jmin as usize;
            self.done[jmin] = true;
            if s.row[jmin] == NONE {
                break jmin;
            }
            self.scanned.push(jmin as u32);
            r = s.row[jmin] as usize;
            base = best;
        };
        let delta = self.dist[sink];
        s.u[r0] += delta;
        for &j in &self.scanned {
            let j = j as usize;
            let t = delta - self.dist[j];
            s.v[j] -= t;
            s.u[s.row[j] as usize] += t;
        }
        let mut j = sink;
        loop {
            let i = self.pred[j] as usize;
            let prev = s.col[i];
            s.col[i] = j as u32;
            s.row[j] = i as u32;
            if i == r0 {
                break;
            }
            j = prev as usize;
        }
        s.value = (0..d).map(|i| self.cost[i * d + s.col[i] as usize]).sum();
        true
    }

    /// Excludes `arcs[t]` and forces `arcs[..t]`.
    fn enter(&mut self, arcs: &[(u32, u32)], t: usize) {
        let (i, j) = arcs[t];
        self.cost[i as usize * self.d + j as usize] = f64::INFINITY;
        for &(a, b) in &arcs[..t] {
            self.force_row[a as usize] = b;
            self.force_col[b as usize] = a;
        }
    }

    /// Undoes [`Bnb::enter`].
    fn leave(&mut self, arcs: &[(u32, u32)], t: usize) {
        let (i, j) = arcs[t];
        self.cost[i as usize * self.d + j as usize] = self.g.c(i as usize, j as usize);
        for &(a, b) in &arcs[..t] {
            self.force_row[a as usize] = NONE;
            self.force_col[b as usize] = NONE;
        }
    }

    /// The frame that breaks the smallest of `s`'s cycles `cyc` (by free arcs), with the
    /// children whose bound is below `ub`; `None` when a cycle is all forced arcs (no tour
    /// keeps them) or when `stop` (asked before each child's augmenting path) says so.
    fn branch(
        &mut self,
        s: &ApState,
        cyc: &[Vec<usize>],
        ub: f64,
        tol: f64,
        stop: &mut impl FnMut(u64) -> bool,
    ) -> Option<Frame> {
        let mut best: Option<Vec<(u32, u32)>> = None;
        for cyc in cyc {
            let arcs: Vec<(u32, u32)> = cyc
                .iter()
                .map(|&i| (i as u32, s.col[i]))
                .filter(|&(i, _)| self.force_row[i as usize] == NONE)
                .collect();
            if arcs.is_empty() {
                return None;
            }
            if best.as_ref().is_none_or(|b| arcs.len() < b.len()) {
                best = Some(arcs);
            }
        }
        let arcs = best?;
        let mut children = Vec::with_capacity(arcs.len());
        for t in 0..arcs.len() {
            if stop(self.work) {
                return None;
            }
            self.enter(&arcs, t);
            let mut c = s.clone();
            let (i, j) = (arcs[t].0 as usize, arcs[t].1 as usize);
            c.col[i] = NONE;
            c.row[j] = NONE;
            if self.augment(&mut c, i) && c.value < ub - tol {
                children.push(Child {
                    bound: c.value,
                    t,
                    state: c,
                });
            }
            self.leave(&arcs, t);
        }
        children.sort_by(|a, b| a.bound.total_cmp(&b.bound).then(a.t.cmp(&b.t)));
        Some(Frame {
            arcs,
            children,
            next: 0,
            entered: None,
        })
    }

    /// Searches from the root assignment `root` with the best tour's cost `ub`. Every node's
    /// tour (its own cycle when it has one, else its patched cycles) goes to `tour` as a cell
    /// order with the value of a one-cycle node (`None` for a patched tour); `tour` returns
    /// the best cost known after it, which becomes the pruning bound. `stop`, given the work
    /// so far, is asked before each node and each child's augmenting path, so that one node
    /// of a large instance does not outlast a deadline.
    pub fn search(
        &mut self,
        root: ApState,
        mut ub: f64,
        tol: f64,
        mut tour: impl FnMut(&[u32], Option<f64>) -> f64,
        mut stop: impl FnMut(u64) -> bool,
    ) -> End {
        let mut stack: Vec<Frame> = Vec::new();
        let mut next = Some(root);
        loop {
            if let Some(s) = next.take() {
                if stop(self.work) {
                    return End::Stopped;
                }
                self.nodes += 1;
                let succ = s.succ();
                let cyc = cycles(&succ);
                if cyc.len() == 1 {
                    ub = ub.min(tour(&path_of(&succ), Some(s.value)));
                } else {
                    if let Some((t, w)) = patch(self.g, &succ) {
                        self.work += w;
                        ub = ub.min(tour(&path_of(&t), None));
                    }
                    if s.value < ub - tol {
                        match self.branch(&s, &cyc, ub, tol, &mut stop) {
                            Some(f) => stack.push(f),
                            None if stop(self.work) => return End::Stopped,
                            None => {}
                        }
                    }
                }
            }
            let Some(top) = stack.last_mut() else {
                return End::Exhausted;
            };
            if let Some(t) = top.entered.take() {
                self.leave(&top.arcs, t);
            }
            if top.next >= top.children.len() || top.children[top.next].bound >= ub - tol {
                stack.pop();
                continue;
            }
            let k = top.next;
            top.next += 1;
            let t = top.children[k].t;
            let state = std::mem::take(&mut top.children[k].state);
            top.entered = Some(t);
            self.enter(&top.arcs, t);
            next = Some(state);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::random_matrix_instance;
    use super::*;
    use crate::bound::assignment::hungarian_duals;
    use crate::cost::CostModel;
    use crate::engine::{Costs, Solution};
    use crate::model::{Objective, Visit};
    use crate::solvers::{Budget, NoObserver, run};
    use std::collections::BTreeMap;

    /// After excluding an assigned arc, one augmentation gives the optimum of the matrix
    /// without that arc (the dense method re-solved from scratch), with feasible potentials.
    #[test]
    fn one_augmentation_matches_a_full_solve() {
        for seed in 0..60u64 {
            let n = 3 + (seed as usize % 25);
            let inst = random_matrix_instance(n, seed, 1 + (seed as i32 % 4) * 30, &[]);
            let m = CostModel::new(&inst, Objective::Matrix);
            let g = ApGraph::new(&m, &vec![0; n]);
            let ap = g.assignment().unwrap();
            let mut b = Bnb::new(&g);
            let mut s = ApState::of(&ap);
            let mut excluded = Vec::new();
            for step in 0..4 {
                let i = (seed as usize * 7 + step * 3) % (n + 1);
                let j = s.col[i] as usize;
                b.cost[i * (n + 1) + j] = f64::INFINITY;
                excluded.push((i, j));
                s.col[i] = NONE;
                s.row[j] = NONE;
                let ok = b.augment(&mut s, i);
                let cost = |r: usize, c: usize| {
                    if excluded.contains(&(r, c)) {
                        f64::INFINITY
                    } else {
                        g.c(r, c)
                    }
                };
                let full = hungarian_duals(n + 1, cost);
                assert_eq!(ok, full.is_some(), "seed {seed} step {step}");
                let Some(full) = full else { break };
                assert!(
                    (s.value - full.value).abs() < 1e-6,
                    "seed {seed} step {step}: {} vs {}",
                    s.value,
                    full.value
                );
                for r in 0..=n {
                    for c in 0..=n {
                        let rc = cost(r, c) - s.u[r] - s.v[c];
                        assert!(rc.is_nan() || rc > -1e-6, "seed {seed}: ({r},{c}) {rc}");
                    }
                    assert!((cost(r, s.col[r] as usize) - s.u[r] - s.v[s.col[r] as usize]).abs() < 1e-6);
                }
            }
        }
    }

    /// The stop condition is asked before every augmenting path, so that a deadline is
    /// checked at least once per O(d²) of work however long the broken cycle; a search whose
    /// stop condition holds ends at once as stopped.
    #[test]
    fn stop_is_asked_before_every_augmenting_path() {
        let mut deep = 0;
        for seed in 0..12u64 {
            let n = 20 + seed as usize * 3;
            let inst = random_matrix_instance(n, 900 + seed, 1000, &[]);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let g = ApGraph::new(&m, &vec![0; n]);
            let ap = g.assignment().unwrap();
            let mut best = f64::INFINITY;
            let mut tour = |order: &[u32], _: Option<f64>| {
                let seq: Vec<Visit> = order.iter().map(|&x| Visit::new(x as usize, 0)).collect();
                best = best.min(Solution::new(&c, &seq).cost);
                best
            };
            let mut b = Bnb::new(&g);
            let mut asked = 0u64;
            let end = b.search(ApState::of(&ap), f64::INFINITY, 1e-9, &mut tour, |_| {
                asked += 1;
                false
            });
            assert_eq!(end, End::Exhausted, "seed {seed}");
            assert!(asked >= b.augments, "seed {seed}: {asked} asks, {} paths", b.augments);
            if asked <= 3 {
                continue;
            }
            deep += 1;
            let mut b = Bnb::new(&g);
            let mut asked = 0u64;
            let end = b.search(ApState::of(&ap), f64::INFINITY, 1e-9, &mut tour, |_| {
                asked += 1;
                asked > 2
            });
            assert_eq!(end, End::Stopped, "seed {seed}");
            assert!(b.augments <= 2, "seed {seed}: {} paths after the stop", b.augments);
        }
        assert!(deep > 0, "every tree was too small to stop inside");
    }

    /// Searched to the end, the tree finds the exact optimum (the DP's) on small instances.
    #[test]
    fn exhausted_search_is_exact() {
        for seed in 0..30u64 {
            let n = 5 + (seed as usize % 6);
            let inst = random_matrix_instance(n, 500 + seed, 10 + (seed as i32 % 3) * 45, &[]);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let opt = run(
                "exact",
                &inst,
                Objective::Matrix,
                &BTreeMap::new(),
                1,
                Budget::default(),
                &mut NoObserver,
            )
            .unwrap()
            .report
            .cost;
            let g = ApGraph::new(&m, &vec![0; n]);
            let ap = g.assignment().unwrap();
            let mut b = Bnb::new(&g);
            let mut best = f64::INFINITY;
            let end = b.search(
                ApState::of(&ap),
                f64::INFINITY,
                1e-9,
                |order, value| {
                    let seq: Vec<Visit> = order.iter().map(|&x| Visit::new(x as usize, 0)).collect();
                    let s = Solution::new(&c, &seq);
                    if let Some(v) = value {
                        assert!((v - s.cost).abs() < 1e-6, "seed {seed}: leaf {v} vs {}", s.cost);
                    }
                    best = best.min(s.cost);
                    best
                },
                |_| false,
            );
            assert_eq!(end, End::Exhausted);
            assert!((best - opt).abs() < 1e-6, "seed {seed}: bnb {best}, exact {opt}");
        }
    }
}

//! Or-3opt on candidate lists, and an iterated local search around it.
//!
//! The move swaps the adjacent blocks `[h+1..=i]` and `[i+1..=j]` without reversing them
//! (the only pure 3-opt reconnection that keeps every arc's direction). It adds the arcs
//! `h → i+1`, `j → h+1` and `i → j+1`. The search looks at a cell `a` at position `p` and
//! tries a new arc `a → b` for each candidate successor `b` of `a`, which is one of the three
//! new arcs; the cell `p + 1` then loses its predecessor, and the third cut point is taken
//! from the candidate predecessors of that cell (and the path's ends):
//!
//! - `b` after `a`, `a → b` as `h → i+1`: `h = p`, `i = pos(b) − 1`, `j` a candidate
//!   predecessor of `s[p+1]` at or after `pos(b)`, or the last position;
//! - `b` before `a`, as `j → h+1`: `j = p`, `h = pos(b) − 1`, `i` a candidate predecessor of
//!   `s[p+1]` in `[pos(b), p − 1]`;
//! - `b` after `a`, as `i → j+1`: `i = p`, `j = pos(b) − 1`, `h` a candidate predecessor of
//!   `s[p+1]` before `p`, or the path's start.
//!
//! Every candidate is one O(1) delta ([`sop3_delta`]); the best improving one of a cell is
//! applied when the precedence allows it (no precedence pair from the first block to the
//! second, checked on the smaller block's arcs). Cells at the six changed positions go back
//! on the queue (don't-look bits).
//!
//! The kicks of [`Or3::kick`] swap two nearby blocks of random lengths: the double bridge of
//! an open path, which keeps every block's orientation.

use crate::engine::moves::sop3_delta;
use crate::engine::vnd::improves;
use crate::engine::{Costs, Neighbours, Solution};
use crate::context::Context;
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::collections::VecDeque;

/// The Or-3opt search state: costs, candidate lists and the don't-look queue.
pub struct Or3<'a> {
    c: Costs<'a>,
    nb: &'a Neighbours,
    queue: VecDeque<u32>,
    on: Vec<bool>,
    /// The precedence has no pair at all (then every block swap is allowed).
    free: bool,
}

/// A block swap: blocks `[h+1..=i]` and `[i+1..=j]` trade places, changing the cost by
/// `delta`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Swap {
    /// Position before the first block (−1: the path's start).
    pub h: isize,
    /// Last position of the first block.
    pub i: usize,
    /// Last position of the second block.
    pub j: usize,
    /// Cost change.
    pub delta: f64,
}

impl<'a> Or3<'a> {
    /// A search on costs `c` with candidate lists `nb`; the queue starts empty.
    pub fn new(c: Costs<'a>, nb: &'a Neighbours) -> Self {
        let n = c.m.n();
        Or3 {
            c,
            nb,
            queue: VecDeque::with_capacity(n),
            on: vec![false; n],
            free: c.m.dag.succs.iter().all(|s| s.is_empty()),
        }
    }

    /// Puts a cell on the queue (once).
    pub fn push(&mut self, cell: u32) {
        if !self.on[cell as usize] {
            self.on[cell as usize] = true;
            self.queue.push_back(cell);
        }
    }

    /// Puts every cell on the queue, in path order.
    pub fn push_all(&mut self, s: &Solution) {
        for p in 0..s.n() {
            self.push(s.order[p]);
        }
    }

    /// Empties the queue.
    pub fn clear(&mut self) {
        while let Some(c) = self.queue.pop_front() {
            self.on[c as usize] = false;
        }
    }

    /// Whether the precedence allows swapping `[h+1..=i]` and `[i+1..=j]`: no arc of the
    /// precedence (its transitive reduction suffices, the order being feasible) leads from
    /// the first block into the second.
    pub fn allowed(&self, s: &Solution, h: isize, i: usize, j: usize) -> bool {
        if self.free {
            return true;
        }
        let dag = &self.c.m.dag;
        let a = (h + 1) as usize;
        if i + 1 - a <= j - i {
            s.order[a..=i].iter().all(|&x| {
                dag.succs[x as usize]
                    .iter()
                    .all(|&y| (s.pos[y as usize] as usize) > j)
            })
        } else {
            s.order[i + 1..=j].iter().all(|&y| {
                dag.preds[y as usize]
                    .iter()
                    .all(|&x| (s.pos[x as usize] as isize) <= h)
            })
        }
    }

    /// The best improving allowed swap that adds an arc out of the cell at position `p`,
    /// and the number of deltas evaluated.
    pub fn best_from(&self, s: &Solution, p: usize) -> (Option<Swap>, u64) {
        let n = s.n();
        let c = &self.c;
        let mut best: Option<Swap> = None;
        let mut evals = 0u64;
        if p + 1 >= n {
            return (None, 0);
        }
        let a = s.order[p] as usize;
        let next = s.order[p + 1] as usize;
        let preds = &self.nb.inn[next];
        let mut consider = |h: isize, i: usize, j: usize, best: &mut Option<Swap>| {
            if h < -1 || h >= i as isize || i >= j || j >= n {
                return;
            }
            evals += 1;
            let d = sop3_delta(c, s, h, i as isize, j as isize);
            if improves(d, s.cost) && best.is_none_or(|b| d < b.delta) && self.allowed(s, h, i, j) {
                *best = Some(Swap { h, i, j, delta: d });
            }
        };
        for &b in &self.nb.out[a] {
            let q = s.pos[b as usize] as usize;
            if q > p + 1 {
                // a → b as h → i+1: j at or after q
                for &x in preds.iter() {
                    let r = s.pos[x as usize] as usize;
                    if r >= q {
                        consider(p as isize, q - 1, r, &mut best);
                    }
                }
                consider(p as isize, q - 1, n - 1, &mut best);
                // a → b as i → j+1: h before p
                for &x in preds.iter() {
                    let r = s.pos[x as usize] as usize;
                    if r < p {
                        consider(r as isize, p, q - 1, &mut best);
                    }
                }
                consider(-1, p, q - 1, &mut best);
            } else if q < p {
                // a → b as j → h+1: i in [q, p-1]
                for &x in preds.iter() {
                    let r = s.pos[x as usize] as usize;
                    if r >= q && r < p {
                        consider(q as isize - 1, r, p, &mut best);
                    }
                }
            }
        }
        // the path's end as the new successor of a: a → end as i → j+1 with j = n − 1
        for &x in preds.iter() {
            let r = s.pos[x as usize] as usize;
            if r < p {
                consider(r as isize, p, n - 1, &mut best);
            }
        }
        consider(-1, p, n - 1, &mut best);
        (best, evals)
    }

    /// Applies a swap and puts the cells at its six block ends back on the queue.
    pub fn apply(&mut self, s: &mut Solution, m: Swap) {
        for cell in s.swap_blocks_touched(m.h, m.i, m.j, m.delta) {
            self.push(cell);
        }
    }

    /// Or-3opt from the queued cells to a local optimum (or until the budget runs out);
    /// true on any improvement.
    pub fn descend(&mut self, s: &mut Solution, ctx: &mut Context) -> bool {
        let mut improved = false;
        while let Some(x) = self.queue.pop_front() {
            self.on[x as usize] = false;
            if ctx.exhausted() {
                self.clear();
                break;
            }
            let p = s.pos[x as usize] as usize;
            let (mv, evals) = self.best_from(s, p);
            ctx.count(evals.max(1));
            if let Some(mv) = mv {
                self.apply(s, mv);
                self.push(x);
                improved = true;
            }
        }
        improved
    }

    /// A random kick near a random place (up to `tries` draws until the precedence allows
    /// one); applies it and queues its ends. With `far` the kick swaps two blocks of
    /// 1..=`max_len` cells with a third such block between them (`A B C D E → A D C B E`,
    /// four arcs change, which no single Or-3opt move undoes); without, two adjacent blocks
    /// (`A B C D → A C B D`, the double bridge of a path). Returns false when no draw was
    /// allowed.
    pub fn kick(
        &mut self,
        s: &mut Solution,
        rng: &mut ChaCha8Rng,
        max_len: usize,
        tries: usize,
        far: bool,
    ) -> bool {
        let n = s.n();
        if n < 3 || (far && n < 4) {
            return false;
        }
        let len = |rng: &mut ChaCha8Rng| rng.random_range(1..=max_len.max(1));
        for _ in 0..tries {
            let h = rng.random_range(0..(n as i64 - 1)) as isize - 1;
            let i = (h + len(rng) as isize) as usize;
            if i + 1 >= n {
                continue;
            }
            let j = (i + len(rng)).min(n - 1);
            if !far {
                if !self.allowed(s, h, i, j) {
                    continue;
                }
                let d = sop3_delta(&self.c, s, h, i as isize, j as isize);
                self.apply(s, Swap { h, i, j, delta: d });
                return true;
            }
            if j + 1 >= n {
                continue;
            }
            let k = (j + len(rng)).min(n - 1);
            // B = [h+1..=i], C = [i+1..=j], D = [j+1..=k]: first B ↔ C D, then C ↔ D
            if !self.allowed(s, h, i, k) || !self.allowed(s, i as isize, j, k) {
                continue;
            }
            let d1 = sop3_delta(&self.c, s, h, i as isize, k as isize);
            self.apply(
                s,
                Swap {
                    h,
                    i,
                    j: k,
                    delta: d1,
                },
            );
            let i2 = (h + (j - i) as isize) as usize;
            let j2 = (h + (k - i) as isize) as usize;
            let d2 = sop3_delta(&self.c, s, h, i2 as isize, j2 as isize);
            self.apply(
                s,
                Swap {
                    h,
                    i: i2,
                    j: j2,
                    delta: d2,
                },
            );
            return true;
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::super::random_matrix_instance;
    use super::*;
    use crate::cost::CostModel;
    use crate::model::{Objective, Visit};
    use crate::solvers::{Budget, NoObserver};
    use rand::SeedableRng;

    /// Every swap the search finds and every kick changes the cost by its delta, exactly as a
    /// full re-evaluation says, and keeps the precedence.
    #[test]
    fn deltas_match_full_evaluation() {
        for seed in 0..20u64 {
            let n = 6 + (seed as usize % 15);
            let prec: Vec<(usize, usize)> = if seed % 2 == 0 {
                Vec::new()
            } else {
                vec![(0, 3), (2, 5), (1, 4)]
            };
            let inst = random_matrix_instance(n, seed, 20, &prec);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let nb = Neighbours::new(&m, 4);
            let seq: Vec<Visit> = crate::precedence::topological_order(&m.dag)
                .unwrap()
                .into_iter()
                .map(|x| Visit::new(x as usize, 0))
                .collect();
            let mut s = Solution::new(&c, &seq);
            let mut or3 = Or3::new(c, &nb);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, seed, Budget::default(), &mut obs);
            for round in 0..30 {
                if round % 3 == 0 {
                    or3.kick(&mut s, &mut rng, 3, 10, round % 2 == 0);
                } else {
                    or3.push_all(&s);
                    or3.descend(&mut s, &mut ctx);
                }
                let full = s.evaluate(&c);
                assert!(
                    (full - s.cost).abs() < 1e-6,
                    "seed {seed}: {full} vs {}",
                    s.cost
                );
                assert!(s.feasible(&m), "seed {seed}: precedence broken");
            }
        }
    }

    /// The candidate search finds exactly the improving swaps a full scan finds when the
    /// candidate lists hold every cell.
    #[test]
    fn full_lists_reach_a_true_or3opt_optimum() {
        for seed in 0..10u64 {
            let n = 9;
            let inst = random_matrix_instance(n, 100 + seed, 20, &[]);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let nb = Neighbours::new(&m, n - 1);
            let seq: Vec<Visit> = (0..n).map(|x| Visit::new(x, 0)).collect();
            let mut s = Solution::new(&c, &seq);
            let mut or3 = Or3::new(c, &nb);
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, seed, Budget::default(), &mut obs);
            or3.push_all(&s);
            or3.descend(&mut s, &mut ctx);
            for h in -1..n as isize {
                for i in (h + 1).max(0) as usize..n {
                    for j in i + 1..n {
                        let d = sop3_delta(&c, &s, h, i as isize, j as isize);
                        assert!(!improves(d, s.cost), "seed {seed}: ({h},{i},{j}) gains {d}");
                    }
                }
            }
        }
    }
}

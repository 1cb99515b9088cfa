//! Partition crossover for precedence-constrained paths.
//!
//! Two feasible paths A and B over the same cells are cut at every position k where their
//! first k + 1 cells form the same set. Between two consecutive cuts both parents visit the
//! same cells, so any choice of parent per segment is again a permutation, and it respects
//! every precedence pair: a pair split over two segments is ordered by the segment order,
//! which both parents share, and a pair inside one segment is ordered as in the parent that
//! segment comes from. The child is the cheapest of these combinations, found by a dynamic
//! programme over the segments with two states (which parent the previous segment came from:
//! that decides the last cell and mode, and so the link into the next segment). O(n) time.
//!
//! This is the sequencing analogue of the partition crossovers of the TSP (Whitley et al.'s
//! GPX): a child is never worse than the better parent, and on instances with many
//! near-optimal paths that differ in independent places (TSPLIB's dense-precedence rbg
//! instances) it combines the best parts of each.

use super::{Costs, Solution};

/// Scratch space of [`Crossover::cross`].
#[derive(Debug, Default, Clone)]
pub struct Crossover {
    cuts: Vec<usize>,
    choice: Vec<[u8; 2]>,
    order: Vec<u32>,
}

impl Crossover {
    /// The number of segments of the last crossover (1 when the parents share no cut but
    /// the end).
    #[cfg(any(test, feature = "internals"))]
    pub fn segments(&self) -> usize {
        self.cuts.len()
    }

    /// Cuts of `a` and `b`: positions k where `a[..=k]` and `b[..=k]` hold the same cells.
    fn cut(&mut self, a: &Solution, b: &Solution) {
        self.cuts.clear();
        let mut reach = 0usize;
        for (k, &x) in b.order.iter().enumerate() {
            reach = reach.max(a.pos[x as usize] as usize);
            if reach == k {
                self.cuts.push(k);
            }
        }
    }

    /// The cheapest combination of the segments of `a` and `b` under `c`, or `None` when it
    /// is not strictly cheaper than both parents (the child would repeat one of them).
    pub fn cross(&mut self, c: &Costs, a: &Solution, b: &Solution) -> Option<Solution> {
        let n = a.n();
        debug_assert_eq!(n, b.n());
        if n == 0 {
            return None;
        }
        self.cut(a, b);
        let parents = [a, b];
        // best[p]: cheapest cost of the prefix up to the current cut when its last segment
        // comes from parent p
        let mut best = [0.0f64; 2];
        self.choice.clear();
        let mut from = 0usize;
        let mut differ = false;
        for (si, &k) in self.cuts.iter().enumerate() {
            let same = a.order[from..=k] == b.order[from..=k]
                && (from..=k).all(|p| {
                    let x = a.order[p] as usize;
                    a.mode[x] == b.mode[x]
                });
            differ |= !same;
            let mut next = [0.0f64; 2];
            let mut pick = [0u8; 2];
            for (q, s) in parents.iter().enumerate() {
                let inner = s.links(c, from as isize, k as isize);
                let first = s.at(from as isize);
                let mut v = [f64::INFINITY; 2];
                for (p, t) in parents.iter().enumerate() {
                    let prev = if si == 0 { 0.0 } else { best[p] };
                    let last = t.at(from as isize - 1);
                    v[p] = prev + c.link(last, first) + inner;
                }
                if v[1] < v[0] {
                    next[q] = v[1];
                    pick[q] = 1;
                } else {
                    next[q] = v[0];
                    pick[q] = 0;
                }
            }
            best = next;
            self.choice.push(pick);
            from = k + 1;
        }
        if !differ {
            return None;
        }
        // close the path: the link to the end from each parent's last cell
        let end = [
            best[0] + a.link(c, n as isize - 1, n as isize),
            best[1] + b.link(c, n as isize - 1, n as isize),
        ];
        let (mut q, cost) = if end[1] < end[0] {
            (1usize, end[1])
        } else {
            (0usize, end[0])
        };
        let tol = 1e-9 * a.cost.abs().max(b.cost.abs()).max(1.0);
        if cost >= a.cost.min(b.cost) - tol {
            return None;
        }
        // walk the choices back from the last segment
        let mut src = vec![0u8; self.cuts.len()];
        for si in (0..self.cuts.len()).rev() {
            src[si] = q as u8;
            q = self.choice[si][q] as usize;
        }
        let mut child = a.clone();
        self.order.clear();
        let mut from = 0usize;
        for (si, &k) in self.cuts.iter().enumerate() {
            let s = parents[src[si] as usize];
            self.order.extend_from_slice(&s.order[from..=k]);
            for p in from..=k {
                let x = s.order[p] as usize;
                child.mode[x] = s.mode[x];
            }
            from = k + 1;
        }
        child.order.copy_from_slice(&self.order);
        for (p, &x) in child.order.iter().enumerate() {
            child.pos[x as usize] = p as u32;
        }
        child.cost = child.evaluate(c);
        Some(child)
    }
}

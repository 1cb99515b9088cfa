//! Candidate lists from the assignment problem's reduced costs.
//!
//! On a random asymmetric matrix with integer costs a row holds several zero-cost arcs, and a
//! ranking by raw cost cannot tell them apart. The assignment's dual potentials can: the
//! reduced cost `c(i, j) − u(i) − v(j)` is 0 on the assignment's arcs and grows with how much
//! an arc would cost a cycle cover that uses it. The lists rank by reduced cost, then by raw
//! cost, then by index (deterministic), and leave out arcs the [`ApGraph`] leaves out.

use super::patch::ApGraph;
use crate::bound::assignment::Assignment;
use crate::engine::Neighbours;

/// How candidates are ranked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rank {
    /// By the assignment's reduced cost, then raw cost.
    Reduced,
    /// By raw cost only.
    Raw,
}

/// The `k` best successors and predecessors of every cell of `g` (the dummy node excluded),
/// ranked by `rank` with the potentials of `ap`.
pub fn candidates(g: &ApGraph, ap: &Assignment, k: usize, rank: Rank) -> Neighbours {
    let n = g.n;
    let key = |i: usize, j: usize| -> (f64, f64) {
        let c = g.c(i, j);
        match rank {
            Rank::Reduced => (c - ap.u[i] - ap.v[j], c),
            Rank::Raw => (c, 0.0),
        }
    };
    let pick = |list: &mut Vec<(f64, f64, u32)>| -> Vec<u32> {
        let kk = k.min(list.len());
        if kk == 0 {
            return Vec::new();
        }
        let cmp = |a: &(f64, f64, u32), b: &(f64, f64, u32)| {
            a.0.total_cmp(&b.0)
                .then(a.1.total_cmp(&b.1))
                .then(a.2.cmp(&b.2))
        };
        list.select_nth_unstable_by(kk - 1, cmp);
        list.truncate(kk);
        list.sort_by(cmp);
        list.iter().map(|e| e.2).collect()
    };
    let mut out = Vec::with_capacity(n);
    let mut inn = Vec::with_capacity(n);
    let mut buf = Vec::with_capacity(n);
    for i in 0..n {
        buf.clear();
        buf.extend((0..n).filter(|&j| g.c(i, j).is_finite()).map(|j| {
            let (a, b) = key(i, j);
            (a, b, j as u32)
        }));
        out.push(pick(&mut buf));
        buf.clear();
        buf.extend((0..n).filter(|&j| g.c(j, i).is_finite()).map(|j| {
            let (a, b) = key(j, i);
            (a, b, j as u32)
        }));
        inn.push(pick(&mut buf));
    }
    Neighbours { out, inn }
}

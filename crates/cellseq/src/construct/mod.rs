//! Construction heuristics: library functions that build one feasible sequence from scratch,
//! counting their arc evaluations through a callback. The solvers call them (`greedy`,
//! `greedy-edge` and `insertion` are thin registry entries over them; `local-search`, `ils`
//! and the others start from them).

pub mod edge;
pub mod greedy;
pub mod insertion;

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::model::{Sequence, Visit};

/// Completes `seq` after its construction was cut off by the clock: the cells it does not
/// hold yet follow in a precedence-feasible order (Kahn's, ready cells by index), each in its
/// cheapest mode from the cell before. O(cells + modes + precedence edges).
pub fn complete(m: &CostModel, seq: &mut Sequence) {
    let n = m.n();
    let mut done = vec![false; n];
    for v in seq.iter() {
        done[v.cell] = true;
    }
    let mut missing: Vec<u32> = (0..n)
        .map(|c| {
            m.dag.preds[c]
                .iter()
                .filter(|&&p| !done[p as usize])
                .count() as u32
        })
        .collect();
    let mut ready: std::collections::BinaryHeap<std::cmp::Reverse<usize>> = (0..n)
        .filter(|&c| !done[c] && missing[c] == 0)
        .map(std::cmp::Reverse)
        .collect();
    while let Some(std::cmp::Reverse(c)) = ready.pop() {
        seq.push(Visit::new(c, cheapest_after(m, seq, c)));
        done[c] = true;
        for &s in &m.dag.succs[c] {
            let s = s as usize;
            missing[s] -= 1;
            if missing[s] == 0 && !done[s] {
                ready.push(std::cmp::Reverse(s));
            }
        }
    }
}

/// The mode of cell `c` that is cheapest to reach from the end of `seq` (from the start when
/// `seq` is empty).
pub(crate) fn cheapest_after(m: &CostModel, seq: &Sequence, c: usize) -> usize {
    let cost = |md: usize| match seq.last() {
        None => m.start(c, md),
        Some(p) => m.arc(p.cell, p.mode, c, md),
    };
    (0..m.modes(c))
        .min_by(|&a, &b| cost(a).total_cmp(&cost(b)))
        .unwrap_or(0)
}

/// The quickest feasible sequence: [`complete`] from nothing. What a solver returns when its
/// deadline has passed before any construction.
pub fn fastest(m: &CostModel) -> Sequence {
    let mut seq = Vec::with_capacity(m.n());
    complete(m, &mut seq);
    seq
}

/// Steps of a construction between two readings of the clock.
pub(crate) const CLOCK_EVERY: u32 = 64;

/// A ticker over `deadline` for the constructions' main loops.
pub(crate) fn ticker(deadline: Deadline) -> crate::clock::Ticker {
    crate::clock::Ticker::new(deadline, CLOCK_EVERY)
}

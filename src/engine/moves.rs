//! Moves with O(1) delta evaluation and O(1) precedence tests per candidate.
//!
//! Positions are `isize` so that −1 (home) and n (path end) can be named; [`Solution::link`]
//! turns them into start and finish costs.

use super::solution::flip_mode;
use super::{Costs, Slot, Solution};
use crate::cost::CostModel;

/// Delta of SOP-3-exchange: blocks L = `[h+1..=i]` and R = `[i+1..=j]` swap places
/// (no reversal), for −1 ≤ h < i < j < n.
#[inline]
pub fn sop3_delta(c: &Costs, s: &Solution, h: isize, i: isize, j: isize) -> f64 {
    s.link(c, h, i + 1) + s.link(c, j, h + 1) + s.link(c, i, j + 1)
        - s.link(c, h, h + 1)
        - s.link(c, i, i + 1)
        - s.link(c, j, j + 1)
}

/// The insertion window of segment `[i..i+len)`: it may go after any position p with
/// `lo <= p < hi` (lo = latest predecessor position, hi = earliest successor position of the
/// segment's cells, both outside the segment in a feasible solution).
pub fn window(m: &CostModel, s: &Solution, i: usize, len: usize) -> (isize, isize) {
    let mut lo = -1isize;
    let mut hi = s.n() as isize;
    for p in i..i + len {
        let c = s.order[p] as usize;
        for &q in &m.dag.preds[c] {
            let pq = s.pos[q as usize] as isize;
            if pq < i as isize {
                lo = lo.max(pq);
            }
        }
        for &q in &m.dag.succs[c] {
            let pq = s.pos[q as usize] as isize;
            if pq >= (i + len) as isize {
                hi = hi.min(pq);
            }
        }
    }
    (lo, hi)
}

/// True when the segment `[i..i+len)` holds no precedence pair and every cell has a
/// reversal mode, so it may be reversed.
pub fn reversible_segment(m: &CostModel, s: &Solution, i: usize, len: usize) -> bool {
    (i..i + len).all(|p| {
        let c = s.order[p] as usize;
        flip_mode(m, c, s.mode[c] as usize).is_some()
            && m.dag.succs[c].iter().all(|&q| {
                let pq = s.pos[q as usize] as usize;
                pq < i || pq >= i + len
            })
    })
}

/// Or-opt: delta of moving segment `[i..i+len)` to just after position `p` (p < i−1 or
/// p ≥ i+len), optionally reversed with mode flip. Feasible iff `lo <= p < hi` from
/// [`window`] (and [`reversible_segment`] when reversed).
pub fn segment_delta(
    c: &Costs,
    s: &Solution,
    i: usize,
    len: usize,
    p: isize,
    reversed: bool,
) -> f64 {
    let (ii, e) = (i as isize, (i + len) as isize - 1);
    if !reversed {
        return if p > e {
            sop3_delta(c, s, ii - 1, e, p)
        } else {
            sop3_delta(c, s, p, ii - 1, e)
        };
    }
    let m = c.m;
    let flipped = |q: isize| -> Slot {
        s.at(q)
            .map(|(cell, md)| (cell, flip_mode(m, cell, md).unwrap_or(md)))
    };
    let (first, last) = (s.at(ii), s.at(e));
    let (ffirst, flast) = (flipped(ii), flipped(e));
    let mut d = s.link(c, ii - 1, e + 1) - s.link(c, ii - 1, ii) - s.link(c, e, e + 1);
    // internal arcs
    for q in ii..e {
        d += c.link(flipped(q + 1), flipped(q)) - s.link(c, q, q + 1);
    }
    let _ = (first, last);
    d += c.link(s.at(p), flast) + c.link(ffirst, s.at(p + 1)) - s.link(c, p, p + 1);
    d
}

/// Applies [`segment_delta`]'s move.
pub fn apply_segment(
    m: &CostModel,
    s: &mut Solution,
    i: usize,
    len: usize,
    p: isize,
    reversed: bool,
    delta: f64,
) {
    let e = i + len - 1;
    let (start, end) = if p > e as isize {
        s.swap_blocks(i as isize - 1, e, p as usize, delta);
        (p as usize + 1 - len, p as usize)
    } else {
        s.swap_blocks(p, i - 1, e, delta);
        ((p + 1) as usize, (p + 1) as usize + len - 1)
    };
    if reversed {
        s.reverse(m, start, end, 0.0);
    }
}

/// Prefix sums for O(1) 2-opt deltas on asymmetric costs, and the reach of every position
/// (the last position a reversal starting there may end at without inverting a precedence
/// pair or reversing a cell that has no reversal mode).
#[derive(Debug, Clone, Default)]
pub struct Reversal {
    fwd: Vec<f64>,
    bwd: Vec<f64>,
    /// `reach[i]`: largest j such that `[i..=j]` may be reversed (i − 1 if none).
    pub reach: Vec<isize>,
}

impl Reversal {
    /// Recomputes everything for the current solution, O(n + edges).
    pub fn refresh(&mut self, c: &Costs, s: &Solution) {
        let m = c.m;
        let n = s.n();
        let flip: Vec<Slot> = (0..n)
            .map(|p| {
                let cell = s.order[p] as usize;
                flip_mode(m, cell, s.mode[cell] as usize).map(|f| (cell, f))
            })
            .collect();
        self.fwd.clear();
        self.bwd.clear();
        self.fwd.push(0.0);
        self.bwd.push(0.0);
        for p in 0..n.saturating_sub(1) {
            let f = self.fwd[p] + s.link(c, p as isize, p as isize + 1);
            let b = self.bwd[p]
                + match (flip[p], flip[p + 1]) {
                    (Some(_), Some(_)) => c.link(flip[p + 1], flip[p]),
                    _ => 0.0,
                };
            self.fwd.push(f);
            self.bwd.push(b);
        }
        let lp: Vec<isize> = (0..n)
            .map(|p| s.last_pred(m, s.order[p] as usize))
            .collect();
        self.reach.clear();
        let mut prev: isize = -1;
        for i in 0..n {
            if flip[i].is_none() {
                self.reach.push(i as isize - 1);
                prev = i as isize - 1;
                continue;
            }
            let mut j = prev.max(i as isize) as usize;
            while j + 1 < n && flip[j + 1].is_some() && lp[j + 1] < i as isize {
                j += 1;
            }
            self.reach.push(j as isize);
            prev = j as isize;
        }
    }
    /// Delta of reversing `[i..=j]` with mode flip (j ≤ reach\[i\]).
    #[inline]
    pub fn delta(&self, c: &Costs, s: &Solution, i: usize, j: usize) -> f64 {
        let m = c.m;
        let fl = |p: usize| -> Slot {
            let cell = s.order[p] as usize;
            let md = s.mode[cell] as usize;
            Some((cell, flip_mode(m, cell, md).unwrap_or(md)))
        };
        let (ii, jj) = (i as isize, j as isize);
        c.link(s.at(ii - 1), fl(j)) + c.link(fl(i), s.at(jj + 1))
            - s.link(c, ii - 1, ii)
            - s.link(c, jj, jj + 1)
            + (self.bwd[j] - self.bwd[i])
            - (self.fwd[j] - self.fwd[i])
    }
}

/// Delta of giving the cell at position `p` the mode `mode`.
#[inline]
pub fn mode_delta(c: &Costs, s: &Solution, p: usize, mode: usize) -> f64 {
    let pp = p as isize;
    let cell = s.order[p] as usize;
    let new = Some((cell, mode));
    c.link(s.at(pp - 1), new) + c.link(new, s.at(pp + 1))
        - s.link(c, pp - 1, pp)
        - s.link(c, pp, pp + 1)
}

/// Delta of reversing `[i..=j]` with mode flip, computed over the segment, O(j − i).
/// Valid when [`reversible_segment`] holds for the segment.
pub fn reverse_delta_direct(c: &Costs, s: &Solution, i: usize, j: usize) -> f64 {
    let m = c.m;
    let fl = |p: isize| -> Slot {
        s.at(p)
            .map(|(cell, md)| (cell, flip_mode(m, cell, md).unwrap_or(md)))
    };
    let (ii, jj) = (i as isize, j as isize);
    let mut d = c.link(s.at(ii - 1), fl(jj)) + c.link(fl(ii), s.at(jj + 1))
        - s.link(c, ii - 1, ii)
        - s.link(c, jj, jj + 1);
    for q in ii..jj {
        d += c.link(fl(q + 1), fl(q)) - s.link(c, q, q + 1);
    }
    d
}

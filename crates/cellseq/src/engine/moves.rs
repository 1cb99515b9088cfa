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
    sop3_sum(
        s.link(c, h, i + 1),
        s.link(c, j, h + 1),
        s.link(c, i, j + 1),
        s.link(c, h, h + 1),
        s.link(c, i, i + 1),
        s.link(c, j, j + 1),
    )
}

/// [`sop3_delta`] from its six links — new (h→i+1, j→h+1, i→j+1) and old (h→h+1, i→i+1,
/// j→j+1) — summed in one fixed order, so that searches which keep the links that do not
/// change along a scan get bit-identical deltas.
#[inline(always)]
pub(crate) fn sop3_sum(a: f64, b: f64, cc: f64, d: f64, e: f64, f: f64) -> f64 {
    a + b + cc - d - e - f
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
    SegmentMove::new(c, s, i, len, reversed).delta(c, s, p, reversed)
}

/// The part of an Or-opt move that does not depend on where the segment goes, computed once
/// per segment so that each insertion point costs three (kept) or two more (reversed) links.
#[derive(Debug, Clone, Copy)]
pub struct SegmentMove {
    /// First and last positions of the segment.
    first: isize,
    last: isize,
    /// Cost change of closing the gap the segment leaves (negative of the removal gain).
    close: f64,
    /// Cost change of the segment's internal links when it is reversed.
    inner_rev: f64,
    /// The segment's end cells in their flipped modes.
    ffirst: Slot,
    flast: Slot,
}

impl SegmentMove {
    /// Prepares moves of `[i..i+len)`; with `reversible` the reversed variant too.
    #[inline]
    pub fn new(c: &Costs, s: &Solution, i: usize, len: usize, reversible: bool) -> Self {
        let (ii, e) = (i as isize, (i + len) as isize - 1);
        let close = s.link(c, ii - 1, e + 1) - s.link(c, ii - 1, ii) - s.link(c, e, e + 1);
        let mut mv = SegmentMove {
            first: ii,
            last: e,
            close,
            inner_rev: 0.0,
            ffirst: None,
            flast: None,
        };
        if reversible {
            let flipped = |q: isize| flipped_at(c, s, q);
            for q in ii..e {
                mv.inner_rev += c.link(flipped(q + 1), flipped(q)) - s.link(c, q, q + 1);
            }
            mv.ffirst = flipped(ii);
            mv.flast = flipped(e);
        }
        mv
    }
    /// Delta of inserting the segment between positions `p` and `p + 1` (outside the
    /// segment and not just before it), `reversed` only if prepared with `reversible`.
    #[inline]
    pub fn delta(&self, c: &Costs, s: &Solution, p: isize, reversed: bool) -> f64 {
        let (a, b) = (s.at(p), s.at(p + 1));
        let open = c.link(a, b);
        if reversed {
            self.close + self.inner_rev + c.link(a, self.flast) + c.link(self.ffirst, b) - open
        } else {
            self.close + c.link(a, s.at(self.first)) + c.link(s.at(self.last), b) - open
        }
    }

    /// For a one-cell segment: the delta of inserting its cell between positions `p` and
    /// `p + 1` in the mode that is cheapest there, and that mode (a cell of several modes
    /// moved elsewhere is often best entered another way; kept in its mode, the move may
    /// not pay and the better mode is never tried there).
    #[inline]
    pub fn delta_best_mode(&self, c: &Costs, s: &Solution, p: isize) -> (f64, usize) {
        let (a, b) = (s.at(p), s.at(p + 1));
        let cell = s.order[self.first as usize] as usize;
        c.cheapest_between(self.close - c.link(a, b), a, cell, b)
    }
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
    let ((h, a, b), (start, end)) = or_as_swap(i, len, p);
    s.swap_blocks(h, a, b, delta);
    if reversed {
        s.reverse(m, start, end, 0.0);
    }
}

/// An Or-opt move (the segment of `len` cells at `i` goes after position `p`) as the swap of
/// two adjacent blocks `(h, i, j)` (blocks `[h+1..=i]` and `[i+1..=j]`, as in
/// [`Solution::swap_blocks`]) and the positions `(start, end)` the segment occupies afterwards
/// (what a reversed insertion then reverses).
#[inline]
pub(crate) fn or_as_swap(
    i: usize,
    len: usize,
    p: isize,
) -> ((isize, usize, usize), (usize, usize)) {
    let e = i + len - 1;
    if p > e as isize {
        (
            (i as isize - 1, e, p as usize),
            (p as usize + 1 - len, p as usize),
        )
    } else {
        (
            (p, i - 1, e),
            ((p + 1) as usize, (p + 1) as usize + len - 1),
        )
    }
}

/// Above this many cells, reversal feasibility under precedence is checked per candidate
/// ([`reversible_segment`], early exit) instead of through a `reach` array that costs O(n) to
/// refresh after every applied reversal.
pub const LAZY_REACH_CELLS: usize = 5000;

/// How [`Reversal`] knows which segments may be reversed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
enum Reach {
    /// Every cell has a reversal mode and there is no precedence: any segment may be reversed.
    #[default]
    All,
    /// `reach[i]` is kept exact (refreshed in O(n) after each applied reversal; small n).
    Array,
    /// Checked per candidate with [`reversible_segment`] (large n with precedence).
    Lazy,
}

/// O(1) 2-opt deltas on asymmetric costs, and which segments may be reversed.
///
/// A reversal of `[i..=j]` changes the cost of the links inside the segment by
/// `Σ_{p=i}^{j−1} asym[p]`, where `asym[p]` is the cost of the link `p → p+1` read backwards
/// (both cells in their flipped modes) minus its cost forwards. On symmetric instances (air
/// length on geometric cells: every `asym[p]` is 0) the sum is 0 and an applied reversal costs
/// O(j − i) to record: the segment's values are reversed and negated (the flip is an
/// involution) and only the two boundary links are recomputed. Asymmetric instances keep
/// prefix sums, rebuilt in O(n) before the next query after a reversal.
#[derive(Debug, Clone)]
pub struct Reversal {
    /// Above this many cells (with precedence or cells that cannot be reversed) feasibility
    /// is checked per candidate; default [`LAZY_REACH_CELLS`].
    pub lazy_above: usize,
    asym: Vec<f64>,
    nonzero: usize,
    prefix: Vec<f64>,
    prefix_ok: bool,
    mode: Reach,
    reach: Vec<isize>,
}

impl Default for Reversal {
    fn default() -> Self {
        Reversal {
            lazy_above: LAZY_REACH_CELLS,
            asym: Vec::new(),
            nonzero: 0,
            prefix: Vec::new(),
            prefix_ok: false,
            mode: Reach::All,
            reach: Vec::new(),
        }
    }
}

fn flipped_slot(m: &CostModel, s: &Solution, p: usize) -> Slot {
    let cell = s.order[p] as usize;
    flip_mode(m, cell, s.mode[cell] as usize).map(|f| (cell, f))
}

impl Reversal {
    fn asym_at(c: &Costs, s: &Solution, p: usize) -> f64 {
        match (flipped_slot(c.m, s, p), flipped_slot(c.m, s, p + 1)) {
            (Some(a), Some(b)) => c.link(Some(b), Some(a)) - s.link(c, p as isize, p as isize + 1),
            _ => 0.0,
        }
    }

    /// Recomputes everything for the current solution, O(n + edges).
    pub fn refresh(&mut self, c: &Costs, s: &Solution) {
        let m = c.m;
        let n = s.n();
        self.asym.clear();
        self.asym
            .extend((0..n.saturating_sub(1)).map(|p| Self::asym_at(c, s, p)));
        self.nonzero = self.asym.iter().filter(|&&v| v != 0.0).count();
        self.prefix_ok = false;
        let all_flip = (0..n).all(|p| flipped_slot(m, s, p).is_some());
        let no_prec = m.dag.is_empty();
        self.mode = if all_flip && no_prec {
            Reach::All
        } else if n <= self.lazy_above {
            Reach::Array
        } else {
            Reach::Lazy
        };
        self.reach.clear();
        if self.mode == Reach::Array {
            self.refresh_reach(m, s);
        }
    }

    fn refresh_reach(&mut self, m: &CostModel, s: &Solution) {
        let n = s.n();
        let flip: Vec<bool> = (0..n).map(|p| flipped_slot(m, s, p).is_some()).collect();
        let lp: Vec<isize> = (0..n)
            .map(|p| s.last_pred(m, s.order[p] as usize))
            .collect();
        self.reach.clear();
        let mut prev: isize = -1;
        for i in 0..n {
            if !flip[i] {
                self.reach.push(i as isize - 1);
                prev = i as isize - 1;
                continue;
            }
            let mut j = prev.max(i as isize) as usize;
            while j + 1 < n && flip[j + 1] && lp[j + 1] < i as isize {
                j += 1;
            }
            self.reach.push(j as isize);
            prev = j as isize;
        }
    }

    /// The last position a reversal starting at `i` may end at: exact for small instances,
    /// an upper bound (n − 1) for large ones with precedence, where [`Reversal::allowed`]
    /// decides per candidate.
    #[inline]
    pub fn reach(&self, i: usize) -> isize {
        match self.mode {
            Reach::Array => self.reach[i],
            _ => self.asym.len() as isize,
        }
    }

    /// True when `[i..=j]` (with j ≤ [`Reversal::reach`]`(i)`) may be reversed.
    #[inline]
    pub fn allowed(&self, m: &CostModel, s: &Solution, i: usize, j: usize) -> bool {
        match self.mode {
            Reach::Lazy => reversible_segment(m, s, i, j - i + 1),
            _ => true,
        }
    }

    /// Records that `[i..=j]` has just been reversed (by [`Solution::reverse`]).
    pub fn reversed(&mut self, c: &Costs, s: &Solution, i: usize, j: usize) {
        let n = s.n();
        if n < 2 {
            return;
        }
        // inside: the link q -> q+1 is the old link (i+j-1-q) read backwards
        let inner = &mut self.asym[i..j];
        inner.reverse();
        inner.iter_mut().for_each(|v| *v = -*v);
        for p in [i.checked_sub(1), (j + 1 < n).then_some(j)]
            .into_iter()
            .flatten()
        {
            let new = Self::asym_at(c, s, p);
            self.nonzero = self.nonzero + (new != 0.0) as usize - (self.asym[p] != 0.0) as usize;
            self.asym[p] = new;
        }
        self.prefix_ok = false;
        if self.mode == Reach::Array {
            self.refresh_reach(c.m, s);
        }
    }

    /// Delta of reversing `[i..=j]` with mode flip (the reversal must be allowed).
    #[inline]
    pub fn delta(&mut self, c: &Costs, s: &Solution, i: usize, j: usize) -> f64 {
        let m = c.m;
        let fl = |p: usize| -> Slot {
            let cell = s.order[p] as usize;
            let md = s.mode[cell] as usize;
            Some((cell, m.turned_or_same(cell, md)))
        };
        let (ii, jj) = (i as isize, j as isize);
        let inner = if self.nonzero == 0 {
            0.0
        } else {
            if !self.prefix_ok {
                self.prefix.clear();
                self.prefix.push(0.0);
                let mut acc = 0.0;
                for &v in &self.asym {
                    acc += v;
                    self.prefix.push(acc);
                }
                self.prefix_ok = true;
            }
            self.prefix[j] - self.prefix[i]
        };
        c.link(s.at(ii - 1), fl(j)) + c.link(fl(i), s.at(jj + 1))
            - s.link(c, ii - 1, ii)
            - s.link(c, jj, jj + 1)
            + inner
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
    let mut d = reverse_delta_ends(c, s, i, j);
    for q in i as isize..j as isize {
        d += c.link(flipped_at(c, s, q + 1), flipped_at(c, s, q)) - s.link(c, q, q + 1);
    }
    d
}

/// The part of [`reverse_delta_direct`] at the segment's two boundary links: the whole delta
/// when reversal leaves inner link costs unchanged (symmetric costs).
pub fn reverse_delta_ends(c: &Costs, s: &Solution, i: usize, j: usize) -> f64 {
    let (ii, jj) = (i as isize, j as isize);
    c.link(s.at(ii - 1), flipped_at(c, s, jj)) + c.link(flipped_at(c, s, ii), s.at(jj + 1))
        - s.link(c, ii - 1, ii)
        - s.link(c, jj, jj + 1)
}

/// The (cell, mode) at position `p` cut the other way (its mode unchanged if it has none).
#[inline]
pub(crate) fn flipped_at(c: &Costs, s: &Solution, p: isize) -> Slot {
    s.at(p)
        .map(|(cell, md)| (cell, c.m.turned_or_same(cell, md)))
}

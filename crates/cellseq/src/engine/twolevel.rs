//! A two-level list for the path: O(√n) reversals and block swaps, O(1) position and
//! neighbour queries (Fredman, Johnson, McGeoch & Ostheimer 1995; the representation LKH uses).
//!
//! In the array form of [`Solution`] a reversal of `[i..=j]` costs O(j − i) and an Or-opt
//! move O(distance). From a greedy start on 10^5 cells most improving 2-opt moves reverse
//! long stretches, so a pass does not finish in seconds. Here the cells sit in a fixed
//! physical array cut into *segments* (ranges of that array, about √n cells each) and the
//! path is the segments in a logical order, each read forwards or backwards (its reverse
//! bit). Reversing a stretch of the path splits at most two segments at its ends (O(√n)
//! relabelling of the smaller parts), then reverses the order of the segments in between and
//! toggles their bits (O(√n)); a block swap splits at three points and rotates the segment
//! order. Each segment keeps its logical start position, so `pos`, `next` and `prev` are O(1)
//! and `at` (cell at a position) is a binary search over the segments. Splits add segments;
//! when there are three times as many as after a rebuild, the path is written out again into
//! a fresh physical array (O(n), amortized O(√n) per operation).
//!
//! Modes follow the reversal semantics of [`Solution::reverse`]: a cell in a reversed stretch
//! is cut the other way ([`CostModel::turned`], the mode itself where there is none). The
//! stored mode is the one for the segment read forwards; a set reverse bit turns it.

use super::{Slot, Solution};
use crate::cost::CostModel;

#[derive(Debug, Clone, Copy)]
struct Seg {
    /// Physical range `lo..=hi`.
    lo: u32,
    hi: u32,
    /// Read from `hi` down to `lo`.
    rev: bool,
    /// Index in the logical segment order.
    rank: u32,
    /// Logical position of the segment's first cell.
    start: u32,
}

impl Seg {
    #[inline]
    fn len(&self) -> u32 {
        self.hi - self.lo + 1
    }
}

/// The mode of `cell` cut the other way (itself where it has no reversal mode); an involution.
#[inline]
pub fn turn(m: &CostModel, cell: usize, mode: u32) -> u32 {
    m.turned_or_same(cell, mode as usize) as u32
}

/// The path of all cells as a two-level list (see the module documentation).
#[derive(Debug, Clone)]
pub struct TwoLevel {
    phys: Vec<u32>,
    /// Physical index of each cell.
    idx: Vec<u32>,
    seg_of: Vec<u32>,
    /// Mode of each cell for its segment read forwards.
    smode: Vec<u32>,
    segs: Vec<Seg>,
    /// Segment ids in path order.
    order: Vec<u32>,
    /// Segment length after a rebuild.
    size: usize,
    /// Cost of the path (as [`Solution::cost`]), kept by the callers' deltas.
    pub cost: f64,
}

impl TwoLevel {
    /// The path of `s` (order, modes and cost).
    pub fn new(s: &Solution) -> Self {
        let n = s.n();
        let mut t = TwoLevel {
            phys: s.order.clone(),
            idx: vec![0; n],
            seg_of: vec![0; n],
            smode: s.mode.clone(),
            segs: Vec::new(),
            order: Vec::new(),
            size: ((n as f64).sqrt() as usize).max(8),
            cost: s.cost,
        };
        t.build();
        t
    }

    /// Number of cells.
    #[inline]
    pub fn n(&self) -> usize {
        self.phys.len()
    }

    /// Number of segments (for tests and statistics).
    #[cfg(any(test, feature = "internals"))]
    pub fn segments(&self) -> usize {
        self.order.len()
    }

    /// Cuts the physical array (read forwards, modes as stored) into segments of `size`.
    fn build(&mut self) {
        let n = self.n();
        self.segs.clear();
        self.order.clear();
        let mut lo = 0usize;
        while lo < n {
            let hi = (lo + self.size).min(n) - 1;
            let id = self.segs.len() as u32;
            self.segs.push(Seg {
                lo: lo as u32,
                hi: hi as u32,
                rev: false,
                rank: id,
                start: lo as u32,
            });
            self.order.push(id);
            for p in lo..=hi {
                let c = self.phys[p] as usize;
                self.idx[c] = p as u32;
                self.seg_of[c] = id;
            }
            lo = hi + 1;
        }
    }

    /// Writes the path into a fresh physical array with every segment read forwards.
    fn rebuild(&mut self, m: &CostModel) {
        let mut phys = Vec::with_capacity(self.n());
        for &sid in &self.order {
            let sg = self.segs[sid as usize];
            if sg.rev {
                for p in (sg.lo..=sg.hi).rev() {
                    let c = self.phys[p as usize];
                    self.smode[c as usize] = turn(m, c as usize, self.smode[c as usize]);
                    phys.push(c);
                }
            } else {
                phys.extend_from_slice(&self.phys[sg.lo as usize..=sg.hi as usize]);
            }
        }
        self.phys = phys;
        self.build();
    }

    fn maybe_rebuild(&mut self, m: &CostModel) {
        if self.order.len() > 3 * (self.n() / self.size + 1) {
            self.rebuild(m);
        }
    }

    /// Position of `cell` in the path.
    #[inline]
    pub fn pos(&self, cell: u32) -> usize {
        let sg = &self.segs[self.seg_of[cell as usize] as usize];
        let i = self.idx[cell as usize];
        (sg.start + if sg.rev { sg.hi - i } else { i - sg.lo }) as usize
    }

    /// Rank (in the segment order) of the segment holding position `p` (< n).
    #[inline]
    fn rank_at(&self, p: usize) -> usize {
        self.order
            .partition_point(|&sid| self.segs[sid as usize].start as usize <= p)
            - 1
    }

    /// The cell at position `p` (< n), O(log n).
    #[inline]
    pub fn cell_at(&self, p: usize) -> u32 {
        let sg = &self.segs[self.order[self.rank_at(p)] as usize];
        let k = p as u32 - sg.start;
        self.phys[(if sg.rev { sg.hi - k } else { sg.lo + k }) as usize]
    }

    #[inline]
    fn first_of(&self, rank: usize) -> u32 {
        let sg = &self.segs[self.order[rank] as usize];
        self.phys[(if sg.rev { sg.hi } else { sg.lo }) as usize]
    }

    #[inline]
    fn last_of(&self, rank: usize) -> u32 {
        let sg = &self.segs[self.order[rank] as usize];
        self.phys[(if sg.rev { sg.lo } else { sg.hi }) as usize]
    }

    /// The first cell of the path.
    pub fn first(&self) -> Option<u32> {
        (!self.order.is_empty()).then(|| self.first_of(0))
    }

    /// The last cell of the path.
    pub fn last(&self) -> Option<u32> {
        (!self.order.is_empty()).then(|| self.last_of(self.order.len() - 1))
    }

    /// The cell after `cell` (`None` at the path end), O(1).
    #[inline]
    pub fn next(&self, cell: u32) -> Option<u32> {
        let sg = &self.segs[self.seg_of[cell as usize] as usize];
        let i = self.idx[cell as usize];
        if !sg.rev && i < sg.hi {
            Some(self.phys[i as usize + 1])
        } else if sg.rev && i > sg.lo {
            Some(self.phys[i as usize - 1])
        } else {
            let r = sg.rank as usize + 1;
            (r < self.order.len()).then(|| self.first_of(r))
        }
    }

    /// The cell before `cell` (`None` at the path start), O(1).
    #[inline]
    pub fn prev(&self, cell: u32) -> Option<u32> {
        let sg = &self.segs[self.seg_of[cell as usize] as usize];
        let i = self.idx[cell as usize];
        if !sg.rev && i > sg.lo {
            Some(self.phys[i as usize - 1])
        } else if sg.rev && i < sg.hi {
            Some(self.phys[i as usize + 1])
        } else {
            let r = sg.rank as usize;
            (r > 0).then(|| self.last_of(r - 1))
        }
    }

    /// The mode of `cell`.
    #[inline]
    pub fn mode(&self, m: &CostModel, cell: u32) -> u32 {
        let st = self.smode[cell as usize];
        if self.segs[self.seg_of[cell as usize] as usize].rev {
            turn(m, cell as usize, st)
        } else {
            st
        }
    }

    /// `cell` in its mode, as a [`Slot`] (`None` for `None`).
    #[inline]
    pub fn slot(&self, m: &CostModel, cell: Option<u32>) -> Slot {
        cell.map(|c| (c as usize, self.mode(m, c) as usize))
    }

    /// The (cell, mode) at position `p`, `None` outside `0..n`.
    #[inline]
    pub fn at(&self, m: &CostModel, p: isize) -> Slot {
        if p < 0 || p as usize >= self.n() {
            None
        } else {
            self.slot(m, Some(self.cell_at(p as usize)))
        }
    }

    /// Sets the mode of `cell`, adding `delta` to the cost.
    pub fn set_mode(&mut self, m: &CostModel, cell: u32, mode: u32, delta: f64) {
        let st = if self.segs[self.seg_of[cell as usize] as usize].rev {
            turn(m, cell as usize, mode)
        } else {
            mode
        };
        self.smode[cell as usize] = st;
        self.cost += delta;
    }

    /// Makes position `p` the first of a segment (0 < p < n; else nothing to do).
    fn split(&mut self, p: usize) {
        if p == 0 || p >= self.n() {
            return;
        }
        let r = self.rank_at(p);
        let sid = self.order[r] as usize;
        let sg = self.segs[sid];
        if sg.start as usize == p {
            return;
        }
        let k = p as u32 - sg.start;
        let len = sg.len();
        // physical ranges of the logical parts [start, p) and [p, end]
        let (a, b) = if sg.rev {
            ((sg.hi - k + 1, sg.hi), (sg.lo, sg.hi - k))
        } else {
            ((sg.lo, sg.lo + k - 1), (sg.lo + k, sg.hi))
        };
        let first = Seg {
            lo: a.0,
            hi: a.1,
            rev: sg.rev,
            rank: 0,
            start: sg.start,
        };
        let second = Seg {
            lo: b.0,
            hi: b.1,
            rev: sg.rev,
            rank: 0,
            start: p as u32,
        };
        // the smaller part gets the new id (its cells are relabelled)
        let new_id = self.segs.len() as u32;
        let (keep, fresh, fresh_first) = if k <= len - k {
            (second, first, true)
        } else {
            (first, second, false)
        };
        self.segs[sid] = keep;
        self.segs.push(fresh);
        for q in fresh.lo..=fresh.hi {
            self.seg_of[self.phys[q as usize] as usize] = new_id;
        }
        self.order
            .insert(if fresh_first { r } else { r + 1 }, new_id);
        for rr in r..self.order.len() {
            self.segs[self.order[rr] as usize].rank = rr as u32;
        }
    }

    /// Renumbers ranks and start positions of the segments at ranks `r1..=r2`, the first
    /// starting at position `start`.
    fn renumber(&mut self, r1: usize, r2: usize, mut start: u32) {
        for r in r1..=r2 {
            let sg = &mut self.segs[self.order[r] as usize];
            sg.rank = r as u32;
            sg.start = start;
            start += sg.len();
        }
    }

    /// Reverses positions `i..=j` (i ≤ j < n), turning every cell there, adding `delta`.
    pub fn reverse(&mut self, m: &CostModel, i: usize, j: usize, delta: f64) {
        self.split(i);
        self.split(j + 1);
        let (r1, r2) = (self.rank_at(i), self.rank_at(j));
        self.order[r1..=r2].reverse();
        for r in r1..=r2 {
            let sg = &mut self.segs[self.order[r] as usize];
            sg.rev = !sg.rev;
        }
        self.renumber(r1, r2, i as u32);
        self.cost += delta;
        self.maybe_rebuild(m);
    }

    /// Swaps the adjacent blocks `[h+1..=i]` and `[i+1..=j]` (−1 ≤ h < i < j < n), adding
    /// `delta` (as [`Solution::swap_blocks`]).
    pub fn swap_blocks(&mut self, m: &CostModel, h: isize, i: usize, j: usize, delta: f64) {
        let a = (h + 1) as usize;
        self.split(a);
        self.split(i + 1);
        self.split(j + 1);
        let (ra, rb, rc) = (self.rank_at(a), self.rank_at(i + 1), self.rank_at(j));
        self.order[ra..=rc].rotate_left(rb - ra);
        self.renumber(ra, rc, a as u32);
        self.cost += delta;
        self.maybe_rebuild(m);
    }

    /// Writes the path into `s` (order, positions, modes, cost).
    pub fn write(&self, m: &CostModel, s: &mut Solution) {
        let mut p = 0usize;
        for r in 0..self.order.len() {
            let sg = self.segs[self.order[r] as usize];
            for k in 0..sg.len() {
                let c = self.phys[(if sg.rev { sg.hi - k } else { sg.lo + k }) as usize];
                s.order[p] = c;
                s.pos[c as usize] = p as u32;
                s.mode[c as usize] = self.mode(m, c);
                p += 1;
            }
        }
        s.cost = self.cost;
    }
}

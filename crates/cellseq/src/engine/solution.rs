//! The solution representation: order, positions, modes and cached cost.

use super::{Costs, Slot};
use crate::cost::CostModel;
use crate::model::{Sequence, Visit};

/// A complete sequence in array form with its inverse and cached cost.
#[derive(Debug, Clone, PartialEq)]
pub struct Solution {
    /// `order[p]`: the cell at position p.
    pub order: Vec<u32>,
    /// `pos[c]`: the position of cell c.
    pub pos: Vec<u32>,
    /// `mode[c]`: the mode of cell c.
    pub mode: Vec<u32>,
    /// Cost under the [`Costs`] it was last evaluated with (cutting constant excluded).
    pub cost: f64,
    /// Every cell of the instance has one mode: [`Solution::at`] does not read `mode`.
    one_mode: bool,
}

impl Solution {
    /// Builds a solution from a complete sequence and evaluates it.
    pub fn new(c: &Costs, seq: &Sequence) -> Self {
        let n = c.m.n();
        let mut s = Solution {
            order: seq.iter().map(|v| v.cell as u32).collect(),
            pos: vec![0; n],
            mode: vec![0; n],
            cost: 0.0,
            one_mode: c.m.one_mode(),
        };
        for (p, v) in seq.iter().enumerate() {
            s.pos[v.cell] = p as u32;
            s.mode[v.cell] = v.mode as u32;
        }
        s.cost = s.evaluate(c);
        s
    }
    /// The cells of `order` (a permutation of this solution's cells) in that order, each in its
    /// mode here, evaluated.
    pub fn reordered(&self, c: &Costs, order: &[u32]) -> Solution {
        let seq: Sequence = order
            .iter()
            .map(|&x| Visit::new(x as usize, self.mode[x as usize] as usize))
            .collect();
        Solution::new(c, &seq)
    }
    /// Number of cells.
    #[inline]
    pub fn n(&self) -> usize {
        self.order.len()
    }
    /// The sequence.
    pub fn sequence(&self) -> Sequence {
        self.order
            .iter()
            .map(|&c| Visit::new(c as usize, self.mode[c as usize] as usize))
            .collect()
    }
    /// The (cell, mode) at position `p`, `None` outside `0..n`.
    #[inline]
    pub fn at(&self, p: isize) -> Slot {
        if p < 0 || p as usize >= self.order.len() {
            None
        } else {
            let c = self.order[p as usize] as usize;
            if self.one_mode {
                return Some((c, 0));
            }
            Some((c, self.mode[c] as usize))
        }
    }
    /// Cost of the link from position `p` to position `q` (either may be out of range).
    #[inline]
    pub fn link(&self, c: &Costs, p: isize, q: isize) -> f64 {
        c.link(self.at(p), self.at(q))
    }
    /// Sum of the links from each position `p` in `from..to` to `p + 1` (positions −1 and
    /// n stand for the path's start and end), in that order.
    pub fn links(&self, c: &Costs, from: isize, to: isize) -> f64 {
        (from..to).map(|p| self.link(c, p, p + 1)).sum()
    }
    /// Full evaluation (without the order-independent constant), O(n).
    pub fn evaluate(&self, c: &Costs) -> f64 {
        let n = self.n() as isize;
        (0..=n).map(|p| self.link(c, p - 1, p)).sum()
    }
    /// Position of the latest predecessor of `cell` (−1 if none).
    #[inline]
    pub fn last_pred(&self, m: &CostModel, cell: usize) -> isize {
        m.dag.preds[cell]
            .iter()
            .map(|&p| self.pos[p as usize] as isize)
            .max()
            .unwrap_or(-1)
    }
    /// Position of the earliest successor of `cell` (n if none).
    #[inline]
    pub fn first_succ(&self, m: &CostModel, cell: usize) -> isize {
        m.dag.succs[cell]
            .iter()
            .map(|&p| self.pos[p as usize] as isize)
            .min()
            .unwrap_or(self.n() as isize)
    }
    /// True when every precedence pair is respected (O(n + edges)).
    pub fn feasible(&self, m: &CostModel) -> bool {
        (0..self.n()).all(|c| {
            m.dag.succs[c]
                .iter()
                .all(|&s| self.pos[c] < self.pos[s as usize])
        })
    }
    /// Replaces the cells at positions `from..from + cells.len()` by `cells` (a permutation
    /// of the cells there; the caller keeps precedence), adding `delta`.
    pub fn rewrite(&mut self, from: usize, cells: &[u32], delta: f64) {
        self.order[from..from + cells.len()].copy_from_slice(cells);
        self.renumber(from, from + cells.len());
        self.cost += delta;
    }
    /// [`Solution::rewrite`], and the cell `cells[i]` takes mode `modes[i]`.
    pub fn rewrite_with_modes(&mut self, from: usize, cells: &[u32], modes: &[u32], delta: f64) {
        debug_assert_eq!(cells.len(), modes.len());
        self.rewrite(from, cells, delta);
        for (&cell, &mode) in cells.iter().zip(modes) {
            self.mode[cell as usize] = mode;
        }
    }
    fn renumber(&mut self, from: usize, to: usize) {
        for p in from..to {
            self.pos[self.order[p] as usize] = p as u32;
        }
    }
    /// Swaps the adjacent blocks `[h+1..=i]` and `[i+1..=j]` (SOP-3-exchange), adding `delta`.
    pub fn swap_blocks(&mut self, h: isize, i: usize, j: usize, delta: f64) {
        let a = (h + 1) as usize;
        self.order[a..=j].rotate_left(i + 1 - a);
        self.renumber(a, j + 1);
        self.cost += delta;
    }
    /// [`Solution::swap_blocks`], returning the cells whose links changed (those at the six
    /// block ends before the swap), for the don't-look queues.
    pub fn swap_blocks_touched(&mut self, h: isize, i: usize, j: usize, delta: f64) -> Vec<u32> {
        let n = self.n() as isize;
        let (ii, jj) = (i as isize, j as isize);
        let cells = [h, h + 1, ii, ii + 1, jj, jj + 1]
            .iter()
            .filter(|&&p| p >= 0 && p < n)
            .map(|&p| self.order[p as usize])
            .collect();
        self.swap_blocks(h, i, j, delta);
        cells
    }
    /// Reverses positions `i..=j` and gives each cell its `flip` mode, adding `delta`.
    pub fn reverse(&mut self, m: &CostModel, i: usize, j: usize, delta: f64) {
        self.order[i..=j].reverse();
        // one pass over the segment: every access by cell is random, so touch each cell once
        for p in i..=j {
            let c = self.order[p] as usize;
            self.pos[c] = p as u32;
            self.mode[c] = match m.turn_xor(c) {
                Some(x) => self.mode[c] ^ x,
                None => {
                    let md = self.mode[c] as usize;
                    m.turned_or_same(c, md) as u32
                }
            };
        }
        self.cost += delta;
    }
    /// Sets the mode of a cell, adding `delta`.
    pub fn set_mode(&mut self, cell: usize, mode: usize, delta: f64) {
        self.mode[cell] = mode as u32;
        self.cost += delta;
    }
}

/// The mode that cuts `cell` in the opposite direction when the cell sits in a reversed
/// segment: its flipped mode when it is reversible, the same mode when the mode has no
/// direction (entry = exit, or a matrix instance whose nodes carry no geometry), else `None`.
#[inline]
pub fn flip_mode(m: &CostModel, cell: usize, mode: usize) -> Option<usize> {
    m.turned(cell, mode)
}

//! The precedence-aware move engine shared by every improvement solver.
//!
//! A [`Solution`] holds the cell order, the inverse positions, the mode of every cell and its
//! cached cost. [`Costs`] answers the cost of a link between two (cell, mode) pairs, where
//! `None` stands for the home position (path start) or the path end. The moves in [`moves`]
//! evaluate their delta in O(1) and check precedence in O(1) per candidate (insertion windows
//! from last-predecessor / first-successor positions, reach arrays for reversals, labelling
//! for SOP-3-exchange). [`neighbours`] builds K-nearest candidate lists, [`modes`] the
//! layered shortest-path mode DP, [`vnd`] the variable neighbourhood descent.

pub mod atsp;
pub mod carry;
pub mod corridor;
pub mod crossover;
pub mod large;
pub mod linked;
pub mod lk;
pub mod modes;
pub mod moves;
pub mod neighbours;
pub mod order;
pub mod ruin;
pub mod shift;
pub mod solution;
pub mod sop3x;
pub mod twolevel;
pub mod vnd;
pub mod window;

pub use neighbours::Neighbours;
pub use solution::Solution;

use crate::cost::CostModel;

/// A (cell, mode) pair, or `None` for the path's start (home) or end.
pub type Slot = Option<(usize, usize)>;

/// True when cost `a` is below cost `b` by more than rounding (relative to `b`, the
/// threshold of the search's improving moves).
#[inline]
pub fn cheaper(a: f64, b: f64) -> bool {
    a < b - 1e-9 * b.abs().max(1.0)
}

/// Link costs used by the search, with open-loop (path) or closed-loop (tour) evaluation.
#[derive(Clone, Copy)]
pub struct Costs<'a> {
    /// The cost model.
    pub m: &'a CostModel,
    /// Closed loop: the path also pays a rapid return from the last exit to the home point
    /// (geometric instances; matrix instances have nothing to return to and stay open).
    pub closed: bool,
}

impl<'a> Costs<'a> {
    /// Open-loop costs (the true objective).
    pub fn open(m: &'a CostModel) -> Self {
        Costs { m, closed: false }
    }
    /// Cost of going from `a` to `b`; `None` on the left is the start, on the right the end.
    #[inline(always)]
    pub fn link(&self, a: Slot, b: Slot) -> f64 {
        match (a, b) {
            (Some((a, ma)), Some((b, mb))) => self.m.arc(a, ma, b, mb),
            (None, Some((b, mb))) => self.m.start(b, mb),
            (Some((a, ma)), None) => self.finish(a, ma),
            (None, None) => 0.0,
        }
    }

    /// The cheapest way to put `cell` between `a` and `b`: the least `base + link(a, x) +
    /// link(x, b)` over the cell's modes x, and that mode (the first of equal ones). `base`
    /// is what the caller's delta adds to the two links (summed first, so that every caller
    /// rounds alike). The caller charges the evaluations (one per mode).
    #[inline]
    pub fn cheapest_between(&self, base: f64, a: Slot, cell: usize, b: Slot) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for md in 0..self.m.modes(cell) {
            let x = Some((cell, md));
            let d = base + self.link(a, x) + self.link(x, b);
            if d < best.0 {
                best = (d, md);
            }
        }
        best
    }

    /// Cost of ending the path with (a, ma), with the closed loop's return home.
    #[inline]
    fn finish(&self, a: usize, ma: usize) -> f64 {
        let f = self.m.finish(a, ma);
        if self.closed && self.m.is_geometric() && f == 0.0 {
            let ex = self.m.exit(self.m.node(a, ma));
            let air = ex.dist(&self.m.home_point());
            match self.m.objective() {
                crate::model::Objective::Time => air * self.m.rapid_rate(),
                _ => air,
            }
        } else {
            f
        }
    }
}

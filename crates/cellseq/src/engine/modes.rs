//! The mode pass: for a fixed cell order, the best mode of every cell by a layered
//! shortest path, O(n·k²). [`ModeLayers`] holds the path itself, shared with the window
//! moves of [`super::window`], which run it over a few cells between two fixed slots.

use super::{Costs, Slot, Solution, cheaper};

/// Scratch space of the layered shortest path over the modes of a run of cells.
#[derive(Debug, Default)]
pub struct ModeLayers {
    /// After [`ModeLayers::run`]: the cheapest cost up to the last cell in each of its modes.
    dist: Vec<f64>,
    next: Vec<f64>,
    /// `back[p][k]`: the mode of cell `p − 1` on the cheapest path to cell `p` in mode `k`.
    back: Vec<Vec<u32>>,
}

impl ModeLayers {
    /// The layered shortest path over the modes of `cells`, entered from `left`. Returns
    /// the arc evaluations between layers and whether it ran to the last cell: it gives up
    /// as soon as every partial path costs at least a finite `cap`.
    pub fn run(&mut self, c: &Costs, cells: &[u32], left: Slot, cap: f64) -> (u64, bool) {
        let m = c.m;
        let len = cells.len();
        let mut evals = 0u64;
        if self.back.len() < len {
            self.back.resize_with(len, Vec::new);
        }
        let first = cells[0] as usize;
        self.dist.clear();
        self.dist
            .extend((0..m.modes(first)).map(|k| c.link(left, Some((first, k)))));
        for p in 1..len {
            let (a, b) = (cells[p - 1] as usize, cells[p] as usize);
            let kb = m.modes(b);
            self.next.clear();
            self.next.resize(kb, f64::INFINITY);
            let bp = &mut self.back[p];
            bp.clear();
            bp.resize(kb, 0);
            let mut low = f64::INFINITY;
            for mb in 0..kb {
                for (ma, &d) in self.dist.iter().enumerate() {
                    let v = d + c.link(Some((a, ma)), Some((b, mb)));
                    if v < self.next[mb] {
                        self.next[mb] = v;
                        bp[mb] = ma as u32;
                    }
                }
                low = low.min(self.next[mb]);
            }
            evals += (self.dist.len() * kb) as u64;
            std::mem::swap(&mut self.dist, &mut self.next);
            if cap.is_finite() && low >= cap {
                return (evals, false);
            }
        }
        (evals, true)
    }

    /// Number of modes of the last cell of the last [`ModeLayers::run`].
    pub fn last_modes(&self) -> usize {
        self.dist.len()
    }

    /// The cheapest total of the last [`ModeLayers::run`] (over `last`, its last cell)
    /// with the link to `right`, and the last cell's mode on it (the first on ties).
    pub fn close(&self, c: &Costs, last: usize, right: Slot) -> (f64, usize) {
        let (mut best, mut bm) = (f64::INFINITY, 0usize);
        for (k, &d) in self.dist.iter().enumerate() {
            let v = d + c.link(Some((last, k)), right);
            if v < best {
                best = v;
                bm = k;
            }
        }
        (best, bm)
    }

    /// The mode of each of the last run's `len` cells on the path that ends in mode `k`,
    /// passed to `set` as (position in the run, mode), last cell first.
    pub fn trace(&self, len: usize, mut k: usize, mut set: impl FnMut(usize, u32)) {
        for p in (0..len).rev() {
            set(p, k as u32);
            if p > 0 {
                k = self.back[p][k] as usize;
            }
        }
    }
}

/// Re-chooses every cell's mode optimally for the current order; returns the number of
/// arc evaluations made. The solution's cost is updated (never increases).
pub fn mode_dp(c: &Costs, s: &mut Solution) -> u64 {
    let n = s.n();
    if n == 0 {
        return 0;
    }
    let mut layers = ModeLayers::default();
    let (evals, _) = layers.run(c, &s.order, None, f64::INFINITY);
    let (best, bm) = layers.close(c, s.order[n - 1] as usize, None);
    if cheaper(best, s.cost) {
        let order = &s.order;
        let mode = &mut s.mode;
        layers.trace(n, bm, |p, k| mode[order[p] as usize] = k);
        s.cost = s.evaluate(c);
    }
    evals
}

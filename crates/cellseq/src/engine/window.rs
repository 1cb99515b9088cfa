//! Window moves with modes: one cell moved inside a short window of positions while the
//! mode of every cell in the window, and of one cell either side of it, is re-chosen by a
//! small layered shortest path.
//!
//! On generalized instances (cells with several modes, PCGTSPLIB) a better sequence often
//! needs an order change and mode changes at once: on kro124p.4 two adjacent cells swap
//! places while four cells around them change mode (62867 → 62818, the best known). Each
//! half alone is worse, so neither Or-opt with the modes kept nor the mode DP with the order
//! kept finds it. A window of `w` positions tries the `w·(w−1)` single-cell moves inside it
//! (an adjacent swap once) plus the order as it is, each scored by a DP over at most
//! `w + 2` layers of modes between the fixed slots outside: O(w³·k²) per window for `k`
//! modes per cell.

use super::modes::ModeLayers;
use super::moves::window;
use super::vnd::improves;
use super::{Costs, Slot, Solution};
use crate::context::Context;

/// Scratch space for window moves.
#[derive(Debug, Default)]
pub struct ModeWindow {
    /// Window length (positions whose cells may move).
    pub w: usize,
    trial: Vec<u32>,
    best_cells: Vec<u32>,
    best_modes: Vec<u32>,
    layers: ModeLayers,
    starts: Vec<usize>,
}

impl ModeWindow {
    /// Window moves over `w` positions.
    pub fn new(w: usize) -> Self {
        ModeWindow {
            w,
            ..Default::default()
        }
    }

    /// Window moves to a local optimum: over every window when `seeds` is `None`, else over
    /// the windows that hold a seed cell (and, after an improvement, the windows around
    /// it). Returns true on any improvement.
    pub fn improve(
        &mut self,
        c: &Costs,
        s: &mut Solution,
        ctx: &mut Context,
        seeds: Option<&[u32]>,
    ) -> bool {
        let n = s.n();
        if self.w < 2 || n < 2 {
            return false;
        }
        let w = self.w.min(n);
        let mut improved = false;
        self.starts.clear();
        match seeds {
            None => self.starts.extend(0..=n - w),
            Some(cells) => {
                for &x in cells {
                    let p = s.pos[x as usize] as usize;
                    self.starts.extend(p.saturating_sub(w - 1)..=p.min(n - w));
                }
            }
        }
        // rounds until a round improves nothing: after an improvement only the windows that
        // it can affect are looked at again (the cost falls strictly, so this ends)
        while !self.starts.is_empty() {
            self.starts.sort_unstable();
            self.starts.dedup();
            let round = std::mem::take(&mut self.starts);
            for &i in &round {
                if ctx.exhausted() {
                    return improved;
                }
                if self.at(c, s, ctx, i, w) {
                    improved = true;
                    // every window whose span, or whose fixed slot either side of the
                    // span, lies in the changed positions i-1..=i+w
                    self.starts
                        .extend(i.saturating_sub(w + 2)..=(i + w + 2).min(n - w));
                }
            }
        }
        improved
    }

    /// The best move in the window at positions `i..i + w`; applies it when it improves.
    fn at(&mut self, c: &Costs, s: &mut Solution, ctx: &mut Context, i: usize, w: usize) -> bool {
        let n = s.n();
        let lo = i.saturating_sub(1);
        let hi = (i + w).min(n - 1); // inclusive
        let left = s.at(lo as isize - 1);
        let right = s.at(hi as isize + 1);
        let current = s.links(c, lo as isize - 1, hi as isize + 1);
        let mut best = current;
        let mut found = false;
        // the order as it is (modes only), then each single-cell move a -> b in the window
        for a in i..i + w {
            let (plo, phi) = window(c.m, s, a, 1);
            for b in i..i + w {
                let identity = a == b;
                if identity && a != i {
                    continue;
                }
                // a -> a-1 is the same swap as (a-1) -> a
                if b + 1 == a {
                    continue;
                }
                let fits = plo < b as isize && (b as isize) < phi;
                if !identity && !fits {
                    continue;
                }
                self.trial.clear();
                self.trial.extend_from_slice(&s.order[lo..=hi]);
                if !identity {
                    let (ra, rb) = (a - lo, b - lo);
                    if ra < rb {
                        self.trial[ra..=rb].rotate_left(1);
                    } else {
                        self.trial[rb..=ra].rotate_right(1);
                    }
                }
                let (v, evals) = self.dp(c, left, right, best);
                ctx.count(evals);
                if v < best && improves(v - current, s.cost) {
                    best = v;
                    found = true;
                    self.best_cells.clone_from(&self.trial);
                    self.trace_modes(c, right);
                }
            }
        }
        if !found {
            return false;
        }
        let delta = best - current;
        s.rewrite_with_modes(lo, &self.best_cells, &self.best_modes, delta);
        true
    }

    /// Cost of the trial cells between the fixed slots `left` and `right` with the best
    /// modes, and the arc evaluations made: infinity once every partial path costs `cap`
    /// or more.
    fn dp(&mut self, c: &Costs, left: Slot, right: Slot, cap: f64) -> (f64, u64) {
        let first = self.trial[0] as usize;
        let (inner, complete) = self.layers.run(c, &self.trial, left, cap);
        let evals = c.m.modes(first) as u64 + inner;
        if !complete {
            return (f64::INFINITY, evals);
        }
        let last = self.trial[self.trial.len() - 1] as usize;
        let (v, _) = self.layers.close(c, last, right);
        (v, evals + self.layers.last_modes() as u64)
    }

    /// The modes of the last [`Self::dp`]'s best path into `best_modes`.
    fn trace_modes(&mut self, c: &Costs, right: Slot) {
        let len = self.trial.len();
        let (_, k) = self.layers.close(c, self.trial[len - 1] as usize, right);
        self.best_modes.clear();
        self.best_modes.resize(len, 0);
        let modes = &mut self.best_modes;
        self.layers.trace(len, k, |p, m| modes[p] = m);
    }
}

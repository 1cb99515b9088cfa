//! Local search passes with candidate lists and don't-look bits, and the VND over them.

use super::modes::mode_dp;
use super::moves::{
    LAZY_REACH_CELLS, Reversal, SegmentMove, apply_segment, mode_delta, reversible_segment, window,
};
use super::sop3x::{Labels, forward};
use super::window::ModeWindow;
use super::{Costs, Neighbours, Solution};
use crate::context::{Context, Deadline};
use std::collections::VecDeque;

/// Improvement threshold (relative) below which a delta does not count as an improvement.
#[inline]
pub(crate) fn improves(delta: f64, cost: f64) -> bool {
    delta < -1e-9 * cost.abs().max(1.0)
}

/// A FIFO of cells with membership bits (the don't-look bits: a cell off the queue is
/// not looked at until a move next to it puts it back).
struct Queue {
    q: VecDeque<u32>,
    on: Vec<bool>,
}

impl Queue {
    fn all(n: usize) -> Self {
        Queue {
            q: (0..n as u32).collect(),
            on: vec![true; n],
        }
    }
    fn seeded(n: usize, seeds: &[u32]) -> Self {
        let mut q = Queue {
            q: VecDeque::with_capacity(seeds.len()),
            on: vec![false; n],
        };
        for &c in seeds {
            q.push(c);
        }
        q
    }
    fn push(&mut self, c: u32) {
        if !self.on[c as usize] {
            self.on[c as usize] = true;
            self.q.push_back(c);
        }
    }
    fn push_around(&mut self, s: &Solution, p: isize, r: isize) {
        for q in (p - r).max(0)..=(p + r).min(s.n() as isize - 1) {
            self.push(s.order[q as usize]);
        }
    }
    fn pop(&mut self) -> Option<u32> {
        let c = self.q.pop_front()?;
        self.on[c as usize] = false;
        Some(c)
    }
}

/// The local search engine: costs, candidate lists, labelling scratch space.
pub struct Search<'a> {
    /// Link costs.
    pub c: Costs<'a>,
    /// Candidate lists.
    pub nb: Neighbours,
    /// Longest block considered by SOP-3-exchange (each side).
    pub max_block: usize,
    /// Window moves with modes (cells with several modes only; `w = 0` elsewhere).
    pub mode_window: ModeWindow,
    labels: Labels,
    rev: Reversal,
}

/// Window length of [`ModeWindow`] moves on instances with several modes per cell.
pub const MODE_WINDOW: usize = 5;

impl<'a> Search<'a> {
    /// An engine with `k` neighbours per cell.
    pub fn new(c: Costs<'a>, k: usize) -> Self {
        Self::new_until(c, k, Deadline::NONE)
    }

    /// Like [`Search::new`], with the neighbour lists cut off at `deadline`
    /// ([`Neighbours::new_until`]).
    pub fn new_until(c: Costs<'a>, k: usize, deadline: Deadline) -> Self {
        Self::with_neighbours(c, Neighbours::new_until(c.m, k, deadline))
    }

    /// A search over `c` with candidate lists `nb` made elsewhere (for other costs of the same
    /// cells, such as the true costs under a search on penalised ones).
    pub fn with_neighbours(c: Costs<'a>, nb: Neighbours) -> Self {
        let n = c.m.n();
        Search {
            c,
            nb,
            max_block: if n <= 120 {
                n
            } else if n <= LAZY_REACH_CELLS {
                64
            } else {
                8
            },
            mode_window: ModeWindow::new(if n <= LAZY_REACH_CELLS && c.m.multimode() {
                MODE_WINDOW
            } else {
                0
            }),
            labels: Labels::default(),
            rev: Reversal::default(),
        }
    }

    /// Or-opt to a local optimum: segments of 1–3 cells starting at a looked-at cell move
    /// next to a candidate neighbour (kept or reversed). Returns true on any improvement.
    pub fn or_opt(&mut self, s: &mut Solution, ctx: &mut Context) -> bool {
        let queue = Queue::all(s.n());
        self.or_opt_from(s, ctx, queue)
    }

    /// Or-opt that starts by looking only at `seeds` (and what their moves disturb).
    pub fn or_opt_seeded(&mut self, s: &mut Solution, ctx: &mut Context, seeds: &[u32]) -> bool {
        let queue = Queue::seeded(s.n(), seeds);
        self.or_opt_from(s, ctx, queue)
    }

    fn or_opt_from(&mut self, s: &mut Solution, ctx: &mut Context, mut queue: Queue) -> bool {
        let c = self.c;
        let m = c.m;
        let n = s.n();
        let mut improved = false;
        while let Some(x) = queue.pop() {
            if ctx.exhausted_polled() {
                break;
            }
            let i = s.pos[x as usize] as usize;
            let mut best = (0.0, 0usize, 0isize, false);
            // with several modes, a single cell goes in the mode that is cheapest where it lands
            let mut best_mode = None;
            let modes = m.modes(x as usize);
            let mut evals = 0u64;
            for len in 1..=3usize.min(n - i) {
                let (lo, hi) = window(m, s, i, len);
                let rev_ok = len > 1 && reversible_segment(m, s, i, len);
                let mv = SegmentMove::new(&c, s, i, len, rev_ok);
                let first = s.order[i];
                let last = s.order[i + len - 1];
                let cands = self.nb.inn[first as usize]
                    .iter()
                    .map(|&v| s.pos[v as usize] as isize)
                    .chain(
                        self.nb.out[last as usize]
                            .iter()
                            .map(|&w| s.pos[w as usize] as isize - 1),
                    )
                    .chain(
                        self.nb.inn[last as usize]
                            .iter()
                            .filter(|_| len > 1)
                            .map(|&v| s.pos[v as usize] as isize),
                    )
                    .chain(
                        self.nb.out[first as usize]
                            .iter()
                            .filter(|_| len > 1)
                            .map(|&w| s.pos[w as usize] as isize - 1),
                    );
                for p in cands {
                    if p >= i as isize - 1 && p <= (i + len - 1) as isize || p < lo || p >= hi {
                        continue;
                    }
                    if modes > 1 && len == 1 {
                        evals += modes as u64;
                        let (d, md) = mv.delta_best_mode(&c, s, p);
                        if d < best.0 {
                            best = (d, 1, p, false);
                            best_mode = Some(md);
                        }
                        continue;
                    }
                    for r in [false, true] {
                        if r && !rev_ok {
                            continue;
                        }
                        evals += 1;
                        let d = mv.delta(&c, s, p, r);
                        if d < best.0 {
                            best = (d, len, p, r);
                            best_mode = None;
                        }
                    }
                }
            }
            ctx.count(evals);
            if improves(best.0, s.cost) {
                let (d, len, p, r) = best;
                match best_mode {
                    Some(md) => {
                        // the move in the cell's current mode, then the mode change in place
                        let keep = SegmentMove::new(&c, s, i, 1, false).delta(&c, s, p, false);
                        apply_segment(m, s, i, 1, p, false, keep);
                        s.set_mode(x as usize, md, d - keep);
                    }
                    None => apply_segment(m, s, i, len, p, r, d),
                }
                improved = true;
                queue.push_around(s, i as isize, 1);
                queue.push_around(s, s.pos[x as usize] as isize, len as isize);
                queue.push(x);
            }
        }
        improved
    }

    /// 2-opt with mode flip to a local optimum (segments without internal precedence pairs
    /// whose cells all have a reversal mode). Returns true on any improvement.
    pub fn two_opt(&mut self, s: &mut Solution, ctx: &mut Context) -> bool {
        let c = self.c;
        let n = s.n();
        if n < 2 {
            return false;
        }
        self.rev.refresh(&c, s);
        let mut queue = Queue::all(n);
        let mut improved = false;
        while let Some(x) = queue.pop() {
            if ctx.exhausted_polled() {
                break;
            }
            let q = s.pos[x as usize] as usize;
            let mut best = (0.0, 0usize, 0usize);
            let mut evals = 0u64;
            // x just before the segment: new arc x -> reversed end
            if q + 1 < n {
                let i = q + 1;
                let reach = self.rev.reach(i);
                let ends = self.nb.out[x as usize]
                    .iter()
                    .map(|&w| s.pos[w as usize] as isize)
                    .chain([n as isize - 1]);
                for j in ends {
                    if j > i as isize && j <= reach {
                        evals += 1;
                        let d = self.rev.delta(&c, s, i, j as usize);
                        if d < best.0 && self.rev.allowed(c.m, s, i, j as usize) {
                            best = (d, i, j as usize);
                        }
                    }
                }
            }
            // x first of the segment: new arc reversed x -> successor candidate
            {
                let i = q;
                let reach = self.rev.reach(i);
                for &w in &self.nb.out[x as usize] {
                    let j = s.pos[w as usize] as isize - 1;
                    if j > i as isize && j <= reach {
                        evals += 1;
                        let d = self.rev.delta(&c, s, i, j as usize);
                        if d < best.0 && self.rev.allowed(c.m, s, i, j as usize) {
                            best = (d, i, j as usize);
                        }
                    }
                }
            }
            ctx.count(evals);
            if improves(best.0, s.cost) {
                let (d, i, j) = best;
                s.reverse(c.m, i, j, d);
                self.rev.reversed(&c, s, i, j);
                improved = true;
                queue.push_around(s, i as isize, 1);
                queue.push_around(s, j as isize, 1);
            }
        }
        improved
    }

    /// SOP-3-exchange (forward lexicographic search with labelling and a don't-push stack) to
    /// a local optimum. Returns true on any improvement.
    pub fn sop3(&mut self, s: &mut Solution, ctx: &mut Context) -> bool {
        let queue = Queue::all(s.n());
        self.sop3_from(s, ctx, queue)
    }

    /// SOP-3-exchange that starts by looking only at `seeds` (and what their moves disturb).
    pub fn sop3_seeded(&mut self, s: &mut Solution, ctx: &mut Context, seeds: &[u32]) -> bool {
        let queue = Queue::seeded(s.n(), seeds);
        self.sop3_from(s, ctx, queue)
    }

    fn sop3_from(&mut self, s: &mut Solution, ctx: &mut Context, mut queue: Queue) -> bool {
        let c = self.c;
        let cl = c.m.closure();
        let mut improved = false;
        while let Some(x) = queue.pop() {
            if ctx.exhausted_polled() {
                break;
            }
            let mut evals = 0u64;
            let found = forward(&c, cl, s, &mut self.labels, x, self.max_block, &mut evals);
            ctx.count(evals);
            if let Some((d, h, i, j)) = found {
                for cell in s.swap_blocks_touched(h, i as usize, j as usize, d) {
                    queue.push(cell);
                }
                improved = true;
                queue.push(x);
            }
        }
        improved
    }

    /// Single-cell mode change to a local optimum. Returns true on any improvement.
    pub fn mode_change(&mut self, s: &mut Solution, ctx: &mut Context) -> bool {
        let c = self.c;
        let mut improved = false;
        for p in 0..s.n() {
            let cell = s.order[p] as usize;
            let k = c.m.modes(cell);
            if k < 2 {
                continue;
            }
            ctx.count(k as u64);
            let mut best = (0.0, 0usize);
            for md in 0..k {
                let d = mode_delta(&c, s, p, md);
                if d < best.0 {
                    best = (d, md);
                }
            }
            if improves(best.0, s.cost) {
                s.set_mode(cell, best.1, best.0);
                improved = true;
            }
        }
        improved
    }

    /// The mode pass (layered shortest path). Returns true on improvement.
    pub fn modes(&mut self, s: &mut Solution, ctx: &mut Context) -> bool {
        let before = s.cost;
        let e = mode_dp(&self.c, s);
        ctx.count(e);
        improves(s.cost - before, before)
    }

    /// Window moves with modes ([`ModeWindow`]) over every window, or over those that hold
    /// a cell of `seeds`. Returns true on improvement.
    pub fn windows(&mut self, s: &mut Solution, ctx: &mut Context, seeds: Option<&[u32]>) -> bool {
        let c = self.c;
        self.mode_window.improve(&c, s, ctx, seeds)
    }

    /// Variable neighbourhood descent: Or-opt, 2-opt, mode change, SOP-3-exchange, mode DP,
    /// window moves with modes (several modes per cell, up to 5000 cells), restarting from
    /// the first neighbourhood after every improvement.
    pub fn vnd(&mut self, s: &mut Solution, ctx: &mut Context) {
        loop {
            if ctx.exhausted() {
                return;
            }
            if self.or_opt(s, ctx) | self.two_opt(s, ctx) | self.mode_change(s, ctx) {
                continue;
            }
            if self.sop3(s, ctx) {
                continue;
            }
            if !self.modes(s, ctx) && !self.windows(s, ctx, None) {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::{Budget, NoObserver};
    use crate::cost::CostModel;
    use crate::engine::moves::{SegmentMove, window};
    use crate::model::Objective;

    /// With candidate lists holding every cell, Or-opt ends where no single cell can move
    /// to any place its precedence allows, in any of its modes, for less: cells of several
    /// modes are inserted in the mode that is cheapest where they land. Generalized
    /// instances with open features (asymmetric costs, two modes per open cell).
    #[test]
    fn or_opt_ends_where_no_cell_moves_for_less_in_any_mode() {
        let mut moved_in_other_mode = false;
        for seed in 1..=6 {
            let kv = [("n", "30"), ("open", "0.6"), ("p", "10")]
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            let inst = crate::generate::generate("generalized", &kv, seed).expect("generated");
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
            let mut s = Solution::new(&c, inst.as_given.as_ref().expect("as given"));
            let mut search = Search::new(c, m.n());
            let before = s.clone();
            // a pass that improves nothing has looked at every cell
            let mut passes = 0;
            while search.or_opt(&mut s, &mut ctx) {
                passes += 1;
                assert!(passes < 1000);
            }
            assert!(s.feasible(&m), "seed {seed}");
            assert!((s.cost - s.evaluate(&c)).abs() < 1e-6, "seed {seed}");
            moved_in_other_mode |=
                (0..m.n()).any(|x| s.mode[x] != before.mode[x] && s.pos[x] != before.pos[x]);
            for i in 0..s.n() {
                let (lo, hi) = window(&m, &s, i, 1);
                let mv = SegmentMove::new(&c, &s, i, 1, false);
                for p in (lo..hi).filter(|&p| p != i as isize && p != i as isize - 1) {
                    let (d, _) = mv.delta_best_mode(&c, &s, p);
                    assert!(!improves(d, s.cost), "seed {seed}: cell at {i} to {p}: {d}");
                }
            }
        }
        assert!(
            moved_in_other_mode,
            "some cell changed place and mode at once"
        );
    }
}

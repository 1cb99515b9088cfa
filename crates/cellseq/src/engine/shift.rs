//! Bounded-shift dynamic programming (Balas–Simonetti): the cheapest sequence, with modes,
//! among every reorder of a run of positions in which no cell passes a cell that lay `k` or
//! more positions after it.
//!
//! Balas and Simonetti (INFORMS J. Computing 13(1), 2001) showed that this neighbourhood,
//! exponential in size, is searched exactly by a shortest path whose stages are the
//! positions of the new order. A stage's state is the first cell not yet placed (`b`, as a
//! position of the current order), the set of cells after it that are placed already (at
//! most `k − 1` of them, a bit mask relative to `b`) and the last placed cell with its
//! mode: `O(k·2^k)` states per stage without precedence, and far fewer with it, since a
//! cell is placed only after its predecessors. Every precedence pair holds in the result:
//! a predecessor `k` or more positions before a cell is placed before `b` can reach the
//! cell, and nearer ones are checked against the mask. The run's cells stay inside the run,
//! so pairs with cells outside it hold too.
//!
//! The neighbourhood holds every exchange of two adjacent blocks whose lengths add up to at
//! most `k` (so every SOP-3-exchange, and every Or-opt move of a segment of `s` cells by `d`
//! places, with `s + d ≤ k`), any number of these at once when they do not overlap, and the
//! best modes for each, so a pass ends in a local optimum of all of them together. `ils`
//! runs it over the span of every kick (`--param shift-repair=K`); on PCGTSPLIB p43.2 it
//! takes the runs at 10 s below the best known more often (notes/lab/sopq9.md). States are kept
//! in a hash map per stage; a stage that would hold more than `max_states` ends the pass
//! without a change.

use super::vnd::improves;
use super::{Costs, Slot, Solution};
use crate::context::Context;
use rustc_hash::FxHashMap;

/// No last cell yet: the run's left neighbour (or the path start) comes before.
const NONE: u32 = u32::MAX;

/// One DP state: placed cells `0..b` and the bits of `x` (relative to `b`), `last`
/// (position in the current order) placed last in `mode`, at `cost` from the run's left end.
#[derive(Debug, Clone, Copy)]
struct State {
    b: u32,
    x: u64,
    last: u32,
    mode: u32,
    cost: f64,
    parent: u32,
}

/// The bounded-shift DP with its scratch space.
#[derive(Debug)]
pub struct ShiftDp {
    /// Largest shift `k` (2..=64): a cell may not pass one that lay `k` or more positions
    /// after it.
    pub k: usize,
    /// Most states in one stage before a pass gives up.
    pub max_states: usize,
    stages: Vec<Vec<State>>,
    index: FxHashMap<(u32, u64, u32, u32), u32>,
    /// Per run position `r`: bit `u` set when the cell at `r − (k − 1) + u` is a direct
    /// predecessor of the cell at `r`.
    preds: Vec<u64>,
    /// States created by the last pass.
    pub last_states: usize,
}

impl ShiftDp {
    /// A DP with shift `k` (clamped to 2..=64) and at most `max_states` states per stage.
    pub fn new(k: usize, max_states: usize) -> Self {
        ShiftDp {
            k: k.clamp(2, 64),
            max_states: max_states.max(1),
            stages: Vec::new(),
            index: FxHashMap::default(),
            preds: Vec::new(),
            last_states: 0,
        }
    }

    /// The best reorder of positions `lo..hi`; applies it when it improves. Returns true on
    /// improvement. Gives up without a change when a stage outgrows `max_states` or the
    /// budget runs out.
    pub fn improve_range(
        &mut self,
        c: &Costs,
        s: &mut Solution,
        ctx: &mut Context,
        lo: usize,
        hi: usize,
    ) -> bool {
        let hi = hi.min(s.n());
        if hi < lo + 2 {
            return false;
        }
        let len = hi - lo;
        let k = self.k.min(len);
        let m = c.m;
        // direct predecessors inside the window of k − 1 positions before each cell
        self.preds.clear();
        for r in 0..len {
            let cell = s.order[lo + r] as usize;
            let mut bits = 0u64;
            for &q in &m.dag.preds[cell] {
                let pq = s.pos[q as usize] as usize;
                if pq >= lo && pq < lo + r && lo + r - pq < k {
                    bits |= 1u64 << (pq - lo + k - 1 - r);
                }
            }
            self.preds.push(bits);
        }
        let left: Slot = s.at(lo as isize - 1);
        let right: Slot = s.at(hi as isize);
        let current = s.links(c, lo as isize - 1, hi as isize);
        if self.stages.len() < len + 1 {
            self.stages.resize_with(len + 1, Vec::new);
        }
        self.stages[0].clear();
        self.stages[0].push(State {
            b: 0,
            x: 0,
            last: NONE,
            mode: 0,
            cost: 0.0,
            parent: NONE,
        });
        let mut states = 1usize;
        let mut evals = 0u64;
        for p in 0..len {
            if ctx.exhausted() {
                ctx.count(evals);
                return false;
            }
            let (done, rest) = self.stages.split_at_mut(p + 1);
            let from = &done[p];
            let to = &mut rest[0];
            to.clear();
            self.index.clear();
            for (si, st) in from.iter().enumerate() {
                let b = st.b as usize;
                let prev: Slot = if st.last == NONE {
                    left
                } else {
                    let cell = s.order[lo + st.last as usize] as usize;
                    Some((cell, st.mode as usize))
                };
                for t in 0..k.min(len - b) {
                    if t > 0 && st.x >> t & 1 == 1 {
                        continue;
                    }
                    let j = b + t;
                    let required = self.preds[j] >> (k - 1 - t);
                    if required & !st.x != 0 {
                        continue;
                    }
                    let (nb, nx) = if t == 0 {
                        let x = st.x | 1;
                        let shift = x.trailing_ones();
                        let nx = if shift >= 64 { 0 } else { x >> shift };
                        (st.b + shift, nx)
                    } else {
                        (st.b, st.x | 1u64 << t)
                    };
                    let cell = s.order[lo + j] as usize;
                    for mode in 0..m.modes(cell) {
                        evals += 1;
                        let cost = st.cost + c.link(prev, Some((cell, mode)));
                        let key = (nb, nx, j as u32, mode as u32);
                        match self.index.get(&key) {
                            Some(&i) => {
                                let e = &mut to[i as usize];
                                if cost < e.cost {
                                    e.cost = cost;
                                    e.parent = si as u32;
                                }
                            }
                            None => {
                                self.index.insert(key, to.len() as u32);
                                to.push(State {
                                    b: nb,
                                    x: nx,
                                    last: j as u32,
                                    mode: mode as u32,
                                    cost,
                                    parent: si as u32,
                                });
                            }
                        }
                    }
                }
            }
            states += to.len();
            if to.len() > self.max_states {
                ctx.count(evals);
                self.last_states = states;
                return false;
            }
        }
        self.last_states = states;
        // close the run on its right neighbour
        let mut best = (f64::INFINITY, NONE);
        for (i, st) in self.stages[len].iter().enumerate() {
            debug_assert_eq!(st.b as usize, len);
            let cell = s.order[lo + st.last as usize] as usize;
            let v = st.cost + c.link(Some((cell, st.mode as usize)), right);
            evals += 1;
            if v < best.0 {
                best = (v, i as u32);
            }
        }
        ctx.count(evals);
        if best.1 == NONE || !improves(best.0 - current, s.cost) {
            return false;
        }
        // trace the path back through the stages
        let mut cells = vec![0u32; len];
        let mut modes = vec![0u32; len];
        let mut i = best.1 as usize;
        for p in (1..=len).rev() {
            let st = self.stages[p][i];
            cells[p - 1] = s.order[lo + st.last as usize];
            modes[p - 1] = st.mode;
            i = st.parent as usize;
        }
        s.rewrite_with_modes(lo, &cells, &modes, best.0 - current);
        true
    }
}

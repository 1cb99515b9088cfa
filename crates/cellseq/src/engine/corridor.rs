//! Corridor search: the cheapest reorder of a sequence inside a corridor around it, by a beam
//! over prefixes with a pilot guide (the corridor method of Sniedovich and Voß, "The corridor
//! method: a dynamic programming inspired metaheuristic", 2006).
//!
//! A prefix of k placed cells is described against the incumbent's first k cells: the
//! positions **behind** (among the incumbent's first k, not placed yet) and the positions
//! **ahead** (placed, from the incumbent's position k on); there are as many of one as of the
//! other. The corridor holds the prefixes with at most `diff` of each in which no cell lands
//! more than `reach` positions from where the incumbent has it. Two prefixes with the same
//! cells and the same last cell are one state (the cheaper is kept), so within the corridor
//! the search is a dynamic program; the beam keeps the `width` states of each length with the
//! lowest **pilot** cost: the prefix's cost plus the cost of finishing it in the incumbent's
//! order (the cells behind first, then the rest, skipping those ahead). That finish is always
//! feasible, so the pilot is the cost of a whole sequence; the incumbent's own prefixes have
//! the incumbent's cost, and the best pilot never rises from one length to the next, so the
//! result is never worse than the incumbent. With a width that holds every state of the
//! corridor the result is the corridor's optimum.
//!
//! What it finds that kicks and exchanges miss: on dense precedence (crane scheduling with
//! time windows) a walk's record and a better sequence may differ in a stretch of 60 cells
//! where 20 move up to 30 places, yet at every position the two prefixes differ by at most
//! five cells. No single kick or exchange makes that reorder; the corridor holds it.
//!
//! Cost: about `width × (reach + diff)` candidate steps per position, each an O(1) link and a
//! precedence check against the direct predecessors; the pilot is O(`diff`). Memory: one
//! parent index and position per kept state, `n × width` of them, and one length's children;
//! the width is capped to keep both bounded ([`MAX_STATES`], [`MAX_CHILDREN`]).

use super::{Costs, Slot, Solution};
use crate::context::Context;
use rustc_hash::FxHashMap;
use std::collections::hash_map::Entry;

/// Largest `diff`: positions behind (and ahead) one prefix may hold.
pub const MAX_DIFF: usize = 8;

/// Largest `reach`: a prefix's positions behind and ahead are one 128-bit mask around its
/// length.
pub const MAX_REACH: usize = 63;

/// Largest number of kept states over all lengths (`n × width`): 2^24, 128 MiB of history.
pub const MAX_STATES: usize = 1 << 24;

/// Largest number of children one length may hold (`width × (reach + diff + 1)`, each with
/// its index entry): 2^21, about 150 MiB.
pub const MAX_CHILDREN: usize = 1 << 21;

/// No last cell: the path's start.
const START: u32 = u32::MAX;

/// The corridor's shape and the beam's width.
#[derive(Debug, Clone, Copy)]
pub struct Corridor {
    /// Most positions behind (and ahead) a prefix may hold, 1..=[`MAX_DIFF`].
    pub diff: usize,
    /// Farthest a cell may land from its position in the incumbent, 1..=[`MAX_REACH`].
    pub reach: usize,
    /// States kept per prefix length.
    pub width: usize,
}

/// One prefix of length k. Bit i of `mask` stands for position `k − reach + i`: below k a set
/// bit is a position behind (not placed), from k on a position ahead (placed); positions below
/// the mask are placed, above it not.
#[derive(Clone, Copy)]
struct State {
    g: f64,
    mask: u128,
    last: u32,
    parent: u32,
}

/// The incumbent, its links and the corridor's shape.
struct Frame<'a> {
    c: &'a Costs<'a>,
    s: &'a Solution,
    /// `tail[p]`: the incumbent's links from position p to the end (the end link included).
    tail: Vec<f64>,
    reach: u32,
    n: u32,
}

impl Frame<'_> {
    /// The slot at position `p` (`START` and `n` stand for the path's start and end).
    fn slot(&self, p: u32) -> Slot {
        if p == START {
            None
        } else {
            self.s.at(p as isize)
        }
    }

    fn link(&self, a: u32, b: u32) -> f64 {
        self.c.link(self.slot(a), self.slot(b))
    }

    /// Whether position `q` is placed in a prefix of length `k` with `mask`.
    #[inline]
    fn placed(&self, k: u32, mask: u128, q: u32) -> bool {
        if q + self.reach < k {
            return true;
        }
        let i = q + self.reach - k;
        if q < k {
            mask >> i & 1 == 0
        } else {
            i <= 2 * self.reach && mask >> i & 1 == 1
        }
    }

    /// The cost of finishing a prefix of length `k` in the incumbent's order: from `last`
    /// through the positions behind, then positions k.. without those ahead, to the end.
    fn finish(&self, k: u32, last: u32, mask: u128) -> f64 {
        let r = self.reach;
        let low = (1u128 << r) - 1;
        let ahead = mask >> r; // bit j: position k + j
        let first = (k + ahead.trailing_ones()).min(self.n);
        let mut cost = self.tail[first as usize];
        // the runs of positions ahead after `first` are skipped over
        let mut rest = ahead >> (first - k);
        let mut at = first;
        while rest != 0 {
            let skip = rest.trailing_zeros();
            let u = at + skip;
            let run = (rest >> skip).trailing_ones();
            let v = u + run - 1;
            cost -= self.tail[u as usize - 1] - self.tail[v as usize + 1];
            cost += self.link(u - 1, v + 1);
            rest = rest.checked_shr(skip + run).unwrap_or(0);
            at = v + 1;
        }
        let mut prev = last;
        let mut behind = mask & low;
        while behind != 0 {
            let b = k + behind.trailing_zeros() - r;
            cost += self.link(prev, b);
            prev = b;
            behind &= behind - 1;
        }
        cost + self.link(prev, first)
    }
}

/// The positions from `k` to `k + reach` that a prefix of length `k` may place: those with at
/// most `diff` ancestors between `k` and themselves (each of which would have to be ahead).
fn possible(c: &Costs, s: &Solution, k: u32, reach: u32, diff: usize, out: &mut Vec<u32>) {
    out.clear();
    let hi = (k + reach).min(s.n() as u32 - 1);
    let Some(cl) = c.m.closure() else {
        out.extend(k..=hi);
        return;
    };
    for p in k..=hi {
        let anc = cl.anc_row(s.order[p as usize] as usize);
        let before = (k..p)
            .filter(|&q| {
                let x = s.order[q as usize] as usize;
                anc[x / 64] >> (x % 64) & 1 == 1
            })
            .count();
        if before <= diff {
            out.push(p);
        }
    }
}

/// The cheapest sequence the corridor search finds around `s`, as the new cell order with its
/// cost, when it is cheaper than `s`; `None` when it is not, or when the budget ran out.
/// Counts one evaluation per candidate step and per kept child; reads the budget at every
/// prefix length and every 1024 states within one. The width is capped so that the history
/// (`n × width`) and one length's children stay within [`MAX_STATES`] and [`MAX_CHILDREN`].
pub fn improve(c: &Costs, s: &Solution, ctx: &mut Context, k: Corridor) -> Option<(Vec<u32>, f64)> {
    let n = s.n();
    if n < 3 || n >= START as usize {
        return None;
    }
    let m = c.m;
    let diff = k.diff.clamp(1, MAX_DIFF);
    let r = k.reach.clamp(1, MAX_REACH) as u32;
    let width = k
        .width
        .min(MAX_STATES / n)
        .min(MAX_CHILDREN / (r as usize + diff + 1))
        .max(1);
    let mut tail = vec![0.0; n + 1];
    for p in (0..n).rev() {
        tail[p] = tail[p + 1] + s.link(c, p as isize, p as isize + 1);
    }
    let f = Frame {
        c,
        s,
        tail,
        reach: r,
        n: n as u32,
    };
    let low = (1u128 << r) - 1;
    let mut level = vec![State {
        g: 0.0,
        mask: 0,
        last: START,
        parent: 0,
    }];
    // for each length, the kept states' (parent, last position)
    let mut history: Vec<Vec<(u32, u32)>> = Vec::with_capacity(n);
    let mut children: Vec<State> = Vec::new();
    let mut index: FxHashMap<(u128, u32), u32> = FxHashMap::default();
    let mut scored: Vec<(f64, u32)> = Vec::new();
    let mut ahead_ok: Vec<u32> = Vec::new();
    for depth in 0..n as u32 {
        if ctx.exhausted() {
            return None;
        }
        children.clear();
        index.clear();
        possible(c, s, depth, r, diff, &mut ahead_ok);
        let mut evals = 0u64;
        for (pi, st) in level.iter().enumerate() {
            // a wide level takes tens of milliseconds: the clock is read within it too
            if pi % 1024 == 1023 && ctx.exhausted() {
                return None;
            }
            let mut behind = st.mask & low;
            let behind_cells = std::iter::from_fn(|| {
                (behind != 0).then(|| {
                    let p = depth + behind.trailing_zeros() - r;
                    behind &= behind - 1;
                    p
                })
            });
            let ahead_cells = ahead_ok
                .iter()
                .copied()
                .filter(|&p| st.mask >> (p + r - depth) & 1 == 0);
            for p in behind_cells.chain(ahead_cells) {
                evals += 1;
                let cell = s.order[p as usize] as usize;
                // ready: every direct predecessor placed
                if !m.dag.preds[cell]
                    .iter()
                    .all(|&q| f.placed(depth, st.mask, s.pos[q as usize]))
                {
                    continue;
                }
                // place p, then position `depth` joins the incumbent's prefix of the next
                // length (its bit flips meaning) and the mask moves up by one position
                let mask = st.mask ^ (1u128 << (p + r - depth)) ^ (1u128 << r);
                if mask & 1 == 1 {
                    // the lowest position would be left behind farther than `reach`
                    continue;
                }
                let mask = mask >> 1;
                if (mask & low).count_ones() as usize > diff {
                    continue;
                }
                let child = State {
                    g: st.g + f.link(st.last, p),
                    mask,
                    last: p,
                    parent: pi as u32,
                };
                match index.entry((mask, p)) {
                    Entry::Occupied(e) => {
                        let old = &mut children[*e.get() as usize];
                        if child.g < old.g {
                            *old = child;
                        }
                    }
                    Entry::Vacant(e) => {
                        e.insert(children.len() as u32);
                        children.push(child);
                    }
                }
            }
        }
        ctx.count(evals + children.len() as u64);
        if children.len() > width {
            scored.clear();
            scored.extend(
                children
                    .iter()
                    .enumerate()
                    .map(|(i, st)| (st.g + f.finish(depth + 1, st.last, st.mask), i as u32)),
            );
            let by = |a: &(f64, u32), b: &(f64, u32)| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1));
            scored.select_nth_unstable_by(width - 1, by);
            scored.truncate(width);
            scored.sort_unstable_by_key(|&(_, i)| i);
            level.clear();
            level.extend(scored.iter().map(|&(_, i)| children[i as usize]));
        } else {
            std::mem::swap(&mut level, &mut children);
        }
        history.push(level.iter().map(|st| (st.parent, st.last)).collect());
    }
    // every state of the last level has placed every cell
    let (best, cost) = level
        .iter()
        .enumerate()
        .map(|(i, st)| (i, st.g + f.link(st.last, n as u32)))
        .min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)))?;
    if !super::cheaper(cost, s.cost) {
        return None;
    }
    let mut order = vec![0u32; n];
    let mut at = best as u32;
    for depth in (0..n).rev() {
        let (parent, last) = history[depth][at as usize];
        order[depth] = s.order[last as usize];
        at = parent;
    }
    Some((order, cost))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::{Budget, NoObserver};
    use crate::cost::CostModel;
    use crate::model::{Instance, Objective, Sequence, Visit};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random matrix instance of `n` cells, each pair a < b ordered with probability `p`
    /// (so the identity order is feasible).
    fn instance(n: usize, seed: u64, p: f64) -> Instance {
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed);
        let pairs: Vec<(usize, usize)> = (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .filter(|_| rng.random_bool(p))
            .collect();
        crate::engine::atsp::random_matrix_instance(n, seed, 100, &pairs)
    }

    /// Every feasible order of `n` cells (small n), by depth-first search.
    fn all_orders(m: &CostModel) -> Vec<Vec<u32>> {
        fn go(m: &CostModel, cur: &mut Vec<u32>, used: &mut Vec<bool>, out: &mut Vec<Vec<u32>>) {
            let n = m.n();
            if cur.len() == n {
                out.push(cur.clone());
                return;
            }
            for x in 0..n {
                if !used[x] && m.dag.preds[x].iter().all(|&q| used[q as usize]) {
                    used[x] = true;
                    cur.push(x as u32);
                    go(m, cur, used, out);
                    cur.pop();
                    used[x] = false;
                }
            }
        }
        let mut out = Vec::new();
        go(m, &mut Vec::new(), &mut vec![false; m.n()], &mut out);
        out
    }

    /// Whether `order` lies in the corridor around `inc`: at every length the prefixes differ
    /// by at most `diff` cells, and no cell moves more than `reach` places.
    fn in_corridor(inc: &[u32], order: &[u32], diff: usize, reach: usize) -> bool {
        let n = inc.len();
        let mut pos = vec![0usize; n];
        for (p, &x) in inc.iter().enumerate() {
            pos[x as usize] = p;
        }
        if order.iter().enumerate().any(|(p, &x)| p.abs_diff(pos[x as usize]) > reach) {
            return false;
        }
        (1..=n).all(|k| order[..k].iter().filter(|&&x| pos[x as usize] >= k).count() <= diff)
    }

    /// With a width that holds every state, the search returns the corridor's optimum (by
    /// brute force over every feasible order of 8 cells), never a sequence outside it, and
    /// nothing when the incumbent is already the corridor's best.
    #[test]
    fn wide_search_is_the_corridors_optimum() {
        for (seed, p) in [(1, 0.0), (2, 0.1), (3, 0.3), (4, 0.6)] {
            let inst = instance(8, seed, p);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let orders = all_orders(&m);
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            for _ in 0..6 {
                let inc = &orders[rng.random_range(0..orders.len())];
                let seq: Sequence = inc.iter().map(|&x| Visit::new(x as usize, 0)).collect();
                let s = Solution::new(&c, &seq);
                for (diff, reach) in [(1, 8), (2, 3), (3, 8)] {
                    let best = orders
                        .iter()
                        .filter(|o| in_corridor(inc, o, diff, reach))
                        .map(|o| {
                            let q: Sequence =
                                o.iter().map(|&x| Visit::new(x as usize, 0)).collect();
                            Solution::new(&c, &q).cost
                        })
                        .fold(f64::INFINITY, f64::min);
                    let mut obs = NoObserver;
                    let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
                    let k = Corridor {
                        diff,
                        reach,
                        width: 1 << 20,
                    };
                    match improve(&c, &s, &mut ctx, k) {
                        Some((order, cost)) => {
                            assert!(in_corridor(inc, &order, diff, reach));
                            let q: Sequence =
                                order.iter().map(|&x| Visit::new(x as usize, 0)).collect();
                            let t = Solution::new(&c, &q);
                            assert!(t.feasible(&m));
                            assert!((t.cost - cost).abs() < 1e-9);
                            assert!((cost - best).abs() < 1e-9, "seed {seed}: {cost} vs {best}");
                        }
                        None => assert!(s.cost <= best + 1e-9, "seed {seed}: missed {best}"),
                    }
                }
            }
        }
    }

    /// A narrow beam never returns anything worse than the incumbent, and its result is
    /// feasible, on larger instances from sparse to dense precedence.
    #[test]
    fn narrow_search_never_worsens() {
        for (seed, p) in [(5, 0.05), (6, 0.3), (7, 0.8)] {
            let n = 60;
            let inst = instance(n, seed, p);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let seq: Sequence = (0..n).map(|x| Visit::new(x, 0)).collect();
            let s = Solution::new(&c, &seq);
            for width in [1, 4, 64] {
                let mut obs = NoObserver;
                let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
                let k = Corridor {
                    diff: 4,
                    reach: 20,
                    width,
                };
                if let Some((order, cost)) = improve(&c, &s, &mut ctx, k) {
                    let q: Sequence = order.iter().map(|&x| Visit::new(x as usize, 0)).collect();
                    let t = Solution::new(&c, &q);
                    assert!(t.feasible(&m));
                    assert!((t.cost - cost).abs() < 1e-6);
                    assert!(cost < s.cost);
                }
            }
        }
    }
}

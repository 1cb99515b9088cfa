//! `insertion`: cheapest feasible insertion in a topological order.
//!
//! Cells are taken in an order that respects precedence, those with more descendants first
//! (ties at random), and each goes, in its best mode, into the cheapest place of the path
//! built so far that lies after all its predecessors. Its successors are not in the path yet,
//! so no other place can break precedence. "After a predecessor" is one comparison of order
//! labels: the path keeps a label per cell that grows along it (an order-maintenance list:
//! a new cell takes the middle of its gap, and a run of cells is spread out again when a
//! gap is used up).
//!
//! Geometric instances look for places next to the inserted cells nearest to the new one:
//! after a cell whose exit is near an entry of the new one, before a cell whose entry is near
//! an exit of it (two grids, one of exits and one of entries, made finer as they fill, searched
//! ring by ring until `k` feasible places are seen), plus the places right after the last
//! predecessor and at the end of the path, which are always feasible: O(k) per cell. Matrix
//! instances try every place (O(n²)).
//!
//! Where precedence is sparse and unrelated to where the cells are (the `uniform` generator's
//! `preds`), the nearest-neighbour walk leaves behind cells that are not ready yet and has to
//! come back for each of them; insertion puts such a cell where the path passes by later.
//! Measured on `uniform` with one random predecessor per cell (lift 0, air length): 0.61–0.67
//! × the nearest-neighbour walk at 2000–5000 cells and, as the strokes (20 mm) grow long
//! against their spacing, 0.95 × at 10^5 and 2.1 × at 10^6 (a cell's mode is fixed once it
//! is in); with points instead of strokes 0.75 × at 10^5. `local-search` starting from it
//! reaches 0.70–0.72 × the walk at 10^5 cells in 10 s, against 0.895 × from the walk itself.

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::engine::order::OrderList;
use crate::engine::{Costs, Slot};
use crate::geom::Point3;
use crate::model::{Sequence, Visit};
use crate::precedence::{ranked_topological_order, topological_order};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::cmp::Reverse;

/// The path under construction, with order labels ([`OrderList`]) and the cells' modes.
struct Path {
    list: OrderList,
    mode: Vec<u32>,
}

impl Path {
    fn slot(&self, a: u32) -> Slot {
        (a != self.list.sentinel()).then(|| (a as usize, self.mode[a as usize] as usize))
    }

    fn sequence(&self) -> Sequence {
        self.list
            .cells()
            .map(|x| Visit::new(x as usize, self.mode[x as usize] as usize))
            .collect()
    }
}

/// Points of the inserted cells bucketed on a uniform grid that is rebuilt finer whenever the
/// number of points doubles, so that a bucket holds about two points at any time and a search
/// for the nearest few visits O(1) buckets however many cells are in.
struct Grid {
    x0: f64,
    y0: f64,
    extent: f64,
    inv: f64,
    side: usize,
    buckets: Vec<Vec<u32>>,
    /// Every point added, in order, for the rebuilds.
    points: Vec<(Point3, u32)>,
}

/// A search around a point stops after `SCAN × k` cells (most may lie before the last
/// predecessor; 16 instead of 32 costs 4 % on `uniform` 10^5 cells with `preds=1`).
const SCAN: usize = 32;

/// A search around a point stops after this many buckets (clustered points leave many empty).
const MAX_BUCKETS: usize = 4096;

impl Grid {
    /// An empty grid over the bounding box of every entry and exit of the model.
    fn new(m: &CostModel) -> Self {
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for nd in 0..m.nodes() {
            for p in [m.entry(nd), m.exit(nd)] {
                x0 = x0.min(p.x);
                y0 = y0.min(p.y);
                x1 = x1.max(p.x);
                y1 = y1.max(p.y);
            }
        }
        let extent = (x1 - x0).max(y1 - y0).max(1e-9);
        let mut g = Grid {
            x0,
            y0,
            extent,
            inv: 0.0,
            side: 0,
            buckets: Vec::new(),
            points: Vec::with_capacity(m.n()),
        };
        g.rebuild(1);
        g
    }

    fn rebuild(&mut self, side: usize) {
        self.side = side;
        self.inv = side as f64 / self.extent;
        self.buckets.clear();
        self.buckets.resize(side * side, Vec::new());
        for i in 0..self.points.len() {
            let (p, c) = self.points[i];
            let b = self.bucket(p);
            self.buckets[b].push(c);
        }
    }

    fn coords(&self, p: Point3) -> (usize, usize) {
        let f = |v: f64| ((v * self.inv) as usize).min(self.side - 1);
        (f(p.x - self.x0), f(p.y - self.y0))
    }

    fn bucket(&self, p: Point3) -> usize {
        let (i, j) = self.coords(p);
        i * self.side + j
    }

    fn add(&mut self, p: Point3, c: u32) {
        self.points.push((p, c));
        if self.points.len() > 4 * self.side * self.side {
            self.rebuild(self.side * 2);
        } else {
            let b = self.bucket(p);
            self.buckets[b].push(c);
        }
    }

    /// Calls `visit` on the cells of the buckets ring by ring around p until it returns
    /// `false`, [`MAX_BUCKETS`] buckets are searched or the grid is exhausted.
    fn rings(&self, p: Point3, mut visit: impl FnMut(u32) -> bool) {
        let (ci, cj) = self.coords(p);
        let (ci, cj, side) = (ci as isize, cj as isize, self.side as isize);
        let mut searched = 0;
        for r in 0..side {
            for i in (ci - r).max(0)..=(ci + r).min(side - 1) {
                let edge = i == ci - r || i == ci + r;
                let step = if edge || r == 0 { 1 } else { 2 * r };
                let mut j = cj - r;
                while j <= cj + r {
                    if j >= 0 && j < side {
                        searched += 1;
                        for &q in &self.buckets[(i * side + j) as usize] {
                            if !visit(q) {
                                return;
                            }
                        }
                    }
                    j += step;
                }
            }
            if searched >= MAX_BUCKETS {
                return;
            }
        }
    }
}

/// A topological order that takes cells with more descendants first: Kahn's algorithm with
/// a priority of 1 + the successors' priorities (the number of descendants on a forest, more
/// where descendants are shared), ties broken at random. Cells that many others wait for are
/// placed while the path is still short, and the cells with few or no successors come last,
/// when the path passes near everything. On a random recursive tree of precedence it is about
/// 0.6 × the nearest-neighbour walk's length where a random topological order is about 1.2 ×.
fn topological(m: &CostModel, rng: &mut ChaCha8Rng) -> Vec<u32> {
    let n = m.n();
    // a validated model is acyclic; the fallbacks only keep this total
    let kahn = topological_order(&m.dag).unwrap_or_else(|_| (0..n as u32).collect());
    let mut weight = vec![1.0f64; n];
    for &c in kahn.iter().rev() {
        let c = c as usize;
        weight[c] += m.dag.succs[c]
            .iter()
            .map(|&s| weight[s as usize])
            .sum::<f64>();
    }
    // rank = place in the order by weight (descending; positive floats order as their
    // bits), then a random draw, then index; among ready cells the lowest rank goes first
    let draw: Vec<u64> = (0..n).map(|_| rng.random()).collect();
    let mut by_key: Vec<usize> = (0..n).collect();
    by_key.sort_unstable_by_key(|&c| (Reverse(weight[c].to_bits()), draw[c], c));
    let mut rank = vec![0usize; n];
    for (r, &c) in by_key.iter().enumerate() {
        rank[c] = r;
    }
    ranked_topological_order(&m.dag, &rank)
        .unwrap_or_else(|_| (0..n).collect())
        .into_iter()
        .map(|c| c as u32)
        .collect()
}

/// The best (delta, mode) of putting c right after a.
fn place(costs: &Costs, path: &Path, a: u32, c: usize) -> (f64, u32) {
    let sa = path.slot(a);
    let sb = path.slot(path.list.next[a as usize]);
    let old = costs.link(sa, sb);
    let mut best = (f64::INFINITY, 0);
    for mc in 0..costs.m.modes(c) {
        let s = Some((c, mc));
        let d = costs.link(sa, s) + costs.link(s, sb) - old;
        if d < best.0 {
            best = (d, mc as u32);
        }
    }
    best
}

/// Most modes of one cell whose points the grids are searched around.
const MAX_SEARCH_MODES: usize = 64;

/// Appends `rest` (cells in a topological order, none in `seq` yet) to `seq`, each in its
/// cheapest mode after the one before.
fn append_in_order(m: &CostModel, seq: &mut Sequence, rest: &[u32]) {
    for &c in rest {
        let c = c as usize;
        seq.push(Visit::new(c, super::cheapest_after(m, seq, c)));
    }
}

/// The insertion sequence (see the module documentation); `k` feasible places next to nearby
/// cells per cell on geometric instances, the topological order drawn from `seed`.
pub fn sequence(m: &CostModel, k: usize, seed: u64, count: &mut dyn FnMut(u64)) -> Sequence {
    sequence_until(m, k, seed, count, Deadline::NONE)
}

/// Like [`sequence`]; once `deadline` passes, the cells not inserted yet follow at the end in
/// their topological order, each in its cheapest mode there ([`super::complete`]).
pub fn sequence_until(
    m: &CostModel,
    k: usize,
    seed: u64,
    count: &mut dyn FnMut(u64),
    deadline: Deadline,
) -> Sequence {
    if deadline.passed() {
        return super::fastest(m);
    }
    let n = m.n();
    let mut clock = super::ticker(deadline);
    let costs = Costs::open(m);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let order = topological(m, &mut rng);
    let mut path = Path {
        list: OrderList::new(n),
        mode: vec![0; n],
    };
    let head = path.list.sentinel();
    let mut grids = m.is_geometric().then(|| (Grid::new(m), Grid::new(m)));
    let mut inserted: Vec<u32> = Vec::with_capacity(n);
    for (i, &c) in order.iter().enumerate() {
        if clock.passed() {
            let mut seq = path.sequence();
            append_in_order(m, &mut seq, &order[i..]);
            return seq;
        }
        let cu = c as usize;
        let after = m.dag.preds[cu]
            .iter()
            .copied()
            .max_by_key(|&p| path.list.after(p))
            .unwrap_or(head);
        let floor = path.list.after(after);
        // (delta, place after, mode); ties go to the candidate tried first
        let mut best = (f64::INFINITY, head, 0u32);
        let mut evals = 0u64;
        let mut consider = |a: u32, best: &mut (f64, u32, u32)| {
            let (d, md) = place(&costs, &path, a, cu);
            evals += 1;
            if d < best.0 {
                *best = (d, a, md);
            }
        };
        consider(after, &mut best);
        let last = path.list.last();
        if last != after {
            consider(last, &mut best);
        }
        match &grids {
            Some((exits, entries)) => {
                // after q where q's exit is near an entry of c; before q where q's entry is
                // near an exit of c; from an evenly spaced share of a cell's modes when it has
                // many (each place tries every mode: O(modes²) per cell otherwise)
                let step = m.modes(cu).div_ceil(MAX_SEARCH_MODES);
                for md in (0..m.modes(cu)).step_by(step) {
                    let nd = m.node(cu, md);
                    for (grid, at, before) in
                        [(exits, m.entry(nd), false), (entries, m.exit(nd), true)]
                    {
                        let (mut found, mut scanned) = (0usize, 0usize);
                        grid.rings(at, |q| {
                            scanned += 1;
                            let a = if before {
                                path.list.prev[q as usize]
                            } else {
                                q
                            };
                            if path.list.after(a) >= floor && a != after {
                                consider(a, &mut best);
                                found += 1;
                            }
                            found < k && scanned < SCAN * k
                        });
                    }
                }
            }
            None => {
                for &q in &inserted {
                    if path.list.after(q) >= floor {
                        consider(q, &mut best);
                    }
                }
            }
        }
        count(evals);
        let (_, a, md) = best;
        path.list.insert_after(a, c);
        path.mode[cu] = md;
        match &mut grids {
            Some((exits, entries)) => {
                let nd = m.node(cu, md as usize);
                exits.add(m.exit(nd), c);
                entries.add(m.entry(nd), c);
            }
            None => inserted.push(c),
        }
    }
    path.sequence()
}

//! Position-indexed path relaxation ("q-path" state-space relaxation) with Lagrangian
//! multipliers on the cells, as a lower bound and as an O(1) table for tree search.
//!
//! A feasible sequence puts every cell `j` at a position `p` (1-based among the `n` cells) with
//! `ancestors(j) ≤ p − 1` and `descendants(j) ≤ n − p` (its *window*), uses only arcs that the
//! precedence closure allows, and never returns to the cell it just left. Relaxing "each cell
//! exactly once" leaves a shortest walk in the layered graph (position, node) — a DP in
//! O(n · arcs). With multipliers `λ` per cell, arcs into cell `j` cost `c − λ_j`, and
//! `L(λ) = constant + min walk + Σ λ` is a lower bound for every `λ`; subgradient steps raise it.
//!
//! The table of the best `λ` also bounds every prefix: a prefix of `p` cells ending in node `l`
//! is completed by a walk from `(p, l)` through the unvisited set `U` to home, so its cost is at
//! least `h(p, l) + Σ_U λ` ([`QPath::completion`]). Dense precedence (narrow windows) makes the
//! bound strong: on rbg048a the root value is 348.8 against an optimum of 351.

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::precedence::Closure;

const NONE: u32 = u32::MAX;

/// Multipliers and completion table of the position-indexed path relaxation.
#[derive(Debug, Clone)]
pub struct QPath {
    n: usize,
    nodes: usize,
    /// multipliers per cell
    lambda: Vec<f64>,
    /// Σ λ over all cells
    lambda_total: f64,
    /// `h[(p − 1) · nodes + node]`: cheapest relaxed completion (costs `c − λ`) from `node`
    /// at position `p` to home (∞ when none)
    h: Vec<f64>,
    /// The root bound `L(λ)` of the best multipliers, constant included.
    pub root: f64,
    /// Subgradient iterations run.
    pub iterations: usize,
}

/// Layered graph: successor arcs in compressed rows (node, cell, cost per arc; the arcs of
/// node `a` are `first[a]..first[a + 1]`, by increasing cost, `rank` their place in (cell,
/// mode) order) and the windows.
struct Graph {
    n: usize,
    nodes: usize,
    cell: Vec<u32>,
    first: Vec<usize>,
    to: Vec<u32>,
    to_cell: Vec<u32>,
    cost: Vec<f64>,
    rank: Vec<u32>,
    /// largest |cost| of an arc, start or finish (for the early end's rounding margin)
    scale: f64,
    start: Vec<f64>,
    finish: Vec<f64>,
    /// per cell: first and last allowed position (1-based)
    window: Vec<(usize, usize)>,
}

/// One DP pass: best and second-best (different next cell) completion per (position, node),
/// with the cell of the best next node (`c1`, [`NONE`] when there is none) kept beside it so
/// that the pass reads it without a lookup. `arc` is scratch: every arc's cost net of the
/// multiplier of the cell it enters.
struct Dp {
    h1: Vec<f64>,
    n1: Vec<u32>,
    c1: Vec<u32>,
    h2: Vec<f64>,
    n2: Vec<u32>,
    arc: Vec<f64>,
}

impl Dp {
    fn new(size: usize, arcs: usize) -> Dp {
        Dp {
            h1: vec![0.0; size],
            n1: vec![NONE; size],
            c1: vec![NONE; size],
            h2: vec![0.0; size],
            n2: vec![NONE; size],
            arc: vec![0.0; arcs],
        }
    }
}

impl Graph {
    /// `shift(i, j)` (cells, home = n) is subtracted from every arc cost.
    fn new(m: &CostModel, cl: &Closure, shift: &dyn Fn(usize, usize) -> f64) -> Graph {
        let n = m.n();
        let nodes = m.nodes();
        let cell: Vec<u32> = (0..nodes).map(|nd| m.cell_mode(nd).0 as u32).collect();
        let mut first = Vec::with_capacity(nodes + 1);
        let (mut to, mut to_cell, mut cost) = (Vec::new(), Vec::new(), Vec::new());
        let mut row: Vec<(f64, u32, u32, u32)> = Vec::new();
        let mut rank = Vec::new();
        let mut start = vec![f64::INFINITY; nodes];
        let mut finish = vec![f64::INFINITY; nodes];
        for a in 0..nodes {
            first.push(to.len());
            let (ca, ma) = m.cell_mode(a);
            if cl.can_be_first(ca) {
                start[a] = m.start(ca, ma);
            }
            if cl.can_be_last(ca) {
                finish[a] = m.finish(ca, ma) - shift(ca, n);
            }
            row.clear();
            for cb in 0..n {
                if !cl.arc_allowed(ca, cb) {
                    continue;
                }
                for mb in 0..m.modes(cb) {
                    let c = m.arc(ca, ma, cb, mb) - shift(ca, cb);
                    if c.is_finite() {
                        row.push((c, row.len() as u32, m.node(cb, mb) as u32, cb as u32));
                    }
                }
            }
            row.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            for &(c, r, b, cb) in &row {
                cost.push(c);
                rank.push(r);
                to.push(b);
                to_cell.push(cb);
            }
        }
        first.push(to.len());
        let scale = cost
            .iter()
            .chain(&start)
            .chain(&finish)
            .filter(|c| c.is_finite())
            .fold(0.0f64, |s, c| s.max(c.abs()));
        let window = (0..n)
            .map(|j| (cl.ancestors(j) + 1, n - cl.descendants(j)))
            .collect();
        Graph {
            n,
            nodes,
            cell,
            first,
            to,
            to_cell,
            cost,
            rank,
            scale,
            start,
            finish,
            window,
        }
    }

    fn in_window(&self, cell: usize, p: usize) -> bool {
        let (lo, hi) = self.window[cell];
        lo <= p && p <= hi
    }

    /// The completion tables for multipliers `lambda`: per (position, node) the cheapest
    /// walk to home and the cheapest one whose next cell differs from the first's (a walk
    /// never returns at once to the cell it just left). O(n · arcs) at most. Every arc's cost
    /// net of its multiplier is computed once per pass, before the layers, and the cell of
    /// each best next node is stored beside it; a row's arcs come by increasing cost, so its
    /// scan ends once no later arc can beat the second best (on random costs most rows end
    /// after a few arcs).
    fn dp(&self, lambda: &[f64], dp: &mut Dp) {
        let (n, nn) = (self.n, self.nodes);
        dp.h1.fill(f64::INFINITY);
        dp.h2.fill(f64::INFINITY);
        dp.n1.fill(NONE);
        dp.c1.fill(NONE);
        dp.n2.fill(NONE);
        for ((a, &c), &cb) in dp.arc.iter_mut().zip(&self.cost).zip(&self.to_cell) {
            *a = c - lambda[cb as usize];
        }
        for a in 0..nn {
            if self.in_window(self.cell[a] as usize, n) {
                dp.h1[(n - 1) * nn + a] = self.finish[a];
            }
        }
        // every computed value lies within a few roundings of its exact value, each at most
        // 2⁻⁵² of the magnitudes summed: this margin keeps the early end below exact
        let lmax = lambda.iter().fold(0.0f64, |s, l| s.max(l.abs()));
        for p in (1..n).rev() {
            let (row, next) = ((p - 1) * nn, p * nn);
            // the layer written (row) lies before the one read (next)
            let (h1w, h1) = dp.h1.split_at_mut(next);
            let (c1w, c1) = dp.c1.split_at_mut(next);
            let (h2w, h2) = dp.h2.split_at_mut(next);
            // the least completion net of its cell's multiplier: an arc of cost c then
            // costs at least c + low, and the arcs of a row come by increasing cost
            let (mut low, mut hmax) = (f64::INFINITY, 0.0f64);
            for (b, &h) in h1[..nn].iter().enumerate() {
                if h.is_finite() {
                    low = low.min(h - lambda[self.cell[b] as usize]);
                    hmax = hmax.max(h.abs());
                }
            }
            let margin = 1e-9 * (self.scale + lmax + hmax + 1.0);
            for a in 0..nn {
                let ca = self.cell[a];
                if !self.in_window(ca as usize, p) {
                    continue;
                }
                // best and second best (another cell) by value, then by (cell, mode) order:
                // the choice a scan in that order with strict comparisons makes (rank 0 while
                // unset: an unreachable ∞ never ties its way in)
                let (mut b1, mut x1, mut y1, mut r1) = (f64::INFINITY, NONE, NONE, 0);
                let (mut b2, mut x2, mut r2) = (f64::INFINITY, NONE, 0);
                let arcs = self.first[a]..self.first[a + 1];
                for (((&b, &cb), &c), (&raw, &r)) in self.to[arcs.clone()]
                    .iter()
                    .zip(&self.to_cell[arcs.clone()])
                    .zip(&dp.arc[arcs.clone()])
                    .zip(self.cost[arcs.clone()].iter().zip(&self.rank[arcs]))
                {
                    if raw + low > b2 + margin {
                        // this arc and every later one end above the second best
                        break;
                    }
                    let b = b as usize;
                    // an unreachable completion (∞) never enters: ∞ < b1 and ∞ < b2 fail
                    let v = c + if c1[b] != ca { h1[b] } else { h2[b] };
                    if v < b1 || (v == b1 && r < r1) {
                        if y1 != cb {
                            (b2, x2, r2) = (b1, x1, r1);
                        }
                        (b1, x1, y1, r1) = (v, b as u32, cb, r);
                    } else if (v < b2 || (v == b2 && r < r2)) && y1 != cb {
                        (b2, x2, r2) = (v, b as u32, r);
                    }
                }
                let k = row + a;
                (h1w[k], c1w[k], h2w[k]) = (b1, y1, b2);
                (dp.n1[k], dp.n2[k]) = (x1, x2);
            }
        }
    }

    /// Root value of the walk (without Σλ) and how often it visits each cell.
    fn root(&self, lambda: &[f64], dp: &Dp, count: &mut [i32]) -> f64 {
        let nn = self.nodes;
        let mut best = (f64::INFINITY, NONE);
        for a in 0..nn {
            let v = self.start[a] - lambda[self.cell[a] as usize] + dp.h1[a];
            if v < best.0 {
                best = (v, a as u32);
            }
        }
        count.fill(0);
        if best.1 == NONE {
            return f64::INFINITY;
        }
        let (mut a, mut prev) = (best.1 as usize, NONE);
        for p in 1..=self.n {
            count[self.cell[a] as usize] += 1;
            if p == self.n {
                break;
            }
            let k = (p - 1) * nn + a;
            let nx = if dp.n1[k] == NONE || self.cell[dp.n1[k] as usize] != prev {
                dp.n1[k]
            } else {
                dp.n2[k]
            };
            if nx == NONE {
                break;
            }
            prev = self.cell[a];
            a = nx as usize;
        }
        best.0
    }
}

impl QPath {
    /// Runs up to `iterations` subgradient steps (Polyak steps towards `upper`, the cost of a
    /// known solution with the constant, when given) and keeps the table of the best
    /// multipliers. `None` when the precedence has a cycle or the instance is empty.
    pub fn new(m: &CostModel, upper: Option<f64>, iterations: usize) -> Option<QPath> {
        QPath::shifted(m, upper, iterations, None, Deadline::NONE)
    }

    /// Like [`QPath::new`] on the arc costs `c(i, j) − μ(i, j)`, where `shift = (μ, Σ μ_S,
    /// λ₀)` comes from [`super::sec::SecBound`]: `μ` is its dense arc-multiplier matrix
    /// (cells and home, `n + 1` columns) and `Σ μ_S` is added to the root value (every set
    /// must be left). The subgradient starts from the multipliers `λ₀`. A prefix's completion
    /// ([`QPath::completion`]) then bounds the rest in the shifted costs only: add `Σ μ_S`
    /// over the sets that the rest must still leave. The subgradient steps stop at
    /// `deadline` with the best multipliers so far; `None` when it passes before the first
    /// step.
    pub fn shifted(
        m: &CostModel,
        upper: Option<f64>,
        iterations: usize,
        shift: Option<(&[f64], f64, &[f64])>,
        deadline: Deadline,
    ) -> Option<QPath> {
        let n = m.n();
        if n == 0 {
            return None;
        }
        let cl = Closure::new(&m.dag)?;
        let d = n + 1;
        let g = match shift {
            Some((mu, _, _)) => Graph::new(m, &cl, &|i, j| mu[i * d + j]),
            None => Graph::new(m, &cl, &|_, _| 0.0),
        };
        let base = shift.map_or(0.0, |s| s.1);
        let nn = g.nodes;
        let mut dp = Dp::new(n * nn, g.to.len());
        let constant = m.constant() + base;
        let upper = upper.map(|u| u - constant);
        let mut lambda = match shift {
            Some((_, _, l0)) if l0.len() == n => l0.to_vec(),
            _ => vec![0.0; n],
        };
        let mut best_lambda = lambda.clone();
        let mut best = f64::NEG_INFINITY;
        let mut count = vec![0i32; n];
        let mut theta = 2.0;
        let mut stale = 0;
        let mut done = 0;
        for it in 0..iterations.max(1) {
            if deadline.passed() {
                if it == 0 {
                    return None;
                }
                break;
            }
            done = it + 1;
            g.dp(&lambda, &mut dp);
            let walk = g.root(&lambda, &dp, &mut count);
            if !walk.is_finite() {
                return None;
            }
            let value = walk + lambda.iter().sum::<f64>();
            if it == 0 || value > best + 1e-9 * best.abs().max(1.0) {
                best = value;
                best_lambda.copy_from_slice(&lambda);
                stale = 0;
            } else {
                stale += 1;
                if stale >= 20 {
                    theta /= 2.0;
                    stale = 0;
                }
            }
            let norm: i64 = count.iter().map(|&c| ((1 - c) * (1 - c)) as i64).sum();
            if norm == 0 || theta < 1e-4 {
                break;
            }
            if let Some(u) = upper
                && best >= u - 1e-9 * u.abs().max(1.0)
            {
                break;
            }
            let target = upper.unwrap_or(best + 0.05 * best.abs().max(1.0));
            let step = theta * (target - value).max(1e-6 * best.abs().max(1.0)) / norm as f64;
            for (l, &c) in lambda.iter_mut().zip(&count) {
                *l += step * (1 - c) as f64;
            }
        }
        g.dp(&best_lambda, &mut dp);
        let walk = g.root(&best_lambda, &dp, &mut count);
        let lambda_total = best_lambda.iter().sum::<f64>();
        Some(QPath {
            n,
            nodes: nn,
            root: constant + walk + lambda_total,
            lambda: best_lambda,
            lambda_total,
            h: dp.h1,
            iterations: done,
        })
    }

    /// Multiplier of a cell.
    #[inline]
    pub fn lambda(&self, cell: usize) -> f64 {
        self.lambda[cell]
    }

    /// Σ λ over all cells.
    pub fn lambda_total(&self) -> f64 {
        self.lambda_total
    }

    /// Lower bound on the cost of completing a prefix of `p` cells (1 ≤ p ≤ n) that ends in
    /// `node`, up to and including the finish, where `lambda_open` = Σ λ over the cells not
    /// yet visited. ∞ when no completion exists.
    #[inline]
    pub fn completion(&self, p: usize, node: usize, lambda_open: f64) -> f64 {
        debug_assert!(p >= 1 && p <= self.n);
        self.h[(p - 1) * self.nodes + node] + lambda_open
    }
}

/// Subgradient iterations affordable within about `work` arc evaluations.
pub fn affordable_iterations(m: &CostModel, work: f64, max: usize) -> usize {
    let n = m.n() as f64;
    let nodes = m.nodes() as f64;
    let per = (n * nodes * nodes).max(1.0);
    ((work / per) as usize).min(max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::generate::generate;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::collections::BTreeMap;

    /// The completion tables straight from the definition: per (position, node), over every
    /// allowed (cell, mode) after it in its window, the cheapest `arc − λ + completion`,
    /// never back to the node's own cell at once; ties to the first in (cell, mode) order.
    fn reference(m: &CostModel, lambda: &[f64]) -> (Vec<f64>, Vec<u32>, Vec<f64>, Vec<u32>) {
        let (n, nn) = (m.n(), m.nodes());
        let cl = Closure::new(&m.dag).unwrap();
        let window = |c: usize, p: usize| cl.ancestors(c) < p && p <= n - cl.descendants(c);
        let (mut h1, mut n1) = (vec![f64::INFINITY; n * nn], vec![NONE; n * nn]);
        let (mut h2, mut n2) = (vec![f64::INFINITY; n * nn], vec![NONE; n * nn]);
        for a in 0..nn {
            let (ca, ma) = m.cell_mode(a);
            if window(ca, n) && cl.can_be_last(ca) {
                h1[(n - 1) * nn + a] = m.finish(ca, ma);
            }
        }
        for p in (1..n).rev() {
            for a in 0..nn {
                let (ca, ma) = m.cell_mode(a);
                if !window(ca, p) {
                    continue;
                }
                let mut cands: Vec<(f64, u32, usize)> = Vec::new();
                for cb in (0..n).filter(|&cb| cl.arc_allowed(ca, cb)) {
                    for mb in 0..m.modes(cb) {
                        let b = m.node(cb, mb);
                        let c = m.arc(ca, ma, cb, mb);
                        let k = p * nn + b;
                        let back = n1[k] != NONE && m.cell_mode(n1[k] as usize).0 == ca;
                        let h = if back { h2[k] } else { h1[k] };
                        if c.is_finite() && h.is_finite() {
                            cands.push((c - lambda[cb] + h, b as u32, cb));
                        }
                    }
                }
                let k = (p - 1) * nn + a;
                // the first minimum, then the first minimum among the other cells
                if let Some((v, b, cb)) = first_min(cands.iter()) {
                    (h1[k], n1[k]) = (v, b);
                    if let Some((v2, b2, _)) = first_min(cands.iter().filter(|x| x.2 != cb)) {
                        (h2[k], n2[k]) = (v2, b2);
                    }
                }
            }
        }
        (h1, n1, h2, n2)
    }

    /// The first candidate of least value.
    fn first_min<'a>(
        it: impl Iterator<Item = &'a (f64, u32, usize)>,
    ) -> Option<(f64, u32, usize)> {
        it.fold(None, |best, &x| match best {
            Some(y) if y.0 <= x.0 => Some(y),
            _ => Some(x),
        })
    }

    fn instance(kind: &str, params: &[(&str, &str)], seed: u64) -> CostModel {
        let kv: BTreeMap<String, String> = params
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let inst = generate(kind, &kv, seed).unwrap();
        CostModel::new(&inst, inst.default_objective())
    }

    #[test]
    fn the_layered_pass_matches_the_definition() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for seed in 1..=4 {
            let models = [
                instance("symmetric", &[("n", "30"), ("c", "20"), ("p", "5")], seed),
                instance("random-sop", &[("n", "25"), ("c", "10"), ("p", "40")], seed),
                instance("generalized", &[("n", "14"), ("modes", "3"), ("open", "0.5")], seed),
                instance("time-window", &[("n", "30"), ("w", "4")], seed),
            ];
            for m in &models {
                let cl = Closure::new(&m.dag).unwrap();
                let g = Graph::new(m, &cl, &|_, _| 0.0);
                let mut dp = Dp::new(m.n() * m.nodes(), g.to.len());
                for round in 0..3 {
                    // multipliers of the size the subgradient steps reach, zero in round 0
                    let lambda: Vec<f64> = (0..m.n())
                        .map(|_| if round == 0 { 0.0 } else { rng.random_range(-30.0..30.0) })
                        .collect();
                    g.dp(&lambda, &mut dp);
                    let (h1, n1, h2, n2) = reference(m, &lambda);
                    assert_eq!(dp.n1, n1, "best next nodes, seed {seed}");
                    assert_eq!(dp.n2, n2, "second next nodes, seed {seed}");
                    let same = |a: &[f64], b: &[f64]| {
                        a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
                    };
                    assert!(same(&dp.h1, &h1), "best completions, seed {seed}");
                    assert!(same(&dp.h2, &h2), "second completions, seed {seed}");
                }
            }
        }
    }
}

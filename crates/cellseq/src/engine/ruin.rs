//! Ruin and recreate: a perturbation that removes a few strings of cells around a random
//! seed cell and inserts every removed cell again at its cheapest feasible place.
//!
//! The ruin follows the string removal of SISR (Christiaens and Vanden Berghe, "Slack
//! induction by string removals for vehicle routing problems", Transportation Science 2020):
//! the seed's candidate neighbours, in order, each lose a string of consecutive cells around
//! them, so the removed cells lie close together in cost but far apart in the sequence. The
//! recreate takes the removed cells in a random topological order of the precedence among
//! them (predecessors first) and puts each at the cheapest place inside its window, in its
//! best mode, skipping each place with a small "blink" probability. The window of a cell is
//! bounded by its kept predecessors and successors and, through removed successors not yet
//! back, by theirs, so every partial sequence can still be completed.
//!
//! Unlike a segment swap or a window shuffle, one kick moves cells that are far apart in the
//! sequence into new places at once, which is what sparse pickup-before-delivery precedence
//! (TSPLIB's prob.100) needs.

use super::{Costs, Neighbours, Solution};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// Places with more candidates than this are not all evaluated: only the candidate
/// neighbours' places and the window's ends are.
const FULL_SCAN: usize = 256;

/// Parameters and scratch space of the ruin and recreate kick.
#[derive(Debug, Clone)]
pub struct Ruin {
    /// Average number of removed cells.
    pub avg: usize,
    /// Longest removed string.
    pub max_string: usize,
    /// Probability of skipping a place during the recreate.
    pub blink: f64,
    removed: Vec<bool>,
    cells: Vec<u32>,
    /// Index in `cells` of each removed cell.
    index: Vec<u32>,
    seq: Vec<u32>,
    at: Vec<u32>,
    missing: Vec<u32>,
    ready: Vec<u32>,
    /// Search scratch of [`Ruin::upper`]: a visit label per cell and the current label.
    visited: Vec<u32>,
    label: u32,
    stack: Vec<u32>,
}

impl Ruin {
    /// A kick removing about `avg` cells in strings of at most `max_string` cells.
    pub fn new(avg: usize, max_string: usize, blink: f64) -> Self {
        Ruin {
            avg: avg.max(1),
            max_string: max_string.max(1),
            blink,
            removed: Vec::new(),
            cells: Vec::new(),
            index: Vec::new(),
            seq: Vec::new(),
            at: Vec::new(),
            missing: Vec::new(),
            ready: Vec::new(),
            visited: Vec::new(),
            label: 0,
            stack: Vec::new(),
        }
    }

    /// Kicks `s`: ruin and recreate. Pushes the removed cells and their new neighbours onto
    /// `seeds` (for a focused repair) and returns the number of evaluated places, or `None`
    /// when `s` is too short to kick.
    pub fn kick(
        &mut self,
        c: &Costs,
        nb: &Neighbours,
        s: &mut Solution,
        rng: &mut ChaCha8Rng,
        seeds: &mut Vec<u32>,
    ) -> Option<u64> {
        let n = s.n();
        if n < 4 {
            return None;
        }
        self.ruin(nb, s, rng);
        let evals = self.recreate(c, nb, s, rng);
        // write back: the whole order (the kick is O(n) anyway), new modes, exact cost
        let seq = std::mem::take(&mut self.seq);
        s.rewrite(0, &seq, 0.0);
        s.cost = s.evaluate(c);
        self.seq = seq;
        for &x in &self.cells {
            let p = s.pos[x as usize] as isize;
            for q in [p - 1, p, p + 1] {
                if q >= 0 && (q as usize) < n {
                    seeds.push(s.order[q as usize]);
                }
            }
        }
        Some(evals)
    }

    /// Marks the removed cells (`self.cells`, `self.removed`) and leaves the kept ones in
    /// `self.seq` with their indices in `self.at`.
    fn ruin(&mut self, nb: &Neighbours, s: &Solution, rng: &mut ChaCha8Rng) {
        let n = s.n();
        self.removed.clear();
        self.removed.resize(n, false);
        self.index.resize(n, 0);
        self.cells.clear();
        let lmax = self.max_string.min(n / 4).max(1);
        // SISR: strings = U(1, 4·avg / (1 + lmax)) so that about avg cells go
        let ks_max = (4 * self.avg / (1 + lmax)).max(1);
        let strings = rng.random_range(1..=ks_max);
        let x = rng.random_range(0..n) as u32;
        let around = std::iter::once(x)
            .chain(nb.out[x as usize].iter().copied())
            .chain(nb.inn[x as usize].iter().copied());
        let mut done = 0;
        for y in around {
            if done == strings || self.cells.len() >= n / 2 {
                break;
            }
            if self.removed[y as usize] {
                continue;
            }
            let len = rng.random_range(1..=lmax);
            let p = s.pos[y as usize] as usize;
            let start = p.saturating_sub(rng.random_range(0..len)).min(n - len);
            for q in start..start + len {
                let z = s.order[q];
                if !self.removed[z as usize] {
                    self.removed[z as usize] = true;
                    self.index[z as usize] = self.cells.len() as u32;
                    self.cells.push(z);
                }
            }
            done += 1;
        }
        self.seq.clear();
        self.seq.extend(
            s.order
                .iter()
                .copied()
                .filter(|&z| !self.removed[z as usize]),
        );
        self.at.clear();
        self.at.resize(n, u32::MAX);
        if self.visited.len() != n {
            self.visited = vec![0; n];
            self.label = 0;
        }
        for (i, &z) in self.seq.iter().enumerate() {
            self.at[z as usize] = i as u32;
        }
    }

    /// The latest index a removed cell may be inserted at (before the cell there): the
    /// smallest index of a cell in the sequence that `x` reaches directly or through removed
    /// cells not yet back. One search over those cells, each visited once (following every
    /// path instead would be exponential on dense precedence).
    fn upper(&mut self, c: &Costs, x: u32) -> usize {
        self.label = self.label.wrapping_add(1);
        if self.label == 0 {
            self.visited.fill(0);
            self.label = 1;
        }
        let mut hi = self.seq.len();
        self.stack.clear();
        self.stack.push(x);
        while let Some(y) = self.stack.pop() {
            for &z in &c.m.dag.succs[y as usize] {
                let zs = z as usize;
                if self.at[zs] != u32::MAX {
                    hi = hi.min(self.at[zs] as usize);
                } else if self.visited[zs] != self.label {
                    self.visited[zs] = self.label;
                    self.stack.push(z);
                }
            }
        }
        hi
    }

    /// Inserts the removed cells again (random topological order, cheapest place, best
    /// mode); returns the number of evaluated places.
    fn recreate(
        &mut self,
        c: &Costs,
        nb: &Neighbours,
        s: &mut Solution,
        rng: &mut ChaCha8Rng,
    ) -> u64 {
        let m = c.m;
        let mut evals = 0u64;
        // removed predecessors still missing, per removed cell
        self.missing.clear();
        self.ready.clear();
        for (k, &x) in self.cells.iter().enumerate() {
            let k_missing = m.dag.preds[x as usize]
                .iter()
                .filter(|&&p| self.removed[p as usize])
                .count() as u32;
            self.missing.push(k_missing);
            if k_missing == 0 {
                self.ready.push(k as u32);
            }
        }
        let mut placed = 0;
        while !self.ready.is_empty() {
            let r = rng.random_range(0..self.ready.len());
            let k = self.ready.swap_remove(r) as usize;
            let x = self.cells[k];
            let xs = x as usize;
            let lo = m.dag.preds[xs]
                .iter()
                .map(|&p| self.at[p as usize] as usize + 1)
                .max()
                .unwrap_or(0);
            let hi = self.upper(c, x);
            debug_assert!(lo <= hi, "recreate window empty");
            let slot = |i: usize| -> super::Slot {
                self.seq
                    .get(i)
                    .map(|&z| (z as usize, s.mode[z as usize] as usize))
            };
            let prev = |g: usize| if g == 0 { None } else { slot(g - 1) };
            let mut best = (f64::INFINITY, lo, s.mode[xs]);
            let try_gap = |g: usize, best: &mut (f64, usize, u32), evals: &mut u64| {
                let (l, r) = (prev(g), slot(g));
                let open = c.link(l, r);
                *evals += m.modes(xs) as u64;
                let (d, md) = c.cheapest_between(-open, l, xs, r);
                if d < best.0 {
                    *best = (d, g, md as u32);
                }
            };
            if hi - lo <= FULL_SCAN {
                for g in lo..=hi {
                    if g != lo && self.blink > 0.0 && rng.random_bool(self.blink) {
                        continue;
                    }
                    try_gap(g, &mut best, &mut evals);
                }
            } else {
                try_gap(lo, &mut best, &mut evals);
                try_gap(hi, &mut best, &mut evals);
                for &w in nb.inn[xs].iter().chain(nb.out[xs].iter()) {
                    let i = self.at[w as usize];
                    if i == u32::MAX {
                        continue;
                    }
                    for g in [i as usize, i as usize + 1] {
                        if g >= lo && g <= hi {
                            try_gap(g, &mut best, &mut evals);
                        }
                    }
                }
            }
            let (_, g, md) = best;
            self.seq.insert(g, x);
            for i in g..self.seq.len() {
                self.at[self.seq[i] as usize] = i as u32;
            }
            s.mode[xs] = md;
            placed += 1;
            for &q in &m.dag.succs[xs] {
                if self.removed[q as usize] {
                    let kq = self.index[q as usize] as usize;
                    self.missing[kq] -= 1;
                    if self.missing[kq] == 0 {
                        self.ready.push(kq as u32);
                    }
                }
            }
        }
        debug_assert_eq!(placed, self.cells.len());
        evals
    }
}

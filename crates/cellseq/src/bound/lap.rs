//! The linear assignment problem by shortest augmenting paths on sparse row lists
//! (Jonker–Volgenant's augmentation, a Hungarian-type method), exact on the full matrix.
//!
//! Every row starts with its [`LIST_LEN`] cheapest finite arcs. Each free row is matched by a
//! Dijkstra search over reduced costs `c(i, j) − v(j)` (a heap, so a step costs O(list ·
//! log d), not O(d) as in the dense method), after which the column prices of the columns it
//! settled move by their distances. When every row is matched, every arc left out of the lists
//! is checked against the duals (O(d²) once per round): a row with an arc of negative reduced
//! cost gets those arcs and is matched again. When a search runs out of listed arcs before it
//! finds a free column, the rows it reached get every finite arc. So the result is an optimal
//! assignment of the full matrix with feasible duals, whatever the lists missed.
//!
//! Why not the dense method: on matrices with many equal costs (small cost ranges: most
//! optimal arcs cost 0) its searches settle columns of equal distance one at a time, each for
//! an O(d) scan, and the method takes its full O(d³) (2.0 s at d = 1002 against 0.09 s with
//! costs ten times as spread).

use super::assignment::Assignment;
use crate::clock::Deadline;
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// Arcs per row in the first lists (the cheapest ones).
pub const LIST_LEN: usize = 12;

/// Marks a free row or column.
const FREE: usize = usize::MAX;

/// A fixed pseudo-random order of the arcs of equal cost (a multiplicative hash).
fn tie_hash(i: usize, j: usize) -> u64 {
    ((i as u64) << 32 ^ j as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15).rotate_left(29)
}

/// A heap entry: a column at a tentative distance, least distance (then column) first.
#[derive(Clone, Copy, PartialEq)]
struct Entry(f64, usize);

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// The solver's state: row lists, the matching, column prices and the search's scratch.
struct Lap<F> {
    d: usize,
    cost: F,
    /// Row lists: (column, cost), finite arcs only.
    rows: Vec<Vec<(usize, f64)>>,
    /// Whether a row's list holds every finite arc of the row.
    full: Vec<bool>,
    /// Column of each row, row of each column (`FREE` when unmatched).
    x: Vec<usize>,
    y: Vec<usize>,
    /// Cost of each row's matched arc.
    xc: Vec<f64>,
    /// Column prices.
    v: Vec<f64>,
    dist: Vec<f64>,
    pred: Vec<usize>,
    settled: Vec<bool>,
    touched: Vec<usize>,
}

/// How a search for one free row ended.
enum Search {
    /// The row is matched.
    Matched,
    /// No free column is reachable on the listed arcs: these rows' lists were not full.
    Stuck(Vec<usize>),
    /// No free column is reachable on any finite arc: no finite assignment exists.
    Infeasible,
}

impl<F: Fn(usize, usize) -> f64> Lap<F> {
    fn new(d: usize, cost: F) -> Self {
        let mut rows = Vec::with_capacity(d);
        let mut full = Vec::with_capacity(d);
        for i in 0..d {
            let mut r: Vec<(usize, f64)> = (0..d)
                .map(|j| (j, cost(i, j)))
                .filter(|a| a.1.is_finite())
                .collect();
            full.push(r.len() <= LIST_LEN);
            if r.len() > LIST_LEN {
                // equal costs by a hash of the arc, so that the lists of rows with many
                // equal cheapest arcs spread over the columns instead of all taking the first
                let key = |a: &(usize, f64)| (a.1, tie_hash(i, a.0));
                r.select_nth_unstable_by(LIST_LEN - 1, |a, b| {
                    let (ka, kb) = (key(a), key(b));
                    ka.0.total_cmp(&kb.0).then(ka.1.cmp(&kb.1))
                });
                r.truncate(LIST_LEN);
            }
            r.sort_unstable_by_key(|a| a.0);
            rows.push(r);
        }
        Lap {
            d,
            cost,
            rows,
            full,
            x: vec![FREE; d],
            y: vec![FREE; d],
            xc: vec![0.0; d],
            v: vec![0.0; d],
            dist: vec![f64::INFINITY; d],
            pred: vec![FREE; d],
            settled: vec![false; d],
            touched: Vec::new(),
        }
    }

    /// Row `i`'s dual: the reduced cost of its matched arc.
    fn u(&self, i: usize) -> f64 {
        self.xc[i] - self.v[self.x[i]]
    }

    /// Matches every row to a free column among its cheapest listed arcs (prices are 0, so
    /// any of them keeps the row's matched arc of least reduced cost); ties, the common case
    /// of small cost ranges, spread the rows over the columns.
    fn greedy_start(&mut self) -> Vec<usize> {
        let mut free = Vec::new();
        for i in 0..self.d {
            let least = self.rows[i].iter().map(|a| a.1).fold(f64::INFINITY, f64::min);
            let pick = self.rows[i]
                .iter()
                .find(|&&(j, c)| c == least && self.y[j] == FREE)
                .copied();
            match pick {
                Some((j, c)) => {
                    self.x[i] = j;
                    self.y[j] = i;
                    self.xc[i] = c;
                }
                None => free.push(i),
            }
        }
        free
    }

    fn relax(&mut self, heap: &mut BinaryHeap<Entry>, i: usize, base: f64) {
        for &(j, c) in &self.rows[i] {
            if self.settled[j] {
                continue;
            }
            let nd = base + c - self.v[j];
            if nd < self.dist[j] {
                if self.dist[j] == f64::INFINITY {
                    self.touched.push(j);
                }
                self.dist[j] = nd;
                self.pred[j] = i;
                heap.push(Entry(nd, j));
            }
        }
    }

    /// One Dijkstra search from free row `r` and, when it finds a free column, the price
    /// update and the augmentation along the path.
    fn search(&mut self, r: usize) -> Search {
        let mut heap = BinaryHeap::new();
        let mut settled_cols = Vec::new();
        self.relax(&mut heap, r, 0.0);
        let mut end = None;
        while let Some(Entry(dj, j)) = heap.pop() {
            if self.settled[j] || dj > self.dist[j] {
                continue;
            }
            if self.y[j] == FREE {
                end = Some((j, dj));
                break;
            }
            self.settled[j] = true;
            settled_cols.push(j);
            let i = self.y[j];
            let base = dj - self.u(i);
            self.relax(&mut heap, i, base);
        }
        let outcome = match end {
            Some((j_end, mu)) => {
                for &j in &settled_cols {
                    self.v[j] += self.dist[j] - mu;
                }
                let mut j = j_end;
                loop {
                    let i = self.pred[j];
                    let prev = self.x[i];
                    self.y[j] = i;
                    self.x[i] = j;
                    self.xc[i] = (self.cost)(i, j);
                    if i == r {
                        break;
                    }
                    j = prev;
                }
                Search::Matched
            }
            None => {
                let mut reached: Vec<usize> = settled_cols.iter().map(|&j| self.y[j]).collect();
                reached.push(r);
                reached.retain(|&i| !self.full[i]);
                if reached.is_empty() {
                    Search::Infeasible
                } else {
                    Search::Stuck(reached)
                }
            }
        };
        for &j in &settled_cols {
            self.settled[j] = false;
        }
        for &j in &self.touched {
            self.dist[j] = f64::INFINITY;
            self.pred[j] = FREE;
        }
        self.touched.clear();
        outcome
    }

    /// Adds to row `i`'s list every finite arc whose reduced cost is below the row's dual
    /// (all of them when `all`); true when some added arc is below it (the row must be matched
    /// again).
    fn widen(&mut self, i: usize, all: bool) -> bool {
        let mut listed = vec![false; self.d];
        for &(j, _) in &self.rows[i] {
            listed[j] = true;
        }
        let u = if self.x[i] == FREE { f64::INFINITY } else { self.u(i) };
        let mut below = false;
        for (j, &seen) in listed.iter().enumerate() {
            if seen {
                continue;
            }
            let c = (self.cost)(i, j);
            if !c.is_finite() {
                continue;
            }
            let red = c - self.v[j];
            let violated = red < u - 1e-9 * (1.0 + u.abs().min(red.abs()));
            if violated || all {
                self.rows[i].push((j, c));
                below |= violated;
            }
        }
        if all {
            self.full[i] = true;
        }
        below
    }

    /// Unmatches row `i` (its column becomes free).
    fn unmatch(&mut self, i: usize) {
        if self.x[i] != FREE {
            self.y[self.x[i]] = FREE;
            self.x[i] = FREE;
        }
    }

    fn run(mut self, deadline: Deadline) -> Option<Assignment> {
        let mut free = self.greedy_start();
        loop {
            while let Some(r) = free.pop() {
                if deadline.passed() {
                    return None;
                }
                match self.search(r) {
                    Search::Matched => {}
                    Search::Infeasible => return None,
                    Search::Stuck(rows) => {
                        for i in rows {
                            if self.widen(i, true) && i != r {
                                self.unmatch(i);
                                free.push(i);
                            }
                        }
                        free.push(r);
                    }
                }
            }
            // every row matched: the left-out arcs against the duals
            for i in 0..self.d {
                if !self.full[i] && self.widen(i, false) {
                    self.unmatch(i);
                    free.push(i);
                }
            }
            if free.is_empty() {
                break;
            }
        }
        let u: Vec<f64> = (0..self.d).map(|i| self.u(i)).collect();
        Some(Assignment {
            value: self.xc.iter().sum(),
            col: self.x,
            u,
            v: self.v,
        })
    }
}

/// An optimal assignment of the `d × d` matrix `cost` (`INFINITY` = no arc) with its duals,
/// `None` when no finite one exists or when `deadline` passes (checked before each search).
pub fn solve(d: usize, cost: impl Fn(usize, usize) -> f64, deadline: Deadline) -> Option<Assignment> {
    Lap::new(d, cost).run(deadline)
}

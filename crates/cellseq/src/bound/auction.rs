//! A forward auction with ε-scaling (Bertsekas) on a square assignment problem whose costs
//! are listed arcs over a background of group floors, used only for its prices.
//!
//! Rows and columns are `0..size`. Row i reaches the columns of its listed arcs at their
//! costs, and, when it belongs to a group, every column of its own group except i at
//! `same[i]` and every column of another group t at `other[i] + tail[t]`: the floors the
//! caller has proven below the true costs. Any prices `p` give the lower bound
//! `Σ_i min_j (c_ij + p_j) − Σ_j p_j` on the optimum of these costs (row duals
//! `u_i = min_j (c_ij + p_j)` and column duals `v_j = −p_j` are feasible), so prices taken
//! at any time are usable ([`Problem::dual_value`]).

use crate::clock::{Deadline, Ticker};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// No group.
pub const NO_GROUP: u32 = u32::MAX;

/// A square assignment problem: listed arcs (compressed rows) over group floors.
#[derive(Debug, Clone, Default)]
pub struct Problem {
    /// Number of rows (= columns).
    pub size: usize,
    /// Row `i`'s arcs are `first[i]..first[i + 1]`.
    pub first: Vec<usize>,
    /// Column of each arc.
    pub col: Vec<u32>,
    /// Cost of each arc (finite).
    pub cost: Vec<f64>,
    /// Group of each row and column ([`NO_GROUP`]: no background arcs).
    pub group: Vec<u32>,
    /// Per row: the floor to the other columns of its group.
    pub same: Vec<f64>,
    /// Per row: the row's part of the floor to a column of another group.
    pub other: Vec<f64>,
    /// Per group: the group's part of the floor into it from another group.
    pub tail: Vec<f64>,
}

/// Columns a group's cache holds when refilled.
const CACHED: usize = 16;

/// Per group, the columns by price (lazy: an entry whose price is no longer the column's
/// is skipped), and a cache of its cheapest columns, sorted by price, with a price `floor`
/// that every column outside the cache is known to reach. Prices only rise during the
/// auction: a cached column raised to at most the floor moves within the cache, one raised
/// above it leaves, and the cache is refilled from the heap only when fewer than three
/// remain.
struct Queues {
    heap: Vec<BinaryHeap<Reverse<(u64, u32)>>>,
    cache: Vec<Vec<(usize, f64)>>,
    floor: Vec<f64>,
}

impl Queues {
    fn new(pb: &Problem, p: &[f64]) -> Queues {
        let mut entries: Vec<Vec<Reverse<(u64, u32)>>> = vec![Vec::new(); pb.tail.len()];
        for (j, &g) in pb.group.iter().enumerate() {
            if g != NO_GROUP {
                entries[g as usize].push(Reverse((p[j].to_bits(), j as u32)));
            }
        }
        let mut q = Queues {
            cache: vec![Vec::with_capacity(CACHED); entries.len()],
            floor: vec![f64::INFINITY; entries.len()],
            heap: entries.into_iter().map(BinaryHeap::from).collect(),
        };
        for g in 0..q.heap.len() {
            q.refill(g, p);
        }
        q
    }

    /// Refills group `g`'s cache with its [`CACHED`] cheapest columns.
    fn refill(&mut self, g: usize, p: &[f64]) {
        let (h, cache) = (&mut self.heap[g], &mut self.cache[g]);
        cache.clear();
        while cache.len() < CACHED {
            let Some(Reverse((bits, j))) = h.pop() else {
                break;
            };
            if p[j as usize].to_bits() == bits {
                cache.push((j as usize, p[j as usize]));
            }
        }
        // the columns left in the heap cost at least the last taken
        self.floor[g] = match cache.last() {
            Some(&(_, last)) if cache.len() == CACHED => last,
            _ => f64::INFINITY,
        };
        h.extend(cache.iter().map(|&(j, pj)| Reverse((pj.to_bits(), j as u32))));
    }

    /// Records the new (higher) price of column j (prices are ≥ 0, so their bits order as
    /// they do).
    fn update(&mut self, pb: &Problem, j: usize, p: f64) {
        let g = pb.group[j];
        if g == NO_GROUP {
            return;
        }
        let g = g as usize;
        self.heap[g].push(Reverse((p.to_bits(), j as u32)));
        let cache = &mut self.cache[g];
        if let Some(at) = cache.iter().position(|&(c, _)| c == j) {
            cache.remove(at);
            if p <= self.floor[g] {
                let to = cache.partition_point(|&(_, pc)| pc <= p);
                cache.insert(to, (j, p));
            }
        }
    }

    /// The three cheapest columns of group `g` as (column, price), `usize::MAX` past the
    /// last.
    fn top(&mut self, g: usize, p: &[f64]) -> [(usize, f64); 3] {
        if self.cache[g].len() < 3 && self.floor[g].is_finite() {
            self.refill(g, p);
        }
        let mut out = [(usize::MAX, f64::INFINITY); 3];
        for (o, &c) in out.iter_mut().zip(&self.cache[g]) {
            *o = c;
        }
        out
    }
}

/// Per group, the two cheapest columns at prices `p` as (column, price), by one scan.
fn two_cheapest(pb: &Problem, p: &[f64]) -> Vec<[(usize, f64); 2]> {
    let mut two = vec![[(usize::MAX, f64::INFINITY); 2]; pb.tail.len()];
    for (j, &g) in pb.group.iter().enumerate() {
        if g != NO_GROUP {
            let t = &mut two[g as usize];
            if p[j] < t[0].1 {
                t[1] = t[0];
                t[0] = (j, p[j]);
            } else if p[j] < t[1].1 {
                t[1] = (j, p[j]);
            }
        }
    }
    two
}

/// The best and second best value a row sees, the second over other columns than the best.
#[derive(Debug, Clone, Copy)]
struct Best {
    b1: f64,
    b2: f64,
    j1: usize,
}

impl Best {
    fn new() -> Best {
        Best {
            b1: f64::INFINITY,
            b2: f64::INFINITY,
            j1: usize::MAX,
        }
    }

    #[inline]
    fn see(&mut self, j: usize, w: f64) {
        if w < self.b1 {
            if j != self.j1 {
                self.b2 = self.b1;
            }
            self.b1 = w;
            self.j1 = j;
        } else if j != self.j1 && w < self.b2 {
            self.b2 = w;
        }
    }
}

impl Problem {
    /// The listed arcs of row `i` as (column, cost).
    #[inline]
    pub fn row(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let r = self.first[i]..self.first[i + 1];
        self.col[r.clone()]
            .iter()
            .zip(&self.cost[r])
            .map(|(&j, &c)| (j as usize, c))
    }

    /// Row `i`'s best and second best `c_ij + p_j`, background included.
    fn best(&self, i: usize, p: &[f64], q: &mut Queues) -> Best {
        let mut b = Best::new();
        for (j, c) in self.row(i) {
            b.see(j, c + p[j]);
        }
        let gi = self.group[i];
        if gi != NO_GROUP {
            for t in 0..self.tail.len() {
                let floor = self.floor(i, gi, t);
                if !floor.is_finite() {
                    continue;
                }
                let top = q.top(t, p);
                // a group whose least price cannot beat the second best is skipped
                if floor + top[0].1 < b.b2 {
                    // the two cheapest columns other than i
                    for &(j, pj) in top.iter().filter(|&&(j, _)| j != i).take(2) {
                        if j != usize::MAX {
                            b.see(j, floor + pj);
                        }
                    }
                }
            }
        }
        b
    }

    /// The floor of row `i` (of group `gi`) to the columns of group `t` it does not list.
    #[inline]
    fn floor(&self, i: usize, gi: u32, t: usize) -> f64 {
        if t == gi as usize {
            self.same[i]
        } else {
            self.other[i] + self.tail[t]
        }
    }

    /// The lower bound `Σ_i min_j (c_ij + p_j) − Σ_j p_j` of prices `p`; `None` when some
    /// row reaches no column.
    pub fn dual_value(&self, p: &[f64]) -> Option<f64> {
        let two = two_cheapest(self, p);
        let mut total = -p.iter().sum::<f64>();
        for i in 0..self.size {
            let mut u = f64::INFINITY;
            for (j, c) in self.row(i) {
                u = u.min(c + p[j]);
            }
            let gi = self.group[i];
            if gi != NO_GROUP {
                for (t, cheap) in two.iter().enumerate() {
                    // the cheapest column of group t other than i
                    let pj = if cheap[0].0 == i { cheap[1].1 } else { cheap[0].1 };
                    u = u.min(self.floor(i, gi, t) + pj);
                }
            }
            if !u.is_finite() {
                return None;
            }
            total += u;
        }
        Some(total)
    }
}

/// Most bids of one ε-phase, per row: a phase that needs more (the arcs hold no perfect
/// matching, so some prices climb without end, or the ε steps are too fine) ends the
/// auction.
const BIDS_PER_ROW: usize = 40;

/// Runs the auction on `pb` from zero prices, ε divided by 5 from a quarter of the listed
/// cost span down to 10⁻⁴ of their mean; calls `phase_done` with the prices after each
/// phase and when stopping early (the deadline, or a phase over its bid cap).
pub fn auction(pb: &Problem, deadline: Deadline, mut phase_done: impl FnMut(&[f64])) {
    let d = pb.size;
    let mut p = vec![0.0; d];
    if d == 0 || pb.cost.is_empty() {
        return;
    }
    let lo = pb.cost.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = pb.cost.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mean = pb.cost.iter().map(|c| c.abs()).sum::<f64>() / pb.cost.len() as f64;
    let span = (hi - lo).max(1e-9);
    let eps_final = (mean * 1e-4).max(1e-12);
    let mut eps = (span / 4.0).max(eps_final);
    const FREE: u32 = u32::MAX;
    let mut owner = vec![FREE; d];
    let mut clock = Ticker::new(deadline, 256);
    let cap = BIDS_PER_ROW * d + 1000;
    loop {
        owner.fill(FREE);
        let mut q = Queues::new(pb, &p);
        let mut queue: Vec<u32> = (0..d as u32).rev().collect();
        let mut bids = 0usize;
        while let Some(i) = queue.pop() {
            bids += 1;
            if bids > cap || clock.passed() {
                phase_done(&p);
                return;
            }
            let b = pb.best(i as usize, &p, &mut q);
            if b.j1 == usize::MAX {
                continue; // a row that reaches no column stays unassigned
            }
            let raise = if b.b2.is_finite() { b.b2 - b.b1 } else { span };
            p[b.j1] += raise + eps;
            q.update(pb, b.j1, p[b.j1]);
            let prev = std::mem::replace(&mut owner[b.j1], i);
            if prev != FREE {
                queue.push(prev);
            }
        }
        phase_done(&p);
        if eps <= eps_final {
            return;
        }
        eps = (eps / 5.0).max(eps_final);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dense(m: &[[f64; 3]; 3]) -> Problem {
        let mut g = Problem {
            size: 3,
            first: vec![0],
            group: vec![NO_GROUP; 3],
            ..Problem::default()
        };
        for row in m {
            for (j, &c) in row.iter().enumerate() {
                if c.is_finite() {
                    g.col.push(j as u32);
                    g.cost.push(c);
                }
            }
            g.first.push(g.col.len());
        }
        g
    }

    #[test]
    fn prices_reach_the_optimum() {
        let g = dense(&[[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]]);
        let mut best = f64::NEG_INFINITY;
        auction(&g, Deadline::NONE, |p| {
            best = best.max(g.dual_value(p).unwrap())
        });
        assert!((5.0 - 1e-2..=5.0 + 1e-9).contains(&best), "{best}");
    }

    #[test]
    fn background_floors_count() {
        // row 0 lists nothing: it reaches columns 1 and 2 of its group at 1
        let mut g = dense(&[[f64::INFINITY; 3], [2.0, 9.0, 0.0], [0.0, 0.0, 9.0]]);
        g.group = vec![0, 0, 0];
        g.same = vec![1.0, 100.0, 100.0];
        g.other = vec![0.0; 3];
        g.tail = vec![0.0];
        let mut best = f64::NEG_INFINITY;
        auction(&g, Deadline::NONE, |p| {
            best = best.max(g.dual_value(p).unwrap())
        });
        // 0→1 (1), 1→2 (0), 2→0 (0)
        assert!((1.0 - 1e-2..=1.0 + 1e-9).contains(&best), "{best}");
    }

    #[test]
    fn no_perfect_matching_stops() {
        let inf = f64::INFINITY;
        let g = dense(&[[1.0, inf, inf], [2.0, inf, inf], [inf, inf, 1.0]]);
        let mut calls = 0;
        auction(&g, Deadline::NONE, |_| calls += 1);
        assert!(calls >= 1);
    }
}

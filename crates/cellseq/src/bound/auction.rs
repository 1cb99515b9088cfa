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

/// Per group, the columns by price (lazy: an entry whose price is no longer the column's
/// is skipped).
struct Queues(Vec<BinaryHeap<Reverse<(u64, u32)>>>);

impl Queues {
    fn new(pb: &Problem, p: &[f64]) -> Queues {
        let mut q: Vec<BinaryHeap<Reverse<(u64, u32)>>> = vec![BinaryHeap::new(); pb.tail.len()];
        for (j, &g) in pb.group.iter().enumerate() {
            if g != NO_GROUP {
                q[g as usize].push(Reverse((p[j].to_bits(), j as u32)));
            }
        }
        Queues(q)
    }

    /// Records the new price of column j (prices are ≥ 0, so their bits order as they do).
    fn update(&mut self, pb: &Problem, j: usize, p: f64) {
        let g = pb.group[j];
        if g != NO_GROUP {
            self.0[g as usize].push(Reverse((p.to_bits(), j as u32)));
        }
    }

    /// The least price in group `g` (`INFINITY` when empty), dropping stale entries on top.
    fn least(&mut self, g: usize, p: &[f64]) -> f64 {
        let h = &mut self.0[g];
        while let Some(&Reverse((bits, j))) = h.peek() {
            if p[j as usize].to_bits() == bits {
                return p[j as usize];
            }
            h.pop();
        }
        f64::INFINITY
    }

    /// The two cheapest columns of group `g` other than `skip`, as (column, price).
    fn two(&mut self, g: usize, skip: usize, p: &[f64]) -> [(usize, f64); 2] {
        let h = &mut self.0[g];
        let mut out = [(usize::MAX, f64::INFINITY); 2];
        let mut held = Vec::with_capacity(3);
        let mut found = 0;
        while let Some(Reverse((bits, j))) = h.pop() {
            if p[j as usize].to_bits() != bits {
                continue;
            }
            held.push(Reverse((bits, j)));
            if j as usize != skip {
                out[found] = (j as usize, p[j as usize]);
                found += 1;
                if found == 2 {
                    break;
                }
            }
        }
        h.extend(held);
        out
    }
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
                let floor = if t == gi as usize {
                    self.same[i]
                } else {
                    self.other[i] + self.tail[t]
                };
                // a group whose least price cannot beat the second best is skipped
                if floor.is_finite() && floor + q.least(t, p) < b.b2 {
                    for (j, pj) in q.two(t, i, p) {
                        if j != usize::MAX {
                            b.see(j, floor + pj);
                        }
                    }
                }
            }
        }
        b
    }

    /// The lower bound `Σ_i min_j (c_ij + p_j) − Σ_j p_j` of prices `p`; `None` when some
    /// row reaches no column.
    pub fn dual_value(&self, p: &[f64]) -> Option<f64> {
        let mut q = Queues::new(self, p);
        let mut total = -p.iter().sum::<f64>();
        for i in 0..self.size {
            let u = self.best(i, p, &mut q).b1;
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

//! Carry moves: an Or-opt of one cell whose way is blocked by a precedence neighbour, made
//! feasible by carrying the blocker's short segment past the cell's new place.
//!
//! Moving a cell `x` forward past one of its own successors `y` breaks a pair, so Or-opt
//! never tries it; moving `y` out of the way first usually costs more than it saves, so no
//! chain of improving Or-opt or SOP-3-exchange moves reaches the better order either. A
//! carry move does both at once: `x` goes forward to a new place, and a segment of at most
//! [`MAX_CARRIED`] cells that holds every successor of `x` in its way goes to a place after
//! `x`'s new one (directly behind it, or further on). The backward move mirrors it with
//! predecessors. Both keep every precedence pair: the carried segment's cells may not pass
//! one of their own successors (predecessors), and `x` passes none of its own outside the
//! segment.
//!
//! The places tried are those of the Or-opt candidate lists: `x` lands next to one of its
//! candidate neighbours, the segment directly behind `x` or next to one of its ends'
//! neighbours. Each candidate's delta is O(1): the new order of the span is five runs of the
//! old one, and only the links at their ends change.

use super::moves::window;
use super::vnd::improves;
use super::{Costs, Neighbours, Solution};
use crate::context::Context;

/// Most cells of a carried segment.
pub const MAX_CARRIED: usize = 3;

/// A run of positions `(first, last)` of the current order, both inclusive.
type Run = (isize, isize);

/// The change in cost when positions `lo..=hi` are replaced by `runs` (each a non-empty run
/// of positions, together a permutation of `lo..=hi`) in that order: only the links at the
/// runs' ends change.
fn runs_delta(c: &Costs, s: &Solution, lo: isize, hi: isize, runs: &[Run]) -> f64 {
    let mut old = s.link(c, hi, hi + 1);
    let mut new = 0.0;
    let mut prev = lo - 1;
    for &(first, last) in runs {
        old += s.link(c, first - 1, first);
        new += s.link(c, prev, first);
        prev = last;
    }
    new += s.link(c, prev, hi + 1);
    new - old
}

/// The best carry move found: where the span it rewrites starts and its new order as runs.
#[derive(Debug, Clone, Copy)]
struct Best {
    delta: f64,
    lo: isize,
    runs: [Run; 5],
    len: usize,
}

impl Best {
    fn none() -> Self {
        Best {
            delta: 0.0,
            lo: 0,
            runs: [(0, 0); 5],
            len: 0,
        }
    }
    /// Keeps the move when it is cheaper than the best so far; empty runs are dropped.
    fn offer(&mut self, c: &Costs, s: &Solution, lo: isize, hi: isize, runs: [Run; 5]) -> u64 {
        let mut kept = [(0, 0); 5];
        let mut len = 0;
        for r in runs {
            if r.0 <= r.1 {
                kept[len] = r;
                len += 1;
            }
        }
        let d = runs_delta(c, s, lo, hi, &kept[..len]);
        if d < self.delta {
            *self = Best {
                delta: d,
                lo,
                runs: kept,
                len,
            };
        }
        1
    }
}

/// The carry-move search with its scratch space.
#[derive(Debug, Default)]
pub struct Carry {
    /// Moves applied so far.
    pub applied: u64,
    places: Vec<isize>,
    targets: Vec<isize>,
    cells: Vec<u32>,
}

impl Carry {
    /// Applies improving carry moves, the best one per cell, until a pass over every cell
    /// finds none or the budget ends. Returns true on any improvement.
    pub fn improve(
        &mut self,
        c: &Costs,
        nb: &Neighbours,
        s: &mut Solution,
        ctx: &mut Context,
    ) -> bool {
        let n = s.n();
        let mut improved = false;
        loop {
            let mut pass = false;
            for x in 0..n as u32 {
                if ctx.exhausted_polled() {
                    return improved;
                }
                let mut best = Best::none();
                let evals = self.forward(c, nb, s, x, &mut best) + self.backward(c, nb, s, x, &mut best);
                ctx.count(evals);
                if improves(best.delta, s.cost) {
                    self.apply(s, &best);
                    self.applied += 1;
                    pass = true;
                }
            }
            improved |= pass;
            if !pass {
                return improved;
            }
        }
    }

    fn apply(&mut self, s: &mut Solution, best: &Best) {
        self.cells.clear();
        for &(first, last) in &best.runs[..best.len] {
            self.cells
                .extend_from_slice(&s.order[first as usize..=last as usize]);
        }
        let cells = std::mem::take(&mut self.cells);
        s.rewrite(best.lo as usize, &cells, best.delta);
        self.cells = cells;
    }

    /// `x` forward past its successors in the way, which a segment carries behind it.
    fn forward(&mut self, c: &Costs, nb: &Neighbours, s: &Solution, x: u32, best: &mut Best) -> u64 {
        let m = c.m;
        let n = s.n() as isize;
        let a = s.pos[x as usize] as isize;
        let succ = &m.dag.succs[x as usize];
        let first = s.first_succ(m, x as usize);
        if first == n {
            return 0;
        }
        // x lands after position b: next to one of its candidate neighbours, past `first`
        self.places.clear();
        self.places.extend(nb.inn[x as usize].iter().map(|&v| s.pos[v as usize] as isize));
        self.places.extend(nb.out[x as usize].iter().map(|&w| s.pos[w as usize] as isize - 1));
        let mut evals = succ.len() as u64;
        for bi in 0..self.places.len() {
            let b = self.places[bi];
            if b < first {
                continue;
            }
            // the successors of x in its way, a..=b
            // every precedence link read counts as an evaluation, so that an evaluation
            // budget bounds the work under dense precedence too
            evals += succ.len() as u64;
            let last = succ
                .iter()
                .map(|&y| s.pos[y as usize] as isize)
                .filter(|&p| p <= b)
                .max()
                .unwrap_or(first);
            if last - first + 1 > MAX_CARRIED as isize {
                continue;
            }
            for len in (last - first + 1)..=MAX_CARRIED as isize {
                for st in (last - len + 1)..=first {
                    let en = st + len - 1;
                    if st <= a || en >= b {
                        continue;
                    }
                    // the segment may not pass a successor of its own
                    evals += (st..=en)
                        .map(|p| m.dag.succs[s.order[p as usize] as usize].len() as u64)
                        .sum::<u64>();
                    let (_, limit) = window(m, s, st as usize, len as usize);
                    self.targets.clear();
                    self.targets.push(b);
                    let (f, l) = (s.order[st as usize], s.order[en as usize]);
                    self.targets.extend(nb.inn[f as usize].iter().map(|&v| s.pos[v as usize] as isize));
                    self.targets.extend(nb.out[l as usize].iter().map(|&w| s.pos[w as usize] as isize - 1));
                    for ti in 0..self.targets.len() {
                        let t = self.targets[ti];
                        if t < b || t >= limit || (t == b && ti > 0) {
                            continue;
                        }
                        let runs = [(a + 1, st - 1), (en + 1, b), (a, a), (b + 1, t), (st, en)];
                        evals += best.offer(c, s, a, t, runs);
                    }
                }
            }
        }
        evals
    }

    /// `x` backward past its predecessors in the way, which a segment carries before it.
    fn backward(&mut self, c: &Costs, nb: &Neighbours, s: &Solution, x: u32, best: &mut Best) -> u64 {
        let m = c.m;
        let a = s.pos[x as usize] as isize;
        let pred = &m.dag.preds[x as usize];
        let first = s.last_pred(m, x as usize);
        if first < 0 {
            return 0;
        }
        // x lands before position b: next to one of its candidate neighbours, before `first`
        self.places.clear();
        self.places.extend(nb.out[x as usize].iter().map(|&w| s.pos[w as usize] as isize));
        self.places.extend(nb.inn[x as usize].iter().map(|&v| s.pos[v as usize] as isize + 1));
        let mut evals = pred.len() as u64;
        for bi in 0..self.places.len() {
            let b = self.places[bi];
            if b > first {
                continue;
            }
            // the predecessors of x in its way, b..a
            // precedence links read count as evaluations (as in `forward`)
            evals += pred.len() as u64;
            let last = pred
                .iter()
                .map(|&y| s.pos[y as usize] as isize)
                .filter(|&p| p >= b)
                .min()
                .unwrap_or(first);
            if first - last + 1 > MAX_CARRIED as isize {
                continue;
            }
            for len in (first - last + 1)..=MAX_CARRIED as isize {
                for st in (first - len + 1)..=last {
                    let en = st + len - 1;
                    if en >= a || st <= b {
                        continue;
                    }
                    // the segment may not pass a predecessor of its own
                    evals += (st..=en)
                        .map(|p| m.dag.preds[s.order[p as usize] as usize].len() as u64)
                        .sum::<u64>();
                    let (limit, _) = window(m, s, st as usize, len as usize);
                    self.targets.clear();
                    self.targets.push(b);
                    let (f, l) = (s.order[st as usize], s.order[en as usize]);
                    self.targets.extend(nb.out[l as usize].iter().map(|&w| s.pos[w as usize] as isize));
                    self.targets.extend(nb.inn[f as usize].iter().map(|&v| s.pos[v as usize] as isize + 1));
                    for ti in 0..self.targets.len() {
                        let t = self.targets[ti];
                        if t > b || t <= limit || (t == b && ti > 0) {
                            continue;
                        }
                        let runs = [(st, en), (t, b - 1), (a, a), (b, st - 1), (en + 1, a - 1)];
                        evals += best.offer(c, s, t, a, runs);
                    }
                }
            }
        }
        evals
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::NoObserver;
    use crate::cost::CostModel;
    use crate::engine::atsp::random_matrix_instance;
    use crate::generate::families::dag::random_dag;
    use crate::model::{Objective, Sequence, Visit};
    use crate::solvers::Budget;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random matrix instance of `n` cells with random precedence and its model.
    fn instance(n: usize, seed: u64) -> (crate::model::Instance, CostModel) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let prec = random_dag(n, 0.15, &mut rng);
        let inst = random_matrix_instance(n, seed, 100, &prec);
        let m = CostModel::new(&inst, Objective::Matrix);
        (inst, m)
    }

    /// A random feasible order: cells drawn at random among those whose predecessors are
    /// placed.
    fn random_order(m: &CostModel, rng: &mut ChaCha8Rng) -> Sequence {
        let n = m.n();
        let mut left: Vec<usize> = (0..n).map(|x| m.dag.preds[x].len()).collect();
        let mut ready: Vec<usize> = (0..n).filter(|&x| left[x] == 0).collect();
        let mut seq = Sequence::new();
        while !ready.is_empty() {
            let x = ready.swap_remove(rng.random_range(0..ready.len()));
            seq.push(Visit::new(x, 0));
            for &y in &m.dag.succs[x] {
                left[y as usize] -= 1;
                if left[y as usize] == 0 {
                    ready.push(y as usize);
                }
            }
        }
        seq
    }

    /// Every carry move of `s`, built cell by cell from its definition (not from runs):
    /// the cheapest feasible result's cost, or `s.cost` when none is cheaper.
    fn cheapest_by_enumeration(c: &Costs, s: &Solution) -> f64 {
        let m = c.m;
        let n = s.n();
        let mut best = s.cost;
        for dir in [false, true] {
            // the backward move is the forward one on the order read backwards
            let order: Vec<u32> = if dir {
                s.order.iter().rev().copied().collect()
            } else {
                s.order.clone()
            };
            let after = |x: u32| -> &Vec<u32> {
                if dir { &m.dag.preds[x as usize] } else { &m.dag.succs[x as usize] }
            };
            for a in 0..n {
                let x = order[a];
                for b in a + 1..n {
                    let blockers: Vec<usize> =
                        (a + 1..=b).filter(|&q| after(x).contains(&order[q])).collect();
                    let (Some(&f), Some(&l)) = (blockers.first(), blockers.last()) else {
                        continue;
                    };
                    for st in a + 1..=f {
                        for en in l..b.min(st + MAX_CARRIED) {
                            for t in b..n {
                                let seg = &order[st..=en];
                                let mut new: Vec<u32> = Vec::with_capacity(n);
                                for (q, &y) in order.iter().enumerate() {
                                    if q != a && !(st..=en).contains(&q) {
                                        new.push(y);
                                    }
                                    if q == b {
                                        new.push(x);
                                        if t == b {
                                            new.extend_from_slice(seg);
                                        }
                                    }
                                    if q == t && t > b {
                                        new.extend_from_slice(seg);
                                    }
                                }
                                if dir {
                                    new.reverse();
                                }
                                let cand = s.reordered(c, &new);
                                if cand.feasible(m) && cand.cost < best {
                                    best = cand.cost;
                                }
                            }
                        }
                    }
                }
            }
        }
        best
    }

    /// From random feasible orders of random instances: every move applied keeps precedence
    /// and changes the cost by its delta, and with complete candidate lists the search ends
    /// where no carry move, enumerated from its definition, is cheaper.
    #[test]
    fn carry_ends_where_no_carry_move_is_cheaper() {
        let mut applied = 0;
        for seed in 0..30u64 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let n = rng.random_range(5..14);
            let (inst, m) = instance(n, seed);
            let c = Costs::open(&m);
            let nb = Neighbours::new(&m, n - 1);
            let mut s = Solution::new(&c, &random_order(&m, &mut rng));
            let budget = Budget {
                time_limit: None,
                max_evals: None,
            };
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, seed, budget, &mut obs);
            let before = s.cost;
            if Carry::default().improve(&c, &nb, &mut s, &mut ctx) {
                applied += 1;
                assert!(s.cost < before);
            }
            assert!(s.feasible(&m), "seed {seed}: a carry move broke precedence");
            let full = s.evaluate(&c);
            assert!((full - s.cost).abs() < 1e-6, "seed {seed}: cost {full}, cached {}", s.cost);
            let cheapest = cheapest_by_enumeration(&c, &s);
            assert!(cheapest >= s.cost - 1e-6, "seed {seed}: a carry move to {cheapest} from {} was missed", s.cost);
        }
        assert!(applied >= 10, "carry improved only {applied} of 30 random orders");
    }
}

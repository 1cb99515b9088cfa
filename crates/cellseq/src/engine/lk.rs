//! Lin–Kernighan style variable-depth search (LK with 2-opt moves) on the open path,
//! restricted to reversals that keep every precedence pair.
//!
//! The path is read as a cycle through a dummy node D (the home position before the first
//! cell and the end after the last). A chain starts at a cell `t1` and one of its path
//! neighbours `t2`: it breaks the link t1–t2, adds a link t2–t3 to a candidate t3 of t2,
//! breaks the link t3–t4 that makes the result a path again and closes with t1–t4 — one
//! reversal of a segment next to t1. The next step breaks the closing link t1–t4 again
//! (t4 becomes the new t2), and so on, for up to `depth` steps. Every step must keep the
//! LK gain criterion (the cost change so far, without the closing link, is a gain), may not
//! break a link added earlier in the chain, and must reverse a segment that holds no
//! precedence pair and whose cells can all be reversed ([`reversible_segment`]), so every
//! intermediate path is feasible. The chain keeps its best prefix when that improves the
//! path and is undone otherwise.
//!
//! On instances whose costs read the same backwards (a symmetric matrix: TSPLIB's prob.100)
//! a step is evaluated in O(1); otherwise the segment's inner links are summed, O(length).

use super::moves::{flipped_at, reverse_delta_direct, reverse_delta_ends, reversible_segment};
use super::solution::flip_mode;
use super::vnd::{Search, improves};
use super::{Costs, Neighbours, Slot, Solution};
use crate::context::Context;
use crate::model::CostMatrix;
use std::collections::VecDeque;

/// Instances with at most this many nodes are tested for symmetric costs (O(nodes²)).
const SYMMETRY_TEST_NODES: usize = 2000;

/// One candidate step of a chain.
#[derive(Debug, Clone, Copy)]
struct Step {
    /// Reversed positions `i..=j`.
    i: usize,
    j: usize,
    /// Cost change of the reversal.
    delta: f64,
    /// Cost change so far minus the closing link (lower is better).
    score: f64,
    /// Position of t1 and the side of its new t2 after the reversal.
    pa: isize,
    dir: isize,
    /// The link t3–t4 the step breaks (as unordered cell pair, D = u32::MAX).
    broken: (u32, u32),
    /// The link t2–t3 the step adds.
    added: (u32, u32),
    /// Precedence pairs out of order after the step (penalty mode only; else 0).
    viol: u32,
}

/// The LK search: candidate lists, chain limits and scratch space.
#[derive(Debug, Clone)]
pub struct Lk {
    /// Longest chain (number of reversals).
    pub depth: usize,
    /// First steps tried from each t1 (the rest of a chain takes the best step).
    pub breadth: usize,
    /// Costs read the same backwards (reversal deltas in O(1)).
    pub symmetric: bool,
    /// Penalty per precedence pair out of order. 0: every step keeps precedence. Above 0:
    /// a chain may pass through paths that break up to [`Lk::max_viol`] pairs, each charged
    /// this much in the gain criterion, and only a prefix that keeps every pair is applied.
    pub penalty: f64,
    /// Most pairs a chain may break on its way (penalty mode).
    pub max_viol: u32,
    added: Vec<(u32, u32)>,
    applied: Vec<(usize, usize, f64)>,
    cands: Vec<Step>,
    /// Per cell t2, the cells t3 a step may link it to: [`Neighbours::merged`] of the first
    /// lists [`Lk::improve`] gets (on symmetric costs out- and in-neighbours mostly hold the
    /// same cells, which would give the same steps twice).
    near: Vec<Vec<u32>>,
}

/// Precedence pairs out of order after reversing `[i..=j]` of `s`, which has `viol` of them:
/// every pair with both cells inside the segment changes sides. O(length · out-degree).
/// Stops early with `cap + 1` once the result must exceed `cap`: the pairs that come back
/// into order are among the `viol` already out of it, so the result is at least the number
/// of pairs the reversal puts out of order (a segment holding a cell ordered before or after
/// every other ends after a few pairs).
fn viol_after(
    m: &crate::cost::CostModel,
    s: &Solution,
    i: usize,
    j: usize,
    viol: u32,
    cap: u32,
) -> u32 {
    let limit = i64::from(cap);
    let mut out_of_order = 0i64;
    let mut back = 0i64;
    for p in i..=j {
        let a = s.order[p] as usize;
        for &q in &m.dag.succs[a] {
            let pq = s.pos[q as usize] as usize;
            if pq >= i && pq <= j {
                if pq > p {
                    out_of_order += 1;
                    if out_of_order > limit {
                        return cap + 1;
                    }
                } else {
                    back += 1;
                }
            }
        }
    }
    (i64::from(viol) + out_of_order - back).max(0) as u32
}

/// True when every cell of `[i..=j]` can be cut the other way.
fn flippable_segment(m: &crate::cost::CostModel, s: &Solution, i: usize, j: usize) -> bool {
    (i..=j).all(|p| {
        let c = s.order[p] as usize;
        flip_mode(m, c, s.mode[c] as usize).is_some()
    })
}

fn pair(a: u32, b: u32) -> (u32, u32) {
    if a < b { (a, b) } else { (b, a) }
}

fn cell_at(s: &Solution, p: isize) -> u32 {
    if p < 0 || p as usize >= s.n() {
        u32::MAX
    } else {
        s.order[p as usize]
    }
}

/// True when reversing any feasible segment leaves its inner link costs unchanged:
/// `arc(a, ma, b, mb) == arc(b, turn(mb), a, turn(ma))` for all nodes of cells that may
/// share a reversible segment (tested for at most `SYMMETRY_TEST_NODES` nodes; larger
/// instances count as asymmetric). Pairs with a forbidden arc ([`CostMatrix::FORBIDDEN`], TSPLIB's
/// −1: a precedence pair) are skipped: a reversible segment never holds both cells.
pub fn symmetric(c: &Costs) -> bool {
    let m = c.m;
    if m.nodes() > SYMMETRY_TEST_NODES {
        return false;
    }
    for nd_a in 0..m.nodes() {
        let (a, ma) = m.cell_mode(nd_a);
        let Some(ta) = flip_mode(m, a, ma) else {
            continue;
        };
        for nd_b in 0..m.nodes() {
            let (b, mb) = m.cell_mode(nd_b);
            if a == b {
                continue;
            }
            let Some(tb) = flip_mode(m, b, mb) else {
                continue;
            };
            let (ab, ba) = (m.arc(a, ma, b, mb), m.arc(b, tb, a, ta));
            if ab >= CostMatrix::FORBIDDEN || ba >= CostMatrix::FORBIDDEN {
                continue;
            }
            if ab != ba {
                return false;
            }
        }
    }
    true
}

impl Lk {
    /// The search a solver's `lk` parameter asks for: `Some(false)` none, `Some(true)` always,
    /// `None` (auto) only on symmetric costs.
    pub fn when(mode: Option<bool>, c: &Costs, depth: usize, breadth: usize) -> Option<Self> {
        match mode {
            Some(false) => None,
            _ => Some(Lk::new(c, depth, breadth)),
        }
        .filter(|l| mode == Some(true) || l.symmetric)
    }

    /// The full descent: `search`'s VND, then, where Lin–Kernighan runs (`lk`), LK
    /// alternating with the VND ([`Lk::alternate_with_vnd`]).
    pub fn full_descent(
        lk: Option<&mut Lk>,
        search: &mut Search,
        s: &mut Solution,
        ctx: &mut Context,
    ) {
        search.vnd(s, ctx);
        if let Some(lk) = lk {
            lk.alternate_with_vnd(search, s, ctx);
        }
    }

    /// Alternates LK from every cell with `search`'s VND until LK finds nothing or the budget
    /// ends (the polish of a new best).
    pub fn alternate_with_vnd(&mut self, search: &mut Search, s: &mut Solution, ctx: &mut Context) {
        let c = search.c;
        while self.improve_all(&c, &search.nb, s, ctx) && !ctx.exhausted() {
            search.vnd(s, ctx);
        }
    }

    /// A search with chains of at most `depth` reversals and `breadth` first steps.
    pub fn new(c: &Costs, depth: usize, breadth: usize) -> Self {
        Lk {
            depth: depth.max(1),
            breadth: breadth.max(1),
            symmetric: symmetric(c),
            penalty: 0.0,
            max_viol: 2,
            added: Vec::new(),
            applied: Vec::new(),
            cands: Vec::new(),
            near: Vec::new(),
        }
    }

    /// Cost change of reversing `[i..=j]` (with mode flip): only the two boundary links
    /// change on symmetric costs, else the segment's inner links are summed.
    fn reverse_delta(&self, c: &Costs, s: &Solution, i: usize, j: usize) -> f64 {
        if self.symmetric && self.penalty > 0.0 {
            // paths inside a chain may put a pair's second cell right before its first: read
            // such a forbidden link backwards, so that the cost stays that of the symmetric
            // matrix (equal to the true cost on every path that keeps precedence)
            let (ii, jj) = (i as isize, j as isize);
            let v = |a: Slot, b: Slot| {
                let x = c.link(a, b);
                if x >= CostMatrix::FORBIDDEN {
                    c.link(b, a)
                } else {
                    x
                }
            };
            v(s.at(ii - 1), flipped_at(c, s, jj)) + v(flipped_at(c, s, ii), s.at(jj + 1))
                - v(s.at(ii - 1), s.at(ii))
                - v(s.at(jj), s.at(jj + 1))
        } else if self.symmetric {
            reverse_delta_ends(c, s, i, j)
        } else {
            reverse_delta_direct(c, s, i, j)
        }
    }

    /// The step that adds a link from t2 (next to t1 at `pa` on side `dir`) to the
    /// position `pb`, if that position gives a proper reversal.
    #[allow(clippy::too_many_arguments)]
    fn step(
        &self,
        c: &Costs,
        s: &Solution,
        pa: isize,
        dir: isize,
        pb: isize,
        cum: f64,
        viol: u32,
        evals: &mut u64,
    ) -> Option<Step> {
        let n = s.n() as isize;
        let t2 = cell_at(s, pa + dir);
        let t3 = cell_at(s, pb);
        // (i, j) reversed; t4's position before the move; t1 and new t2 after it
        let (i, j, p4, new_pa, new_dir) = if dir > 0 {
            if pb > pa + 2 {
                (pa + 1, pb - 1, pb - 1, pa, 1)
            } else if pb < pa && pb >= 0 {
                (pb, pa, pb - 1, pb, -1)
            } else {
                return None;
            }
        } else if pb < pa - 2 {
            (pb + 1, pa - 1, pb + 1, pa, -1)
        } else if pb > pa && pb < n {
            (pa, pb, pb + 1, pb, 1)
        } else {
            return None;
        };
        let t4 = cell_at(s, p4);
        *evals += 1;
        let delta = self.reverse_delta(c, s, i as usize, j as usize);
        let new_cum = cum + delta;
        // the closing link t1–t4 after the move, read in its direction on the path
        let t1_after = |q: isize| -> Slot {
            // the slot at position q after reversing [i..=j]
            if q >= i && q <= j {
                flipped_at(c, s, i + j - q)
            } else {
                s.at(q)
            }
        };
        let (x, y) = if new_dir > 0 {
            (t1_after(new_pa), t1_after(new_pa + 1))
        } else {
            (t1_after(new_pa - 1), t1_after(new_pa))
        };
        let closing = c.link(x, y);
        let score = new_cum - closing;
        // gain criterion: without its closing link the chain must still gain (the penalty,
        // charged later by `charge`, only adds to the score, so a step that fails here fails
        // there too)
        if score >= 0.0 {
            return None;
        }
        Some(Step {
            i: i as usize,
            j: j as usize,
            delta,
            score,
            pa: new_pa,
            dir: new_dir,
            broken: pair(t3, t4),
            added: pair(t2, t3),
            viol,
        })
    }

    /// Builds [`Lk::near`] from `nb` for a path of `n` cells, once.
    fn link_candidates(&mut self, nb: &Neighbours, n: usize) {
        if self.near.len() != n {
            self.near = nb.merged();
        }
    }

    /// Penalty mode: charges `st` (as [`Lk::step`] made it, with the chain's pairs out of
    /// order so far in `viol`) for the pairs out of order after it. `None` when that breaks
    /// more than [`Lk::max_viol`] pairs or the charged step no longer gains.
    fn charge(&self, m: &crate::cost::CostModel, s: &Solution, mut st: Step) -> Option<Step> {
        st.viol = viol_after(m, s, st.i, st.j, st.viol, self.max_viol);
        if st.viol > self.max_viol {
            return None;
        }
        st.score += self.penalty * st.viol as f64;
        (st.score < 0.0).then_some(st)
    }

    /// The feasible steps from t1 at `pa` (t2 on side `dir`), best first, at most `want`.
    #[allow(clippy::too_many_arguments)]
    fn steps(
        &mut self,
        c: &Costs,
        s: &Solution,
        pa: isize,
        dir: isize,
        cum: f64,
        viol: u32,
        want: usize,
        evals: &mut u64,
    ) -> Vec<Step> {
        let n = s.n() as isize;
        let p2 = pa + dir;
        if p2 < 0 || p2 >= n {
            return Vec::new();
        }
        let t2 = s.order[p2 as usize] as usize;
        self.cands.clear();
        let end = if dir > 0 { n } else { -1 };
        let positions = self.near[t2]
            .iter()
            .map(|&w| s.pos[w as usize] as isize)
            .chain([end]);
        for pb in positions {
            if let Some(st) = self.step(c, s, pa, dir, pb, cum, viol, evals)
                && !self.added.contains(&st.broken)
            {
                self.cands.push(st);
            }
        }
        let by_score = |a: &Step, b: &Step| a.score.total_cmp(&b.score).then(a.i.cmp(&b.i));
        self.cands.sort_by(by_score);
        self.cands.dedup_by(|a, b| a.i == b.i && a.j == b.j);
        let m = c.m;
        if self.penalty <= 0.0 {
            return self
                .cands
                .iter()
                .filter(|st| reversible_segment(m, s, st.i, st.j - st.i + 1))
                .take(want)
                .copied()
                .collect();
        }
        // Penalty mode. Counting the pairs a reversal puts out of order costs O(length ·
        // out-degree), so it is done lazily: the candidates are in order of their score
        // before the charge, which only adds to it, so once that score is above the
        // `want`-th best charged score found so far no later candidate can enter. The result
        // is the one charging every candidate and sorting would give, but for exact ties of
        // charged score and position, which go to the lower score before the charge.
        let mut kept: Vec<Step> = Vec::with_capacity(want + 1);
        for &st in &self.cands {
            if kept.len() >= want && st.score > kept[want - 1].score {
                break;
            }
            let Some(st) = self.charge(m, s, st) else {
                continue;
            };
            if !flippable_segment(m, s, st.i, st.j) {
                continue;
            }
            // insert after every kept step that sorts before or level with it
            let at = kept.partition_point(|k| by_score(k, &st).is_le());
            kept.insert(at, st);
            kept.truncate(want);
        }
        kept
    }

    /// Runs chains from t1 at `pa` towards side `dir`, trying the `breadth` best first
    /// steps; keeps the best prefix of the first chain that improves `s` (returns true) and
    /// undoes the others. Cells at the ends of the kept reversals go to `touched`.
    fn chain(
        &mut self,
        c: &Costs,
        s: &mut Solution,
        pa: isize,
        dir: isize,
        evals: &mut u64,
        touched: &mut Vec<u32>,
    ) -> bool {
        let n = s.n() as isize;
        let m = c.m;
        let start_cost = s.cost;
        self.added.clear();
        let firsts = self.steps(c, s, pa, dir, 0.0, 0, self.breadth, evals);
        for first in firsts {
            self.added.clear();
            self.applied.clear();
            let mut st = first;
            let mut cum = 0.0;
            let mut best = (0.0, 0usize);
            loop {
                s.reverse(m, st.i, st.j, st.delta);
                self.applied.push((st.i, st.j, st.delta));
                self.added.push(st.added);
                cum += st.delta;
                if st.viol == 0 && cum < best.0 {
                    best = (cum, self.applied.len());
                }
                if self.applied.len() >= self.depth {
                    break;
                }
                match self
                    .steps(c, s, st.pa, st.dir, cum, st.viol, 1, evals)
                    .first()
                {
                    Some(&next) => st = next,
                    None => break,
                }
            }
            let keep = if improves(best.0, start_cost) {
                best.1
            } else {
                0
            };
            while self.applied.len() > keep {
                let (i, j, d) = self.applied.pop().expect("non-empty");
                s.reverse(m, i, j, -d);
            }
            if keep == 0 {
                s.cost = start_cost;
                continue;
            }
            for &(i, j, _) in &self.applied {
                for p in [i as isize - 1, i as isize, j as isize, j as isize + 1] {
                    if p >= 0 && p < n {
                        touched.push(s.order[p as usize]);
                    }
                }
            }
            return true;
        }
        false
    }

    /// LK to a local optimum starting from the cells `seeds` (don't-look bits on all
    /// others; cells next to an applied chain are looked at again). Returns true on any
    /// improvement.
    pub fn improve(
        &mut self,
        c: &Costs,
        nb: &Neighbours,
        s: &mut Solution,
        ctx: &mut Context,
        seeds: &[u32],
    ) -> bool {
        let n = s.n();
        if n < 4 {
            return false;
        }
        self.link_candidates(nb, n);
        let mut on = vec![false; n];
        let mut queue: VecDeque<u32> = VecDeque::with_capacity(seeds.len());
        for &x in seeds {
            if !on[x as usize] {
                on[x as usize] = true;
                queue.push_back(x);
            }
        }
        let mut touched = Vec::new();
        let mut improved = false;
        while let Some(x) = queue.pop_front() {
            on[x as usize] = false;
            if ctx.exhausted_polled() {
                break;
            }
            let mut evals = 0;
            let mut found = false;
            for dir in [1, -1] {
                let pa = s.pos[x as usize] as isize;
                touched.clear();
                if self.chain(c, s, pa, dir, &mut evals, &mut touched) {
                    found = true;
                    break;
                }
            }
            ctx.count(evals);
            if found {
                improved = true;
                touched.push(x);
                for &t in &touched {
                    if !on[t as usize] {
                        on[t as usize] = true;
                        queue.push_back(t);
                    }
                }
            }
        }
        improved
    }

    /// LK to a local optimum from every cell.
    pub fn improve_all(
        &mut self,
        c: &Costs,
        nb: &Neighbours,
        s: &mut Solution,
        ctx: &mut Context,
    ) -> bool {
        let all: Vec<u32> = s.order.clone();
        self.improve(c, nb, s, ctx, &all)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::{Budget, NoObserver};
    use crate::cost::CostModel;
    use crate::engine::vnd::Search;
    use crate::model::{Instance, Objective, Sequence, Visit};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// A random TSPLIB SOP instance (symmetric or not): each pair a < b is ordered with
    /// probability 0.03 (so the identity order is feasible).
    fn instance(n: usize, seed: u64, sym: bool) -> Instance {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut w = vec![vec![0i64; n]; n];
        for i in 0..n {
            for j in 0..n {
                if i != j {
                    w[i][j] = rng.random_range(1..500);
                }
            }
        }
        for i in 0..n {
            for j in 0..i {
                if sym {
                    w[j][i] = w[i][j];
                }
                if rng.random_bool(0.03) {
                    w[i][j] = -1;
                }
            }
        }
        let mut text = format!(
            "NAME: t\nTYPE: SOP\nDIMENSION: {n}\nEDGE_WEIGHT_TYPE: EXPLICIT\nEDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n{n}\n"
        );
        for row in &w {
            for v in row {
                text.push_str(&format!("{v} "));
            }
            text.push('\n');
        }
        text.push_str("EOF\n");
        crate::formats::tsplib::parse_sop("t.sop", &text).expect("valid instance")
    }

    fn descend(inst: &Instance, depth: usize) -> (f64, f64, Vec<u32>, bool) {
        descend_with(inst, depth, 0.0)
    }

    fn descend_with(inst: &Instance, depth: usize, penalty: f64) -> (f64, f64, Vec<u32>, bool) {
        let m = CostModel::new(inst, Objective::Matrix);
        let c = Costs::open(&m);
        let mut obs = NoObserver;
        let mut ctx = Context::new(inst, &m, 1, Budget::default(), &mut obs);
        let seq: Sequence = (0..inst.n()).map(|c| Visit::new(c, 0)).collect();
        let mut s = Solution::new(&c, &seq);
        let start = s.cost;
        let search = Search::new(c, 8);
        let mut lk = Lk::new(&c, depth, 3);
        lk.penalty = penalty;
        let mut rounds = 0;
        while lk.improve_all(&c, &search.nb, &mut s, &mut ctx) {
            // every kept chain: feasible, and the cached cost equals a full re-evaluation
            assert!(s.feasible(&m));
            assert!((s.cost - s.evaluate(&c)).abs() < 1e-6);
            rounds += 1;
            assert!(rounds < 1000);
        }
        assert!(s.feasible(&m));
        assert!((s.cost - s.evaluate(&c)).abs() < 1e-6);
        (start, s.cost, s.order.clone(), lk.symmetric)
    }

    #[test]
    fn symmetry_is_detected() {
        let m = CostModel::new(&instance(30, 1, true), Objective::Matrix);
        assert!(symmetric(&Costs::open(&m)));
        let m = CostModel::new(&instance(30, 1, false), Objective::Matrix);
        assert!(!symmetric(&Costs::open(&m)));
    }

    #[test]
    fn chains_stay_feasible_consistent_and_improve() {
        for seed in 0..4 {
            for sym in [true, false] {
                let inst = instance(60, seed, sym);
                let (start, end, _, detected) = descend(&inst, 10);
                assert_eq!(detected, sym);
                // a random order of random costs is far from any LK optimum
                assert!(end < 0.7 * start, "seed {seed} sym {sym}: {start} -> {end}");
            }
        }
    }

    #[test]
    fn chains_through_broken_pairs_keep_only_feasible_paths() {
        // chains may break up to two pairs on their way (checked to fail when a prefix that
        // breaks one is kept)
        for seed in 0..6 {
            for sym in [true, false] {
                let inst = instance(60, seed, sym);
                // every applied chain ends feasible with an exact cost (asserted inside)
                let (start, end, order, _) = descend_with(&inst, 10, 40.0);
                assert!(end < 0.7 * start, "seed {seed} sym {sym}: {start} -> {end}");
                assert_eq!(order.len(), 60);
            }
        }
    }

    #[test]
    fn undone_chains_leave_the_solution_untouched_and_runs_repeat() {
        let inst = instance(50, 7, true);
        let a = descend(&inst, 8);
        let b = descend(&inst, 8);
        assert_eq!(a.2, b.2);
        assert_eq!(a.1, b.1);
        // at an LK optimum a further pass changes nothing
        let m = CostModel::new(&inst, Objective::Matrix);
        let c = Costs::open(&m);
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
        let seq: Sequence = a.2.iter().map(|&c| Visit::new(c as usize, 0)).collect();
        let mut s = Solution::new(&c, &seq);
        let before = s.clone();
        let search = Search::new(c, 8);
        let mut lk = Lk::new(&c, 8, 3);
        assert!(!lk.improve_all(&c, &search.nb, &mut s, &mut ctx));
        assert_eq!(s, before);
    }
    /// Pairs `(a before b)` of the precedence graph that `order` puts the other way round.
    fn out_of_order(m: &CostModel, order: &[u32]) -> u32 {
        let mut pos = vec![0usize; order.len()];
        for (p, &x) in order.iter().enumerate() {
            pos[x as usize] = p;
        }
        let mut v = 0;
        for a in 0..order.len() {
            for &b in &m.dag.succs[a] {
                v += u32::from(pos[b as usize] < pos[a]);
            }
        }
        v
    }

    #[test]
    fn capped_pair_counts_are_exact_up_to_the_cap() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let inst = instance(40, 3, true);
        let m = CostModel::new(&inst, Objective::Matrix);
        let c = Costs::open(&m);
        let (mut early, mut back_in_order) = (0, 0);
        for _ in 0..2000 {
            // an order a few reversals away from a feasible one (the identity), so that it
            // breaks a few pairs, and a random segment of it
            let mut order: Vec<u32> = (0..40).collect();
            for _ in 0..rng.random_range(0..3) {
                let a = rng.random_range(0..39);
                let b = rng.random_range(a + 1..40);
                order[a..=b].reverse();
            }
            let seq: Sequence = order.iter().map(|&x| Visit::new(x as usize, 0)).collect();
            let s = Solution::new(&c, &seq);
            let viol = out_of_order(&m, &order);
            let i = rng.random_range(0..39);
            let j = rng.random_range(i + 1..40);
            let mut after = order.clone();
            after[i..=j].reverse();
            let truth = out_of_order(&m, &after);
            back_in_order += u32::from(viol > 0 && truth < viol);
            for cap in [0, 2, 5, 400] {
                let got = viol_after(&m, &s, i, j, viol, cap);
                if truth <= cap {
                    assert_eq!(got, truth, "cap {cap}");
                } else {
                    assert!(got > cap, "cap {cap}: {got} for {truth}");
                    early += u32::from(got != truth);
                }
            }
        }
        // the cap does end counts early, and reversals that put broken pairs back in order
        // occur (else this test would check nothing about either; stopping at `cap` pairs
        // put out of order instead of `cap + 1` fails it)
        assert!(early > 0 && back_in_order > 0, "{early} {back_in_order}");
    }

    #[test]
    fn lazily_charged_steps_are_the_best_charged_steps() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let mut compared = 0;
        for seed in 0..4 {
            let inst = instance(60, seed, true);
            let m = CostModel::new(&inst, Objective::Matrix);
            let c = Costs::open(&m);
            let search = Search::new(c, 8);
            let seq: Sequence = (0..60).map(|x| Visit::new(x, 0)).collect();
            let s = Solution::new(&c, &seq);
            let mut lk = Lk::new(&c, 10, 3);
            lk.penalty = 30.0;
            lk.max_viol = 2;
            for _ in 0..200 {
                let pa = rng.random_range(0..60) as isize;
                let dir = if rng.random_bool(0.5) { 1 } else { -1 };
                let want = rng.random_range(1..=3);
                let mut evals = 0;
                lk.link_candidates(&search.nb, 60);
                let got = lk.steps(&c, &s, pa, dir, 0.0, 0, want, &mut evals);
                // the reference: charge every candidate, sort, keep the flippable best
                let p2 = pa + dir;
                if !(0..60).contains(&p2) {
                    assert!(got.is_empty());
                    continue;
                }
                let t2 = s.order[p2 as usize] as usize;
                let end = if dir > 0 { 60 } else { -1 };
                let mut all: Vec<Step> = search.nb.out[t2]
                    .iter()
                    .chain(search.nb.inn[t2].iter())
                    .map(|&w| s.pos[w as usize] as isize)
                    .chain([end])
                    .filter_map(|pb| lk.step(&c, &s, pa, dir, pb, 0.0, 0, &mut evals))
                    .filter_map(|st| lk.charge(&m, &s, st))
                    .collect();
                all.sort_by(|a, b| a.score.total_cmp(&b.score).then(a.i.cmp(&b.i)));
                all.dedup_by(|a, b| a.i == b.i && a.j == b.j);
                let want_scores: Vec<f64> = all
                    .iter()
                    .filter(|st| flippable_segment(&m, &s, st.i, st.j))
                    .take(want)
                    .map(|st| st.score)
                    .collect();
                let got_scores: Vec<f64> = got.iter().map(|st| st.score).collect();
                assert_eq!(got_scores, want_scores);
                compared += usize::from(!got.is_empty());
            }
        }
        assert!(compared > 100, "{compared}");
    }
}

//! Local search for large instances on the [`TwoLevel`] list: 2-opt with mode flip, Or-opt
//! (segments of 1–3 cells, kept or reversed) and single-cell mode changes, with candidate
//! lists and don't-look bits, each applied move O(√n), and optionally ([`Large::three`])
//! sequential 3-opt moves (segment insertion of any length, see `three_opt`); then an
//! iterated local search whose kicks are local double bridges (two adjacent short blocks swap
//! places, or with 3-opt on three blocks come back in reverse order), each followed by the
//! local search from the kick's cells and undone unless the path got no worse.
//!
//! A 2-opt delta is read off the two boundary links only, which needs costs that read the same
//! backwards (the reversed link between the turned modes costs what the link forwards does):
//! true for the air length and for the time objective without linking at cutting feed
//! ([`applies`]). Precedence is kept: Or-opt moves stay inside the window between the latest
//! predecessor and the earliest successor (O(1) positions); a reversal is allowed when its
//! cells hold no precedence pair, checked over the segment for stretches up to
//! [`Large::rev_max`] cells (longer ones are skipped when the instance has precedence); kicks
//! check their blocks the same way.

mod three_opt;

pub use three_opt::THREE_K;
use three_opt::Three;

use super::moves::or_as_swap;
use super::twolevel::{TwoLevel, turn};
use super::vnd::improves;
use super::{Costs, Neighbours, Slot, Solution};
use crate::context::Context;
use crate::model::Objective;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::VecDeque;

/// Candidates per list tried as Or-opt insertion points ([`Large::or_k`]): on 10^5 `uniform`
/// cells 5 converges in 15 M evaluations to 0.790 × greedy's air, 10 in 28 M to 0.787, and
/// the kicks gain more with the evaluations saved.
pub const OR_K: usize = 5;

/// Steps of each random walk of a random-walk kick ([`Large::walk`]): the cut points stay
/// within a few candidate-list hops of the first, so the kick reconnects parts of the path
/// that are close in the plane but may lie far apart along it.
pub const WALK_STEPS: usize = 8;

/// True when the search applies: open-loop costs on a geometric instance whose links cost
/// the same read backwards (air length, or time with no linking at cutting feed).
pub fn applies(c: &Costs) -> bool {
    let m = c.m;
    !c.closed && m.is_geometric() && (m.objective() == Objective::Air || m.link_distance() == 0.0)
}

/// An applied operation, for undoing a rejected kick.
#[derive(Debug, Clone, Copy)]
enum Op {
    Rev(usize, usize),
    Swap(isize, usize, usize),
    Mode(u32, u32),
}

/// The best move found for a looked-at cell.
#[derive(Debug, Clone, Copy)]
enum Move {
    None,
    /// Or-opt: segment at `i` of `len` cells after position `p`, reversed or not.
    Or(usize, usize, isize, bool),
    /// Reversal of `i..=j`.
    Rev(usize, usize),
    /// Mode change of a cell.
    Mode(u32, u32),
    /// A sequential 3-opt move.
    Three(Three),
}

/// The large-instance search state.
pub struct Large<'a> {
    c: Costs<'a>,
    nb: &'a Neighbours,
    /// The path.
    pub t: TwoLevel,
    /// No precedence and every mode has a reversal mode: every reversal is allowed.
    free: bool,
    /// Longest stretch whose reversal is checked against precedence (instances with
    /// precedence; longer ones are not tried).
    pub rev_max: usize,
    /// Candidates per list tried as Or-opt insertion points.
    pub or_k: usize,
    /// Share of the kicks that are random-walk double bridges (cuts a few candidate-list
    /// hops apart; on instances where every reversal is allowed), the rest local ones.
    pub walk: f64,
    /// Steps of each random walk of a random-walk kick.
    pub walk_steps: usize,
    /// Also try sequential 3-opt moves from every looked-at cell (the best of all moves is
    /// applied), and kick with three blocks where there is no precedence.
    pub three: bool,
    /// Candidates per list tried for the 3-opt moves' added links.
    pub three_k: usize,
    queue: VecDeque<u32>,
    on: Vec<bool>,
    log: Vec<Op>,
    logging: bool,
}

impl<'a> Large<'a> {
    /// The search from `s` (call only when [`applies`] holds).
    pub fn new(c: Costs<'a>, nb: &'a Neighbours, s: &Solution) -> Self {
        let m = c.m;
        let free = m.dag.is_empty()
            && (0..m.n()).all(|cell| (0..m.modes(cell)).all(|md| m.turned(cell, md).is_some()));
        Large {
            c,
            nb,
            t: TwoLevel::new(s),
            free,
            rev_max: 1000,
            or_k: OR_K,
            walk: 0.0,
            walk_steps: WALK_STEPS,
            three: false,
            three_k: THREE_K,
            queue: VecDeque::new(),
            on: vec![false; s.n()],
            log: Vec::new(),
            logging: false,
        }
    }

    /// Writes the path back into `s`.
    pub fn write(&self, s: &mut Solution) {
        self.t.write(self.c.m, s);
    }

    fn push(&mut self, cell: Option<u32>) {
        if let Some(x) = cell
            && !self.on[x as usize]
        {
            self.on[x as usize] = true;
            self.queue.push_back(x);
        }
    }

    #[inline]
    fn link(&self, a: Slot, b: Slot) -> f64 {
        self.c.link(a, b)
    }

    #[inline]
    fn sl(&self, cell: Option<u32>) -> Slot {
        self.t.slot(self.c.m, cell)
    }

    /// `cell` cut the other way.
    #[inline]
    fn fl(&self, cell: Option<u32>) -> Slot {
        let m = self.c.m;
        cell.map(|x| (x as usize, turn(m, x as usize, self.t.mode(m, x)) as usize))
    }

    /// True when the cell in its current mode has a reversal mode.
    #[inline]
    fn turnable(&self, cell: u32) -> bool {
        let m = self.c.m;
        m.turned(cell as usize, self.t.mode(m, cell) as usize)
            .is_some()
    }

    /// True when `i..=j` may be reversed.
    fn reversible(&self, i: usize, j: usize) -> bool {
        if self.free {
            return true;
        }
        if j - i + 1 > self.rev_max {
            return false;
        }
        let m = self.c.m;
        let mut x = self.t.cell_at(i);
        for _ in i..=j {
            if !self.turnable(x) {
                return false;
            }
            for &q in &m.dag.succs[x as usize] {
                let pq = self.t.pos(q);
                if pq >= i && pq <= j {
                    return false;
                }
            }
            match self.t.next(x) {
                Some(y) => x = y,
                None => break,
            }
        }
        true
    }

    /// Insertion window of the segment `seg` starting at position `i` (as [`super::moves::window`]).
    fn window(&self, seg: &[u32], i: usize) -> (isize, isize) {
        let m = self.c.m;
        let len = seg.len();
        let (mut lo, mut hi) = (-1isize, self.t.n() as isize);
        for &x in seg {
            for &q in &m.dag.preds[x as usize] {
                let pq = self.t.pos(q) as isize;
                if pq < i as isize {
                    lo = lo.max(pq);
                }
            }
            for &q in &m.dag.succs[x as usize] {
                let pq = self.t.pos(q) as isize;
                if pq >= (i + len) as isize {
                    hi = hi.min(pq);
                }
            }
        }
        (lo, hi)
    }

    /// The best improving move around cell `x` and the number of deltas evaluated.
    fn best_move(&self, x: u32) -> (f64, Move, u64) {
        let mut best = (0.0, Move::None);
        let mut evals = 0u64;
        self.mode_moves(x, &mut best, &mut evals);
        let lx = self.link(self.sl(self.t.prev(x)), self.sl(Some(x)));
        self.two_opt_moves(x, lx, &mut best, &mut evals);
        if !(self.three && self.free) {
            // without precedence, segment insertions are among the 3-opt moves
            self.or_moves(x, lx, &mut best, &mut evals);
        }
        if self.three {
            self.three_opt_moves(x, &mut best, &mut evals);
        }
        (best.0, best.1, evals)
    }

    /// Mode changes of cell `x` in place, where better than `best`.
    fn mode_moves(&self, x: u32, best: &mut (f64, Move), evals: &mut u64) {
        let m = self.c.m;
        let t = &self.t;
        let (px, nx) = (t.prev(x), t.next(x));
        // mode change
        let k = m.modes(x as usize) as u32;
        if k > 1 {
            let cur = t.mode(m, x);
            let (a, b) = (self.sl(px), self.sl(nx));
            let here = self.link(a, Some((x as usize, cur as usize)))
                + self.link(Some((x as usize, cur as usize)), b);
            for md in 0..k {
                if md != cur {
                    *evals += 1;
                    let s = Some((x as usize, md as usize));
                    let d = self.link(a, s) + self.link(s, b) - here;
                    if d < best.0 {
                        *best = (d, Move::Mode(x, md));
                    }
                }
            }
        }
    }

    /// 2-opt moves with an end at cell `x` (new links x → y' or x' → y for y after x,
    /// y → x' or y' → x for y before x), where better than `best`; `lx`: the link into x.
    fn two_opt_moves(&self, x: u32, lx: f64, best: &mut (f64, Move), evals: &mut u64) {
        let t = &self.t;
        let nb = self.nb;
        let q = t.pos(x);
        let (px, nx) = (t.prev(x), t.next(x));
        // 2-opt: new links x → y' or x' → y (y after x), y → x' or y' → x (y before x)
        let rx = self.link(self.sl(Some(x)), self.sl(nx));
        let (flx, frx) = (self.fl(Some(x)), self.sl(Some(x)));
        for (k, &y) in nb.out[x as usize].iter().chain(t.last().iter()).enumerate() {
            let r = t.pos(y);
            if r <= q + 1 || (k == nb.out[x as usize].len() && nb.out[x as usize].contains(&y)) {
                continue;
            }
            let ny = t.next(y);
            let py = t.prev(y);
            // reverse [q+1..=r]: x → y', (x+1)' → y+1
            *evals += 2;
            let d = self.link(frx, self.fl(Some(y))) + self.link(self.fl(nx), self.sl(ny))
                - rx
                - self.link(self.sl(Some(y)), self.sl(ny));
            if d < best.0 && self.reversible(q + 1, r) {
                *best = (d, Move::Rev(q + 1, r));
            }
            // reverse [q..=r-1]: x-1 → (y-1)', x' → y
            if r - 1 > q {
                let d = self.link(self.sl(px), self.fl(py)) + self.link(flx, self.sl(Some(y)))
                    - lx
                    - self.link(self.sl(py), self.sl(Some(y)));
                if d < best.0 && self.reversible(q, r - 1) {
                    *best = (d, Move::Rev(q, r - 1));
                }
            }
        }
        for (k, &y) in nb.inn[x as usize]
            .iter()
            .chain(t.first().iter())
            .enumerate()
        {
            let r = t.pos(y);
            if r + 1 >= q || (k == nb.inn[x as usize].len() && nb.inn[x as usize].contains(&y)) {
                continue;
            }
            let ny = t.next(y);
            let py = t.prev(y);
            *evals += 2;
            // reverse [r+1..=q]: y → x', (y+1)' → x+1
            let d = self.link(self.sl(Some(y)), flx) + self.link(self.fl(ny), self.sl(nx))
                - self.link(self.sl(Some(y)), self.sl(ny))
                - rx;
            if d < best.0 && self.reversible(r + 1, q) {
                *best = (d, Move::Rev(r + 1, q));
            }
            // reverse [r..=q-1]: y-1 → (x-1)', y' → x
            let d = self.link(self.sl(py), self.fl(px)) + self.link(self.fl(Some(y)), frx)
                - self.link(self.sl(py), self.sl(Some(y)))
                - lx;
            if d < best.0 && self.reversible(r, q - 1) {
                *best = (d, Move::Rev(r, q - 1));
            }
        }
    }

    /// Or-opt moves of the segments x, x+1, x+2 (following the path), kept or reversed, to
    /// an insertion point next to a candidate neighbour, where better than `best`; `lx`: the
    /// link into x.
    fn or_moves(&self, x: u32, lx: f64, best: &mut (f64, Move), evals: &mut u64) {
        let t = &self.t;
        let n = t.n();
        let nb = self.nb;
        let q = t.pos(x);
        let px = t.prev(x);
        // Or-opt: segments x, x+1, x+2 following the path
        let mut seg = [x; 3];
        let mut len = 0usize;
        let mut y = Some(x);
        while len < 3
            && let Some(z) = y
        {
            seg[len] = z;
            len += 1;
            let (first, last) = (seg[0], seg[len - 1]);
            let after = t.next(last);
            let (lo, hi) = if self.free {
                (-1, n as isize)
            } else {
                self.window(&seg[..len], q)
            };
            let rev_ok = len > 1 && self.reversible(q, q + len - 1);
            let e = (q + len - 1) as isize;
            let close = self.link(self.sl(px), self.sl(after))
                - lx
                - self.link(self.sl(Some(last)), self.sl(after));
            let mut inner_rev = 0.0;
            if rev_ok {
                for w in seg[..len].windows(2) {
                    inner_rev += self.link(self.fl(Some(w[1])), self.fl(Some(w[0])))
                        - self.link(self.sl(Some(w[0])), self.sl(Some(w[1])));
                }
            }
            let (sf, sl) = (self.sl(Some(first)), self.sl(Some(last)));
            let (ff, fl) = (self.fl(Some(first)), self.fl(Some(last)));
            // insertion between v and its successor: v from inn(first/last), prev of out(last/first)
            let ok = self.or_k;
            let cut = |v: &'a [u32]| &v[..ok.min(v.len())];
            let cands = cut(&nb.inn[first as usize])
                .iter()
                .map(|&v| Some(v))
                .chain(cut(&nb.out[last as usize]).iter().map(|&w| t.prev(w)))
                .chain(
                    cut(&nb.inn[last as usize])
                        .iter()
                        .filter(|_| len > 1)
                        .map(|&v| Some(v)),
                )
                .chain(
                    cut(&nb.out[first as usize])
                        .iter()
                        .filter(|_| len > 1)
                        .map(|&w| t.prev(w)),
                );
            for v in cands {
                let p = v.map_or(-1, |v| t.pos(v) as isize);
                if (p >= q as isize - 1 && p <= e) || p < lo || p >= hi {
                    continue;
                }
                let w = match v {
                    Some(v) => t.next(v),
                    None => t.first(),
                };
                let (a, b) = (self.sl(v), self.sl(w));
                let open = self.link(a, b);
                *evals += 1;
                let d = close + self.link(a, sf) + self.link(sl, b) - open;
                if d < best.0 {
                    *best = (d, Move::Or(q, len, p, false));
                }
                if rev_ok {
                    *evals += 1;
                    let d = close + inner_rev + self.link(a, fl) + self.link(ff, b) - open;
                    if d < best.0 {
                        *best = (d, Move::Or(q, len, p, true));
                    }
                }
            }
            y = after;
        }
    }

    fn apply_reverse(&mut self, i: usize, j: usize, d: f64) {
        let t = &self.t;
        let cells = [
            if i > 0 { Some(t.cell_at(i - 1)) } else { None },
            Some(t.cell_at(i)),
            Some(t.cell_at(j)),
            t.next(t.cell_at(j)),
        ];
        self.t.reverse(self.c.m, i, j, d);
        if self.logging {
            self.log.push(Op::Rev(i, j));
        }
        for x in cells {
            self.push(x);
        }
    }

    fn apply_swap(&mut self, h: isize, i: usize, j: usize, d: f64) {
        let t = &self.t;
        let cells = [
            (h >= 0).then(|| t.cell_at(h as usize)),
            Some(t.cell_at((h + 1) as usize)),
            Some(t.cell_at(i)),
            Some(t.cell_at(i + 1)),
            Some(t.cell_at(j)),
            t.next(t.cell_at(j)),
        ];
        self.t.swap_blocks(self.c.m, h, i, j, d);
        if self.logging {
            self.log.push(Op::Swap(h, i, j));
        }
        for x in cells {
            self.push(x);
        }
    }

    fn apply(&mut self, d: f64, mv: Move) {
        let m = self.c.m;
        match mv {
            Move::None => {}
            Move::Mode(x, md) => {
                if self.logging {
                    self.log.push(Op::Mode(x, self.t.mode(m, x)));
                }
                self.t.set_mode(m, x, md, d);
                let (p, q) = (self.t.prev(x), self.t.next(x));
                for y in [p, Some(x), q] {
                    self.push(y);
                }
            }
            Move::Rev(i, j) => self.apply_reverse(i, j, d),
            Move::Three(mv) => self.apply_three(mv, d),
            Move::Or(i, len, p, rev) => {
                // the cells next to the insertion point (they get new links)
                let v = (p >= 0).then(|| self.t.cell_at(p as usize));
                let w = match v {
                    Some(v) => self.t.next(v),
                    None => self.t.first(),
                };
                let ((h, a, b), (start, end)) = or_as_swap(i, len, p);
                self.apply_swap(h, a, b, d);
                if rev {
                    self.apply_reverse(start, end, 0.0);
                }
                self.push(v);
                self.push(w);
            }
        }
    }

    /// Runs the local search until no looked-at cell has an improving move (or the budget
    /// ends). Returns true on any improvement.
    fn descend(&mut self, ctx: &mut Context) -> bool {
        let mut improved = false;
        while let Some(x) = self.queue.pop_front() {
            self.on[x as usize] = false;
            if ctx.exhausted() {
                break;
            }
            let (d, mv, evals) = self.best_move(x);
            ctx.count(evals);
            if improves(d, self.t.cost) {
                self.apply(d, mv);
                self.push(Some(x));
                improved = true;
            }
        }
        improved
    }

    /// 2-opt, Or-opt and mode changes from every cell to a local optimum (or the budget).
    /// Returns true on any improvement.
    pub fn optimize(&mut self, ctx: &mut Context) -> bool {
        for p in 0..self.t.n() {
            let x = self.t.cell_at(p);
            self.push(Some(x));
        }
        self.descend(ctx)
    }

    /// Iterated local search with local double-bridge kicks: blocks of 1..=`block` cells at a
    /// random place swap, the search runs from the cells whose links changed, and the result
    /// is kept when it is no worse (else every operation since the kick is undone). Runs
    /// until the budget ends, or after `patience` kicks in a row without improvement.
    /// Returns the number of kicks.
    pub fn kicks(&mut self, ctx: &mut Context, seed: u64, block: usize, patience: u64) -> u64 {
        let n = self.t.n();
        let block = block.max(1);
        if n < 4 {
            return 0;
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut kicks = 0u64;
        let mut fails = 0u64;
        self.logging = true;
        while !ctx.exhausted() && fails < patience {
            kicks += 1;
            ctx.count(1);
            let before = self.t.cost;
            self.log.clear();
            if !self.kick(&mut rng, block) {
                fails += 1;
                continue;
            }
            self.descend(ctx);
            if self.t.cost <= before {
                if improves(self.t.cost - before, before) {
                    fails = 0;
                } else {
                    fails += 1;
                }
            } else {
                self.undo();
                self.t.cost = before;
                fails += 1;
            }
        }
        self.clear_queue();
        self.logging = false;
        kicks
    }

    /// Applies one kick (logged): with [`Large::three`] on an instance without precedence,
    /// three adjacent blocks B C D come back as D C B (four links change, so a 3-opt move
    /// cannot simply take it back); else two adjacent blocks swap. The cuts are a random
    /// walk's ([`Large::walk`]) or blocks of 1..=`block` cells at a random place. False
    /// when no kick was applied (cuts coinciding, precedence).
    fn kick(&mut self, rng: &mut ChaCha8Rng, block: usize) -> bool {
        let n = self.t.n();
        let m = self.c.m;
        let blocks = if self.three && self.free && n >= 6 {
            3
        } else {
            2
        };
        let mut cuts = [0isize; 4];
        if self.free && self.walk > 0.0 && rng.random_bool(self.walk) {
            if !self.walk_cuts(rng, &mut cuts[..=blocks]) {
                return false;
            }
        } else {
            let most = block.min(n / (blocks + 1)).max(1);
            let mut lens = [0usize; 3];
            for l in &mut lens[..blocks] {
                *l = rng.random_range(1..=most);
            }
            let total: usize = lens.iter().sum();
            cuts[0] = rng.random_range(0..(n - total) as i64) as isize - 1;
            for b in 0..blocks {
                cuts[b + 1] = cuts[b] + lens[b] as isize;
            }
        }
        let at = |p: isize| self.t.at(m, p);
        let removed: f64 = cuts[..=blocks]
            .iter()
            .map(|&c| self.link(at(c), at(c + 1)))
            .sum();
        if blocks == 2 {
            let [h, i, j, _] = cuts;
            if !self.free && !self.swappable(h, i as usize, j as usize) {
                return false;
            }
            let d = self.link(at(h), at(i + 1))
                + self.link(at(j), at(h + 1))
                + self.link(at(i), at(j + 1))
                - removed;
            self.apply_swap(h, i as usize, j as usize, d);
        } else {
            // A B C D E → A D C B E
            let [h, i, j, k] = cuts;
            let d = self.link(at(h), at(j + 1))
                + self.link(at(k), at(i + 1))
                + self.link(at(j), at(h + 1))
                + self.link(at(i), at(k + 1))
                - removed;
            let (lc, ld) = ((j - i) as usize, (k - j) as usize);
            self.apply_swap(h, i as usize, k as usize, d);
            let c_end = h as usize + lc;
            self.apply_swap(h, c_end, c_end + ld, 0.0);
        }
        true
    }

    /// Leaves no cell queued.
    fn clear_queue(&mut self) {
        while let Some(x) = self.queue.pop_front() {
            self.on[x as usize] = false;
        }
    }

    /// The cuts of a random-walk kick (after Applegate, Cook and Rohe's kick for large
    /// instances), into `cuts` (3 or 4 of them): a random cell and the ends of random walks of
    /// [`Large::walk_steps`] hops over the candidate lists from it, sorted along the path, cut
    /// after each; false when two of them coincide.
    fn walk_cuts(&self, rng: &mut ChaCha8Rng, cuts: &mut [isize]) -> bool {
        let n = self.t.n();
        let start = self.t.cell_at(rng.random_range(0..n));
        cuts[0] = self.t.pos(start) as isize;
        for c in cuts[1..].iter_mut() {
            let mut x = start;
            for _ in 0..self.walk_steps {
                let out = &self.nb.out[x as usize];
                if out.is_empty() {
                    break;
                }
                x = out[rng.random_range(0..out.len())];
            }
            *c = self.t.pos(x) as isize;
        }
        cuts.sort_unstable();
        cuts.windows(2).all(|w| w[0] < w[1])
    }

    /// True when blocks `[h+1..=i]` and `[i+1..=j]` may swap: no cell of the first block
    /// precedes one of the second.
    fn swappable(&self, h: isize, i: usize, j: usize) -> bool {
        let m = self.c.m;
        let mut x = self.t.cell_at((h + 1) as usize);
        for _ in (h + 1) as usize..=i {
            for &q in &m.dag.succs[x as usize] {
                let pq = self.t.pos(q);
                if pq > i && pq <= j {
                    return false;
                }
            }
            match self.t.next(x) {
                Some(y) => x = y,
                None => break,
            }
        }
        true
    }

    fn undo(&mut self) {
        let m = self.c.m;
        while let Some(op) = self.log.pop() {
            match op {
                Op::Rev(i, j) => self.t.reverse(m, i, j, 0.0),
                Op::Swap(h, i, j) => {
                    let b = j - i;
                    self.t.swap_blocks(m, h, (h + b as isize) as usize, j, 0.0)
                }
                Op::Mode(x, md) => self.t.set_mode(m, x, md, 0.0),
            }
        }
        self.clear_queue();
    }
}

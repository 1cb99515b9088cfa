//! `drawing`: the sequencer for pen-plotter, laser and cutter drawings.
//!
//! Precedence-aware nearest neighbour (the `greedy` solver's k-d trees, exact and robust to
//! coincident or far-apart points), then, on flat single-tool instances without precedence
//! whose air cost is the planar distance (every drawing a plotter or laser draws), a local
//! search over the open path: 2-opt (reversing a block of the order also reverses each stroke
//! in it), Or-opt (one stroke moved next to a neighbour, in any of its modes: direction or
//! start vertex) and mode change, driven by a queue of cells (don't-look bits) and candidate
//! lists of the K nearest cells ([`crate::engine::neighbours`], k-d trees, no n × n matrix).
//! Then, while the budget lasts, iterated local search: a random swap of two short adjacent
//! blocks, the queue-driven repair around it, and the change undone unless it saves travel.
//! Last, on drawings of up to 3000 strokes, sweeps of 2-opt and Or-opt over every pair (not
//! only the candidate lists) to a local optimum.
//! Every move costs O(1) to evaluate; a 2-opt costs the length of the reversed block to
//! apply. Other instances (precedence, several tools, lifts, matrix costs) get `local-search`.

use super::Build;
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo, outcome_of};
use crate::cost::CostModel;
use crate::engine::neighbours::Neighbours;
use crate::error::Result;
use crate::model::{Objective, Visit};
use std::collections::VecDeque;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "drawing",
    summary: "drawings: greedy, then 2-opt/Or-opt with reversal and iterated local search \
              (flat single-tool instances without precedence; else local-search)",
    description: "The default of `cellseq optimize` on SVG and DXF drawings: strokes are cells that may be \
drawn either way (and closed paths from any vertex). Greedy on k-d trees, then 2-opt with \
stroke reversal, Or-opt and start-vertex moves on candidate lists, then iterated local \
search until the budget. Other instances get `local-search`. Details: \
[drawings.md](drawings.md).",
    params: &[
        ParamSpec {
            name: "k",
            default: "10",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate neighbours per stroke",
        },
        ParamSpec {
            name: "kick-len",
            default: "30",
            kind: ParamKind::int(2, crate::params::MAX_CELLS),
            help: "longest block moved by an iterated-local-search kick",
        },
    ],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Drawing {
            k: p.int("k") as usize,
            kick_len: p.int("kick-len") as usize,
        }))
    }),
};

/// The drawing sequencer.
pub struct Drawing {
    /// Candidate neighbours per cell.
    pub k: usize,
    /// Longest block of a kick.
    pub kick_len: usize,
}

impl Solver for Drawing {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        if !m.is_geometric() {
            return fallback(ctx);
        }
        let deadline = ctx.deadline();
        let start = crate::construct::greedy::geometric_until(m, &mut |k| ctx.count(k), deadline);
        if !flat(m) || start.len() < 4 || deadline.passed() {
            let out = outcome_of(m, start);
            ctx.report(out.cost);
            if !flat(m) && !deadline.passed() {
                return fallback_from(ctx, out);
            }
            return Ok(out);
        }
        ctx.report(m.evaluate(&start));
        let nb = Neighbours::new_until(m, self.k, ctx.deadline());
        let mut p = Path::new(m, start, nb.merged());
        let all: Vec<u32> = p.t.iter().map(|v| v.cell as u32).collect();
        p.descend(ctx, all);
        ctx.report(m.evaluate(&p.t));
        let limited = ctx.budget.max_evals.is_some() || ctx.budget.time_limit.is_some();
        let mut rng = SplitMix(ctx.seed ^ 0x9e37_79b9_7f4a_7c15);
        while limited && !ctx.exhausted() {
            p.kick(ctx, &mut rng, self.kick_len);
        }
        p.polish(ctx, deadline);
        let out = outcome_of(m, p.t);
        ctx.report(out.cost);
        Ok(out)
    }
}

/// Flat, single tool, no precedence, every mode can be turned, air = planar distance.
fn flat(m: &CostModel) -> bool {
    if m.objective() != Objective::Air || m.dag.preds.iter().any(|p| !p.is_empty()) {
        return false;
    }
    let n = m.n();
    if n == 0 {
        return false;
    }
    let tool = m.tool(0);
    let z = m.entry(0).z;
    (0..n).all(|c| {
        m.tool(c) == tool
            && (0..m.modes(c)).all(|md| {
                let nd = m.node(c, md);
                m.entry(nd).z == z
                    && m.exit(nd).z == z
                    && m.lift_floor(c, md) == 0.0
                    && m.turned(c, md).is_some()
            })
    })
}

fn fallback(ctx: &mut Context) -> Result<Outcome> {
    let budget = super::Budget {
        time_limit: ctx.budget.time_limit,
        max_evals: ctx
            .budget
            .max_evals
            .map(|e| e.saturating_sub(ctx.evaluations())),
    };
    let seed = ctx.seed;
    let out = super::sub_run(ctx, super::Sub::new("local-search", budget, seed))?;
    ctx.report(out.cost);
    Ok(out)
}

fn fallback_from(ctx: &mut Context, greedy: Outcome) -> Result<Outcome> {
    let out = fallback(ctx)?;
    Ok(if out.cost <= greedy.cost { out } else { greedy })
}

/// A small deterministic generator (SplitMix64).
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// An applied change, kept to undo a rejected kick.
#[derive(Clone, Copy)]
enum Op {
    /// Block i..=j reversed (its own inverse).
    Reverse(usize, usize),
    /// The visit at `from` moved to `to` (with its old mode `mode`).
    Move { from: usize, to: usize, mode: u32 },
    /// Mode of the visit at position `at` changed from `mode`.
    Mode { at: usize, mode: u32 },
    /// `t[a..b]` rotated left by `k`.
    Rotate(usize, usize, usize),
}

/// The open path with positions, candidate lists and an undo log.
struct Path<'m> {
    m: &'m CostModel,
    t: Vec<Visit>,
    pos: Vec<usize>,
    cands: Vec<Vec<u32>>,
    log: Vec<Op>,
    queued: Vec<bool>,
}

const EPS: f64 = 1e-9;

/// Largest drawing (strokes) that gets the final all-pairs pass ([`Path::polish`]).
const POLISH_MAX: usize = 3000;

/// Most sweeps of the final all-pairs pass.
const POLISH_SWEEPS: usize = 20;

impl<'m> Path<'m> {
    fn new(m: &'m CostModel, t: Vec<Visit>, cands: Vec<Vec<u32>>) -> Self {
        let mut pos = vec![0; t.len()];
        for (i, v) in t.iter().enumerate() {
            pos[v.cell] = i;
        }
        let n = t.len();
        Path {
            m,
            t,
            pos,
            cands,
            log: Vec::new(),
            queued: vec![false; n],
        }
    }

    /// Cost of arriving at position `i` with visit `v` (from position i-1).
    fn arc_into(&self, i: usize, v: Visit) -> f64 {
        if i == 0 {
            self.m.start(v.cell, v.mode)
        } else {
            let u = self.t[i - 1];
            self.m.arc(u.cell, u.mode, v.cell, v.mode)
        }
    }
    /// Cost of leaving position `j` with visit `v` (to position j+1, or the finish).
    fn out_of(&self, j: usize, v: Visit) -> f64 {
        if j + 1 == self.t.len() {
            self.m.finish(v.cell, v.mode)
        } else {
            let w = self.t[j + 1];
            self.m.arc(v.cell, v.mode, w.cell, w.mode)
        }
    }
    fn turned(&self, v: Visit) -> Visit {
        Visit::new(v.cell, self.m.turned_or_same(v.cell, v.mode))
    }
    /// Saving of reversing block i..=j (costs are symmetric inside the block).
    fn reverse_gain(&self, i: usize, j: usize) -> f64 {
        let (a, b) = (self.t[i], self.t[j]);
        self.arc_into(i, a) + self.out_of(j, b)
            - self.arc_into(i, self.turned(b))
            - self.out_of(j, self.turned(a))
    }
    fn reverse(&mut self, i: usize, j: usize) {
        self.t[i..=j].reverse();
        for k in i..=j {
            let v = self.turned(self.t[k]);
            self.t[k] = v;
            self.pos[v.cell] = k;
        }
        self.log.push(Op::Reverse(i, j));
    }
    fn set_mode(&mut self, at: usize, mode: usize) {
        let old = self.t[at].mode as u32;
        self.t[at].mode = mode;
        self.log.push(Op::Mode { at, mode: old });
    }
    /// Moves the visit at `from` so that it ends at index `to`, in mode `mode`.
    fn move_to(&mut self, from: usize, to: usize, mode: usize) {
        let old = self.t[from].mode as u32;
        if from < to {
            self.t[from..=to].rotate_left(1);
        } else {
            self.t[to..=from].rotate_right(1);
        }
        self.t[to].mode = mode;
        let (lo, hi) = (from.min(to), from.max(to));
        for k in lo..=hi {
            self.pos[self.t[k].cell] = k;
        }
        self.log.push(Op::Move {
            from,
            to,
            mode: old,
        });
    }
    fn rotate(&mut self, a: usize, b: usize, k: usize) {
        self.t[a..b].rotate_left(k);
        for i in a..b {
            self.pos[self.t[i].cell] = i;
        }
        self.log.push(Op::Rotate(a, b, k));
    }
    /// Undoes the log back to length `mark`.
    fn undo(&mut self, mark: usize) {
        while self.log.len() > mark {
            match self.log.pop().expect("log entry") {
                Op::Reverse(i, j) => {
                    self.reverse(i, j);
                    self.log.pop();
                }
                Op::Move { from, to, mode } => {
                    self.move_to(to, from, mode as usize);
                    self.log.pop();
                }
                Op::Mode { at, mode } => {
                    self.t[at].mode = mode as usize;
                }
                Op::Rotate(a, b, k) => {
                    self.rotate(a, b, b - a - k);
                    self.log.pop();
                }
            }
        }
    }

    /// The best improving move around the cell `c`; applies it and returns its saving and
    /// the positions whose neighbourhood changed.
    fn improve(&mut self, ctx: &mut Context, c: usize, touched: &mut Vec<usize>) -> f64 {
        let n = self.t.len();
        let p = self.pos[c];
        let mut evals = 0u64;
        // (gain, kind, a, b, mode): kind 0 = reverse a..=b, 1 = move a -> b in mode, 2 = mode
        let mut best = (EPS, 0u8, 0usize, 0usize, 0usize);
        // 2-opt: blocks starting at p (new first visit near the predecessor) and ending at p
        let pred = if p == 0 {
            self.t[0].cell
        } else {
            self.t[p - 1].cell
        };
        for &x in &self.cands[pred] {
            let j = self.pos[x as usize];
            if j >= p {
                evals += 1;
                let g = self.reverse_gain(p, j);
                if g > best.0 {
                    best = (g, 0, p, j, 0);
                }
            }
        }
        if p + 1 < n {
            for &x in &self.cands[self.t[p + 1].cell] {
                let i = self.pos[x as usize];
                if i <= p {
                    evals += 1;
                    let g = self.reverse_gain(i, p);
                    if g > best.0 {
                        best = (g, 0, i, p, 0);
                    }
                }
            }
        }
        // mode change in place
        let v = self.t[p];
        let here = self.arc_into(p, v) + self.out_of(p, v);
        for md in 0..self.m.modes(c) {
            if md != v.mode {
                evals += 1;
                let w = Visit::new(c, md);
                let g = here - self.arc_into(p, w) - self.out_of(p, w);
                if g > best.0 {
                    best = (g, 2, p, p, md);
                }
            }
        }
        // Or-opt: take the visit out and put it next to a candidate, in its best mode
        let removed = if n > 1 {
            let bridge = if p == 0 {
                let w = self.t[1];
                self.m.start(w.cell, w.mode)
            } else if p + 1 == n {
                let u = self.t[p - 1];
                self.m.finish(u.cell, u.mode)
            } else {
                let (u, w) = (self.t[p - 1], self.t[p + 1]);
                self.m.arc(u.cell, u.mode, w.cell, w.mode)
            };
            here - bridge
        } else {
            0.0
        };
        for &x in &self.cands[c] {
            let q = self.pos[x as usize];
            // insert between positions (g-1, g) of the path without c
            for gap in [q, q + 1] {
                if gap == p || gap == p + 1 || gap > n {
                    continue;
                }
                let before = if gap == 0 {
                    None
                } else {
                    Some(self.t[gap - 1])
                };
                let after = (gap < n).then(|| self.t[gap]);
                let old = match (before, after) {
                    (Some(u), Some(w)) => self.m.arc(u.cell, u.mode, w.cell, w.mode),
                    (None, Some(w)) => self.m.start(w.cell, w.mode),
                    (Some(u), None) => self.m.finish(u.cell, u.mode),
                    (None, None) => 0.0,
                };
                for md in 0..self.m.modes(c) {
                    evals += 1;
                    let inn = match before {
                        Some(u) => self.m.arc(u.cell, u.mode, c, md),
                        None => self.m.start(c, md),
                    };
                    let out = match after {
                        Some(w) => self.m.arc(c, md, w.cell, w.mode),
                        None => self.m.finish(c, md),
                    };
                    let g = removed - (inn + out - old);
                    if g > best.0 {
                        let to = if gap > p { gap - 1 } else { gap };
                        best = (g, 1, p, to, md);
                    }
                }
            }
        }
        ctx.count(evals);
        let (g, kind, a, b, md) = best;
        if g <= EPS {
            return 0.0;
        }
        match kind {
            0 => self.reverse(a, b),
            1 => self.move_to(a, b, md),
            _ => self.set_mode(a, md),
        }
        let (lo, hi) = (a.min(b), a.max(b));
        touched.extend([lo.saturating_sub(1), lo, hi, (hi + 1).min(n - 1)]);
        g
    }

    /// Queue-driven descent from the cells `seed`; returns the total saving.
    fn descend(&mut self, ctx: &mut Context, seed: Vec<u32>) -> f64 {
        let mut queue: VecDeque<u32> = VecDeque::with_capacity(seed.len());
        for c in seed {
            if !self.queued[c as usize] {
                self.queued[c as usize] = true;
                queue.push_back(c);
            }
        }
        let mut saved = 0.0;
        let mut touched = Vec::new();
        let mut pops = 0u32;
        while let Some(c) = queue.pop_front() {
            self.queued[c as usize] = false;
            pops += 1;
            if pops.is_multiple_of(64) && ctx.exhausted() {
                break;
            }
            touched.clear();
            let g = self.improve(ctx, c as usize, &mut touched);
            if g > 0.0 {
                saved += g;
                for &k in &touched {
                    let x = self.t[k].cell;
                    if !self.queued[x] {
                        self.queued[x] = true;
                        queue.push_back(x as u32);
                    }
                }
                if !self.queued[c as usize] {
                    self.queued[c as usize] = true;
                    queue.push_back(c);
                }
            }
        }
        for c in queue {
            self.queued[c as usize] = false;
        }
        saved
    }

    /// One iterated-local-search step: swap two adjacent short blocks, repair, keep the
    /// result only when it saves travel.
    fn kick(&mut self, ctx: &mut Context, rng: &mut SplitMix, max_len: usize) {
        let n = self.t.len();
        let a = rng.below(n - 2);
        let l1 = 1 + rng.below(max_len.min(n - a - 1).max(1));
        let rest = n - a - l1;
        if rest == 0 {
            return;
        }
        let l2 = 1 + rng.below(max_len.min(rest));
        let b = a + l1 + l2;
        let mark = self.log.len();
        let before = self.window_cost(a, b);
        self.rotate(a, b, l1);
        ctx.count(4);
        let cost = before - self.window_cost(a, b);
        let seed: Vec<u32> = [a, a + l2 - 1, a + l2, b - 1]
            .into_iter()
            .chain([a.saturating_sub(1), (b).min(n - 1)])
            .map(|k| self.t[k].cell as u32)
            .collect();
        let saved = cost + self.descend(ctx, seed);
        if saved > EPS {
            self.log.truncate(mark);
        } else {
            self.undo(mark);
        }
    }

    /// Cost of going from `a` to `b` (`None`: the path's start or end).
    fn link(&self, a: Option<Visit>, b: Option<Visit>) -> f64 {
        match (a, b) {
            (Some(a), Some(b)) => self.m.arc(a.cell, a.mode, b.cell, b.mode),
            (None, Some(b)) => self.m.start(b.cell, b.mode),
            (Some(a), None) => self.m.finish(a.cell, a.mode),
            (None, None) => 0.0,
        }
    }

    /// The final pass to a local optimum over every pair, not only the candidate lists:
    /// sweeps of 2-opt (every block reversed, strokes turned) and Or-opt (every stroke moved to
    /// every place, in every mode) until a sweep finds nothing, on drawings of at most
    /// [`POLISH_MAX`] strokes, at most [`POLISH_SWEEPS`] sweeps. It runs after the budget (a
    /// sweep is O(n²) cheap evaluations, milliseconds at the cap) and depends on nothing but
    /// the path, so results stay deterministic; under a time limit it stops at `deadline`
    /// (the clock read once per row of pairs).
    fn polish(&mut self, ctx: &mut Context, deadline: crate::clock::Deadline) {
        let n = self.t.len();
        if n > POLISH_MAX {
            return;
        }
        let past = || deadline.passed();
        for _ in 0..POLISH_SWEEPS {
            let mut improved = false;
            for i in 0..n {
                if past() {
                    self.log.clear();
                    return;
                }
                for j in i + 1..n {
                    if self.reverse_gain(i, j) > EPS {
                        self.reverse(i, j);
                        improved = true;
                    }
                }
            }
            ctx.count((n * n / 2) as u64);
            for p in 0..n {
                if past() {
                    self.log.clear();
                    return;
                }
                let v = self.t[p];
                let (prev, next) = (
                    p.checked_sub(1).map(|k| self.t[k]),
                    self.t.get(p + 1).copied(),
                );
                let removal =
                    self.link(prev, Some(v)) + self.link(Some(v), next) - self.link(prev, next);
                // the path without v: s[k] = t[k] before p, t[k + 1] from p on
                let s = |k: usize| if k < p { self.t[k] } else { self.t[k + 1] };
                let mut best = (EPS, p, v.mode);
                for to in 0..n {
                    let a = (to > 0).then(|| s(to - 1));
                    let b = (to + 1 < n).then(|| s(to));
                    let gap = self.link(a, b);
                    for md in 0..self.m.modes(v.cell) {
                        if to == p && md == v.mode {
                            continue;
                        }
                        let w = Visit::new(v.cell, md);
                        let g = removal - (self.link(a, Some(w)) + self.link(Some(w), b) - gap);
                        if g > best.0 {
                            best = (g, to, md);
                        }
                    }
                }
                ctx.count(n as u64);
                if best.0 > EPS {
                    self.move_to(p, best.1, best.2);
                    improved = true;
                }
            }
            self.log.clear();
            if !improved {
                break;
            }
        }
    }

    /// Cost of the arcs into positions a..b and out of b-1.
    fn window_cost(&self, a: usize, b: usize) -> f64 {
        let mut s = 0.0;
        for i in a..b {
            s += self.arc_into(i, self.t[i]);
        }
        s + self.out_of(b - 1, self.t[b - 1])
    }
}

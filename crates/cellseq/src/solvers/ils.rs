//! `ils`: iterated local search over the shared engine — cellseq's strongest general solver.
//!
//! Start from the greedy sequence and descend with the full VND. Then repeat: kick the
//! current solution (`perturb`: a random feasible reorder of a window, the default; random
//! feasible segment swaps; or ruin and recreate, [`crate::engine::ruin`], whose O(n) kick
//! suits instances of up to a few thousand cells), repair with Or-opt and SOP-3-exchange
//! started only from the cells the kick disturbed (don't-look bits everywhere else),
//! re-choose modes, and accept the result when it lies within a record-to-record band above
//! the best (`accept`, relative). After `restart` kicks without a new best the walk
//! restarts from the best solution. On instances
//! whose costs read the same backwards (`lk=auto`; TSPLIB's prob.100) the repair and the
//! polish of a new best also run Lin–Kernighan chains of feasible reversals
//! ([`crate::engine::lk`]). Without a budget it stops after `stall` kicks without a new
//! best; with `end-stall` it stops after that many under a budget too, so that a plan's next
//! phases get the rest of its share (the `sparse-small` rule's rounds,
//! notes/lab/stall-rounds.md). With `walks` > 1 several such walks take kicks in turn, each
//! in the band above its own record, and every repaired kick is crossed with the best of all
//! walks (notes/lab/ils-walks.md). With `halve` the worse half of the walks is dropped each time
//! that share of the budget is used, down to one: the `symmetric` rule's plan without a beam
//! runs eight walks so (notes/lab/halved-walks.md). Walks then start only within the first
//! such share: on 1500 cells eight starts took a whole 10 s budget
//! (notes/lab/large-symmetric-kicks.md). With `corridor` the walk, once stalled, shares the
//! budget with corridor passes from the best ([`crate::engine::corridor`];
//! notes/lab/corridor.md).

use super::Build;
use super::StartsFrom;
use super::start::{greedy_solution, outcome};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, SolverInfo};
use crate::engine::corridor::{self, Corridor as Shape};
use crate::engine::carry::Carry;
use crate::engine::crossover::Crossover;
use crate::engine::lk::Lk;
use crate::engine::moves::sop3_delta;
use crate::engine::ruin::Ruin;
use crate::engine::shift::ShiftDp;
use crate::engine::sop3x::{TwoWay, sop3_two_way};
use crate::engine::vnd::Search;
use crate::engine::{Costs, Solution, cheaper};
use crate::error::Result;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "ils",
    summary: "iterated local search: segment-swap kicks, focused SOP-3-exchange/Or-opt repair, mode DP, record-to-record acceptance",
    description: "Iterated local search.

- **Kick**: a random feasible reorder of a window (`perturb=shuffle`), random segment swaps \
(`swap`), or ruin and recreate (`ruin`: strings of cells around a random cell removed and \
reinserted at their cheapest feasible places; `ruin-size`, `ruin-string`).
- **Repair**: Or-opt and SOP-3-exchange (both directions with `two-way`) from the cells the \
kick touched; on costs that read the same backwards also Lin–Kernighan chains of reversals \
(`lk`, `lk-depth`, `lk-breadth`) that may pass through up to `lk-max-viol` broken \
precedence pairs, each charged `lk-penalty` in the gain criterion, keeping only feasible \
prefixes. `shift-repair=K` ends every repair with the bounded-shift DP of Balas and \
Simonetti over the kicked span (the best reorder, with modes, in which no cell passes one \
that lay K or more places after it).
- **Crossover** (`cross`): each repaired kick is recombined with the best by partition \
crossover: the two sequences are cut wherever their prefixes hold the same cells and the \
cheapest feasible mix of segments is kept, in O(n).
- **Acceptance**: record-to-record, within `accept` above the best; a restart from the best \
after `restart` kicks without a gain.
- **End**: the budget; without one, `stall` kicks without a new best; with `end-stall` > 0, \
that many kicks without a new best under a budget too (a plan's later phases get the rest).
- **Corridor passes** (`corridor` > 0): once the walk has spent as many evaluations since its \
last record as the last pass took, the corridor search (engine::corridor) reorders the best \
within prefixes that differ from its own by at most `corridor-diff` cells; a gain is \
polished and the walk goes on from it. In `auto` the `dense-random` rule runs them.
- On instances whose cells have several modes (PCGTSPLIB), the polish of a new best adds \
window moves with modes (a cell moved inside a 5-position window while the modes around it \
are re-chosen); `window-repair=true` runs them in every repair as well.",
    params: &[
        ParamSpec {
            name: "k",
            default: "12",
            kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
            help: "candidate neighbours per cell",
        },
        ParamSpec {
            name: "kicks",
            default: "1",
            kind: ParamKind::int(1, 100_000),
            help: "random segment swaps per perturbation",
        },
        ParamSpec {
            name: "perturb",
            default: "shuffle",
            kind: ParamKind::Choice(&["shuffle", "swap", "ruin"]),
            help: "kick: random feasible reorder of a window, random segment swaps, or ruin and recreate (strings of cells around a random cell removed and inserted again at their cheapest places; engine::ruin)",
        },
        ParamSpec {
            name: "ruin-size",
            default: "10",
            kind: ParamKind::int(1, crate::params::MAX_CELLS),
            help: "perturb=ruin: average number of removed cells",
        },
        ParamSpec {
            name: "ruin-string",
            default: "10",
            kind: ParamKind::int(1, crate::params::MAX_CELLS),
            help: "perturb=ruin: longest removed string of consecutive cells",
        },
        ParamSpec {
            name: "max-seg",
            default: "0",
            kind: ParamKind::int(0, crate::params::MAX_CELLS),
            help: "longest swapped segment in a kick (0 = automatic: min(n/4, 30))",
        },
        ParamSpec {
            name: "accept",
            default: "0.001",
            kind: ParamKind::float(0.0, 1000.0),
            help: "accept a kicked solution within this relative band above the best",
        },
        ParamSpec {
            name: "restart",
            default: "2000",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "kicks without a new best before the walk restarts from the best",
        },
        ParamSpec {
            name: "two-way",
            default: "true",
            kind: ParamKind::Bool,
            help: "the repair's SOP-3-exchange searches backward as well as forward",
        },
        ParamSpec {
            name: "lk",
            default: "auto",
            kind: ParamKind::Choice(&["auto", "true", "false"]),
            help: "the repair also runs Lin-Kernighan chains of feasible reversals (engine::lk); auto = when costs read the same backwards (symmetric matrix)",
        },
        ParamSpec {
            name: "lk-depth",
            default: "12",
            kind: ParamKind::int(1, 1000),
            help: "longest Lin-Kernighan chain (reversals)",
        },
        ParamSpec {
            name: "lk-breadth",
            default: "3",
            kind: ParamKind::int(1, 1000),
            help: "first steps tried from each cell by a Lin-Kernighan chain",
        },
        ParamSpec {
            name: "lk-penalty",
            default: "2",
            kind: ParamKind::float(0.0, 1000.0),
            help: "Lin-Kernighan chains may pass through paths that break precedence pairs (at most lk-max-viol at a time), each charged this many times the start's mean link cost; only paths that keep every pair are kept (0: chains never break a pair)",
        },
        ParamSpec {
            name: "lk-max-viol",
            default: "2",
            kind: ParamKind::int(0, 1000),
            help: "most precedence pairs a Lin-Kernighan chain may break on its way (with lk-penalty > 0)",
        },
        ParamSpec {
            name: "sop3",
            default: "true",
            kind: ParamKind::Bool,
            help: "the repair runs SOP-3-exchange (off: Or-opt, and LK when on, only)",
        },
        ParamSpec {
            name: "max-block",
            default: "0",
            kind: ParamKind::int(0, crate::params::MAX_CELLS),
            help: "longest block of SOP-3-exchange in the descent and every repair (0 = the engine's: n up to 120 cells, 64 up to 5000, else 8)",
        },
        ParamSpec {
            name: "cross",
            default: "true",
            kind: ParamKind::Bool,
            help: "partition crossover of every repaired kick with the best (engine::crossover): segments that hold the same cells in both are taken from the cheaper one",
        },
        ParamSpec {
            name: "window-repair",
            default: "false",
            kind: ParamKind::Bool,
            help: "on instances with several modes per cell, the repair of every kick also runs window moves with modes (engine::window) over the cells the kick disturbed; the polish of a new best always runs them",
        },
        ParamSpec {
            name: "shift-repair",
            default: "0",
            kind: ParamKind::int(0, 64),
            help: "every kick's repair ends with the bounded-shift DP (engine::shift, Balas-Simonetti: the best reorder of the kicked span, with modes, in which no cell passes one that lay this many places or more after it) over the kicked span and this many cells either side (0: off)",
        },
        ParamSpec {
            name: "carry",
            default: "false",
            kind: ParamKind::Bool,
            help: "the polish of the start and of every new record ends with carry moves (engine::carry: a cell moved past a precedence successor or predecessor in its way, which a segment of at most 3 cells carries behind or before it), alternating with the full descent until neither improves",
        },
        ParamSpec {
            name: "walks",
            default: "1",
            kind: ParamKind::int(1, MAX_WALKS),
            help: "record-to-record walks kicked in turn, each in its own band above its own record and restarted from its own record; every repaired kick is crossed with the best of all walks, so walks in different basins exchange segments (walks after the first start from the first's local optimum scattered by random feasible reorders over the whole path, only while the first share of the budget lasts: halve's, or half the budget with halve = 0; at most 64, more count as 64)",
        },
        ParamSpec {
            name: "halve",
            default: "0",
            kind: ParamKind::float(0.0, 0.5),
            help: "with walks > 1: each time this share of the budget is used (of the evaluation budget when one is set, else of the time limit; without either none is dropped), the walks with the worse records are dropped, half at a time, down to one; early records pick the basin the rest of the budget deepens; no walk starts after the first such share, so on large instances, where a walk's start takes seconds, the rest is left to the kicks (0: every walk runs to the end)",
        },
        ParamSpec {
            name: "corridor",
            default: "0",
            kind: ParamKind::int(0, 1 << 20),
            help: "corridor search (engine::corridor: prefixes within `corridor-diff` cells of the best's, no cell moved more than `corridor-reach` places) from the best with this many states per prefix length, once the walk has spent as many evaluations since its last record, or since the last pass, as the last pass took; a pass without a gain doubles the width up to 65536, a gain is polished and the walk goes on from it (0: off)",
        },
        ParamSpec {
            name: "corridor-diff",
            default: "5",
            kind: ParamKind::int(1, crate::engine::corridor::MAX_DIFF as u64),
            help: "with corridor > 0: most cells by which a prefix may differ from the best's prefix of the same length",
        },
        ParamSpec {
            name: "corridor-reach",
            default: "30",
            kind: ParamKind::int(1, crate::engine::corridor::MAX_REACH as u64),
            help: "with corridor > 0: most places a cell may move",
        },
        ParamSpec {
            name: "stall",
            default: "20000",
            kind: ParamKind::int(1, crate::params::MAX_ITERATIONS),
            help: "stop after this many kicks without a new best when no budget is set",
        },
        ParamSpec {
            name: "end-stall",
            default: "0",
            kind: ParamKind::int(0, crate::params::MAX_ITERATIONS),
            help: "end the walk after this many kicks without a new best under a budget too, leaving the rest of its share to the phases after it in a plan (0: off, the walk runs to its budget)",
        },
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::StartsFrom(|p: &Params| Ok(Box::new(from_params(p)))),
};

/// Kicks between two looks at whether walks are to be dropped (`halve`).
const HALVE_EVERY: u64 = 16;

/// Without `halve`, walks after the first start only within this share of the budget: on
/// large instances a start (a scatter and a full descent) takes seconds, and the walks need
/// the rest for their kicks.
const START_SHARE: f64 = 0.5;

/// Most walks kept at once (each holds two solutions, so memory stays bounded).
const MAX_WALKS: u64 = 64;

/// Builds the solver from validated parameters.
pub fn from_params(p: &Params) -> Ils {
    Ils {
        k: p.int("k") as usize,
        kicks: p.int("kicks") as usize,
        perturb: match p.word("perturb") {
            "shuffle" => Perturb::Shuffle,
            "swap" => Perturb::Swap,
            _ => Perturb::Ruin,
        },
        ruin_size: p.int("ruin-size") as usize,
        ruin_string: p.int("ruin-string") as usize,
        max_seg: p.int("max-seg") as usize,
        accept: p.float("accept"),
        restart: p.int("restart"),
        stall: p.int("stall"),
        end_stall: p.int("end-stall"),
        two_way: p.bool("two-way"),
        lk: p.switch("lk"),
        lk_depth: p.int("lk-depth") as usize,
        lk_breadth: p.int("lk-breadth") as usize,
        sop3: p.bool("sop3"),
        max_block: p.int("max-block") as usize,
        lk_penalty: p.float("lk-penalty"),
        lk_max_viol: p.int("lk-max-viol") as u32,
        cross: p.bool("cross"),
        window_repair: p.bool("window-repair"),
        shift_repair: p.int("shift-repair") as usize,
        carry: p.bool("carry"),
        walks: p.int("walks") as usize,
        halve: p.float("halve"),
        corridor: Shape {
            diff: p.int("corridor-diff") as usize,
            reach: p.int("corridor-reach") as usize,
            width: p.int("corridor") as usize,
        },
    }
}

/// The iterated local search.
pub struct Ils {
    /// Candidate neighbours per cell.
    pub k: usize,
    /// Segment swaps per kick.
    pub kicks: usize,
    /// The kick.
    pub perturb: Perturb,
    /// Ruin and recreate: average number of removed cells.
    pub ruin_size: usize,
    /// Ruin and recreate: longest removed string.
    pub ruin_string: usize,
    /// Longest segment in a kick (0 = automatic).
    pub max_seg: usize,
    /// Record-to-record band.
    pub accept: f64,
    /// Kicks without improvement before restarting from the best.
    pub restart: u64,
    /// Kicks without improvement before stopping (no budget).
    pub stall: u64,
    /// Kicks without improvement before stopping under a budget too (0: off).
    pub end_stall: u64,
    /// Backward as well as forward SOP-3-exchange in the repair.
    pub two_way: bool,
    /// Lin-Kernighan chains in the repair (`None`: when the costs are symmetric).
    pub lk: Option<bool>,
    /// Longest Lin-Kernighan chain.
    pub lk_depth: usize,
    /// First steps tried per Lin-Kernighan chain.
    pub lk_breadth: usize,
    /// SOP-3-exchange in the repair.
    pub sop3: bool,
    /// Longest SOP-3-exchange block (0 = the engine's choice).
    pub max_block: usize,
    /// Penalty per broken precedence pair inside a Lin-Kernighan chain (0: none).
    pub lk_penalty: f64,
    /// Most pairs a Lin-Kernighan chain may break on its way.
    pub lk_max_viol: u32,
    /// Partition crossover of every repaired kick with the best.
    pub cross: bool,
    /// Window moves with modes in the repair of every kick.
    pub window_repair: bool,
    /// Largest shift of the bounded-shift DP in every kick's repair (0: off).
    pub shift_repair: usize,
    /// Carry moves in the polish of the start and of every new record.
    pub carry: bool,
    /// Record-to-record walks kicked in turn.
    pub walks: usize,
    /// Share of the budget after which the worse half of the walks is dropped (0: never).
    pub halve: f64,
    /// The corridor of the passes and the first pass's width (0: no passes).
    pub corridor: Shape,
}

/// Widest corridor pass of [`Ils`].
const CORRIDOR_MAX_WIDTH: usize = 1 << 16;

/// [`Ils`]'s corridor passes: a pass from the best is due once the walk has spent, since its
/// last record or the last pass, as many evaluations as that pass took (the first pass's
/// count is estimated), so a stalled walk and the passes share the budget evenly.
struct Passes {
    shape: Shape,
    /// Evaluations of the last pass (estimated before the first).
    spent: u64,
    /// Evaluation count at the walk's last record or the end of the last pass.
    mark: u64,
    gains: u64,
    runs: u64,
}

impl Passes {
    fn new(shape: Shape, n: usize, evals: u64) -> Self {
        Passes {
            shape,
            spent: (shape.width as u64).saturating_mul(n as u64 * 8),
            mark: evals,
            gains: 0,
            runs: 0,
        }
    }

    fn due(&self, evals: u64) -> bool {
        self.shape.width > 0 && evals >= self.mark.saturating_add(self.spent)
    }

    /// One pass from `best`: the cheaper sequence it finds, if any, polished by the VND (and
    /// Lin–Kernighan where it runs).
    fn run(
        &mut self,
        ctx: &mut Context,
        (search, lk): (&mut Search, Option<&mut Lk>),
        best: &Solution,
    ) -> Option<Solution> {
        let before = ctx.evaluations();
        let c = &search.c;
        let found = corridor::improve(c, best, ctx, self.shape);
        self.runs += 1;
        self.mark = ctx.evaluations();
        self.spent = self.mark - before;
        match found {
            Some((order, _)) => {
                self.gains += 1;
                let mut s = best.reordered(c, &order);
                Lk::full_descent(lk, search, &mut s, ctx);
                if super::trace_enabled() {
                    eprintln!(
                        "ils: best {} by a corridor pass of width {}, {:.2} s",
                        s.cost + ctx.model.constant(),
                        self.shape.width,
                        ctx.elapsed()
                    );
                }
                Some(s)
            }
            None => {
                self.shape.width = (self.shape.width * 2).min(CORRIDOR_MAX_WIDTH);
                None
            }
        }
    }
}

/// One record-to-record walk of [`Ils`]: its current solution, its record and the kicks since
/// the record last improved.
struct Walk {
    cur: Solution,
    record: Solution,
    since: u64,
}

/// The kick of [`Ils`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Perturb {
    /// A random feasible reorder of a window of positions.
    Shuffle,
    /// Random feasible segment swaps.
    Swap,
    /// Ruin and recreate ([`crate::engine::ruin`]).
    Ruin,
}

/// One random feasible segment swap on `s`: blocks `[h+1..=i]` and `[i+1..=j]` trade places.
/// Returns the cells at the six positions around the cut points (to seed the repair).
fn kick(
    c: &Costs,
    s: &mut Solution,
    rng: &mut ChaCha8Rng,
    max_seg: usize,
    stamp: &mut [u32],
    label: &mut u32,
    seeds: &mut Vec<u32>,
) -> bool {
    let n = s.n();
    if n < 3 {
        return false;
    }
    let m = c.m;
    for _ in 0..200 {
        let h = rng.random_range(0..(n as i64 - 1)) as isize - 1;
        let lmax = max_seg.min((n as isize - 2 - h) as usize).max(1);
        let len = rng.random_range(1..=lmax);
        let i = h + len as isize;
        if i > n as isize - 2 {
            continue;
        }
        *label = label.wrapping_add(1).max(1);
        for p in (h + 1)..=i {
            for &q in &m.dag.succs[s.order[p as usize] as usize] {
                stamp[q as usize] = *label;
            }
        }
        // the right block may grow while it holds no successor of the left block
        let mut jmax = i;
        while jmax + 1 < n as isize
            && jmax - i < max_seg as isize
            && stamp[s.order[(jmax + 1) as usize] as usize] != *label
        {
            jmax += 1;
        }
        if jmax == i {
            continue;
        }
        let j = rng.random_range((i + 1) as i64..=jmax as i64) as isize;
        for p in [h, h + 1, i, i + 1, j, j + 1] {
            if p >= 0 && p < n as isize {
                seeds.push(s.order[p as usize]);
            }
        }
        let d = sop3_delta(c, s, h, i, j);
        s.swap_blocks(h, i as usize, j as usize, d);
        return true;
    }
    false
}

/// Perturbation that an exchange move cannot simply undo: the cells of a random window of
/// positions are put in a random order that respects the precedence among them (a random
/// topological order; constraints with cells outside the window hold whatever the order).
fn shuffle(
    c: &Costs,
    s: &mut Solution,
    rng: &mut ChaCha8Rng,
    max_seg: usize,
    scratch: &mut Shuffle,
    seeds: &mut Vec<u32>,
) -> bool {
    let n = s.n();
    if n < 3 {
        return false;
    }
    let m = c.m;
    let w = rng.random_range(3..=max_seg.clamp(3, n));
    let a = rng.random_range(0..=(n - w));
    let cells: Vec<u32> = s.order[a..a + w].to_vec();
    scratch.missing.clear();
    scratch.ready.clear();
    scratch.out.clear();
    for (k, &x) in cells.iter().enumerate() {
        let inside = m.dag.preds[x as usize]
            .iter()
            .filter(|&&p| {
                let pp = s.pos[p as usize] as usize;
                pp >= a && pp < a + w
            })
            .count();
        scratch.missing.push(inside as u32);
        if inside == 0 {
            scratch.ready.push(k);
        }
    }
    while !scratch.ready.is_empty() {
        let r = rng.random_range(0..scratch.ready.len());
        let k = scratch.ready.swap_remove(r);
        let x = cells[k];
        scratch.out.push(x);
        for &q in &m.dag.succs[x as usize] {
            let pq = s.pos[q as usize] as usize;
            if pq >= a && pq < a + w {
                let kk = pq - a;
                scratch.missing[kk] -= 1;
                if scratch.missing[kk] == 0 {
                    scratch.ready.push(kk);
                }
            }
        }
    }
    if scratch.out == cells {
        return false;
    }
    let (lo, hi) = (a as isize - 1, (a + w) as isize);
    let old = s.links(c, lo, hi);
    let slot = |x: u32| Some((x as usize, s.mode[x as usize] as usize));
    let mut new =
        c.link(s.at(lo), slot(scratch.out[0])) + c.link(slot(scratch.out[w - 1]), s.at(hi));
    for k in 0..w - 1 {
        new += c.link(slot(scratch.out[k]), slot(scratch.out[k + 1]));
    }
    seeds.extend_from_slice(&scratch.out);
    for p in [lo, hi] {
        if p >= 0 && p < n as isize {
            seeds.push(s.order[p as usize]);
        }
    }
    let out = std::mem::take(&mut scratch.out);
    s.rewrite(a, &out, new - old);
    scratch.out = out;
    true
}

/// Scratch space of [`shuffle`].
#[derive(Default)]
struct Shuffle {
    missing: Vec<u32>,
    ready: Vec<usize>,
    out: Vec<u32>,
}

impl StartsFrom for Ils {
    /// Runs the search from `start` (evaluated with open-loop costs), or from the greedy
    /// sequence when `start` is `None`.
    fn run_from(&self, ctx: &mut Context, start: Option<Solution>) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        let c = Costs::open(m);
        let mut cur = match start {
            Some(s) => s,
            None => greedy_solution(ctx, &c),
        };
        if ctx.deadline().passed() {
            return Ok(outcome(m, &cur));
        }
        let (mut search, mut lk) = self.descend(ctx, c, &mut cur);
        let mut carry = Carry::default();
        self.carry_moves((&mut search, lk.as_mut()), &mut carry, &mut cur, ctx);
        let mut best = cur.clone();
        ctx.report(best.cost + m.constant());
        let max_seg = if self.max_seg > 0 {
            self.max_seg
        } else {
            (n / 4).clamp(1, 30)
        };
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed ^ 0x11_5eed);
        let mut stamp = vec![0u32; n];
        let mut label = 0u32;
        let mut seeds: Vec<u32> = Vec::new();
        let mut scratch = Shuffle::default();
        let mut walks = self.start_walks(
            ctx,
            (&mut search, lk.as_mut()),
            cur,
            &mut best,
            (&mut rng, max_seg),
        );
        let mut ruin = Ruin::new(self.ruin_size, self.ruin_string, 0.01);
        let mut w = TwoWay::default();
        let bounded = ctx.budget.max_evals.is_some() || ctx.budget.time_limit.is_some();
        let mut since_best = 0u64;
        let mut trial = best.clone();
        let mut px = Crossover::default();
        let mut crosses = 0u64;
        let mut kicks_done = 0u64;
        let mut shift_repair = ShiftDp::new(self.shift_repair.max(2), 200_000);
        let mut shift_gains = 0u64;
        let trace = super::trace_enabled();
        let mut passes = Passes::new(self.corridor, n, ctx.evaluations());
        while !ctx.exhausted() {
            if self.stalled(bounded, since_best) {
                break;
            }
            if kicks_done.is_multiple_of(HALVE_EVERY) {
                self.drop_walks(ctx, &mut walks);
            }
            let at = (kicks_done % walks.len() as u64) as usize;
            let walk = &mut walks[at];
            if passes.due(ctx.evaluations())
                && let Some(s) = passes.run(ctx, (&mut search, lk.as_mut()), &best)
            {
                walk.record.clone_from(&s);
                walk.cur.clone_from(&s);
                walk.since = 0;
                best = s;
                ctx.report(best.cost + m.constant());
                since_best = 0;
                continue;
            }
            trial.clone_from(&walk.cur);
            seeds.clear();
            let mut kicked = false;
            for _ in 0..self.kicks {
                kicked |= match self.perturb {
                    Perturb::Shuffle => {
                        shuffle(&c, &mut trial, &mut rng, max_seg, &mut scratch, &mut seeds)
                    }
                    Perturb::Swap => kick(
                        &c, &mut trial, &mut rng, max_seg, &mut stamp, &mut label, &mut seeds,
                    ),
                    Perturb::Ruin => {
                        match ruin.kick(&c, &search.nb, &mut trial, &mut rng, &mut seeds) {
                            Some(e) => {
                                ctx.count(e);
                                true
                            }
                            None => false,
                        }
                    }
                };
            }
            ctx.count(seeds.len() as u64 + 1);
            kicks_done += 1;
            if !kicked {
                since_best += 1;
                continue;
            }
            shift_gains += self.repair(
                ctx,
                &c,
                (&mut search, lk.as_mut(), &mut w, &mut shift_repair),
                &mut trial,
                &seeds,
            );
            since_best += 1;
            walk.since += 1;
            // a repaired kick that does not beat the best may still hold better segments:
            // the partition crossover takes each segment from the cheaper of the two
            let mut crossed = false;
            if self.cross && !cheaper(trial.cost, best.cost) {
                // every attempt is charged its O(n), whether it gives a child or not
                ctx.count(n as u64);
                if let Some(child) = px.cross(&c, &trial, &best) {
                    crosses += 1;
                    trial = child;
                    crossed = true;
                }
            }
            if crossed || cheaper(trial.cost, walk.record.cost) {
                // polish a new record with the full descent before keeping it
                self.polish((&mut search, lk.as_mut()), &mut carry, &mut trial, ctx);
                walk.record.clone_from(&trial);
                walk.since = 0;
                if crossed || cheaper(trial.cost, best.cost) {
                    best.clone_from(&trial);
                    ctx.report(best.cost + m.constant());
                    if trace {
                        eprintln!(
                            "ils: best {} at kick {kicks_done}, {:.2} s",
                            best.cost + m.constant(),
                            ctx.elapsed()
                        );
                    }
                    since_best = 0;
                    passes.mark = ctx.evaluations();
                }
            }
            if trial.cost <= walk.record.cost + self.accept * walk.record.cost.abs() {
                std::mem::swap(&mut walk.cur, &mut trial);
            }
            if walk.since >= self.restart {
                walk.cur.clone_from(&walk.record);
                walk.since = 0;
            }
        }
        if trace {
            eprintln!(
                "ils: {kicks_done} kicks, {crosses} crossovers gave a new best, {shift_gains} repairs improved by the shift DP, {} corridor passes gave {} new bests, {} carry moves",
                passes.runs, passes.gains, carry.applied
            );
        }
        Ok(outcome(m, &best))
    }
}

impl Ils {
    /// True when the walk ends after `since_best` kicks without a new best: `stall` of them
    /// without a budget (`bounded` false), `end-stall` (when set) under any.
    fn stalled(&self, bounded: bool, since_best: u64) -> bool {
        !bounded && since_best >= self.stall || self.end_stall > 0 && since_best >= self.end_stall
    }

    /// The walks: the first from `first`, the others (`walks` > 1) from its local optimum
    /// scattered by random feasible reorders, while [`Ils::may_start_walk`] allows; `best`
    /// follows their records.
    fn start_walks(
        &self,
        ctx: &mut Context,
        (search, mut lk): (&mut Search, Option<&mut Lk>),
        first: Solution,
        best: &mut Solution,
        (rng, max_seg): (&mut ChaCha8Rng, usize),
    ) -> Vec<Walk> {
        let mut walks = vec![Walk {
            record: first.clone(),
            cur: first,
            since: 0,
        }];
        while self.may_start_walk(ctx, walks.len()) {
            let mut s = walks[0].record.clone();
            self.scatter(ctx, (&mut *search, lk.as_deref_mut()), &mut s, rng, max_seg);
            if cheaper(s.cost, best.cost) {
                best.clone_from(&s);
                ctx.report(best.cost + ctx.model.constant());
            }
            walks.push(Walk {
                record: s.clone(),
                cur: s,
                since: 0,
            });
        }
        if super::trace_enabled() && self.walks > 1 {
            eprintln!("ils: {} walks started, {:.2} s", walks.len(), ctx.elapsed());
        }
        walks
    }

    /// Whether another walk may start, `started` being under way: fewer than `walks`, budget
    /// left, and only within the first share of the budget, `halve`'s or [`START_SHARE`] (on
    /// large instances, where a walk's descent takes seconds, the rest is left to the kicks).
    fn may_start_walk(&self, ctx: &Context, started: usize) -> bool {
        let share = if self.halve > 0.0 {
            self.halve
        } else {
            START_SHARE
        };
        started < self.walks && !ctx.exhausted() && ctx.used_share() < share
    }

    /// With `halve` > 0, keeps the `walks >> stage` walks of the best records, where `stage`
    /// counts the shares of `halve` of the budget used so far ([`Context::used_share`]).
    fn drop_walks(&self, ctx: &Context, walks: &mut Vec<Walk>) {
        if self.halve <= 0.0 || walks.len() <= 1 {
            return;
        }
        let stage = (ctx.used_share() / self.halve).floor().min(63.0) as u32;
        let keep = (self.walks >> stage).max(1);
        if keep < walks.len() {
            // stable: among equal records the walk started first stays
            walks.sort_by(|a, b| a.record.cost.total_cmp(&b.record.cost));
            walks.truncate(keep);
        }
    }

    /// The search engine and Lin–Kernighan (when it runs) with this solver's settings, and
    /// `cur` taken to their local optimum: the walk's first solution.
    fn descend<'a>(
        &self,
        ctx: &mut Context,
        c: Costs<'a>,
        cur: &mut Solution,
    ) -> (Search<'a>, Option<Lk>) {
        let mut search = Search::new_until(c, self.k, ctx.deadline());
        if self.max_block > 0 {
            search.max_block = self.max_block;
        }
        search.vnd(cur, ctx);
        let mut lk = Lk::when(self.lk, &c, self.lk_depth, self.lk_breadth);
        if let Some(lk) = lk.as_mut() {
            lk.alternate_with_vnd(&mut search, cur, ctx);
            lk.penalty = self.lk_penalty * cur.cost.abs() / (cur.n() as f64 + 1.0);
            lk.max_viol = self.lk_max_viol;
        }
        (search, lk)
    }

    /// The polish of a new record: the full descent (with Lin–Kernighan when it runs), then
    /// [`Ils::carry_moves`].
    fn polish(
        &self,
        (search, mut lk): (&mut Search, Option<&mut Lk>),
        carry: &mut Carry,
        s: &mut Solution,
        ctx: &mut Context,
    ) {
        Lk::full_descent(lk.as_deref_mut(), search, s, ctx);
        self.carry_moves((search, lk), carry, s, ctx);
    }

    /// With `carry`: carry moves on `s` (a local optimum of the full descent), each round
    /// that improves followed by the full descent again, until a round finds none.
    fn carry_moves(
        &self,
        (search, mut lk): (&mut Search, Option<&mut Lk>),
        carry: &mut Carry,
        s: &mut Solution,
        ctx: &mut Context,
    ) {
        while self.carry && !ctx.exhausted() && carry.improve(&search.c, &search.nb, s, ctx) {
            Lk::full_descent(lk.as_deref_mut(), search, s, ctx);
        }
    }

    /// Starts another walk: `s` (a local optimum) gets random feasible reorders of windows
    /// spread over the whole path, about two per window length, and descends again with the
    /// full search (and Lin–Kernighan when it runs).
    fn scatter(
        &self,
        ctx: &mut Context,
        moves: (&mut Search, Option<&mut Lk>),
        s: &mut Solution,
        rng: &mut ChaCha8Rng,
        max_seg: usize,
    ) {
        let (search, lk) = moves;
        let c = search.c;
        let mut scratch = Shuffle::default();
        let mut seeds = Vec::new();
        for _ in 0..(2 * s.n() / max_seg.max(1)).max(1) {
            shuffle(&c, s, rng, max_seg, &mut scratch, &mut seeds);
        }
        ctx.count(seeds.len() as u64 + 1);
        Lk::full_descent(lk, search, s, ctx);
    }

    /// Repairs a kicked `trial` around the kicked cells `seeds`: Or-opt, SOP-3-exchange and
    /// Lin–Kernighan to a local optimum, the shift DP over the kicked range, then the modes
    /// (and windows). `moves`: the search, Lin–Kernighan, the two-way SOP-3 scratch and the
    /// shift DP. Returns the number of improvements by the shift DP.
    fn repair(
        &self,
        ctx: &mut Context,
        c: &Costs,
        moves: (&mut Search, Option<&mut Lk>, &mut TwoWay, &mut ShiftDp),
        trial: &mut Solution,
        seeds: &[u32],
    ) -> u64 {
        let (search, mut lk, w, shift_repair) = moves;
        let n = ctx.model.n();
        loop {
            let a = search.or_opt_seeded(trial, ctx, seeds);
            let b = if !self.sop3 {
                false
            } else if self.two_way {
                sop3_two_way(search, w, trial, ctx, seeds)
            } else {
                search.sop3_seeded(trial, ctx, seeds)
            };
            let l = match lk.as_deref_mut() {
                Some(lk) => lk.improve(c, &search.nb, trial, ctx, seeds),
                None => false,
            };
            if !(a || b || l) || ctx.exhausted() {
                break;
            }
        }
        let mut gains = 0;
        if self.shift_repair > 0 && !seeds.is_empty() {
            let k = self.shift_repair;
            let (mut lo, mut hi) = (usize::MAX, 0usize);
            for &x in seeds {
                let p = trial.pos[x as usize] as usize;
                lo = lo.min(p);
                hi = hi.max(p);
            }
            let lo = lo.saturating_sub(k);
            let hi = (hi + k + 1).min(n);
            gains += shift_repair.improve_range(c, trial, ctx, lo, hi) as u64;
        }
        if ctx.model.multimode() {
            search.modes(trial, ctx);
            if self.window_repair {
                search.windows(trial, ctx, Some(seeds));
            }
        }
        gains
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::context::NoObserver;
    use crate::cost::CostModel;
    use crate::engine::atsp::random_matrix_instance;
    use crate::model::{Instance, Objective};
    use crate::solvers::Budget;
    use crate::solvers::start::greedy_solution;

    /// A 12-cell random matrix instance and its model, for the walk tests.
    fn small() -> (Instance, CostModel) {
        let inst = random_matrix_instance(12, 5, 100, &[]);
        let m = CostModel::new(&inst, Objective::Matrix);
        (inst, m)
    }

    /// An evaluation budget whose shares the tests count out exactly.
    const THOUSAND: Budget = Budget {
        time_limit: None,
        max_evals: Some(1000),
    };

    /// The default `ils` with `walks` walks and `halve`.
    fn walker(walks: usize, halve: f64) -> Ils {
        Ils {
            halve,
            walks,
            ..from_params(&INFO.check_params(&Default::default()).unwrap())
        }
    }

    /// `halve`: the walks are dropped half at a time, at each share of the evaluation budget,
    /// down to one, keeping the best records (the first among equals), and never without it.
    #[test]
    fn halve_keeps_the_best_records_half_at_a_time() {
        let (inst, m) = small();
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, THOUSAND, &mut obs);
        let s = greedy_solution(&mut ctx, &Costs::open(&m));
        // records 7, 6, …, 0 with two walks at 3: walk i has record cost 7 - i (i = 3, 4 tie)
        let costs = [7.0, 6.0, 5.0, 3.0, 3.0, 2.0, 1.0, 0.0];
        let fresh = || -> Vec<Walk> {
            costs
                .iter()
                .map(|&k| {
                    let mut r = s.clone();
                    r.cost = k;
                    Walk {
                        cur: r.clone(),
                        record: r,
                        since: 0,
                    }
                })
                .collect()
        };
        let ils = |halve: f64| walker(costs.len(), halve);
        let records = |w: &[Walk]| w.iter().map(|w| w.record.cost).collect::<Vec<_>>();
        let mut walks = fresh();
        // nothing used yet: all eight stay
        ils(0.15).drop_walks(&ctx, &mut walks);
        assert_eq!(walks.len(), 8);
        // 0.15 of the budget used: the best four
        ctx.count(150);
        ils(0.15).drop_walks(&ctx, &mut walks);
        assert_eq!(records(&walks), [0.0, 1.0, 2.0, 3.0]);
        // 0.30: two; 0.45: one, the best; later shares keep that one
        ctx.count(150);
        ils(0.15).drop_walks(&ctx, &mut walks);
        assert_eq!(records(&walks), [0.0, 1.0]);
        ctx.count(150);
        ils(0.15).drop_walks(&ctx, &mut walks);
        assert_eq!(records(&walks), [0.0]);
        ctx.count(500);
        ils(0.15).drop_walks(&ctx, &mut walks);
        assert_eq!(records(&walks), [0.0]);
        // halve = 0 never drops a walk, however much is used
        let mut walks = fresh();
        ils(0.0).drop_walks(&ctx, &mut walks);
        assert_eq!(walks.len(), 8);
        // among equal records the earlier walk stays: at 0.45 of a budget with halve = 0.2
        // (stage 2: two walks) from the records 3, 3, 7 the two walks of cost 3 stay in order
        let mut walks = fresh();
        walks.retain(|w| w.record.cost == 3.0 || w.record.cost == 7.0);
        for (i, w) in walks.iter_mut().enumerate() {
            w.since = i as u64;
        }
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, THOUSAND, &mut obs);
        ctx.count(450);
        ils(0.2).drop_walks(&ctx, &mut walks);
        assert_eq!(walks.iter().map(|w| w.since).collect::<Vec<_>>(), [1, 2]);
    }

    /// Walks start while fewer than `walks` are under way and only within the first share of
    /// the budget: `halve`'s, or half of it without `halve`.
    #[test]
    fn walks_start_only_within_the_first_share() {
        let (inst, m) = small();
        let mut obs = NoObserver;
        let mut ctx = Context::new(&inst, &m, 1, THOUSAND, &mut obs);
        let ils = |halve: f64| walker(8, halve);
        assert!(ils(0.15).may_start_walk(&ctx, 1));
        assert!(!ils(0.15).may_start_walk(&ctx, 8));
        ctx.count(149);
        assert!(ils(0.15).may_start_walk(&ctx, 7));
        ctx.count(1);
        assert!(!ils(0.15).may_start_walk(&ctx, 1));
        assert!(ils(0.0).may_start_walk(&ctx, 7));
        assert!(!ils(0.0).may_start_walk(&ctx, 8));
        ctx.count(349);
        assert!(ils(0.0).may_start_walk(&ctx, 7));
        ctx.count(1);
        assert!(!ils(0.0).may_start_walk(&ctx, 1), "half the budget is used");
    }

    /// `end-stall`: under an evaluation budget the walk ends after that many kicks without a
    /// new best, well inside the budget, with the same result on every run; without it the
    /// walk spends the whole budget.
    #[test]
    fn end_stall_ends_a_walk_inside_its_budget() {
        let inst = random_matrix_instance(30, 4, 100, &[(2, 9), (5, 20), (11, 12)]);
        let m = CostModel::new(&inst, Objective::Matrix);
        let budget = Budget {
            time_limit: None,
            max_evals: Some(3_000_000),
        };
        let run = |end_stall: u64| {
            let ils = Ils {
                end_stall,
                ..from_params(&INFO.check_params(&Default::default()).unwrap())
            };
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, 5, budget, &mut obs);
            let out = ils.run_from(&mut ctx, None).unwrap();
            (out, ctx.evaluations())
        };
        let (a, used_a) = run(20);
        let (b, used_b) = run(20);
        assert_eq!(a.sequence, b.sequence);
        assert_eq!(used_a, used_b);
        assert!(used_a < 1_000_000, "20 kicks without a gain end the walk: {used_a}");
        let (c, used_c) = run(0);
        assert!(used_c >= 3_000_000, "without end-stall the walk runs to its budget");
        assert!(c.cost <= a.cost + 1e-9, "the longer walk is no worse");
        crate::checker::check(&inst, &a.sequence, Objective::Matrix).expect("feasible");
    }

    /// Corridor passes are due once the walk has spent, since the mark, as many evaluations
    /// as the last pass took (the first estimated as 8 × width × n); width 0 never runs one.
    /// A walk with passes under an evaluation budget is feasible and the same on every run.
    #[test]
    fn corridor_passes_are_scheduled_by_evaluations() {
        let shape = |width| Shape {
            diff: 5,
            reach: 30,
            width,
        };
        let p = Passes::new(shape(10), 5, 100);
        assert!(!p.due(100 + 399));
        assert!(p.due(100 + 400));
        assert!(!Passes::new(shape(0), 5, 0).due(u64::MAX));
        // dense precedence among 40 cells: pairs (i, j), j = i + 2.., every third one
        let pairs: Vec<(usize, usize)> = (0..40)
            .flat_map(|i| (i + 2..40).map(move |j| (i, j)))
            .filter(|&(i, j)| (i + j) % 3 == 0)
            .collect();
        let inst = random_matrix_instance(40, 9, 100, &pairs);
        let m = CostModel::new(&inst, Objective::Matrix);
        let ils = Ils {
            corridor: shape(16),
            ..from_params(&INFO.check_params(&Default::default()).unwrap())
        };
        let run = || {
            let mut obs = NoObserver;
            let budget = Budget {
                time_limit: None,
                max_evals: Some(300_000),
            };
            let mut ctx = Context::new(&inst, &m, 3, budget, &mut obs);
            ils.run_from(&mut ctx, None).unwrap()
        };
        let (a, b) = (run(), run());
        assert_eq!(a.sequence, b.sequence);
        let report = crate::checker::check(&inst, &a.sequence, Objective::Matrix)
            .expect("a feasible sequence");
        assert!((report.cost - a.cost).abs() < 1e-6);
    }
}

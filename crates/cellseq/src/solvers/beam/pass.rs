//! One beam pass of a given width: level by level, children of every kept prefix, bound
//! pruning, prefix dominance, lazy refinement and the width cut; then the best complete
//! sequence read back from the trail.

use super::Beam;
use super::prefix::{Prefix, first_prefixes, keep_best, open_cells, rank};
use super::refine::refined;
use super::tables::Tables;
use crate::bound::qpath::QPath;
use crate::context::Context;
use crate::model::{Sequence, Visit};
use rustc_hash::FxHashMap;
use std::collections::hash_map::Entry;

/// Evaluations charged per generated child (and per refined candidate): a child copies a
/// prefix, computes its bound and probes the dominance map, which takes about as long as 8
/// arc evaluations of the local search (evaluations per second on TSPLIB SOP: beam 2.4–7.6
/// million, ils 17–75 million: 5–16 times as many, about 9 in the median; notes/lab/sopq5.md).
/// So an evaluation budget buys the beam about the wall time it buys the other solvers, and
/// `auto`'s shares of an evaluation budget match its shares of a time budget.
pub const CHILD_EVALS: u64 = 8;

/// Charges `children` generated or refined candidates to the evaluation count.
pub(super) fn charge(ctx: &mut Context, children: u64) {
    ctx.count(children * CHILD_EVALS);
}

impl Beam {
    /// One beam pass of the given width (`usize::MAX`: unbounded, an exhaustive search when
    /// it ends). The pass stops early when the budget is spent (`may_abort`) or when its
    /// stored prefixes would pass `mem_cap` bytes.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn iteration<const W: usize>(
        &self,
        ctx: &mut Context,
        t: &Tables,
        qp: Option<&QPath>,
        width: usize,
        cut: f64,
        may_abort: bool,
        mem_cap: Option<u64>,
    ) -> Pass {
        let lv = Level::<W> {
            beam: self,
            t,
            qp,
            width,
            cut,
            may_abort,
            mem_cap,
        };
        let n = ctx.model.n();
        let mut scratch = vec![(0.0, 0.0); n + t.clusters.len()];
        // completed levels, compact: (parent index, node) per prefix
        let mut trail: Vec<Vec<(u32, u32)>> = Vec::with_capacity(n);
        let (mut prev, mut truncated) = lv.first_level(ctx, &mut scratch);
        trail.push(prev.iter().map(|p| (p.parent, p.node)).collect());
        let mut stored = prev.len() as u64;
        let mut index: FxHashMap<([u64; W], u32), u32> = FxHashMap::default();
        for k in 1..n {
            if prev.is_empty() {
                break;
            }
            let cands = match lv.children(ctx, &prev, k + 1, stored, &mut index) {
                Ok(cands) => cands,
                Err(stop) => return stop,
            };
            let Some(mut cands) = lv.refine_level(ctx, cands, &mut scratch) else {
                return Pass::aborted();
            };
            truncated |= keep_best(&mut cands, width, self.by_cost);
            trail.push(cands.iter().map(|p| (p.parent, p.node)).collect());
            stored += cands.len() as u64;
            prev = cands;
            if may_abort && ctx.exhausted() {
                return Pass {
                    truncated,
                    ..Pass::aborted()
                };
            }
            if lv.overflow(stored, prev.len(), 0) {
                return Pass::overflow();
            }
        }
        if crate::solvers::trace_enabled() {
            let sizes: Vec<usize> = trail.iter().map(|l| l.len()).collect();
            eprintln!("beam: level sizes {sizes:?}");
            eprintln!(
                "beam: width {width} stored {} largest level {}",
                sizes.iter().sum::<usize>(),
                sizes.iter().max().unwrap_or(&0)
            );
        }
        Pass {
            found: lv.complete(ctx, &trail, &prev),
            truncated,
            aborted: false,
            overflow: false,
        }
    }
}

/// Per parent Σ μ_S, per cell the parents it may extend, and the number of such pairs
/// ([`Level::parent_lists`]).
type ParentLists = (Vec<f64>, Vec<Vec<u32>>, usize);

/// The fixed inputs of one pass (see [`Beam::iteration`]).
struct Level<'a, const W: usize> {
    beam: &'a Beam,
    t: &'a Tables,
    qp: Option<&'a QPath>,
    width: usize,
    /// prune a prefix whose bound is above this
    cut: f64,
    /// the budget may stop the pass
    may_abort: bool,
    /// bytes the stored prefixes may take (unbounded passes)
    mem_cap: Option<u64>,
}

impl<const W: usize> Level<'_, W> {
    /// The incremental bound of prefix `p` of `cells` cells: the larger of the degree bounds
    /// (plus the sets still to leave, `p.act`) and the path relaxation's completion.
    #[inline]
    fn bound(&self, p: &Prefix<W>, cells: usize) -> f64 {
        let t = self.t;
        let act = p.act;
        let h_in = p.rem_in + t.node_in[p.node as usize];
        let h_out = p.rem_out + t.node_out[p.node as usize];
        let h = match self.qp {
            // rounding slack: λ sums are kept incrementally
            Some(q) => {
                // shifted costs: the sets still to leave are charged on top
                let h_q = q.completion(cells, p.node as usize, p.lam_open)
                    + if t.mu_arc.is_empty() { 0.0 } else { act };
                h_q - 1e-9 * h_q.abs().max(1.0)
            }
            None => f64::NEG_INFINITY,
        };
        p.g + (h_in.max(h_out) + act).max(h)
    }

    /// Whether the budget stops this pass now (only a pass that may abort is stopped).
    fn out_of_budget(&self, ctx: &mut Context) -> bool {
        self.may_abort && ctx.exhausted()
    }

    /// The path relaxation's multiplier of cell `c` (0 without it).
    #[inline]
    fn lam(&self, c: usize) -> f64 {
        self.qp.map_or(0.0, |q| q.lambda(c))
    }

    /// Whether `stored` trail entries, `live` prefixes and a dominance map of `map` entries
    /// would pass the memory cap.
    fn overflow(&self, stored: u64, live: usize, map: usize) -> bool {
        let prefix_bytes = std::mem::size_of::<Prefix<W>>() as u64;
        let entry_bytes = std::mem::size_of::<(([u64; W], u32), u32)>() as u64 + 8;
        self.mem_cap.is_some_and(|cap| {
            stored * 8 + live as u64 * prefix_bytes + map as u64 * entry_bytes > cap
        })
    }

    /// Level 1: every cell that may come first, in every mode, bounded, refined and cut to
    /// the width; with whether the cut discarded any.
    fn first_level(&self, ctx: &mut Context, scratch: &mut [(f64, f64)]) -> (Vec<Prefix<W>>, bool) {
        let (m, t) = (ctx.model, self.t);
        let lam_total = self.qp.map_or(0.0, |q| q.lambda_total());
        let mut cands: Vec<Prefix<W>> = first_prefixes(m, t, lam_total, |c| self.lam(c));
        for p in cands.iter_mut() {
            p.f = self.bound(p, 1);
        }
        cands.retain(|p| p.f <= self.cut);
        charge(ctx, cands.len() as u64);
        if self.beam.refine {
            for c in cands.iter_mut() {
                c.f = c.f.max(refined(m, t, c, scratch));
            }
        }
        if self.width == 1 && crate::solvers::trace_enabled() {
            let lb = cands.iter().map(|c| c.f).fold(f64::INFINITY, f64::min);
            eprintln!("beam: first-level bound {lb}");
        }
        let truncated = keep_best(&mut cands, self.width, self.beam.by_cost);
        (cands, truncated)
    }

    /// Per parent: Σ μ_S over the sets its children must still leave; per cell: the parents
    /// it may extend (all its predecessors visited, itself not), and how many such pairs.
    /// A wide level holds millions of parents: the budget and the memory cap (with `stored`
    /// trail entries so far) are asked every 4096 parents, `Err` when they stop the pass.
    fn parent_lists(
        &self,
        ctx: &mut Context,
        prev: &[Prefix<W>],
        stored: u64,
    ) -> Result<ParentLists, Pass> {
        let (m, t) = (ctx.model, self.t);
        let mut acts: Vec<f64> = Vec::with_capacity(prev.len());
        let n = m.n();
        let mut by_cell: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut listed = 0usize;
        for (pi, p) in prev.iter().enumerate() {
            if pi % 4096 == 4095 {
                if self.out_of_budget(ctx) {
                    return Err(Pass::aborted());
                }
                // the lists count as stored prefixes, as in `children`
                if self.overflow(stored + (listed / 2 + pi) as u64, prev.len(), 0) {
                    return Err(Pass::overflow());
                }
            }
            let a = m.cell_mode(p.node as usize).0;
            // every child leaves the same sets: the parent's, less those that `a` closes
            acts.push(p.act - t.closing_mu(&p.bits, a));
            for v in open_cells(&p.bits, n) {
                let ready = t.pred_mask[v]
                    .iter()
                    .zip(p.bits.iter())
                    .all(|(need, have)| need & !have == 0);
                if ready {
                    by_cell[v].push(pi as u32);
                    listed += 1;
                }
            }
        }
        Ok((acts, by_cell, listed))
    }

    /// The children of the level `prev` (prefixes of `cells` cells), pruned by the bound and
    /// merged by prefix dominance (same visited set and last node: the cheaper stays), with
    /// their evaluations charged; `Err` when the budget or the memory cap stops the pass
    /// (`stored`: trail entries so far; `index`: the dominance map, reused).
    fn children(
        &self,
        ctx: &mut Context,
        prev: &[Prefix<W>],
        cells: usize,
        stored: u64,
        index: &mut FxHashMap<([u64; W], u32), u32>,
    ) -> Result<Vec<Prefix<W>>, Pass> {
        let (m, t) = (ctx.model, self.t);
        let mut cands: Vec<Prefix<W>> = Vec::with_capacity(prev.len() * 2);
        let mut evals = 0u64;
        // children grouped by their new cell, so the dominance map holds one cell's
        // children at a time: small enough to stay in cache (on p43.2 a whole level's map
        // had millions of entries and its cache misses took ~40 % of the time)
        let (acts, by_cell, listed) = self.parent_lists(ctx, prev, stored)?;
        // the parent lists and their Σ μ count as stored prefixes (8 bytes each)
        let lists = (listed / 2 + acts.len()) as u64;
        let mut done = 0usize;
        for (v, list) in by_cell.iter().enumerate() {
            index.clear();
            for &pi in list {
                // a wide level takes seconds: honour the time limit inside it too (the
                // evaluation count is only updated per level, so evaluation budgets stay
                // deterministic)
                done += 1;
                if done % 1024 == 1023 {
                    if self.out_of_budget(ctx) {
                        return Err(Pass::aborted());
                    }
                    if self.overflow(stored + lists, prev.len() + cands.len(), index.len()) {
                        charge(ctx, evals);
                        return Err(Pass::overflow());
                    }
                }
                let p = &prev[pi as usize];
                let (a, ma) = m.cell_mode(p.node as usize);
                let act = acts[pi as usize];
                let mut bits = p.bits;
                bits[v / 64] |= 1 << (v % 64);
                for mv in 0..m.modes(v) {
                    evals += 1;
                    let mut c = Prefix {
                        bits,
                        node: m.node(v, mv) as u32,
                        parent: pi,
                        g: p.g + m.arc(a, ma, v, mv),
                        rem_in: p.rem_in - t.cell_in[v],
                        rem_out: p.rem_out - t.cell_out[v],
                        lam_open: p.lam_open - self.lam(v),
                        act,
                        f: 0.0,
                    };
                    c.f = self.bound(&c, cells);
                    if c.f > self.cut {
                        continue;
                    }
                    // one hash per child: the entry is looked up and filled in place
                    match index.entry((bits, c.node)) {
                        Entry::Occupied(o) => {
                            let e = &mut cands[*o.get() as usize];
                            if c.g < e.g {
                                *e = c;
                            }
                        }
                        Entry::Vacant(slot) => {
                            slot.insert(cands.len() as u32);
                            cands.push(c);
                        }
                    }
                }
            }
        }
        drop(by_cell);
        charge(ctx, evals);
        Ok(cands)
    }

    /// Refines the bounds of a level's candidates and drops those it prunes; `None` when the
    /// budget stops the pass. Refinement pays only where it prunes: each level refines a
    /// first sample of candidates and goes on only when it pruned at least a quarter of them
    /// (on p43.2 it prunes ~4 % of the candidates and took 76 % of the time).
    fn refine_level(
        &self,
        ctx: &mut Context,
        mut cands: Vec<Prefix<W>>,
        scratch: &mut [(f64, f64)],
    ) -> Option<Vec<Prefix<W>>> {
        let (m, t, width) = (ctx.model, self.t, self.width);
        let mut sample = Sample::default();
        if self.beam.refine && cands.len() > width && !self.beam.by_cost {
            // refine lazily in order of the incremental bound until more than `width`
            // survive: the rest is discarded (and the level counts as truncated). Only the
            // order's head is needed, so it is sorted a chunk at a time: each chunk is the
            // least of what is left (`rank` is a total order, so this is the full sort's
            // order) and twice what may still be kept.
            let mut kept = Vec::with_capacity(width + 1);
            let mut from = 0;
            'chunks: while from < cands.len() {
                let want = (width.saturating_add(1) - kept.len())
                    .saturating_mul(2)
                    .max(64);
                let rest = &mut cands[from..];
                let chunk = want.min(rest.len());
                if chunk < rest.len() {
                    rest.select_nth_unstable_by(chunk - 1, rank);
                }
                rest[..chunk].sort_unstable_by(rank);
                for mut c in rest[..chunk].iter().copied() {
                    if sample.on() {
                        if sample.done % 4096 == 4095 && self.out_of_budget(ctx) {
                            return None;
                        }
                        c.f = c.f.max(refined(m, t, &c, scratch));
                        if !sample.record(c.f <= self.cut) {
                            continue;
                        }
                    }
                    kept.push(c);
                    if kept.len() > width {
                        break 'chunks;
                    }
                }
                from += chunk;
            }
            charge(ctx, sample.done);
            cands = kept;
        } else if self.beam.refine {
            // an unbounded level may hold millions of candidates: the time limit is asked
            // here too
            let mut stopped = false;
            cands.retain_mut(|c| {
                if stopped || !sample.on() {
                    return true;
                }
                if sample.done % 4096 == 4095 && self.out_of_budget(ctx) {
                    stopped = true;
                    return true;
                }
                c.f = c.f.max(refined(m, t, c, scratch));
                sample.record(c.f <= self.cut)
            });
            charge(ctx, sample.done);
            if stopped {
                return None;
            }
        }
        Some(cands)
    }

    /// The best complete sequence within the cut, read back through the trail from the
    /// last level `last` (none when the pass did not reach every cell).
    fn complete(
        &self,
        ctx: &Context,
        trail: &[Vec<(u32, u32)>],
        last: &[Prefix<W>],
    ) -> Option<(f64, Sequence)> {
        let m = ctx.model;
        let n = m.n();
        if trail.len() < n {
            return None;
        }
        let mut best: Option<(f64, usize)> = None;
        for (i, p) in last.iter().enumerate() {
            let (c, md) = m.cell_mode(p.node as usize);
            let total = p.g + m.finish(c, md);
            if total <= self.cut && best.is_none_or(|b| total < b.0) {
                best = Some((total, i));
            }
        }
        let (_, mut i) = best?;
        let mut seq = Vec::with_capacity(n);
        for lvl in trail.iter().rev() {
            let (parent, node) = lvl[i];
            let (c, md) = m.cell_mode(node as usize);
            seq.push(Visit::new(c, md));
            i = parent as usize;
        }
        seq.reverse();
        let cost = m.evaluate(&seq);
        Some((cost, seq))
    }
}

/// Candidates refined at the start of a level before deciding whether refinement goes on.
const REFINE_SAMPLE: u64 = 1024;

/// Counts of the refined candidates of one level: refinement stops for the rest of the
/// level when fewer than a quarter of the first [`REFINE_SAMPLE`] were pruned.
#[derive(Default)]
pub(super) struct Sample {
    done: u64,
    pruned: u64,
    off: bool,
}

impl Sample {
    fn on(&self) -> bool {
        !self.off
    }

    /// Records one refined candidate (`kept`: it survived) and returns `kept`.
    fn record(&mut self, kept: bool) -> bool {
        self.done += 1;
        self.pruned += u64::from(!kept);
        if self.done == REFINE_SAMPLE && self.pruned * 4 < self.done {
            self.off = true;
        }
        kept
    }
}

/// Result of one beam pass.
pub(super) struct Pass {
    /// the best complete sequence found (cost, sequence)
    pub(super) found: Option<(f64, Sequence)>,
    /// some candidate was discarded because of the width
    pub(super) truncated: bool,
    /// the budget stopped the pass
    pub(super) aborted: bool,
    /// an unbounded pass stopped at its memory cap
    pub(super) overflow: bool,
}

impl Pass {
    fn aborted() -> Pass {
        Pass {
            found: None,
            truncated: true,
            aborted: true,
            overflow: false,
        }
    }

    fn overflow() -> Pass {
        Pass {
            found: None,
            truncated: true,
            aborted: false,
            overflow: true,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tables::tables;
    use super::*;
    use crate::clock::Deadline;
    use crate::cost::CostModel;
    use crate::generate::generate;
    use crate::params::Params;
    use crate::solvers::{Budget, NoObserver};
    use std::collections::BTreeMap;

    /// A wide level's parent lists ask the budget as they go (a 5-million-prefix level took
    /// 3 s there, past a 12 s limit by 3.4 s), and only when the pass may abort.
    #[test]
    fn parent_lists_ask_the_budget() {
        let params: BTreeMap<String, String> = [("n", "98"), ("c", "500"), ("p", "1")]
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let inst = generate("symmetric", &params, 1).unwrap();
        let m = CostModel::new(&inst, inst.default_objective());
        let t = tables(&m, true, true, true, None, Deadline::NONE)
            .unwrap()
            .unwrap();
        let beam = super::super::from_params(
            &Params::new("beam", super::super::INFO.params, &BTreeMap::new()).unwrap(),
        );
        let firsts: Vec<Prefix<2>> = first_prefixes(&m, &t, 0.0, |_| 0.0);
        let prev: Vec<Prefix<2>> = firsts.iter().copied().cycle().take(10_000).collect();
        for may_abort in [true, false] {
            let lv = Level::<2> {
                beam: &beam,
                t: &t,
                qp: None,
                width: usize::MAX,
                cut: f64::INFINITY,
                may_abort,
                mem_cap: None,
            };
            let mut obs = NoObserver;
            // an evaluation budget of 0: spent from the start
            let budget = Budget {
                time_limit: None,
                max_evals: Some(0),
            };
            let mut ctx = Context::new(&inst, &m, 1, budget, &mut obs);
            match lv.parent_lists(&mut ctx, &prev, 0) {
                Err(pass) => assert!(may_abort && pass.aborted),
                Ok((acts, _, listed)) => {
                    assert!(!may_abort);
                    assert_eq!(acts.len(), prev.len());
                    assert!(listed > 0);
                }
            }
        }
    }
}

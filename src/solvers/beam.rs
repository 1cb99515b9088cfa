//! `beam`: anytime iterative beam search (Libralesso et al. 2020) that doubles as an exact
//! solver.
//!
//! The tree branches forward over the precedence fringe: a node is a prefix (visited set, last
//! (cell, mode), cost so far). Each iteration runs a beam of width 1, 2, 4, … level by level:
//! children are generated from every kept prefix, pruned when their cost plus a cheap
//! incremental lower bound cannot beat the incumbent, merged by **prefix dominance** (same
//! visited set and same last node: keep the cheaper), and the `width` best by bound are kept.
//! When an iteration finishes without having discarded anything because of the width, the
//! search was exhaustive and the incumbent is **proven optimal**.
//!
//! The incremental bound is the larger of two degree bounds over the part still to do, both
//! maintained in O(1) per child: every unvisited cell (and home) is still to be entered once
//! (Σ cheapest allowed in-arc), and the last node and every unvisited cell are still to be left
//! once (Σ cheapest allowed out-arc). A root bound from [`crate::bound`] (Lagrangian
//! arborescence) may close the gap at once.

use super::{Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::bound::cells::CellGraph;
use crate::bound::closure::Closure;
use crate::bound::{self, BoundOptions};
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::model::{Sequence, Visit};
use rustc_hash::FxHashMap;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "beam",
    summary: "iterative beam search with prefix dominance and bound pruning; proves optimality \
              when a beam is wide enough",
    params: &[
        ParamSpec {
            name: "max_width",
            default: "1048576",
            kind: ParamKind::Int,
            help: "stop doubling the beam width after this width",
        },
        ParamSpec {
            name: "memory_mb",
            default: "2048",
            kind: ParamKind::Int,
            help: "do not start an iteration whose stored prefixes could pass this many MiB",
        },
        ParamSpec {
            name: "guide",
            default: "bound",
            kind: ParamKind::Choice(&["bound", "cost"]),
            help: "rank prefixes by cost + lower bound, or by cost so far",
        },
        ParamSpec {
            name: "refine",
            default: "true",
            kind: ParamKind::Bool,
            help: "recompute each kept prefix's degree bound over the arcs still possible",
        },
        ParamSpec {
            name: "root_bound",
            default: "true",
            kind: ParamKind::Bool,
            help: "compute the Lagrangian root bound (stops as soon as the incumbent meets it)",
        },
    ],
    make: |p: &Params| {
        Box::new(Beam {
            max_width: p.int("max_width").max(1) as usize,
            memory_mb: p.int("memory_mb"),
            root_bound: p.bool("root_bound"),
            refine: p.bool("refine"),
            by_cost: p.word("guide") == "cost",
        })
    },
};

/// The iterative beam search solver.
pub struct Beam {
    /// Largest beam width tried.
    pub max_width: usize,
    /// Memory limit for stored prefixes (MiB).
    pub memory_mb: u64,
    /// Whether to compute a root lower bound.
    pub root_bound: bool,
    /// Whether to recompute the degree bound over the arcs still possible.
    pub refine: bool,
    /// Rank prefixes by cost so far instead of cost + bound.
    pub by_cost: bool,
}

/// Largest instance accepted (visited sets are fixed-size bitsets).
pub const MAX_CELLS: usize = 1024;

impl Solver for Beam {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let n = ctx.model.n();
        match n.div_ceil(64) {
            0 | 1 => self.run::<1>(ctx),
            2 => self.run::<2>(ctx),
            3 | 4 => self.run::<4>(ctx),
            5..=8 => self.run::<8>(ctx),
            9..=16 => self.run::<16>(ctx),
            _ => Err(Error::Solver {
                solver: "beam".into(),
                msg: format!("instance has {n} cells; beam accepts at most {MAX_CELLS}"),
            }),
        }
    }
}

/// One stored prefix.
#[derive(Clone, Copy)]
struct Prefix<const W: usize> {
    bits: [u64; W],
    node: u32,
    parent: u32,
    g: f64,
    /// Σ cheapest in-arc over unvisited cells
    rem_in: f64,
    /// Σ cheapest out-arc over unvisited cells
    rem_out: f64,
    f: f64,
}

/// Static data of the incremental bound.
struct Tables {
    pred_mask: Vec<Vec<u64>>,
    cell_in: Vec<f64>,
    cell_out: Vec<f64>,
    node_out: Vec<f64>,
    home_in: f64,
    integral: bool,
    /// per cell: allowed predecessor cells by increasing arc cost
    in_list: Vec<Vec<(f64, u32)>>,
    /// per cell: allowed successor cells (and home = n when it may be last) by increasing cost
    out_list: Vec<Vec<(f64, u32)>>,
}

fn tables(m: &CostModel) -> Result<Tables> {
    let n = m.n();
    let words = n.div_ceil(64).max(1);
    let cl = Closure::new(&m.dag).ok_or_else(|| Error::Solver {
        solver: "beam".into(),
        msg: "precedence has a cycle".into(),
    })?;
    let g = CellGraph::new(m, &cl);
    let min_in = g.min_in();
    let min_out = g.min_out();
    let pred_mask = (0..n)
        .map(|c| {
            let mut v = vec![0u64; words];
            for &p in &m.dag.preds[c] {
                v[p as usize / 64] |= 1 << (p % 64);
            }
            v
        })
        .collect();
    let mut node_out = vec![f64::INFINITY; m.nodes()];
    for (u, slot) in node_out.iter_mut().enumerate() {
        let (a, ma) = m.cell_mode(u);
        let mut best = if cl.can_be_last(a) {
            m.finish(a, ma)
        } else {
            f64::INFINITY
        };
        for b in 0..n {
            if cl.arc_allowed(a, b) {
                for mb in 0..m.modes(b) {
                    best = best.min(m.arc(a, ma, b, mb));
                }
            }
        }
        *slot = best;
    }
    let fin = |x: f64| if x.is_finite() { x } else { 0.0 };
    let mut in_list = vec![Vec::new(); n];
    let mut out_list = vec![Vec::new(); n];
    #[allow(clippy::needless_range_loop)]
    for i in 0..n {
        for j in 0..=n {
            let c = g.c(i, j);
            if c.is_finite() {
                out_list[i].push((c, j as u32));
                if j < n {
                    in_list[j].push((c, i as u32));
                }
            }
        }
    }
    for l in in_list.iter_mut().chain(out_list.iter_mut()) {
        l.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
    Ok(Tables {
        in_list,
        out_list,
        pred_mask,
        cell_in: min_in[..n].iter().map(|&x| fin(x)).collect(),
        cell_out: min_out[..n].iter().map(|&x| fin(x)).collect(),
        node_out: node_out.into_iter().map(fin).collect(),
        home_in: fin(min_in[n]),
        integral: g.integral() && m.constant().fract() == 0.0,
    })
}

impl Beam {
    fn run<const W: usize>(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        if n == 0 {
            return Ok(super::outcome_of(m, Vec::new()));
        }
        let t = tables(m)?;
        let constant = m.constant();
        let mut root_lb = f64::NEG_INFINITY;
        // prune a bound f when it cannot beat `ub` strictly
        let cut = |ub: f64| {
            if !ub.is_finite() {
                f64::INFINITY
            } else if t.integral {
                ub - 1.0 + 1e-6
            } else {
                ub - 1e-9 * ub.abs().max(1.0)
            }
        };
        let mut best: Option<(f64, Sequence)> = None;
        let mut proven = false;
        let prefix_bytes = (std::mem::size_of::<Prefix<W>>() + 24) as u64;
        let mut width = 1usize;
        loop {
            let ub = best.as_ref().map(|b| b.0).unwrap_or(f64::INFINITY);
            let (found, truncated, aborted) =
                self.iteration::<W>(ctx, &t, width, cut(ub), best.is_some());
            if let Some((c, seq)) = found
                && best
                    .as_ref()
                    .is_none_or(|b| c < b.0 - 1e-9 * c.abs().max(1.0))
            {
                ctx.report(c);
                best = Some((c, seq));
            }
            if std::env::var_os("CELLSEQ_BEAM_TRACE").is_some() {
                eprintln!(
                    "beam width {width}: best {:?} truncated {truncated} aborted {aborted} {:.2}s",
                    best.as_ref().map(|b| b.0),
                    ctx.elapsed()
                );
            }
            if !aborted && !truncated && best.is_some() {
                proven = true;
                break;
            }
            // the Lagrangian root bound costs O(iterations · n²) arc evaluations: worth it on
            // matrix instances and small geometric ones, not when the budget is already spent
            let bound_affordable = !m.is_geometric() || n <= 100;
            if width == 1
                && self.root_bound
                && bound_affordable
                && !ctx.exhausted()
                && best.is_some()
            {
                let opts = BoundOptions {
                    assignment_max_cells: 0,
                    lagrangian_iterations: 150,
                    upper: best.as_ref().map(|b| b.0),
                    ..BoundOptions::default()
                };
                root_lb = bound::compute(m, &opts).best;
            }
            if let Some((c, _)) = &best
                && root_lb > cut(*c)
            {
                proven = true;
                break;
            }
            if aborted || ctx.exhausted() || width >= self.max_width {
                break;
            }
            width *= 2;
            let need = prefix_bytes * width as u64 * (n as u64 + 1) * 2;
            if need > self.memory_mb.saturating_mul(1 << 20) {
                break;
            }
        }
        let (cost, sequence) = best.ok_or_else(|| Error::Solver {
            solver: "beam".into(),
            msg: "no feasible sequence found".into(),
        })?;
        Ok(Outcome {
            sequence,
            cost,
            proven_optimal: proven,
            lower_bound: Some(if proven { cost } else { root_lb.max(constant) }),
        })
    }

    /// One beam pass of the given width. Returns the best complete sequence found (cost, seq),
    /// whether any child was discarded because of the width, and whether the budget stopped it.
    fn iteration<const W: usize>(
        &self,
        ctx: &mut Context,
        t: &Tables,
        width: usize,
        cut: f64,
        may_abort: bool,
    ) -> (Option<(f64, Sequence)>, bool, bool) {
        let m = ctx.model;
        let n = m.n();
        let total_in: f64 = t.cell_in.iter().sum();
        let total_out: f64 = t.cell_out.iter().sum();
        let bound = |p: &Prefix<W>| {
            let h_in = p.rem_in + t.home_in;
            let h_out = p.rem_out + t.node_out[p.node as usize];
            p.g + h_in.max(h_out)
        };
        let mut levels: Vec<Vec<Prefix<W>>> = Vec::with_capacity(n);
        let mut truncated = false;
        // level 1: every cell that may come first, in every mode
        let mut cands: Vec<Prefix<W>> = Vec::new();
        for c in 0..n {
            if t.pred_mask[c].iter().any(|&w| w != 0) {
                continue;
            }
            for md in 0..m.modes(c) {
                let mut bits = [0u64; W];
                bits[c / 64] |= 1 << (c % 64);
                let mut p = Prefix {
                    bits,
                    node: m.node(c, md) as u32,
                    parent: u32::MAX,
                    g: m.constant() + m.start(c, md),
                    rem_in: total_in - t.cell_in[c],
                    rem_out: total_out - t.cell_out[c],
                    f: 0.0,
                };
                p.f = bound(&p);
                if p.f <= cut {
                    cands.push(p);
                }
            }
        }
        ctx.count(cands.len() as u64);
        truncated |= keep_best(&mut cands, width, self.by_cost);
        levels.push(cands);
        let mut index: FxHashMap<([u64; W], u32), u32> = FxHashMap::default();
        for _k in 1..n {
            let prev = levels.last().expect("a level");
            if prev.is_empty() {
                break;
            }
            let mut cands: Vec<Prefix<W>> = Vec::with_capacity(prev.len() * 4);
            index.clear();
            let mut evals = 0u64;
            for (pi, p) in prev.iter().enumerate() {
                let (a, ma) = m.cell_mode(p.node as usize);
                for v in 0..n {
                    if p.bits[v / 64] >> (v % 64) & 1 == 1 {
                        continue;
                    }
                    let ready = t.pred_mask[v]
                        .iter()
                        .zip(p.bits.iter())
                        .all(|(need, have)| need & !have == 0);
                    if !ready {
                        continue;
                    }
                    let mut bits = p.bits;
                    bits[v / 64] |= 1 << (v % 64);
                    for mv in 0..m.modes(v) {
                        evals += 1;
                        let mut c = Prefix {
                            bits,
                            node: m.node(v, mv) as u32,
                            parent: pi as u32,
                            g: p.g + m.arc(a, ma, v, mv),
                            rem_in: p.rem_in - t.cell_in[v],
                            rem_out: p.rem_out - t.cell_out[v],
                            f: 0.0,
                        };
                        c.f = bound(&c);
                        if c.f > cut {
                            continue;
                        }
                        match index.get(&(bits, c.node)) {
                            Some(&i) => {
                                let e = &mut cands[i as usize];
                                if c.g < e.g {
                                    *e = c;
                                }
                            }
                            None => {
                                index.insert((bits, c.node), cands.len() as u32);
                                cands.push(c);
                            }
                        }
                    }
                }
            }
            ctx.count(evals);
            if self.refine {
                for c in cands.iter_mut() {
                    c.f = c.f.max(refined(m, t, c));
                }
                ctx.count(cands.len() as u64);
                cands.retain(|c| c.f <= cut);
            }
            truncated |= keep_best(&mut cands, width, self.by_cost);
            levels.push(cands);
            if may_abort && ctx.exhausted() {
                return (None, truncated, true);
            }
        }
        // complete sequences
        let last = levels.last().expect("a level");
        if levels.len() < n {
            return (None, truncated, false);
        }
        let mut best: Option<(f64, usize)> = None;
        for (i, p) in last.iter().enumerate() {
            let (c, md) = m.cell_mode(p.node as usize);
            let total = p.g + m.finish(c, md);
            if total <= cut && best.is_none_or(|b| total < b.0) {
                best = Some((total, i));
            }
        }
        let Some((_, mut i)) = best else {
            return (None, truncated, false);
        };
        let mut seq = Vec::with_capacity(n);
        for lvl in levels.iter().rev() {
            let p = &lvl[i];
            let (c, md) = m.cell_mode(p.node as usize);
            seq.push(Visit::new(c, md));
            i = p.parent as usize;
        }
        seq.reverse();
        let cost = m.evaluate(&seq);
        (Some((cost, seq)), truncated, false)
    }
}

/// The dynamic degree bound of a prefix: every unvisited cell is entered from an unvisited cell
/// or the last one, and left to an unvisited cell or home; the last node is left to an
/// unvisited cell. O(|unvisited| · scan) with the sorted arc lists.
fn refined<const W: usize>(m: &CostModel, t: &Tables, p: &Prefix<W>) -> f64 {
    let n = m.n();
    let open = |c: usize| c < n && p.bits[c / 64] >> (c % 64) & 1 == 0;
    let (l, lm) = m.cell_mode(p.node as usize);
    let mut h_in = 0.0;
    let mut h_out = 0.0;
    let mut home_in = f64::INFINITY;
    let mut last_out = f64::INFINITY;
    let mut any = false;
    for j in 0..n {
        if !open(j) {
            continue;
        }
        any = true;
        let i = t.in_list[j]
            .iter()
            .find(|&&(_, i)| open(i as usize) || i as usize == l)
            .map(|e| e.0);
        let Some(i) = i else {
            return f64::INFINITY;
        };
        h_in += i;
        let o = t.out_list[j]
            .iter()
            .find(|&&(_, k)| open(k as usize) || k as usize == n)
            .map(|e| e.0);
        let Some(o) = o else {
            return f64::INFINITY;
        };
        h_out += o;
        if let Some(&(c, _)) = t.out_list[j].iter().find(|&&(_, k)| k as usize == n) {
            home_in = home_in.min(c);
        }
        for mj in 0..m.modes(j) {
            last_out = last_out.min(m.arc(l, lm, j, mj));
        }
    }
    if !any {
        return p.g + m.finish(l, lm);
    }
    let home_in = if home_in.is_finite() { home_in } else { 0.0 };
    p.g + (h_in + home_in).max(h_out + last_out)
}

/// Keeps the `width` candidates with the smallest bound (ties: cost, then last node and visited
/// set, so the choice is deterministic). Returns true when some were discarded.
fn keep_best<const W: usize>(c: &mut Vec<Prefix<W>>, width: usize, by_cost: bool) -> bool {
    if c.len() <= width {
        return false;
    }
    let key = |a: &Prefix<W>, b: &Prefix<W>| {
        let (x, y) = if by_cost { (a.g, b.g) } else { (a.f, b.f) };
        x.total_cmp(&y)
            .then(a.f.total_cmp(&b.f))
            .then(a.g.total_cmp(&b.g))
            .then(a.node.cmp(&b.node))
            .then(a.bits.cmp(&b.bits))
    };
    c.select_nth_unstable_by(width - 1, key);
    c.truncate(width);
    true
}

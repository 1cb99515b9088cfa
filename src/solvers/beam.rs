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
//! once (Σ cheapest allowed out-arc). With `qpath` (default), the position-indexed path
//! relaxation of [`crate::bound::qpath`] adds an O(1) table bound per (cells visited, last
//! node), strong under dense precedence. With `sec` (default), the potentials come from the
//! assignment with subtour-elimination multipliers ([`crate::bound::sec`]) and every prefix
//! is also charged the multipliers of the sets it must still leave. A root bound from [`crate::bound`] (Lagrangian
//! arborescence) may close the gap at once.

use super::{Budget, Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::bound::cells::CellGraph;
use crate::bound::qpath::{self, QPath};
use crate::bound::sec::{self, SecBound};
use crate::bound::{self, BoundOptions, assignment};
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::model::{Sequence, Visit};
use crate::precedence::Closure;
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
        ParamSpec {
            name: "potentials",
            default: "true",
            kind: ParamKind::Bool,
            help: "bound in reduced costs of the root assignment duals, with its subtours as \
                   clusters that must be entered and left (n <= 600)",
        },
        ParamSpec {
            name: "sec",
            default: "true",
            kind: ParamKind::Bool,
            help: "take the potentials from the assignment with subtour-elimination multipliers \
                   (bound::sec) and charge each set's multiplier while the path must still \
                   leave it (with potentials=true)",
        },
        ParamSpec {
            name: "qpath",
            default: "true",
            kind: ParamKind::Bool,
            help: "also bound prefixes with the position-indexed path relaxation \
                   (bound::qpath, multipliers from subgradient steps at the root)",
        },
        ParamSpec {
            name: "twins",
            default: "true",
            kind: ParamKind::Bool,
            help: "order interchangeable cells (same costs to and from every other cell, same \
                   precedence) by index: symmetry breaking that keeps an optimum",
        },
        ParamSpec {
            name: "growth",
            default: "4",
            kind: ParamKind::Int,
            help: "factor by which the beam width grows from width 1024 on (doubling before)",
        },
        ParamSpec {
            name: "exhaustive_from",
            default: "16384",
            kind: ParamKind::Int,
            help: "after the pass of this width, one pass without a width limit (stopped at \
                   memory_mb) before wider truncated passes; 0 = never",
        },
        ParamSpec {
            name: "warm_evals",
            default: "2000000",
            kind: ParamKind::Int,
            help: "evaluations of an `ils` run that gives the first incumbent (0 = none)",
        },
    ],
    caps: Caps {
        exact: true,
        warm_start: true,
        ..Caps::NONE
    },
    make: |p: &Params| Ok(Box::new(from_params(p))),
};

/// Builds the solver from validated parameters.
pub fn from_params(p: &Params) -> Beam {
    Beam {
        max_width: p.int("max_width").max(1) as usize,
        memory_mb: p.int("memory_mb"),
        root_bound: p.bool("root_bound"),
        refine: p.bool("refine"),
        by_cost: p.word("guide") == "cost",
        potentials: p.bool("potentials"),
        warm_evals: p.int("warm_evals"),
        qpath: p.bool("qpath"),
        sec: p.bool("sec"),
        growth: p.int("growth").max(2) as usize,
        twins: p.bool("twins"),
        exhaustive_from: p.int("exhaustive_from") as usize,
    }
}

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
    /// Bound in reduced costs of the root assignment (with clusters).
    pub potentials: bool,
    /// Evaluation budget of the `ils` warm start (0 = none).
    pub warm_evals: u64,
    /// Bound prefixes with the position-indexed path relaxation too.
    pub qpath: bool,
    /// Order interchangeable cells by index (symmetry breaking).
    pub twins: bool,
    /// Potentials from the subtour-elimination Lagrangian, with its set multipliers.
    pub sec: bool,
    /// Width growth factor from width 1024 on.
    pub growth: usize,
    /// Width after which one unbounded pass is tried (0: never).
    pub exhaustive_from: usize,
}

/// Width from which the beam grows by the `growth` factor instead of doubling.
const GROWTH_FROM: usize = 1024;

/// Largest instance accepted (visited sets are fixed-size bitsets).
pub const MAX_CELLS: usize = 1024;

impl Solver for Beam {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        self.search_from(ctx, None)
    }
    fn solve_from(&self, ctx: &mut Context, start: Option<&Sequence>) -> Result<Outcome> {
        self.search_from(ctx, start.cloned())
    }
}

impl Beam {
    /// The search with `incumbent` (a feasible sequence) as its first upper bound instead of
    /// the `ils` warm start: the result is never worse than it.
    pub fn search_from(&self, ctx: &mut Context, incumbent: Option<Sequence>) -> Result<Outcome> {
        let n = ctx.model.n();
        let inc = incumbent.map(|seq| (ctx.model.evaluate(&seq), seq));
        match n.div_ceil(64) {
            0 | 1 => self.run::<1>(ctx, inc),
            2 => self.run::<2>(ctx, inc),
            3 | 4 => self.run::<4>(ctx, inc),
            5..=8 => self.run::<8>(ctx, inc),
            9..=16 => self.run::<16>(ctx, inc),
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
    /// Σ qpath multipliers over unvisited cells
    lam_open: f64,
    /// Σ μ_S over the sets the rest must still leave ([`Tables::active_mu`], kept
    /// incrementally: a child has its parent's less [`Tables::closing_mu`] of the parent)
    act: f64,
    f: f64,
}

impl<const W: usize> Prefix<W> {
    /// The one-cell prefix of cell `c` in mode `md` with its incremental bound terms
    /// (`lam_open`: Σ qpath multipliers over the other cells); `f` is left at 0.
    fn first(m: &CostModel, t: &Tables, c: usize, md: usize, lam_open: f64) -> Self {
        let mut bits = [0u64; W];
        bits[c / 64] |= 1 << (c % 64);
        Prefix {
            bits,
            node: m.node(c, md) as u32,
            parent: u32::MAX,
            g: m.constant() + m.start(c, md),
            rem_in: t.total_in - t.cell_in[c],
            rem_out: t.total_out - t.cell_out[c],
            lam_open,
            act: t.active_mu(&bits, c),
            f: 0.0,
        }
    }
}

/// Every one-cell prefix: each cell that may come first (no predecessor, twins included), in
/// each mode; `lam_total` = Σ qpath multipliers, `lam(c)` the multiplier of cell `c`.
fn first_prefixes<const W: usize>(
    m: &CostModel,
    t: &Tables,
    lam_total: f64,
    lam: impl Fn(usize) -> f64,
) -> Vec<Prefix<W>> {
    (0..m.n())
        .filter(|&c| t.pred_mask[c].iter().all(|&w| w == 0))
        .flat_map(|c| (0..m.modes(c)).map(move |md| (c, md)))
        .map(|(c, md)| Prefix::first(m, t, c, md, lam_total - lam(c)))
        .collect()
}

/// Static data of the incremental bound.
///
/// All bound terms are written with the dual potentials `u`, `v` of the root assignment
/// problem (cells plus home = index n): every arc cost splits as `c(i, j) = u_i + v_j +
/// r(i, j)` with reduced cost `r`, so the rest of a path from the last cell `l` through the
/// unvisited set `U` to home costs exactly `u_l + v_home + Σ_{U} (u + v) + Σ r` over its arcs,
/// and `Σ r` is bounded below by degree arguments on reduced costs (valid for any potentials;
/// the assignment duals make them strong).
///
/// With `sec` the split is `c(i, j) = u_i + v_j + μ(i, j) + r(i, j)` where `μ(i, j)` sums
/// the multipliers `μ_S ≥ 0` of the sets `S` that the arc leaves ([`crate::bound::sec`]):
/// the rest of the path leaves every set that holds an unvisited cell or the last cell, so it
/// pays at least Σ μ_S over those on top of `Σ r` (and dropping `μ(i, j) ≥ 0` keeps the
/// O(1) incremental terms valid).
struct Tables {
    pred_mask: Vec<Vec<u64>>,
    /// per cell: u + v + cheapest reduced in-arc
    cell_in: Vec<f64>,
    /// per cell: u + v + cheapest reduced out-arc
    cell_out: Vec<f64>,
    /// per node: u(cell) + v(home) + cheapest reduced arc out of the node (μ excluded: the
    /// sets' multipliers are charged separately)
    node_out: Vec<f64>,
    /// per node: u(cell) + v(home) + cheapest reduced arc into home
    node_in: Vec<f64>,
    /// row potentials (cells, then home)
    u: Vec<f64>,
    /// column potentials (cells, then home)
    v: Vec<f64>,
    /// per cell: reduced cost of the cheapest finish (∞ when the cell cannot be last)
    r_home: Vec<f64>,
    integral: bool,
    /// per cell: allowed predecessor cells by increasing reduced cost
    in_list: Vec<Vec<(f64, u32)>>,
    /// per cell: allowed successor cells (and home = n when it may be last) by increasing
    /// reduced cost
    out_list: Vec<Vec<(f64, u32)>>,
    /// cluster index of each cell (`u32::MAX`: none); clusters are the subtours of the root
    /// assignment, which any path must enter and leave at least once
    cluster: Vec<u32>,
    /// the clusters' cells
    clusters: Vec<Vec<u32>>,
    /// Σ cell_in, Σ cell_out over all cells
    total_in: f64,
    total_out: f64,
    /// `μ(i, j)` over cells and home, row-major with n + 1 columns (empty: all zero)
    mu_arc: Vec<f64>,
    /// subtour-elimination sets as cell bitsets (words of 64) with their multipliers
    sec_sets: Vec<(Vec<u64>, f64)>,
    /// per cell: the indices of the subtour-elimination sets that hold it
    sets_of: Vec<Vec<u32>>,
}

impl Tables {
    /// Σ μ_S over the subtour-elimination sets that the rest of a path must still leave:
    /// those holding the last cell `l` or an unvisited cell (`bits`: the visited set).
    #[inline]
    fn active_mu(&self, bits: &[u64], l: usize) -> f64 {
        let mut sum = 0.0;
        for (set, mu) in &self.sec_sets {
            if set[l / 64] >> (l % 64) & 1 == 1 || set.iter().zip(bits).any(|(s, b)| s & !b != 0) {
                sum += mu;
            }
        }
        sum
    }

    /// Σ μ_S over the sets that hold `l` and lie inside `bits`: a prefix (`bits`, last `l`)
    /// must still leave them, each of its children no longer (they are visited and the child's
    /// last cell lies outside them); every other set keeps its status. So every child of the
    /// prefix has `active_mu` = the prefix's minus this.
    #[inline]
    fn closing_mu(&self, bits: &[u64], l: usize) -> f64 {
        let mut sum = 0.0;
        for &k in &self.sets_of[l] {
            let (set, mu) = &self.sec_sets[k as usize];
            if set.iter().zip(bits).all(|(s, b)| s & !b == 0) {
                sum += mu;
            }
        }
        sum
    }

    /// `μ(i, j)`: Σ multipliers of the sets that the arc i → j leaves (home = n).
    #[inline]
    fn mu(&self, n: usize, i: usize, j: usize) -> f64 {
        arc_mu(&self.mu_arc, n, i, j)
    }
}

/// `μ(i, j)` read from the dense multiplier matrix `mu_arc` (n + 1 columns; empty: all zero).
#[inline]
fn arc_mu(mu_arc: &[f64], n: usize, i: usize, j: usize) -> f64 {
    if mu_arc.is_empty() {
        0.0
    } else {
        mu_arc[i * (n + 1) + j]
    }
}

/// Evaluations charged per generated child (and per refined candidate): a child copies a
/// prefix, computes its bound and probes the dominance map, which takes about as long as 8
/// arc evaluations of the local search (evaluations per second on TSPLIB SOP: beam 2.4–7.6
/// million, ils 17–75 million: 5–16 times as many, about 9 in the median; notes/lab/sopq5.md).
/// So an evaluation budget buys the beam about the wall time it buys the other solvers, and
/// `auto`'s shares of an evaluation budget match its shares of a time budget.
pub const CHILD_EVALS: u64 = 8;

/// Charges `children` generated or refined candidates to the evaluation count.
fn charge(ctx: &mut Context, children: u64) {
    ctx.count(children * CHILD_EVALS);
}

/// Work budget (arc evaluations) of the qpath multipliers' subgradient steps.
const QPATH_WORK: f64 = 4e8;

/// Largest instance for which the root assignment (O(n³)) gives the potentials.
const POTENTIAL_MAX_CELLS: usize = 600;

/// Work budget (d³ per iteration) of the subtour-elimination multipliers' subgradient steps.
const SEC_WORK: f64 = 2e8;

/// `upper`: cost of a known solution (constant included), for the subgradient steps.
fn tables(
    m: &CostModel,
    use_potentials: bool,
    use_sec: bool,
    twins: bool,
    upper: Option<f64>,
) -> Result<Tables> {
    let n = m.n();
    let words = n.div_ceil(64).max(1);
    let cl = Closure::new(&m.dag).ok_or_else(|| Error::Solver {
        solver: "beam".into(),
        msg: "precedence has a cycle".into(),
    })?;
    let g = CellGraph::new(m, &cl);
    let with_potentials = use_potentials && n <= POTENTIAL_MAX_CELLS;
    let sec: Option<SecBound> = (with_potentials && use_sec)
        .then(|| {
            let iters = sec::affordable_iterations(n, SEC_WORK, 1000);
            let upper = upper.map(|x| x - m.constant());
            sec::sec_bound(&g, Some(&cl), upper, iters, 4 * n + 16)
        })
        .flatten()
        .filter(|s| s.u.iter().chain(&s.v).chain(&s.mu).all(|x| x.is_finite()));
    let asg = if sec.is_some() {
        None
    } else {
        with_potentials
            .then(|| assignment::hungarian_duals(g.size(), |i, j| g.c(i, j)))
            .flatten()
            .filter(|a| a.u.iter().chain(&a.v).all(|x| x.is_finite()))
    };
    let (u, v) = match (&sec, &asg) {
        (Some(s), _) => (s.u.clone(), s.v.clone()),
        (None, Some(a)) => (a.u.clone(), a.v.clone()),
        _ => (vec![0.0; n + 1], vec![0.0; n + 1]),
    };
    let mu_arc = sec
        .as_ref()
        .map(|s| s.arc_multipliers(n))
        .unwrap_or_default();
    let sec_sets: Vec<(Vec<u64>, f64)> = sec
        .as_ref()
        .map(|s| {
            s.sets
                .iter()
                .zip(&s.mu)
                .map(|(cells, &mu)| {
                    let mut w = vec![0u64; words];
                    for &c in cells {
                        w[c as usize / 64] |= 1 << (c % 64);
                    }
                    (w, mu)
                })
                .collect()
        })
        .unwrap_or_default();
    let mu = |i: usize, j: usize| arc_mu(&mu_arc, n, i, j);
    let r = |i: usize, j: usize| g.c(i, j) - u[i] - v[j] - mu(i, j);
    let mut pred_mask: Vec<Vec<u64>> = (0..n)
        .map(|c| {
            let mut v = vec![0u64; words];
            for &p in &m.dag.preds[c] {
                v[p as usize / 64] |= 1 << (p % 64);
            }
            v
        })
        .collect();
    if twins && n <= TWIN_MAX_CELLS {
        for (a, b) in twin_order(m, &cl) {
            pred_mask[b][a / 64] |= 1 << (a % 64);
        }
    }
    let fin = |x: f64| if x.is_finite() { x } else { 0.0 };
    let mut node_out = vec![0.0; m.nodes()];
    let mut node_in = vec![0.0; m.nodes()];
    let home_in = fin((0..n).map(|i| r(i, n)).fold(f64::INFINITY, f64::min));
    for (nd, slot) in node_out.iter_mut().enumerate() {
        let (a, ma) = m.cell_mode(nd);
        let mut best = if cl.can_be_last(a) {
            m.finish(a, ma) - u[a] - v[n] - mu(a, n)
        } else {
            f64::INFINITY
        };
        for b in 0..n {
            if cl.arc_allowed(a, b) {
                for mb in 0..m.modes(b) {
                    best = best.min(m.arc(a, ma, b, mb) - u[a] - v[b] - mu(a, b));
                }
            }
        }
        *slot = u[a] + v[n] + fin(best);
        node_in[nd] = u[a] + v[n] + home_in;
    }
    let mut in_list = vec![Vec::new(); n];
    let mut out_list = vec![Vec::new(); n];
    #[allow(clippy::needless_range_loop)]
    for i in 0..n {
        for j in 0..=n {
            if g.c(i, j).is_finite() {
                out_list[i].push((r(i, j), j as u32));
                if j < n {
                    in_list[j].push((r(i, j), i as u32));
                }
            }
        }
    }
    for l in in_list.iter_mut().chain(out_list.iter_mut()) {
        l.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
    let first = |l: &Vec<(f64, u32)>| l.first().map(|e| e.0).unwrap_or(0.0);
    let clusters = if asg.is_some() || sec.is_some() {
        choose_clusters(&g, &r)
    } else {
        Vec::new()
    };
    if super::trace_enabled() {
        eprintln!(
            "beam: assignment {:?}, clusters {:?}",
            asg.as_ref().map(|a| a.value),
            clusters
        );
        if let Some(s) = &sec {
            eprintln!(
                "beam: sec bound {} after {} iterations, {} sets with a multiplier",
                s.value + m.constant(),
                s.iterations,
                s.sets.len()
            );
        }
    }
    let mut cluster = vec![u32::MAX; n];
    for (k, cs) in clusters.iter().enumerate() {
        for &c in cs {
            cluster[c as usize] = k as u32;
        }
    }
    let cell_in: Vec<f64> = (0..n).map(|c| u[c] + v[c] + first(&in_list[c])).collect();
    let cell_out: Vec<f64> = (0..n).map(|c| u[c] + v[c] + first(&out_list[c])).collect();
    let r_home: Vec<f64> = (0..n).map(|i| r(i, n)).collect();
    Ok(Tables {
        total_in: cell_in.iter().sum(),
        total_out: cell_out.iter().sum(),
        cell_in,
        cell_out,
        mu_arc,
        sets_of: (0..n)
            .map(|c| {
                (0..sec_sets.len() as u32)
                    .filter(|&k| sec_sets[k as usize].0[c / 64] >> (c % 64) & 1 == 1)
                    .collect()
            })
            .collect(),
        sec_sets,
        r_home,
        in_list,
        out_list,
        pred_mask,
        node_out,
        node_in,
        u,
        v,
        integral: g.integral() && m.constant().fract() == 0.0,
        cluster,
        clusters,
    })
}

impl Beam {
    fn run<const W: usize>(
        &self,
        ctx: &mut Context,
        incumbent: Option<(f64, Sequence)>,
    ) -> Result<Outcome> {
        let m = ctx.model;
        let n = m.n();
        if n == 0 {
            return Ok(super::outcome_of(m, Vec::new()));
        }
        let mut best: Option<(f64, Sequence)> = match incumbent {
            Some(inc) => Some(inc),
            None => self.warm_start(ctx)?,
        };
        if let Some((c, _)) = &best {
            ctx.report(*c);
        }
        let t = tables(
            m,
            self.potentials,
            self.sec,
            self.twins,
            best.as_ref().map(|b| b.0),
        )?;
        let constant = m.constant();
        // the node bound at the first level (every possible first cell and mode) bounds the
        // optimum: reported as the lower bound when no proof is reached
        let mut root_lb = if self.refine {
            first_level_bound::<W>(m, &t)
        } else {
            f64::NEG_INFINITY
        };
        if !root_lb.is_finite() {
            root_lb = f64::NEG_INFINITY;
        } else if t.integral {
            root_lb = (root_lb - 1e-6).ceil();
        }
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
        let qp = if self.qpath {
            // short runs (e.g. a portfolio phase) get a smaller share: ~10⁸ per second of limit
            let work = match ctx.budget.time_limit {
                Some(t) => QPATH_WORK.min(t.as_secs_f64() * 1e8),
                None => QPATH_WORK,
            };
            let iters = qpath::affordable_iterations(m, work, 1000);
            (iters >= 10)
                .then(|| {
                    let upper = best.as_ref().map(|b| b.0);
                    if t.mu_arc.is_empty() {
                        QPath::new(m, upper, iters)
                    } else {
                        // on the costs net of the subtour-elimination multipliers: a walk no
                        // longer gains by looping inside an expensive-to-leave set
                        let total: f64 = t.sec_sets.iter().map(|s| s.1).sum();
                        let l0 = vec![0.0; n];
                        QPath::shifted(m, upper, iters, Some((&t.mu_arc, total, &l0)))
                    }
                })
                .flatten()
        } else {
            None
        };
        if let Some(q) = &qp {
            let r = if t.integral {
                (q.root - 1e-6).ceil()
            } else {
                q.root
            };
            if super::trace_enabled() {
                eprintln!(
                    "beam: qpath root {} after {} iterations, {:.2}s",
                    q.root,
                    q.iterations,
                    ctx.elapsed()
                );
            }
            root_lb = root_lb.max(r);
        }
        let mut proven = false;
        let prefix_bytes = (std::mem::size_of::<Prefix<W>>() + 24) as u64;
        let grow = |w: usize| {
            // doubling, then faster: a pass that is not truncated stores only what survives
            // the bound, so a wider-than-needed final pass costs little, while every narrower
            // pass is repeated work
            if w < GROWTH_FROM {
                w * 2
            } else {
                w.saturating_mul(self.growth)
            }
        };
        let mut width = 1usize;
        // the bounded width to go on from after the unbounded pass
        let mut resume = None;
        loop {
            let ub = best.as_ref().map(|b| b.0).unwrap_or(f64::INFINITY);
            let unbounded = width == usize::MAX;
            let cap = unbounded.then(|| self.memory_mb.saturating_mul(1 << 20));
            let pass =
                self.iteration::<W>(ctx, &t, qp.as_ref(), width, cut(ub), best.is_some(), cap);
            if let Some((c, seq)) = pass.found
                && best
                    .as_ref()
                    .is_none_or(|b| c < b.0 - 1e-9 * c.abs().max(1.0))
            {
                ctx.report(c);
                best = Some((c, seq));
            }
            if super::trace_enabled() {
                eprintln!(
                    "beam width {}: best {:?} truncated {} aborted {} overflow {} {:.2}s",
                    if unbounded {
                        "unbounded".to_string()
                    } else {
                        width.to_string()
                    },
                    best.as_ref().map(|b| b.0),
                    pass.truncated,
                    pass.aborted,
                    pass.overflow,
                    ctx.elapsed()
                );
            }
            if !pass.aborted && !pass.truncated && best.is_some() {
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
                    qpath_work: 0.0,
                    upper: best.as_ref().map(|b| b.0),
                    ..BoundOptions::default()
                };
                root_lb = root_lb.max(bound::compute(m, &opts).best);
            }
            if let Some((c, _)) = &best
                && root_lb > cut(*c)
            {
                proven = true;
                break;
            }
            if pass.aborted || ctx.exhausted() {
                break;
            }
            let from = match resume {
                Some(w) if unbounded => w,
                _ => width,
            };
            if from >= self.max_width {
                break;
            }
            let next = grow(from);
            // once the bounded passes pass `exhaustive_from`, one unbounded pass (cut by the
            // memory cap): it proves the incumbent optimal as soon as every prefix within
            // the bound fits, without the wider truncated passes in between
            if resume.is_none()
                && !unbounded
                && self.exhaustive_from > 0
                && next > self.exhaustive_from
            {
                resume = Some(width);
                width = usize::MAX;
                continue;
            }
            width = next;
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

    /// A first incumbent from a short, evaluation-bounded `ils` run (deterministic).
    fn warm_start(&self, ctx: &mut Context) -> Result<Option<(f64, Sequence)>> {
        if self.warm_evals == 0 || ctx.model.n() < 3 {
            return Ok(None);
        }
        let budget = Budget {
            max_evals: Some(match ctx.budget.max_evals {
                Some(b) => (b / 4).min(self.warm_evals),
                None => self.warm_evals,
            }),
            time_limit: ctx.budget.time_limit.map(|t| t.mul_f64(0.25)),
        };
        let seed = ctx.seed;
        let out = super::sub_run(ctx, super::Sub::new("ils", budget, seed))?;
        let cost = ctx.model.evaluate(&out.sequence);
        Ok(Some((cost, out.sequence)))
    }

    /// One beam pass of the given width (`usize::MAX`: unbounded, an exhaustive search when
    /// it ends). The pass stops early when the budget is spent (`may_abort`) or when its
    /// stored prefixes would pass `mem_cap` bytes.
    #[allow(clippy::too_many_arguments)]
    fn iteration<const W: usize>(
        &self,
        ctx: &mut Context,
        t: &Tables,
        qp: Option<&QPath>,
        width: usize,
        cut: f64,
        may_abort: bool,
        mem_cap: Option<u64>,
    ) -> Pass {
        let m = ctx.model;
        let n = m.n();
        // `cells`: the prefix's number of cells
        // `act`: Σ μ_S over the sets the rest must still leave (`Tables::active_mu`)
        let bound = |p: &Prefix<W>, cells: usize| {
            let act = p.act;
            let h_in = p.rem_in + t.node_in[p.node as usize];
            let h_out = p.rem_out + t.node_out[p.node as usize];
            let h = match qp {
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
        };
        let lam = |c: usize| qp.map_or(0.0, |q| q.lambda(c));
        let lam_total = qp.map_or(0.0, |q| q.lambda_total());
        let mut scratch = vec![(0.0, 0.0); n + t.clusters.len()];
        // completed levels, compact: (parent index, node) per prefix
        let mut trail: Vec<Vec<(u32, u32)>> = Vec::with_capacity(n);
        let mut stored = 0u64;
        let prefix_bytes = std::mem::size_of::<Prefix<W>>() as u64;
        let entry_bytes = std::mem::size_of::<(([u64; W], u32), u32)>() as u64 + 8;
        let mut truncated = false;
        let overflow = |stored: u64, live: usize, map: usize| {
            mem_cap.is_some_and(|cap| {
                stored * 8 + live as u64 * prefix_bytes + map as u64 * entry_bytes > cap
            })
        };
        // level 1: every cell that may come first, in every mode
        let mut cands: Vec<Prefix<W>> = first_prefixes(m, t, lam_total, lam);
        for p in cands.iter_mut() {
            p.f = bound(p, 1);
        }
        cands.retain(|p| p.f <= cut);
        charge(ctx, cands.len() as u64);
        if self.refine {
            for c in cands.iter_mut() {
                c.f = c.f.max(refined(m, t, c, &mut scratch));
            }
        }
        if width == 1 && super::trace_enabled() {
            let lb = cands.iter().map(|c| c.f).fold(f64::INFINITY, f64::min);
            eprintln!("beam: first-level bound {lb}");
        }
        truncated |= keep_best(&mut cands, width, self.by_cost);
        let mut prev = cands;
        trail.push(prev.iter().map(|p| (p.parent, p.node)).collect());
        stored += prev.len() as u64;
        let mut index: FxHashMap<([u64; W], u32), u32> = FxHashMap::default();
        for k in 1..n {
            if prev.is_empty() {
                break;
            }
            let mut cands: Vec<Prefix<W>> = Vec::with_capacity(prev.len() * 2);
            let mut evals = 0u64;
            // children grouped by their new cell, so the dominance map holds one cell's
            // children at a time: small enough to stay in cache (on p43.2 a whole level's map
            // had millions of entries and its cache misses took ~40 % of the time)
            let mut acts: Vec<f64> = Vec::with_capacity(prev.len());
            let mut by_cell: Vec<Vec<u32>> = vec![Vec::new(); n];
            let mut listed = 0usize;
            for (pi, p) in prev.iter().enumerate() {
                let a = m.cell_mode(p.node as usize).0;
                // every child leaves the same sets: the parent's, less those that `a` closes
                acts.push(p.act - t.closing_mu(&p.bits, a));
                for (v, list) in by_cell.iter_mut().enumerate() {
                    if p.bits[v / 64] >> (v % 64) & 1 == 1 {
                        continue;
                    }
                    let ready = t.pred_mask[v]
                        .iter()
                        .zip(p.bits.iter())
                        .all(|(need, have)| need & !have == 0);
                    if ready {
                        list.push(pi as u32);
                        listed += 1;
                    }
                }
            }
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
                        if may_abort && ctx.exhausted() {
                            return Pass::aborted();
                        }
                        if overflow(stored + lists, prev.len() + cands.len(), index.len()) {
                            charge(ctx, evals);
                            return Pass::overflow();
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
                            lam_open: p.lam_open - lam(v),
                            act,
                            f: 0.0,
                        };
                        c.f = bound(&c, k + 1);
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
            drop(by_cell);
            charge(ctx, evals);
            // refinement pays only where it prunes: each level refines a first sample of
            // candidates and goes on only when it pruned at least a quarter of them (on
            // p43.2 it prunes ~4 % of the candidates and took 76 % of the time)
            let mut sample = Sample::default();
            if self.refine && cands.len() > width && !self.by_cost {
                // refine lazily in order of the incremental bound until more than `width`
                // survive: the rest is discarded (and the level counts as truncated)
                cands.sort_unstable_by(rank);
                let mut kept = Vec::with_capacity(width + 1);
                for mut c in cands.drain(..) {
                    if sample.on() {
                        if may_abort && sample.done % 4096 == 4095 && ctx.exhausted() {
                            return Pass::aborted();
                        }
                        c.f = c.f.max(refined(m, t, &c, &mut scratch));
                        if !sample.record(c.f <= cut) {
                            continue;
                        }
                    }
                    kept.push(c);
                    if kept.len() > width {
                        break;
                    }
                }
                charge(ctx, sample.done);
                cands = kept;
            } else if self.refine {
                cands.retain_mut(|c| {
                    if !sample.on() {
                        return true;
                    }
                    c.f = c.f.max(refined(m, t, c, &mut scratch));
                    sample.record(c.f <= cut)
                });
                charge(ctx, sample.done);
            }
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
            if overflow(stored, prev.len(), 0) {
                return Pass::overflow();
            }
        }
        if super::trace_enabled() {
            let sizes: Vec<usize> = trail.iter().map(|l| l.len()).collect();
            eprintln!("beam: level sizes {sizes:?}");
            eprintln!(
                "beam: width {width} stored {} largest level {}",
                sizes.iter().sum::<usize>(),
                sizes.iter().max().unwrap_or(&0)
            );
        }
        // complete sequences
        let done = Pass {
            found: None,
            truncated,
            aborted: false,
            overflow: false,
        };
        if trail.len() < n {
            return done;
        }
        let mut best: Option<(f64, usize)> = None;
        for (i, p) in prev.iter().enumerate() {
            let (c, md) = m.cell_mode(p.node as usize);
            let total = p.g + m.finish(c, md);
            if total <= cut && best.is_none_or(|b| total < b.0) {
                best = Some((total, i));
            }
        }
        let Some((_, mut i)) = best else {
            return done;
        };
        let mut seq = Vec::with_capacity(n);
        for lvl in trail.iter().rev() {
            let (parent, node) = lvl[i];
            let (c, md) = m.cell_mode(node as usize);
            seq.push(Visit::new(c, md));
            i = parent as usize;
        }
        seq.reverse();
        let cost = m.evaluate(&seq);
        Pass {
            found: Some((cost, seq)),
            ..done
        }
    }
}

/// Candidates refined at the start of a level before deciding whether refinement goes on.
const REFINE_SAMPLE: u64 = 1024;

/// Counts of the refined candidates of one level: refinement stops for the rest of the
/// level when fewer than a quarter of the first [`REFINE_SAMPLE`] were pruned.
#[derive(Default)]
struct Sample {
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
struct Pass {
    /// the best complete sequence found (cost, sequence)
    found: Option<(f64, Sequence)>,
    /// some candidate was discarded because of the width
    truncated: bool,
    /// the budget stopped the pass
    aborted: bool,
    /// an unbounded pass stopped at its memory cap
    overflow: bool,
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

/// Largest instance searched for interchangeable cells (O(n² · n · modes²)).
const TWIN_MAX_CELLS: usize = 300;

/// Whether cells `a` and `b` are *cost twins*: neither precedes the other, same modes, same
/// start and finish costs, `arc(a, i, b, j) = arc(b, i, a, j)`, and the same arc costs to and
/// from every other cell (mode by mode) wherever the precedence closure allows both arcs.
/// Exchanging `a` and `b` (with their modes) in a feasible sequence whose exchanged version is
/// feasible too keeps its cost: every arc of a feasible sequence is allowed by the closure, so
/// every arc that changes is one compared here.
fn cost_twins(m: &CostModel, cl: &Closure, a: usize, b: usize) -> bool {
    let k = m.modes(a);
    if k != m.modes(b) || cl.before(a, b) || cl.before(b, a) {
        return false;
    }
    for i in 0..k {
        if m.start(a, i) != m.start(b, i) || m.finish(a, i) != m.finish(b, i) {
            return false;
        }
        for j in 0..k {
            if m.arc(a, i, b, j) != m.arc(b, i, a, j) {
                return false;
            }
        }
    }
    for c in 0..m.n() {
        if c == a || c == b {
            continue;
        }
        let out = cl.arc_allowed(a, c) && cl.arc_allowed(b, c);
        let inn = cl.arc_allowed(c, a) && cl.arc_allowed(c, b);
        for i in 0..k {
            for j in 0..m.modes(c) {
                if (out && m.arc(a, i, c, j) != m.arc(b, i, c, j))
                    || (inn && m.arc(c, j, a, i) != m.arc(c, j, b, i))
                {
                    return false;
                }
            }
        }
    }
    true
}

/// Whether `a` may lead `b`: every ancestor of `a` is an ancestor of `b`, and every
/// descendant of `b` is a descendant of `a` (neither precedes the other). Then in a feasible
/// sequence with `b` before `a`, exchanging them keeps it feasible: `a` moves earlier but
/// still after all of its ancestors, `b` moves later but still before all of its descendants.
fn may_lead(cl: &Closure, a: usize, b: usize) -> bool {
    (0..cl.n()).all(|c| {
        c == a
            || c == b
            || ((!cl.before(c, a) || cl.before(c, b)) && (!cl.before(b, c) || cl.before(a, c)))
    })
}

/// Symmetry breaking: pairs `(a, b)` of cost twins (`cost_twins`: copies of each other apart
/// from the precedence) where `a` may lead `b` (`may_lead`; when each may lead the other,
/// the smaller index leads). Any optimum can be turned into one where `a` comes before `b`
/// for every pair: exchange an inverted pair while there is one; each exchange keeps
/// feasibility and cost and lowers the number of inversions against a linear extension of
/// the strict order "leads, then index", so the exchanges end. Cells with the same precedence
/// (e.g. 1–3 of p43.1) are ordered by index; p43.2's cells 5 and 6 too (6 has one more
/// predecessor). Empty when the precedence has a cycle.
pub fn interchangeable_order(m: &CostModel) -> Vec<(usize, usize)> {
    Closure::new(&m.dag)
        .map(|cl| twin_order(m, &cl))
        .unwrap_or_default()
}

fn twin_order(m: &CostModel, cl: &Closure) -> Vec<(usize, usize)> {
    let n = m.n();
    let mut out = Vec::new();
    for a in 0..n {
        for b in a + 1..n {
            if !cost_twins(m, cl, a, b) {
                continue;
            }
            if may_lead(cl, a, b) {
                out.push((a, b));
            } else if may_lead(cl, b, a) {
                out.push((b, a));
            }
        }
    }
    out
}

/// Disjoint clusters of cells for the bound: subtours of the assignment relaxation, found
/// hierarchically (contract every subtour that avoids home into one group, solve the
/// assignment on the groups again, repeat), then the laminar family is cut so that the root
/// surcharge (Σ of entering + leaving surcharges, reduced costs `r`) is largest: each cluster
/// is kept whole or replaced by its best sub-family.
fn choose_clusters(g: &CellGraph, r: &dyn Fn(usize, usize) -> f64) -> Vec<Vec<u32>> {
    let n = g.n;
    // tree of clusters: cells and children
    let mut tree: Vec<(Vec<u32>, Vec<usize>)> = Vec::new();
    // current groups: cells (home = n) and tree node
    let mut groups: Vec<(Vec<u32>, Option<usize>)> =
        (0..=n).map(|c| (vec![c as u32], None)).collect();
    for _round in 0..16 {
        let k = groups.len();
        if k <= 2 {
            break;
        }
        let mut cost = vec![f64::INFINITY; k * k];
        for a in 0..k {
            for b in 0..k {
                if a == b {
                    continue;
                }
                let mut best = f64::INFINITY;
                for &x in &groups[a].0 {
                    for &y in &groups[b].0 {
                        best = best.min(g.c(x as usize, y as usize));
                    }
                }
                cost[a * k + b] = best;
            }
        }
        let Some(asg) = assignment::hungarian(k, |a, b| cost[a * k + b]) else {
            break;
        };
        let home = groups.iter().position(|gr| gr.0.contains(&(n as u32)));
        let mut seen = vec![false; k];
        let mut next: Vec<(Vec<u32>, Option<usize>)> = Vec::new();
        let mut merged = false;
        for s0 in 0..k {
            if seen[s0] {
                continue;
            }
            let mut cyc = Vec::new();
            let mut x = s0;
            while !seen[x] {
                seen[x] = true;
                cyc.push(x);
                x = asg.1[x];
            }
            if cyc.len() >= 2 && !cyc.iter().any(|&x| Some(x) == home) {
                let cells: Vec<u32> = cyc.iter().flat_map(|&x| groups[x].0.clone()).collect();
                let children: Vec<usize> = cyc.iter().filter_map(|&x| groups[x].1).collect();
                tree.push((cells.clone(), children));
                next.push((cells, Some(tree.len() - 1)));
                merged = true;
            } else {
                next.extend(cyc.iter().map(|&x| groups[x].clone()));
            }
        }
        groups = next;
        if !merged {
            break;
        }
    }
    // root surcharge of each cluster
    let d = n + 1;
    let mut min_in = vec![f64::INFINITY; n];
    let mut min_out = vec![f64::INFINITY; n];
    for i in 0..d {
        for j in 0..d {
            let c = r(i, j);
            if g.c(i, j).is_finite() {
                if j < n {
                    min_in[j] = min_in[j].min(c);
                }
                if i < n {
                    min_out[i] = min_out[i].min(c);
                }
            }
        }
    }
    let mut inside = vec![false; d];
    let surcharge = |cells: &[u32], inside: &mut Vec<bool>| {
        for &c in cells {
            inside[c as usize] = true;
        }
        let mut d_in = f64::INFINITY;
        let mut d_out = f64::INFINITY;
        for &j in cells {
            let j = j as usize;
            for i in 0..d {
                if !inside[i] && g.c(i, j).is_finite() {
                    d_in = d_in.min(r(i, j) - min_in[j]);
                }
                if !inside[i] && g.c(j, i).is_finite() {
                    d_out = d_out.min(r(j, i) - min_out[j]);
                }
            }
        }
        for &c in cells {
            inside[c as usize] = false;
        }
        let f = |x: f64| if x.is_finite() { x.max(0.0) } else { 0.0 };
        f(d_in) + f(d_out)
    };
    // children come before parents in `tree`
    let mut val = vec![0.0; tree.len()];
    let mut whole = vec![false; tree.len()];
    for t in 0..tree.len() {
        let own = surcharge(&tree[t].0, &mut inside);
        let sub: f64 = tree[t].1.iter().map(|&c| val[c]).sum();
        whole[t] = own >= sub && own > 0.0;
        val[t] = own.max(sub);
    }
    let mut out = Vec::new();
    let mut stack: Vec<usize> = groups.iter().filter_map(|gr| gr.1).collect();
    while let Some(t) = stack.pop() {
        if whole[t] {
            out.push(tree[t].0.clone());
        } else {
            stack.extend(tree[t].1.iter().copied());
        }
    }
    out.sort();
    out
}

/// The dynamic bound of a prefix, in reduced costs (see [`Tables`]): every unvisited cell is
/// entered from an unvisited cell or the last one, and left to an unvisited cell or home; the
/// last node is left to an unvisited cell; and every root-assignment cluster's unvisited part
/// must be entered from outside it and left to outside it at least once, which adds the
/// cheapest surcharge of doing so over its members' own cheapest arcs.
/// O(|unvisited| · scan) with the sorted arc lists; `scratch` holds n + clusters entries.
fn refined<const W: usize>(
    m: &CostModel,
    t: &Tables,
    p: &Prefix<W>,
    scratch: &mut [(f64, f64)],
) -> f64 {
    let n = m.n();
    let open = |c: usize| c < n && p.bits[c / 64] >> (c % 64) & 1 == 0;
    let (l, lm) = m.cell_mode(p.node as usize);
    let mut pot = t.u[l] + t.v[n];
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
        pot += t.u[j] + t.v[j];
        let Some(i) = t.in_list[j]
            .iter()
            .find(|&&(_, i)| open(i as usize) || i as usize == l)
            .map(|e| e.0)
        else {
            return f64::INFINITY;
        };
        h_in += i;
        let Some(o) = t.out_list[j]
            .iter()
            .find(|&&(_, k)| open(k as usize) || k as usize == n)
            .map(|e| e.0)
        else {
            return f64::INFINITY;
        };
        h_out += o;
        scratch[j] = (i, o);
        home_in = home_in.min(t.r_home[j]);
        let mu = t.mu(n, l, j);
        for mj in 0..m.modes(j) {
            last_out = last_out.min(m.arc(l, lm, j, mj) - t.u[l] - t.v[j] - mu);
        }
    }
    if !any {
        return p.g + m.finish(l, lm);
    }
    if !last_out.is_finite() {
        return f64::INFINITY;
    }
    let home_in = if home_in.is_finite() { home_in } else { 0.0 };
    let nc = t.clusters.len();
    let (io, dd) = scratch.split_at_mut(n);
    // pass 1: entering / leaving surcharge of each cluster's open part
    let mut any_cluster = false;
    for (s, cells) in t.clusters.iter().enumerate() {
        let s = s as u32;
        let mut d_in = f64::INFINITY;
        let mut d_out = f64::INFINITY;
        let mut touched = false;
        for &j in cells {
            let j = j as usize;
            if !open(j) {
                continue;
            }
            touched = true;
            let (i0, o0) = io[j];
            if let Some(&(c, _)) = t.in_list[j].iter().find(|&&(_, i)| {
                let i = i as usize;
                i == l || (open(i) && t.cluster[i] != s)
            }) {
                d_in = d_in.min(c - i0);
            }
            if let Some(&(c, _)) = t.out_list[j].iter().find(|&&(_, k)| {
                let k = k as usize;
                k == n || (open(k) && t.cluster[k] != s)
            }) {
                d_out = d_out.min(c - o0);
            }
        }
        if !touched {
            dd[s as usize] = (f64::NAN, f64::NAN);
            continue;
        }
        if !d_in.is_finite() || !d_out.is_finite() {
            return f64::INFINITY;
        }
        any_cluster = true;
        dd[s as usize] = (d_in.max(0.0), d_out.max(0.0));
        h_in += d_in.max(0.0);
        h_out += d_out.max(0.0);
    }
    if any_cluster {
        // pass 2: a cluster's leaving arc enters some cell k (or home); in the in-degree sum
        // it costs at least min_in(k) plus, when k's cluster is entered by it, that cluster's
        // entering surcharge: the rest is an extra surcharge on top (and symmetrically for
        // entering arcs in the out-degree sum). Each arc is charged at most one entering and
        // one leaving surcharge, so the sums stay valid.
        let open_d = |k: usize| -> (f64, f64) {
            let c = t.cluster[k];
            if c == u32::MAX || dd[c as usize].0.is_nan() {
                (0.0, 0.0)
            } else {
                dd[c as usize]
            }
        };
        let mut max_in = home_in;
        let mut max_out = last_out;
        for j in 0..n {
            if open(j) {
                let d = open_d(j);
                max_in = max_in.max(io[j].0 + d.0);
                max_out = max_out.max(io[j].1 + d.1);
            }
        }
        for (s, cells) in t.clusters.iter().enumerate() {
            if dd[s].0.is_nan() {
                continue;
            }
            let s = s as u32;
            let mut e_out = f64::INFINITY;
            let mut e_in = f64::INFINITY;
            for &j in cells {
                let j = j as usize;
                if !open(j) {
                    continue;
                }
                for &(c, k) in &t.out_list[j] {
                    if c - max_in >= e_out {
                        break;
                    }
                    let k = k as usize;
                    let base = if k == n {
                        home_in
                    } else if open(k) && t.cluster[k] != s {
                        io[k].0 + open_d(k).0
                    } else {
                        continue;
                    };
                    e_out = e_out.min(c - base);
                }
                for &(c, i) in &t.in_list[j] {
                    if c - max_out >= e_in {
                        break;
                    }
                    let i = i as usize;
                    let base = if i == l {
                        last_out
                    } else if open(i) && t.cluster[i] != s {
                        io[i].1 + open_d(i).1
                    } else {
                        continue;
                    };
                    e_in = e_in.min(c - base);
                }
            }
            if e_out.is_finite() {
                h_in += e_out.max(0.0);
            }
            if e_in.is_finite() {
                h_out += e_in.max(0.0);
            }
        }
    }
    let _ = nc;
    // every set holding the last cell or an unvisited one must still be left
    pot += t.active_mu(&p.bits, l);
    p.g + pot + (h_in + home_in).max(h_out + last_out)
}

/// The node bound (`refined`: potentials, subtour-elimination multipliers, degree sums and
/// cluster surcharges) of every prefix of `seq`, in order, with the tables built as the beam
/// builds them (`upper`: a known solution cost for the subgradient steps; no symmetry
/// breaking). For tests: along an optimal sequence every value is at most the optimum.
pub fn prefix_bounds(m: &CostModel, seq: &[Visit], upper: Option<f64>) -> Result<Vec<f64>> {
    fn go<const W: usize>(m: &CostModel, seq: &[Visit], upper: Option<f64>) -> Result<Vec<f64>> {
        let t = tables(m, true, true, false, upper)?;
        let mut scratch = vec![(0.0, 0.0); m.n() + t.clusters.len()];
        let mut out = Vec::with_capacity(seq.len());
        let Some(v0) = seq.first() else {
            return Ok(out);
        };
        let mut p = Prefix::<W>::first(m, &t, v0.cell, v0.mode, 0.0);
        out.push(refined(m, &t, &p, &mut scratch));
        for w in seq.windows(2) {
            let (a, b) = (w[0], w[1]);
            p.bits[b.cell / 64] |= 1 << (b.cell % 64);
            p.node = m.node(b.cell, b.mode) as u32;
            p.g += m.arc(a.cell, a.mode, b.cell, b.mode);
            out.push(refined(m, &t, &p, &mut scratch));
        }
        Ok(out)
    }
    match m.n().div_ceil(64) {
        0 | 1 => go::<1>(m, seq, upper),
        2 => go::<2>(m, seq, upper),
        3 | 4 => go::<4>(m, seq, upper),
        5..=8 => go::<8>(m, seq, upper),
        9..=16 => go::<16>(m, seq, upper),
        _ => Err(Error::Solver {
            solver: "beam".into(),
            msg: format!(
                "instance has {} cells; beam accepts at most {MAX_CELLS}",
                m.n()
            ),
        }),
    }
}

/// The smallest refined bound over all one-cell prefixes: a lower bound on the optimum.
fn first_level_bound<const W: usize>(m: &CostModel, t: &Tables) -> f64 {
    let n = m.n();
    let mut scratch = vec![(0.0, 0.0); n + t.clusters.len()];
    first_prefixes::<W>(m, t, 0.0, |_| 0.0)
        .iter()
        .map(|p| refined(m, t, p, &mut scratch))
        .fold(f64::INFINITY, f64::min)
}

/// Order by bound, then cost, last node and visited set (a total order on distinct prefixes).
fn rank<const W: usize>(a: &Prefix<W>, b: &Prefix<W>) -> std::cmp::Ordering {
    a.f.total_cmp(&b.f)
        .then(a.g.total_cmp(&b.g))
        .then(a.node.cmp(&b.node))
        .then(a.bits.cmp(&b.bits))
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

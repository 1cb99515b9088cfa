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

mod clusters;
mod pass;
mod prefix;
mod refine;
mod tables;
mod twins;

#[cfg(any(test, feature = "internals"))]
pub use refine::prefix_bounds;
#[cfg(any(test, feature = "internals"))]
pub use twins::interchangeable_order;

use super::Build;
use super::WarmStart;
use super::{Budget, Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::bound::qpath::{self, QPath};
use crate::bound::{self, BoundOptions};
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::model::Sequence;
use prefix::Prefix;
use refine::first_level_bound;
use tables::{Tables, tables};

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "beam",
    summary: "iterative beam search with prefix dominance and bound pruning; proves optimality \
              when a beam is wide enough",
    description: "The exact/anytime tree search, and the one that proves optimality on instances too large \
for `exact`.

- A short deterministic `ils` run (`warm_evals`) gives the incumbent.
- Iterative beam search over the precedence fringe: prefixes with the same visited set and \
last (cell, mode) are merged (prefix dominance), interchangeable cells are visited in index \
order (`twins`), and every prefix whose lower bound cannot beat the incumbent is pruned.
- Node bounds: the `sec` relaxation (assignment with Lagrangian subtour-elimination \
multipliers sharpened by precedence: each prefix is charged the prices of the sets it must \
still leave; `sec=false` falls back to the plain assignment duals), cluster bounds, and the \
`qpath` bound (a position-indexed path relaxation priced by Lagrange multipliers; \
`qpath=false` turns it off).
- Widths double per pass and grow ×`growth` from 1024; after the pass of width \
`exhaustive_from`, one pass without a width limit, stopped only by `memory_mb`.
- A pass that never had to drop a prefix for its width was exhaustive: the result is then \
reported as proven optimal. Within 60 s this proves ESC07–ESC63, br17.*, rbg048a, rbg050c, \
rbg109a, prob.42, p43.1–p43.4, ft53.4 and ry48p.4 (p43.2 the slowest, at about 55 s). \
`CELLSEQ_TRACE=1` prints each pass. Design: [notes/bounds.md](../notes/bounds.md).",
    params: &[
        ParamSpec {
            name: "max_width",
            default: "1048576",
            kind: ParamKind::int(1, 1_000_000_000),
            help: "stop doubling the beam width after this width",
        },
        ParamSpec {
            name: "memory_mb",
            default: "2048",
            kind: ParamKind::int(0, crate::params::MAX_MEMORY_MB),
            help: "do not start an iteration whose stored prefixes could pass this many MiB \
                   (0: none that stores prefixes; the exhaustive pass stops at once)",
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
            kind: ParamKind::int(2, 1024),
            help: "factor by which the beam width grows from width 1024 on (doubling before)",
        },
        ParamSpec {
            name: "exhaustive_from",
            default: "16384",
            kind: ParamKind::int(0, 1_000_000_000),
            help: "after the pass of this width, one pass without a width limit (stopped at \
                   memory_mb) before wider truncated passes; 0 = never",
        },
        ParamSpec {
            name: "soft",
            default: "1",
            kind: ParamKind::float(0.01, 1.0),
            help: "the passes run within this share of the budget (time and evaluations) \
                   except the widest bounded one (the last before the unbounded pass: width \
                   exhaustive_from when the widths reach it), which may use the whole budget \
                   when the pass before it, scaled by the width ratio, predicts that it ends in \
                   time; the warm start and the bounds are sized by the whole budget (1: every \
                   pass has the whole budget)",
        },
        ParamSpec {
            name: "warm_evals",
            default: "2000000",
            kind: ParamKind::int(0, 1_000_000_000_000),
            help: "evaluations of an `ils` run that gives the first incumbent (0 = none)",
        },
    ],
    caps: Caps {
        exact: true,
        ..Caps::NONE
    },
    build: Build::WarmStart(|p: &Params| Ok(Box::new(from_params(p)))),
};

/// Builds the solver from validated parameters.
pub fn from_params(p: &Params) -> Beam {
    Beam {
        max_width: p.int("max_width") as usize,
        memory_mb: p.int("memory_mb"),
        root_bound: p.bool("root_bound"),
        refine: p.bool("refine"),
        by_cost: p.word("guide") == "cost",
        potentials: p.bool("potentials"),
        warm_evals: p.int("warm_evals"),
        qpath: p.bool("qpath"),
        sec: p.bool("sec"),
        growth: p.int("growth") as usize,
        twins: p.bool("twins"),
        exhaustive_from: p.int("exhaustive_from") as usize,
        soft: p.float("soft"),
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
    /// Share of the budget the passes run within, but the widest bounded one (the last before
    /// the unbounded pass) when it is predicted to fit in the whole budget (the warm start and
    /// the bounds are sized by the whole budget).
    pub soft: f64,
}

/// Width from which the beam grows by the `growth` factor instead of doubling.
const GROWTH_FROM: usize = 1024;

/// Largest instance accepted (visited sets are fixed-size bitsets).
pub const MAX_CELLS: usize = 1024;

impl Solver for Beam {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        self.search_from(ctx, None)
    }
}

impl WarmStart for Beam {
    fn warm_start(&self, ctx: &mut Context, start: &Sequence) -> Result<Outcome> {
        self.search_from(ctx, Some(start.clone()))
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

/// The outcome when the clock ran out before the search could start: the incumbent, if any.
fn incumbent_only(m: &CostModel, best: Option<(f64, Sequence)>) -> Result<Outcome> {
    let (cost, sequence) = best.ok_or_else(|| Error::Solver {
        solver: "beam".into(),
        msg: "no feasible sequence found before the time limit".into(),
    })?;
    Ok(Outcome {
        sequence,
        cost,
        proven_optimal: false,
        lower_bound: Some(m.constant()),
    })
}

/// Work budget (arc evaluations) of the qpath multipliers' subgradient steps.
const QPATH_WORK: f64 = 4e8;

/// The pruning threshold for an incumbent of cost `ub`: a bound above it cannot beat `ub`
/// strictly (`integral`: every cost is an integer).
fn cut(ub: f64, integral: bool) -> f64 {
    if !ub.is_finite() {
        f64::INFINITY
    } else if integral {
        ub - 1.0 + 1e-6
    } else {
        ub - 1e-9 * ub.abs().max(1.0)
    }
}

/// The position-indexed path relaxation for the prefix bound (on the costs net of the
/// subtour-elimination multipliers when there are some), or `None` when too few subgradient
/// steps are affordable. `upper`: a known solution cost.
fn qpath_relaxation(ctx: &Context, t: &Tables, upper: Option<f64>) -> Option<QPath> {
    let m = ctx.model;
    // short runs (e.g. a portfolio phase) get a smaller share: ~10⁸ per second of limit
    let work = match ctx.budget.time_limit {
        Some(t) => QPATH_WORK.min(t.as_secs_f64() * 1e8),
        None => QPATH_WORK,
    };
    let iters = qpath::affordable_iterations(m, work, 1000);
    (iters >= 10)
        .then(|| {
            if t.mu_arc.is_empty() {
                QPath::shifted(m, upper, iters, None, ctx.deadline())
            } else {
                // on the costs net of the subtour-elimination multipliers: a walk no
                // longer gains by looping inside an expensive-to-leave set
                let total: f64 = t.sec_sets.iter().map(|s| s.1).sum();
                let l0 = vec![0.0; m.n()];
                QPath::shifted(
                    m,
                    upper,
                    iters,
                    Some((&t.mu_arc, total, &l0)),
                    ctx.deadline(),
                )
            }
        })
        .flatten()
}

impl Beam {
    fn run<const W: usize>(
        &self,
        ctx: &mut Context,
        incumbent: Option<(f64, Sequence)>,
    ) -> Result<Outcome> {
        let m = ctx.model;
        if m.n() == 0 {
            return Ok(super::outcome_of(m, Vec::new()));
        }
        let mut best: Option<(f64, Sequence)> = match incumbent {
            Some(inc) => Some(inc),
            None => self.warm_start(ctx)?,
        };
        if let Some((c, _)) = &best {
            ctx.report(*c);
        }
        let built = tables(
            m,
            self.potentials,
            self.sec,
            self.twins,
            best.as_ref().map(|b| b.0),
            ctx.deadline(),
        )?;
        let Some(t) = built else {
            // the clock ran out while the bound's tables were built: the incumbent stands
            return incumbent_only(m, best);
        };
        let mut root_lb = self.first_level_lb::<W>(m, &t);
        let qp = if self.qpath {
            qpath_relaxation(ctx, &t, best.as_ref().map(|b| b.0))
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
        // the warm start and the bounds above are sized by the whole budget; the passes by
        // the soft share of it, but for the widest (`Beam::soft`)
        let full = ctx.budget;
        if self.soft < 1.0 {
            ctx.budget = full.scaled(self.soft);
        }
        let proven = self.widen::<W>(ctx, (&t, qp.as_ref()), full, &mut best, &mut root_lb);
        ctx.budget = full;
        let (cost, sequence) = best.ok_or_else(|| Error::Solver {
            solver: "beam".into(),
            msg: "no feasible sequence found".into(),
        })?;
        Ok(Outcome {
            sequence,
            cost,
            proven_optimal: proven,
            lower_bound: Some(if proven {
                cost
            } else {
                root_lb.max(m.constant())
            }),
        })
    }

    /// The node bound at the first level (every possible first cell and mode): it bounds the
    /// optimum, and is reported as the lower bound when no proof is reached.
    fn first_level_lb<const W: usize>(&self, m: &CostModel, t: &Tables) -> f64 {
        let lb = if self.refine {
            first_level_bound::<W>(m, t)
        } else {
            f64::NEG_INFINITY
        };
        if !lb.is_finite() {
            f64::NEG_INFINITY
        } else if t.integral {
            (lb - 1e-6).ceil()
        } else {
            lb
        }
    }

    /// Beam passes of growing width from width 1, until one proves the incumbent optimal (it
    /// ends without truncation, or `root_lb` meets the incumbent) or the budget, `max_width`
    /// or `memory_mb` stops them. Returns whether the incumbent is proven optimal; `best` is
    /// the incumbent, `root_lb` rises with the Lagrangian root bound after the first pass.
    /// With [`Beam::soft`] below 1, `ctx.budget` is the soft share of `full`, and only the
    /// widest bounded pass (the one the unbounded pass follows: width
    /// [`Beam::exhaustive_from`] when that is a width of the ladder) may run under `full`.
    fn widen<const W: usize>(
        &self,
        ctx: &mut Context,
        (t, qp): (&Tables, Option<&QPath>),
        full: Budget,
        best: &mut Option<(f64, Sequence)>,
        root_lb: &mut f64,
    ) -> bool {
        let m = ctx.model;
        let soft = ctx.budget;
        let mut width = 1usize;
        // the bounded width to go on from after the unbounded pass
        let mut resume = None;
        loop {
            let ub = best.as_ref().map(|b| b.0).unwrap_or(f64::INFINITY);
            let unbounded = width == usize::MAX;
            let (t0, e0) = (ctx.elapsed(), ctx.evaluations());
            let cap = unbounded.then(|| self.memory_mb.saturating_mul(1 << 20));
            let pass =
                self.iteration::<W>(ctx, t, qp, width, cut(ub, t.integral), best.is_some(), cap);
            let spent = (ctx.elapsed() - t0, ctx.evaluations() - e0);
            if let Some((c, seq)) = pass.found
                && best
                    .as_ref()
                    .is_none_or(|b| c < b.0 - 1e-9 * c.abs().max(1.0))
            {
                ctx.report(c);
                *best = Some((c, seq));
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
                return true;
            }
            // the Lagrangian root bound costs O(iterations · n²) arc evaluations: worth it on
            // matrix instances and small geometric ones, not when the budget is already spent
            let bound_affordable = !m.is_geometric() || m.n() <= 100;
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
                    deadline: ctx.deadline(),
                    ..BoundOptions::default()
                };
                *root_lb = root_lb.max(bound::compute(m, &opts).best);
            }
            if let Some((c, _)) = best
                && *root_lb > cut(*c, t.integral)
            {
                return true;
            }
            if pass.aborted || ctx.exhausted() {
                return false;
            }
            let next = match self.next_width::<W>(width, &mut resume, m.n()) {
                Some(w) => w,
                None => return false,
            };
            if self.soft < 1.0 {
                // the widest bounded pass: the one the unbounded pass follows (so both it and
                // the pass before it are bounded); its work is predicted from that pass's by
                // the width ratio (a pass's work grows about linearly in its width)
                let mut after = resume;
                let widest = next != usize::MAX
                    && self.next_width::<W>(next, &mut after, m.n()) == Some(usize::MAX)
                    && fits(ctx, full, spent, next as f64 / width as f64);
                ctx.budget = if widest { full } else { soft };
                if ctx.exhausted() {
                    return false;
                }
            }
            width = next;
        }
    }

    /// The width of the pass after one of `width` (`usize::MAX`: unbounded), or `None` when
    /// `max_width` or `memory_mb` says stop. Doubling, then growing by `growth` from
    /// [`GROWTH_FROM`]: a pass that is not truncated stores only what survives the bound, so a
    /// wider-than-needed final pass costs little, while every narrower pass is repeated work.
    /// Once the bounded widths pass `exhaustive_from`, one unbounded pass (cut by the memory
    /// cap) comes first: it proves the incumbent optimal as soon as every prefix within the
    /// bound fits, without the wider truncated passes in between; `resume` keeps the bounded
    /// width to go on from after it.
    fn next_width<const W: usize>(
        &self,
        width: usize,
        resume: &mut Option<usize>,
        n: usize,
    ) -> Option<usize> {
        let unbounded = width == usize::MAX;
        let from = match *resume {
            Some(w) if unbounded => w,
            _ => width,
        };
        if from >= self.max_width {
            return None;
        }
        let next = if from < GROWTH_FROM {
            from * 2
        } else {
            from.saturating_mul(self.growth)
        };
        if resume.is_none() && !unbounded && self.exhaustive_from > 0 && next > self.exhaustive_from
        {
            *resume = Some(width);
            return Some(usize::MAX);
        }
        let prefix_bytes = (std::mem::size_of::<Prefix<W>>() + 24) as u64;
        let need = prefix_bytes * next as u64 * (n as u64 + 1) * 2;
        (need <= self.memory_mb.saturating_mul(1 << 20)).then_some(next)
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
}


/// Whether a pass predicted to cost `factor` times `spent` (seconds, evaluations) of the pass
/// before fits in what is left of `budget` on `ctx`'s clock and count.
fn fits(ctx: &Context, budget: Budget, spent: (f64, u64), factor: f64) -> bool {
    let time_ok = budget
        .time_limit
        .is_none_or(|t| ctx.elapsed() + spent.0 * factor <= t.as_secs_f64());
    let evals_ok = budget
        .max_evals
        .is_none_or(|b| ctx.evaluations() as f64 + spent.1 as f64 * factor <= b as f64);
    time_ok && evals_ok
}

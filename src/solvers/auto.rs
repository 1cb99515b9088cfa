//! `auto`: the default solver — a portfolio chosen by measurement on TSPLIB SOP.
//!
//! 1. `beam` (iterative beam search with dominance and bounds) for a small share of the
//!    budget (`beam-share`, 10 %) on instances of at most `beam-max-cells` cells, and only
//!    when the wall-clock budget is at least `beam-min-seconds`: it proves small and densely
//!    constrained instances optimal in milliseconds, and then `auto` stops.
//! 2. The phases of `plan`, each with a share of what is left. The default
//!    `local-search:0.3,eacs:0.5,ils*:1` runs `local-search` (greedy, VND, iterated VND)
//!    for 30 %, then `eacs` (enhanced ant colony, its own colony: started from the best so
//!    far it stalled there: 40959 on ft70.2, best known 40419) for half of the rest,
//!    then `ils` for the rest; a `*` starts a phase from the best sequence so far instead of
//!    from greedy. On matrix instances whose costs read the same backwards the
//!    default is `symmetric-plan` (`local-search:0.2,eacs*:0.3,ils*:1`), which gives `ils`
//!    and its Lin–Kernighan chains more of the time; there, when the beam phase ran, it gets
//!    `symmetric-beam-share` (30 %) and is followed by `symmetric-beam-plan` (`ils` in a
//!    1 % band): `ils` started from the beam's sequence (on prob.100 at 10 s the median of
//!    16 seeds went from 1210.5 to 1172; notes/lab/sopq5.md). On other matrix instances whose
//!    precedence closure is sparser than `dense-density` (0.8) the default is `sparse-plan`:
//!    a shorter `local-search`, the colony run backwards, `ils` in a narrow and then a
//!    wider acceptance band, and a short window re-optimization (see [`SPARSE_PLAN`]). On
//!    the other matrix instances (dense precedence) of at most `dense-beam-max-cells` (300)
//!    cells the beam gets `dense-beam-share` (50 %): there its wider passes find what the
//!    plan misses (PCGTSPLIB rbg174a: 1641, the proven optimum, on 13 of 13 seeds at 10 s,
//!    against 1642–1643 with 10 %; notes/lab/sopq8.md). On larger dense instances
//!    (rbg323a–rbg378a) the passes do not finish: there is no beam phase, and the default is
//!    `large-dense-plan`: `ils` with longer kicks (see [`LARGE_DENSE_PLAN`]). Asymmetric
//!    matrix instances with (almost) no precedence apart from a fixed start and end
//!    ([`free_density`] at most `free-density`) get `free-plan`: the `atsp` solver
//!    (see [`FREE_PLAN`]); this case is checked before the sparse one.
//!
//! Plan syntax: `solver[key=value;...]:share`, with `*` after the name to start from the
//! best sequence so far, `+` to start from the sequence of the phase just before, and `~`
//! before the name to run the phase on the instance travelled backwards
//! ([`crate::model::Instance::reversed_matrix`]; matrix instances only, elsewhere the phase
//! runs forwards). A solver named twice in a plan gets a new seed each time
//! ([`phase_seed`]), so `eacs:0.4,~eacs:0.5` runs two independent colonies.
//!
//! The best sequence wins. Budgets are split by fraction, evaluations as well as time, so a
//! run with an evaluation budget stays deterministic. Without any budget `auto` gives itself
//! `seconds` of wall-clock time.

use super::{
    Budget, Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo, Sub, sub_run,
};
use crate::cost::CostModel;
use crate::engine::atsp::free_density;
use crate::engine::{Costs, lk};
use crate::error::{Error, Result};
use crate::model::Instance;
use crate::precedence::closure_density;
use std::collections::BTreeMap;
use std::time::Duration;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "auto",
    summary: "portfolio (default): beam proof attempt on small instances, then local-search, eacs and ils chained; best wins",
    params: &[
        ParamSpec {
            name: "seconds",
            default: "10",
            kind: ParamKind::Float,
            help: "wall-clock budget used when neither --time-limit nor --max-evals is given",
        },
        ParamSpec {
            name: "beam-share",
            default: "0.1",
            kind: ParamKind::Float,
            help: "share of the budget given to the beam proof attempt",
        },
        ParamSpec {
            name: "beam-max-cells",
            default: "400",
            kind: ParamKind::Int,
            help: "skip the beam phase on larger instances",
        },
        ParamSpec {
            name: "beam-min-seconds",
            default: "2",
            kind: ParamKind::Float,
            help: "skip the beam phase under a wall-clock budget shorter than this (its set-up can take a large part of a short budget)",
        },
        ParamSpec {
            name: "symmetric-plan",
            default: SYMMETRIC_PLAN,
            kind: ParamKind::Text,
            help: "the phases used instead of the default plan on matrix instances whose costs read the same backwards (TSPLIB's prob.100, prob.42), where ils runs Lin-Kernighan chains; ignored when plan is given",
        },
        ParamSpec {
            name: "symmetric-beam-share",
            default: "0.3",
            kind: ParamKind::Float,
            help: "share of the budget given to the beam phase on matrix instances whose costs read the same backwards (with the default plan)",
        },
        ParamSpec {
            name: "symmetric-beam-plan",
            default: SYMMETRIC_BEAM_PLAN,
            kind: ParamKind::Text,
            help: "the phases after a beam phase that ran (budget >= beam-min-seconds, at most beam-max-cells cells) on matrix instances whose costs read the same backwards; ignored when plan is given",
        },
        ParamSpec {
            name: "sparse-plan",
            default: SPARSE_PLAN,
            kind: ParamKind::Text,
            help: "the phases used instead of the default plan on matrix instances whose precedence closure is sparser than dense-density (and whose costs do not read the same backwards); ignored when plan is given",
        },
        ParamSpec {
            name: "dense-density",
            default: "0.8",
            kind: ParamKind::Float,
            help: "matrix instances with a precedence closure density (pairs ordered over n(n-1)/2) below this get sparse-plan",
        },
        ParamSpec {
            name: "free-plan",
            default: FREE_PLAN,
            kind: ParamKind::Text,
            help: "the phases used instead of the default plan on asymmetric matrix instances whose precedence, apart from cells ordered against every other (a fixed start and end), has a closure density of at most free-density; ignored when plan is given",
        },
        ParamSpec {
            name: "free-density",
            default: "0.001",
            kind: ParamKind::Float,
            help: "asymmetric matrix instances whose closure density among the cells not ordered against every other cell is at most this get free-plan",
        },
        ParamSpec {
            name: "dense-beam-share",
            default: "0.5",
            kind: ParamKind::Float,
            help: "share of the budget given to the beam phase on asymmetric matrix instances whose precedence closure is at least dense-density and that have at most dense-beam-max-cells cells (with the default plan)",
        },
        ParamSpec {
            name: "dense-beam-max-cells",
            default: "300",
            kind: ParamKind::Int,
            help: "dense matrix instances with more cells get large-dense-plan and no beam phase: there the beam's passes over the whole instance do not finish in a useful time",
        },
        ParamSpec {
            name: "large-dense-plan",
            default: LARGE_DENSE_PLAN,
            kind: ParamKind::Text,
            help: "the phases used instead of the default plan, without a beam phase, on asymmetric matrix instances whose precedence closure is at least dense-density and that have more than dense-beam-max-cells cells; ignored when plan is given",
        },
        ParamSpec {
            name: "plan",
            default: PLAN,
            kind: ParamKind::Text,
            help: "phases after the beam: solver[key=value;...]:share,... (share of what is left; optional parameters in brackets; a '*' after the name starts ils, eacs or reopt from the best so far, a '+' from the sequence of the phase before; a '~' before the name runs the phase on the matrix instance travelled backwards; a solver named twice gets a new seed each time)",
        },
    ],
    caps: Caps { ..Caps::NONE },
    make: |p: &Params| {
        let auto = Auto::from_params(p);
        // every plan is parsed, so a malformed one is refused when the solver is built
        for plan in auto.plans() {
            parse_plan(plan)?;
        }
        Ok(Box::new(auto))
    },
};

/// The portfolio.
pub struct Auto {
    /// Default wall-clock budget.
    pub seconds: f64,
    /// Share of the budget for the beam phase.
    pub beam_share: f64,
    /// Largest instance for the beam phase.
    pub beam_max_cells: usize,
    /// Phases after the beam (`solver[key=value;...][*]:share,...`).
    pub plan: String,
    /// Phases used instead of the default `plan` on symmetric matrix costs.
    pub symmetric_plan: String,
    /// Shortest wall-clock budget that gets a beam phase.
    pub beam_min_seconds: f64,
    /// Share of the budget for the beam phase on symmetric matrix costs.
    pub symmetric_beam_share: f64,
    /// Phases after a beam phase that ran, on symmetric matrix costs.
    pub symmetric_beam_plan: String,
    /// Phases used instead of the default `plan` on matrix instances with sparse precedence.
    pub sparse_plan: String,
    /// Precedence closure density at and above which a matrix instance counts as dense.
    pub dense_density: f64,
    /// Phases used instead of the default `plan` on asymmetric matrix instances with (almost)
    /// no precedence.
    pub free_plan: String,
    /// Largest [`free_density`] that counts as (almost) no precedence.
    pub free_density: f64,
    /// Share of the budget for the beam phase on dense matrix instances of at most
    /// `dense_beam_max_cells` cells.
    pub dense_beam_share: f64,
    /// Largest dense matrix instance that gets `dense_beam_share`.
    pub dense_beam_max_cells: usize,
    /// Phases used instead of the default `plan` on larger dense matrix instances.
    pub large_dense_plan: String,
}

/// Default phases after the beam.
pub const PLAN: &str = "local-search:0.3,eacs:0.5,ils*:1";

/// Default phases on matrix instances with symmetric costs: `ils` (with its Lin–Kernighan
/// chains) gets 56 % of the time instead of 35 %. On prob.100 the median of 5 seeds at 10 s
/// went from 1238 to 1211 and of 10 seeds at 1 s from 1380.5 to 1282; prob.42 from 245.5
/// to 243 at 1 s (notes/lab/sopq3.md).
pub const SYMMETRIC_PLAN: &str = "local-search:0.2,eacs*:0.3,ils*:1";

/// Default phases on matrix instances with symmetric costs after a beam phase that ran:
/// `ils` from the beam's sequence. The beam builds its paths with bounds over the whole
/// remainder and lands in a better basin for `ils` than greedy, `local-search` or `eacs`
/// starts: on prob.100 at 10 s, median of 16 seeds 1172 against the symmetric plan's 1210.5
/// (and 1205 from local-search, 1217 from eacs; notes/lab/sopq5.md). Its acceptance band is
/// 1 % (the default 0.1 % stalls: a walk that finds no new best in 2000 kicks goes back
/// to the best): prob.100 at 10 s, seeds 1–20, 12 runs at or below the best known 1163
/// and median 1161, against 6 and 1172 (notes/lab/sopq10.md).
pub const SYMMETRIC_BEAM_PLAN: &str = "ils[accept=0.01]*:1";

/// Default phases on asymmetric matrix instances whose precedence closure is sparser than
/// `dense-density` (on TSPLIB SOP every instance but rbg109a–rbg378a, which lie at
/// 0.89–0.95 while the others lie at 0.05–0.62): the last `ils` accepts kicked solutions up
/// to 3 % above the best instead of 0.1 %. With few precedences the walk needs the wider
/// band to leave the basin that `eacs` hands it (kro124p.3: median 49703 → 49499, its best
/// known), while on the dense rbg instances the wider band wanders (rbg358a: 2545 → 2565;
/// notes/lab/sopq5.md, notes/lab/sopq6.md). Its colony runs backwards (`~eacs`, on the transposed
/// twin of the instance) and gets the time `local-search` gave up (0.3 → 0.1): built from
/// the other end, the ants fall less often into the basin that holds forward colonies on
/// kro124p.3 (10 s, seeds 1–10: 8 runs at the best known 49499 and 2 at 49519, against 6
/// and 4 in the 50183–50207 basin; notes/lab/sopq7.md). The last `ils` ends every kick's repair
/// with the bounded-shift DP at shift 2 (adjacent swaps and the modes re-chosen over the
/// kicked span): PCGTSPLIB p43.2 16/16 and kro124p.4 11/16 seeds at or below the best known,
/// against 13/16 and 8/16 without; shift 5 lost rbg050c (12/16 against 16/16; notes/lab/sopq9.md).
/// The `ils` time is split: first a walk in a 1 % band from the colony's sequence, which
/// stays in that basin and settles there (PCGTSPLIB kro124p.4 reaches 62818 or 62831, where
/// the 3 % band wanders to 62915–62953), then the 3 % walk from the best, which leaves a poor
/// basin that the narrow one cannot (PCGTSPLIB ft70.2: 33912 from the colony), then window
/// re-optimization ([`super::reopt`], windows of 16) of the best, which turns 62831 into
/// 62818: kro124p.4 at 10 s, seeds 101–112, 8/12 at 62818 against 6/12 (notes/lab/sopq10.md).
pub const SPARSE_PLAN: &str = "local-search:0.1,~eacs:0.5,ils[accept=0.01;shift-repair=2]*:0.25,ils[accept=0.03;shift-repair=2]*:0.85,reopt[window=16]*:1";

/// Default phases on asymmetric matrix instances with dense precedence and more than
/// `dense-beam-max-cells` cells (TSPLIB rbg323a–rbg378a): a short `local-search`, then `ils`
/// from its sequence for the rest, with no beam phase (its passes over the whole instance do
/// not finish there and never beat `ils`). Its kicks reorder stretches of up to 45 cells
/// (`max-seg`; the automatic length is 30): the gains left at 3141/2569/2548/2818 lie in
/// reorders of 40–90 consecutive cells, which shorter kicks reach too rarely and longer ones
/// (60, 80) bury in repair. At 10 s, seeds 101–108 on the four instances, 23 of 32 runs
/// reach the best known value, against 5 with the plan before (`ils` for 40 %, then window
/// re-optimization by the exact tree search, [`super::reopt`]) and 15 and 15 with kicks of
/// 60 and 80; seeds 109–116 gave 17 of 32 (notes/lab/sopq11.md).
pub const LARGE_DENSE_PLAN: &str = "local-search:0.1,ils[max-seg=45]*:1";

/// Default phases on asymmetric matrix instances with no precedence apart from a fixed start
/// and end: the assignment's cycles patched into a path, then iterated Or-3opt
/// ([`super::atsp`]). On random asymmetric matrices of 200–700 cells with integer costs in
/// [0, 100] and [0, 1000] (notes/atsp.md) the default plan ended 1.4–27 × above the assignment
/// bound, this one within a few percent of it. `free-density` (0.001) lets in instances with a
/// handful of constraints: at inner closure densities of 0.0005–0.0006 `atsp` was at or below
/// the default plan on 4 of 4 generated instances, at 0.002–0.003 on 3 of 4, at 0.04–0.1 on
/// none (1 s each).
pub const FREE_PLAN: &str = "atsp:1";

/// Where a plan phase starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Start {
    /// From scratch (the solver's own construction).
    Fresh,
    /// From the best sequence so far (`*` after the name; ils, eacs and reopt only).
    Best,
    /// From the sequence of the phase just before (`+`; ils, eacs and reopt only): polishes one
    /// colony's result even when an earlier phase found a cheaper sequence.
    Previous,
}

/// One phase of a plan: solver name, share of what is left, where it starts.
#[derive(Debug, Clone, PartialEq)]
pub struct Phase {
    /// Solver name.
    pub solver: String,
    /// Share of the remaining budget.
    pub share: f64,
    /// Where the phase starts.
    pub start: Start,
    /// Run on the instance travelled backwards (`~` before the name; matrix instances,
    /// see [`crate::model::Instance::reversed_matrix`]; elsewhere the phase runs forwards).
    pub reversed: bool,
    /// The phase's own solver parameters (`solver[key=value;...]`), validated.
    pub params: BTreeMap<String, String>,
}

/// Parses a plan `[~]solver[key=value;...][*|+]:share,...` (parameters in brackets are optional and
/// checked against the solver's declared parameters).
pub fn parse_plan(plan: &str) -> Result<Vec<Phase>> {
    let bad = |msg: String| Error::Solver {
        solver: "auto".to_string(),
        msg,
    };
    let mut out = Vec::new();
    for part in plan.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, share) = part
            .split_once(':')
            .ok_or_else(|| bad(format!("plan phase '{part}' is not solver:share")))?;
        let share: f64 = share
            .trim()
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite() && *v > 0.0 && *v <= 1.0)
            .ok_or_else(|| bad(format!("plan phase '{part}': share must be in (0, 1]")))?;
        let name = name.trim();
        let (name, reversed) = match name.strip_prefix('~') {
            Some(b) => (b.trim_start(), true),
            None => (name, false),
        };
        let (name, start) = match (name.strip_suffix('*'), name.strip_suffix('+')) {
            (Some(b), _) => (b.trim_end(), Start::Best),
            (_, Some(b)) => (b.trim_end(), Start::Previous),
            _ => (name, Start::Fresh),
        };
        let (solver, params) = match name.split_once('[') {
            Some((solver, rest)) => {
                let body = rest.strip_suffix(']').ok_or_else(|| {
                    bad(format!(
                        "plan phase '{part}': parameters are written solver[key=value;...]"
                    ))
                })?;
                let mut params = BTreeMap::new();
                for kv in body.split(';').map(str::trim).filter(|kv| !kv.is_empty()) {
                    let (k, v) = kv.split_once('=').ok_or_else(|| {
                        bad(format!("plan phase '{part}': '{kv}' is not key=value"))
                    })?;
                    params.insert(k.trim().to_string(), v.trim().to_string());
                }
                (solver.trim().to_string(), params)
            }
            None => (name.to_string(), BTreeMap::new()),
        };
        if solver == "auto" {
            return Err(bad("a plan cannot contain auto itself".to_string()));
        }
        let info = super::find(&solver)?;
        info.build(&params)
            .map_err(|e| bad(format!("plan phase '{part}': {e}")))?;
        if start != Start::Fresh && !info.caps.starts_from {
            return Err(bad(format!(
                "plan phase '{part}': only {} can start from an earlier sequence",
                startable()
            )));
        }
        if start == Start::Previous && out.is_empty() {
            return Err(bad(format!(
                "plan phase '{part}': the first phase has no phase before it to follow"
            )));
        }
        out.push(Phase {
            solver,
            share,
            start,
            reversed,
            params,
        });
    }
    if out.is_empty() {
        return Err(bad("empty plan".to_string()));
    }
    Ok(out)
}

/// The solvers a plan phase can start from an earlier sequence (`*`, `+`): those whose
/// capabilities say `starts_from`, as "ils, eacs and reopt".
fn startable() -> String {
    let mut names: Vec<&str> = super::registry()
        .into_iter()
        .filter(|i| i.caps.starts_from)
        .map(|i| i.name)
        .collect();
    names.sort_by_key(|n| (n.len(), *n));
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        Some((last, _)) => last.to_string(),
        None => "no solver".to_string(),
    }
}

/// Which settings of [`Auto`] apply to an instance (only with the default `plan`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Case {
    /// `plan` and `beam-share`.
    Default,
    /// Matrix costs that read the same backwards: `symmetric-plan` (or
    /// `symmetric-beam-plan` after a beam phase) and `symmetric-beam-share`.
    Symmetric,
    /// Asymmetric matrix costs with sparse precedence: `sparse-plan` and `beam-share`.
    Sparse,
    /// Asymmetric matrix costs with (almost) no precedence apart from a fixed start and end
    /// ([`free_density`] at most `free-density`): `free-plan` and `beam-share`.
    Free,
    /// Asymmetric matrix costs with dense precedence, at most `dense-beam-max-cells` cells:
    /// `plan` and `dense-beam-share`.
    Dense,
    /// Asymmetric matrix costs with dense precedence, more than `dense-beam-max-cells`
    /// cells: `large-dense-plan` and no beam phase.
    LargeDense,
}

/// The seed of a plan phase: the run's own seed for the first phase of each solver, so
/// that a plan naming each solver once draws the streams it always drew, and a different
/// seed for each repeat (`eacs:0.4,eacs:0.6` runs two independent colonies).
pub fn phase_seed(seed: u64, repeat: u64) -> u64 {
    seed.wrapping_add(repeat.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// A share of `b` (what is left of it after `used_evals` and `used_s`).
fn share(b: Budget, used_evals: u64, used_s: f64, frac: f64) -> Budget {
    Budget {
        time_limit: b
            .time_limit
            .map(|t| Duration::from_secs_f64((t.as_secs_f64() - used_s).max(0.0) * frac)),
        max_evals: b
            .max_evals
            .map(|m| ((m.saturating_sub(used_evals)) as f64 * frac) as u64),
    }
}

/// One phase as it runs: what [`Phase`] says, resolved against the run so far.
struct Run<'p> {
    /// Solver name.
    name: &'p str,
    /// The phase's own solver parameters.
    given: &'p BTreeMap<String, String>,
    /// Its share of the budget.
    budget: Budget,
    /// Where it starts ([`Start::Fresh`] for the beam).
    from: Start,
    /// The sequence it starts from (`None` with [`Start::Fresh`]).
    start: Option<&'p Outcome>,
    /// How often the solver ran before in the plan (its seed's repeat index).
    repeat: u64,
    /// The backwards twin it runs on (`~`), if any.
    twin: Option<&'p (Instance, CostModel)>,
}

impl Auto {
    /// The portfolio with validated parameters `p` (of [`INFO`]).
    pub fn from_params(p: &Params) -> Auto {
        Auto {
            seconds: p.float("seconds").max(0.001),
            beam_share: p.float("beam-share").clamp(0.0, 1.0),
            beam_max_cells: p.int("beam-max-cells") as usize,
            plan: p.word("plan").to_string(),
            symmetric_plan: p.word("symmetric-plan").to_string(),
            symmetric_beam_share: p.float("symmetric-beam-share").clamp(0.0, 1.0),
            symmetric_beam_plan: p.word("symmetric-beam-plan").to_string(),
            sparse_plan: p.word("sparse-plan").to_string(),
            dense_density: p.float("dense-density"),
            free_plan: p.word("free-plan").to_string(),
            free_density: p.float("free-density"),
            dense_beam_share: p.float("dense-beam-share").clamp(0.0, 1.0),
            dense_beam_max_cells: p.int("dense-beam-max-cells") as usize,
            large_dense_plan: p.word("large-dense-plan").to_string(),
            beam_min_seconds: p.float("beam-min-seconds").max(0.0),
        }
    }

    fn phase(&self, ctx: &mut Context, run: Run) -> Result<Outcome> {
        let Run {
            name,
            given,
            budget,
            from,
            start,
            repeat,
            twin,
        } = run;
        let (instance, on) = match twin {
            Some((i, m)) => (i, Some((i, m))),
            None => (ctx.instance, None),
        };
        let seq = start.map(|o| match twin {
            Some(_) => ctx.instance.reverse_sequence(&o.sequence),
            None => o.sequence.clone(),
        });
        let sub = Sub {
            name,
            params: given,
            budget,
            seed: phase_seed(ctx.seed, repeat),
            start: seq.as_ref(),
            on,
        };
        let mut out = sub_run(ctx, sub)?;
        if twin.is_some() {
            out.sequence = instance.reverse_sequence(&out.sequence);
        }
        ctx.report(out.cost);
        if super::trace_enabled() {
            eprintln!(
                "auto: {}{name}{} cost {} after {} evaluations, {:.2} s",
                if twin.is_some() { "~" } else { "" },
                match (from, start.is_some()) {
                    (Start::Best, true) => "*",
                    (Start::Previous, true) => "+",
                    _ => "",
                },
                out.cost,
                ctx.evaluations(),
                ctx.elapsed()
            );
        }
        Ok(out)
    }

    /// The phases for model `m`: the plan of its case ([`Auto::case`]), or
    /// `symmetric_beam_plan` in the symmetric case after a beam phase that ran (`after_beam`).
    pub fn plan_for(&self, m: &CostModel, after_beam: bool) -> &str {
        self.plan_in(self.case(m), after_beam)
    }

    /// The phases in `case`: `symmetric_beam_plan` after a beam phase that ran
    /// (`after_beam`) and `symmetric_plan` otherwise in the symmetric case, `sparse_plan` in
    /// the sparse one, `large_dense_plan` in the large dense one, else `plan`.
    fn plan_in(&self, case: Case, after_beam: bool) -> &str {
        match (case, after_beam) {
            (Case::Default | Case::Dense, _) => &self.plan,
            (Case::LargeDense, _) => &self.large_dense_plan,
            (Case::Symmetric, false) => &self.symmetric_plan,
            (Case::Symmetric, true) => &self.symmetric_beam_plan,
            (Case::Sparse, _) => &self.sparse_plan,
            (Case::Free, _) => &self.free_plan,
        }
    }

    /// The beam phase's share of the budget for model `m`.
    pub fn beam_share_for(&self, m: &CostModel) -> f64 {
        self.beam_share_when(self.case(m))
    }

    /// Every plan: `plan`, `free_plan`, `symmetric_plan`, `symmetric_beam_plan`, `sparse_plan` and
    /// `large_dense_plan`.
    fn plans(&self) -> [&str; 6] {
        [
            &self.plan,
            &self.free_plan,
            &self.symmetric_plan,
            &self.symmetric_beam_plan,
            &self.sparse_plan,
            &self.large_dense_plan,
        ]
    }

    /// The beam share in `case`.
    fn beam_share_when(&self, case: Case) -> f64 {
        match case {
            Case::Symmetric => self.symmetric_beam_share,
            Case::Dense => self.dense_beam_share,
            Case::LargeDense => 0.0,
            _ => self.beam_share,
        }
    }

    /// Which settings apply to model `m`: the default ones when the user gave a `plan` or
    /// for geometric instances; else the symmetric ones when the matrix reads the same
    /// backwards, the free ones when [`free_density`] is at most `free_density` (no
    /// precedence apart from a fixed start and end), the sparse ones when the precedence
    /// closure is sparser than
    /// `dense_density`, else the dense ones up to `dense_beam_max_cells` cells and the large
    /// dense ones above.
    pub fn case(&self, m: &CostModel) -> Case {
        if self.plan != PLAN || m.is_geometric() {
            Case::Default
        } else if lk::symmetric(&Costs::open(m)) {
            Case::Symmetric
        } else if free_density(m) <= self.free_density {
            Case::Free
        } else if closure_density(&m.dag) < self.dense_density {
            Case::Sparse
        } else if m.n() <= self.dense_beam_max_cells {
            Case::Dense
        } else {
            Case::LargeDense
        }
    }
}

impl Solver for Auto {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let case = self.case(ctx.model);
        let mut budget = ctx.budget;
        if budget.time_limit.is_none() && budget.max_evals.is_none() {
            budget.time_limit = Some(Duration::from_secs_f64(self.seconds));
        }
        let mut best: Option<Outcome> = None;
        let keep = |best: &mut Option<Outcome>, o: Outcome| {
            if best.as_ref().is_none_or(|b| o.cost < b.cost) {
                *best = Some(o);
            }
        };
        let short = budget
            .time_limit
            .is_some_and(|t| t.as_secs_f64() < self.beam_min_seconds);
        let beam_share = self.beam_share_when(case);
        let mut after_beam = false;
        if ctx.model.n() <= self.beam_max_cells && beam_share > 0.0 && !short {
            let b = share(budget, 0, 0.0, beam_share);
            let beam = Run {
                name: "beam",
                given: &BTreeMap::new(),
                budget: b,
                from: Start::Fresh,
                start: None,
                repeat: 0,
                twin: None,
            };
            if let Ok(o) = self.phase(ctx, beam) {
                if o.proven_optimal {
                    return Ok(o);
                }
                keep(&mut best, o);
                after_beam = true;
            }
        }
        let plan = parse_plan(self.plan_in(case, after_beam))?;
        let mut last: Option<Outcome> = None;
        let twin = if plan.iter().any(|p| p.reversed) {
            ctx.instance.reversed_matrix().map(|i| {
                let m = CostModel::new(&i, ctx.model.objective());
                (i, m)
            })
        } else {
            None
        };
        for (i, ph) in plan.iter().enumerate() {
            // past the time limit, a later phase would only overrun it (its construction alone
            // can take seconds on large instances): stop with the best so far
            let late = budget
                .time_limit
                .is_some_and(|t| ctx.elapsed() >= t.as_secs_f64());
            if late && best.is_some() {
                break;
            }
            let b = share(budget, ctx.evaluations(), ctx.elapsed(), ph.share);
            let start = match ph.start {
                Start::Fresh => None,
                Start::Best => best.as_ref(),
                Start::Previous => last.as_ref(),
            };
            // how often this solver ran before in the plan: its seed's repeat index
            let repeat = plan[..i].iter().filter(|p| p.solver == ph.solver).count() as u64;
            let on = if ph.reversed { twin.as_ref() } else { None };
            let run = Run {
                name: &ph.solver,
                given: &ph.params,
                budget: b,
                from: ph.start,
                start,
                repeat,
                twin: on,
            };
            let o = self.phase(ctx, run)?;
            keep(&mut best, o.clone());
            last = Some(o);
        }
        let mut out = best.expect("at least one phase ran");
        out.proven_optimal = false;
        Ok(out)
    }
}

//! `auto`: the default solver — a portfolio whose rules are data.
//!
//! The instance's [`Features`] are computed once; the first rule of the [`Portfolio`] whose
//! conditions hold gives the plan (the built-in portfolio is `portfolio.toml` beside this
//! module; the `portfolio` parameter or `--portfolio FILE` names another):
//!
//! 1. `beam` (iterative beam search with dominance and bounds) for the rule's beam share of
//!    the budget, on instances of at most its `max_cells` cells and, under a wall-clock
//!    budget, only when that budget is at least its `min_seconds`: when it proves the
//!    optimum, `auto` stops.
//! 2. The rule's phases (or its `after_beam` phases after a beam phase that ran), each with
//!    a share of what is left; each phase starts fresh, from the best sequence so far or from
//!    the previous phase's, and may run on the instance travelled backwards.
//!
//! The `plan` parameter replaces the rule selection: its phases run with the beam settings
//! of the portfolio's last (catch-all) rule. Plan syntax: `solver[key=value;...]:share`,
//! with `*` after the name to start from the best sequence so far, `+` to start from the
//! sequence of the phase just before, and `~` before the name to run the phase on the
//! instance travelled backwards ([`crate::model::Instance::reversed_matrix`]; matrix
//! instances only, elsewhere the phase runs forwards). A solver named twice in a plan gets a
//! new seed each time ([`phase_seed`]), so `eacs:0.4,~eacs:0.5` runs two independent colonies.
//! `@U` after a share (`eacs:0.08@0.7`) skips the phase once more than U of the budget is used.
//!
//! The best sequence wins. Budgets are split by fraction, evaluations as well as time, so a
//! run with an evaluation budget stays deterministic. Without any budget `auto` gives itself
//! `seconds` of wall-clock time.

pub mod features;
pub mod phases;
pub mod portfolio;

pub use features::Features;
pub use phases::{Phase, Start, parse_plan, phase_seed, plan_text};
pub use portfolio::{Beam, Long, Portfolio};

use super::Build;
use super::{
    Budget, Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo, Sub, sub_run,
};
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::model::Instance;
use std::collections::BTreeMap;
use std::time::Duration;

/// The `plan` and `beam-share` parameters' default: take them from the portfolio's rule.
pub const FROM_RULE: &str = "rule";

/// The rule name reported when the `plan` parameter replaces the rule selection.
pub const PLAN_RULE: &str = "plan parameter";

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "auto",
    summary: "portfolio (default): instance features pick a rule of a portfolio file; a beam proof attempt on small instances, then the rule's phases (local-search, eacs, ils, atsp...) chained; best wins",
    description: "A portfolio: phases of other solvers, each given a share of what is left of the budget \
(evaluations as well as time, so a run under `--max-evals` stays deterministic), each later \
phase able to start from the best sequence so far; the best sequence wins. What runs is data: \
`auto` computes the instance's features once (cells, modes per cell, geometric or matrix, \
symmetric costs, precedence closure density, free density, widest precedence level, share of \
zero-cost arcs, cost spread) and takes the first rule of a portfolio file whose conditions \
hold; the built-in file is `crates/cellseq/src/solvers/auto/portfolio.toml`, `--portfolio FILE` (or \
`--param portfolio=FILE`) names another. The format, the features and what is refused: \
[portfolio.md](portfolio.md).

1. A `beam` proof attempt gets the rule's beam share of the budget, on instances of at most \
its `max_cells` cells and, under a wall-clock budget, only when that budget is at least its \
`min_seconds`; when it proves the optimum, `auto` stops there. Time bounds are compared with \
the whole limit given (`--time-limit`), not with what reading the file and the lower bound's \
share leave of it.
2. Then the rule's phases (or its `after_beam` phases after a beam phase that ran). The \
built-in rules: **symmetric** cost matrices with one mode per cell (a short `local-search`, \
then guided local search, `gls`, also after the beam when it ran; on 401–1000 cells with \
closure density below 0.8 **symmetric-medium**, `gls` alone; otherwise above 400 cells \
**symmetric-large**, `ils` with Lin–Kernighan chains in a 1 % acceptance band, eight walks of \
which the worse half is dropped at 15, 30 and 45 % of its budget, its kicks reordering at most \
10 cells under sparse precedence, and **symmetric-large-dense**, with the longer kicks, from \
closure density 0.2) \
and **symmetric-modes**, several modes per cell (a colony before `ils`); \
**free** asymmetric matrices with no precedence apart from a fixed start and end (`atsp`); \
**sparse** precedence (a short `local-search`, a colony run backwards, `ils` in a 1 % then a 3 \
% acceptance band, its kicks two random segment swaps, with the bounded-shift DP ending every \
repair, window re-optimization of the best), with costs spread as random ones \
(`cost_spread` 0.5 and above) on up to 1000 cells **sparse-random**, the `sparse` plan except \
under budgets of 5 s and more (or 1.5·10⁸ evaluations), where `gls` runs between the two \
`ils` phases, with one mode per cell on up to 500 cells **sparse-small**, the `sparse` plan \
with carry moves (a cell moved past a precedence neighbour in its way, which a short segment \
carried along lets through) in the polish of every walk's records, except under budgets of \
7.5 s and more (or 2.5·10⁸ evaluations), where rounds of a fresh \
colony, each polished by `ils` in the 1 % band until it stalls (three, and up to five more \
while less than 70 % of the budget is used), come before the walk in the 3 % band, and \
with several modes per cell on up to 300 \
cells **sparse-modes** (three rounds of a fresh colony, each polished by `ils` in the 1 % \
band, then `ils` in the 3 % band from the best of the three and window re-optimization); \
**dense** precedence (a short `local-search`, then \
`ils` with kicks that reorder up to 45 cells; on up to 300 cells, when the beam runs, half the \
budget for the beam, then the default phases), with costs spread as random ones \
(`cost_spread` 0.5 and above) **dense-random**, whose walk also runs corridor passes when it \
stalls, and with many zero-cost links (`zero_arcs` 0.01 and above, crane jobs at stations) on \
up to 400 cells **dense-ties**, the `dense` plan except under budgets of at least 5 s (or \
3·10⁸ evaluations), where `gls` takes 70 % of the budget before the walk; **geometric free** instances (geometric, no or \
very sparse precedence, links that cost the same both ways: `local-search` on the two-level \
list with local and random-walk double-bridge kicks for the whole budget); and the catch-all \
**default**, the other geometric instances among them (`local-search`, an `eacs` colony of its \
own, `ils` from the best so far).

`cellseq solve F --explain` prints the features, the rule and its plan before solving; \
`CELLSEQ_TRACE=1` prints them and one line per phase on stderr. `--param plan=...` skips the \
rules: its phases run with the beam settings of the portfolio's last rule. Plan syntax: \
`solver[key=value;...]:share,...`, where the share is a fraction of what is left. After the \
name, `*` starts the phase from the best sequence so far and `+` from the previous phase's \
sequence; `~` before the name runs the phase on the instance travelled backwards (matrix \
instances; elsewhere the phase runs forwards). `@U` after the share skips the phase once more \
than U (in (0, 1]) of the whole budget is used. A solver named twice gets a new seed each time. \
Example: `cellseq solve F --param plan=local-search:0.3,eacs:0.5,ils*:1`. How the built-in \
rules were chosen: [notes/portfolio.md](../notes/portfolio.md).",
    params: &[
        ParamSpec {
            name: "seconds",
            default: "10",
            kind: ParamKind::float_above(0.0, crate::params::MAX_SECONDS),
            help: "wall-clock budget used when neither --time-limit nor --max-evals is given",
        },
        ParamSpec {
            name: "portfolio",
            default: portfolio::BUILT_IN_NAME,
            kind: ParamKind::Text,
            help: "the portfolio file (TOML, docs/portfolio.md) whose rules choose the plan; built-in: the one compiled in (`cellseq solve --portfolio FILE` sets it)",
        },
        ParamSpec {
            name: "plan",
            default: FROM_RULE,
            kind: ParamKind::Text,
            help: "phases that replace the rule selection, with the beam settings of the portfolio's last rule: solver[key=value;...]:share,... (share of what is left; a '*' after the name starts ils, eacs or reopt from the best so far, a '+' from the sequence of the phase before; a '~' before the name runs the phase on the matrix instance travelled backwards; '@U' after the share skips the phase once more than U of the budget is used; a solver named twice gets a new seed each time); rule: the chosen rule's phases",
        },
        ParamSpec {
            name: "beam-share",
            default: FROM_RULE,
            kind: ParamKind::Text,
            help: "share of the budget given to the beam proof attempt, in [0, 1] (0: none), without the rule's stretch; rule: the chosen rule's share and stretch",
        },
    ],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|p: &Params| Ok(Box::new(Auto::from_params(p)?))),
};

/// The portfolio solver.
pub struct Auto {
    /// Default wall-clock budget.
    pub seconds: f64,
    /// The rules.
    pub portfolio: Portfolio,
    /// Phases that replace the rule selection (the `plan` parameter).
    pub plan: Option<Vec<Phase>>,
    /// Beam share that replaces the rule's (the `beam-share` parameter).
    pub beam_share: Option<f64>,
}

/// What `auto` runs on one instance: the rule, the features it was chosen by, and the
/// settings in force.
#[derive(Debug, Clone)]
pub struct Choice<'a> {
    /// The rule's name ([`PLAN_RULE`] when the `plan` parameter replaced the selection).
    pub rule: &'a str,
    /// The instance's features.
    pub features: Features,
    /// The beam phase's settings (share, limits).
    pub beam: Beam,
    /// The phases.
    pub phases: &'a [Phase],
    /// The phases after a beam phase that ran, when they differ.
    pub after_beam: Option<&'a [Phase]>,
    /// The phases for long budgets, when the rule has them.
    pub long: Option<&'a Long>,
}

impl Choice<'_> {
    /// The phases to run under `budget`: after a beam phase that ran, its `after_beam`
    /// phases when the rule has them; otherwise the `long` phases when the budget reaches
    /// them; else the phases.
    pub fn plan(&self, after_beam: bool, budget: Budget) -> &[Phase] {
        match (after_beam, self.after_beam, self.long) {
            (true, Some(p), _) => p,
            (_, _, Some(l)) if l.applies(budget) => &l.phases,
            _ => self.phases,
        }
    }

    /// A few lines for `solve --explain` and the trace: the rule, the features, the beam
    /// settings and the phases.
    pub fn lines(&self, source: &str) -> Vec<String> {
        let mut out = vec![
            format!("portfolio  {source}"),
            format!("rule       {}", self.rule),
            format!("features   {}", self.features.line()),
            format!(
                "beam       share {} up to {} cells, budgets of at least {} s{}",
                self.beam.share,
                self.beam.max_cells,
                self.beam.min_seconds,
                if self.beam.stretch > 1.0 {
                    format!(", its widest pass up to {}× the share", self.beam.stretch)
                } else {
                    String::new()
                }
            ),
            format!("phases     {}", plan_text(self.phases)),
        ];
        if let Some(p) = self.after_beam {
            out.push(format!("after beam {}", plan_text(p)));
        }
        if let Some(l) = self.long {
            out.push(format!(
                "long       budgets of at least {} s or {} evaluations: {}",
                l.min_seconds,
                l.min_evals,
                plan_text(&l.phases)
            ));
        }
        out
    }
}

/// A share of `b` (what is left of it after `used_evals` and `used_s`).
fn share(b: Budget, used_evals: u64, used_s: f64, frac: f64) -> Budget {
    Budget {
        time_limit: b
            .time_limit
            .map(|t| Duration::from_secs_f64((t.as_secs_f64() - used_s).max(0.0))),
        max_evals: b.max_evals.map(|m| m.saturating_sub(used_evals)),
    }
    .scaled(frac)
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
    /// The solver for validated parameters `p` (of [`INFO`]): loads and validates the
    /// portfolio, parses a given `plan` and checks a given `beam-share`.
    pub fn from_params(p: &Params) -> Result<Auto> {
        let portfolio = Portfolio::load(p.word("portfolio"))?;
        let plan = match p.word("plan") {
            FROM_RULE => None,
            text => Some(parse_plan(text)?),
        };
        let beam_share = match p.word("beam-share") {
            FROM_RULE => None,
            text => Some(
                text.parse::<f64>()
                    .ok()
                    .filter(|s| s.is_finite() && (0.0..=1.0).contains(s))
                    .ok_or_else(|| Error::Param(format!(
                        "'auto': parameter 'beam-share' must be a number in [0, 1] or {FROM_RULE}, got '{text}'"
                    )))?,
            ),
        };
        Ok(Auto {
            seconds: p.float("seconds"),
            portfolio,
            plan,
            beam_share,
        })
    }

    /// What runs on model `m`: the features, the first rule that holds (or the `plan`
    /// parameter with the last rule's beam settings), and the beam share in force.
    pub fn choose(&self, m: &CostModel) -> Choice<'_> {
        let features = Features::of(m);
        let (rule, phases, after_beam, long, mut beam) = match &self.plan {
            Some(p) => (
                PLAN_RULE,
                p.as_slice(),
                None,
                None,
                self.portfolio.catch_all().beam,
            ),
            None => {
                let r = self.portfolio.select(&features);
                (
                    r.name.as_str(),
                    r.phases.as_slice(),
                    r.after_beam.as_deref(),
                    r.long.as_ref(),
                    r.beam,
                )
            }
        };
        if let Some(s) = self.beam_share {
            // the share given is the whole beam phase: no pass stretches it
            beam.share = s;
            beam.stretch = 1.0;
        }
        Choice {
            rule,
            features,
            beam,
            phases,
            after_beam,
            long,
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
}

impl Solver for Auto {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let choice = self.choose(ctx.model);
        if super::trace_enabled() {
            for l in choice.lines(&self.portfolio.source) {
                eprintln!("auto: {l}");
            }
        }
        let mut budget = ctx.budget;
        if budget.time_limit.is_none() && budget.max_evals.is_none() {
            budget.time_limit = Some(Duration::from_secs_f64(self.seconds));
            // on the run's own clock too, so that no phase (a sub-run) outlives it
            ctx.budget.time_limit = budget.time_limit;
        }
        let mut best: Option<Outcome> = None;
        let keep = |best: &mut Option<Outcome>, o: Outcome| {
            if best.as_ref().is_none_or(|b| o.cost < b.cost) {
                *best = Some(o);
            }
        };
        // the beam and the long plan are chosen by the limit the caller stated (a command's
        // `--time-limit`), not by what reading the input and the bound's share left of it
        let sized = Budget {
            time_limit: ctx.nominal_limit(),
            ..budget
        };
        let beam_cfg = choice.beam;
        let short = sized
            .time_limit
            .is_some_and(|t| t.as_secs_f64() < beam_cfg.min_seconds);
        let mut after_beam = false;
        if ctx.model.n() <= beam_cfg.max_cells && beam_cfg.share > 0.0 && !short {
            // the widest bounded pass may stretch the share (the beam's `soft` share of its
            // budget holds every other pass)
            let hard = (beam_cfg.share * beam_cfg.stretch).min(1.0);
            let b = share(budget, 0, 0.0, hard);
            let mut given = BTreeMap::new();
            if hard > beam_cfg.share {
                given.insert("soft".to_string(), (beam_cfg.share / hard).to_string());
            }
            let beam = Run {
                name: "beam",
                given: &given,
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
        let plan = choice.plan(after_beam, sized);
        let mut last: Option<Outcome> = None;
        // the instance travelled backwards, built when a phase first needs it (a copy of the
        // matrix: none when the time runs out before)
        let mut twin: Option<Option<(Instance, CostModel)>> = None;
        for (i, ph) in plan.iter().enumerate() {
            // past the time limit, a later phase would only overrun it (its construction alone
            // can take seconds on large instances): stop with the best so far
            let late = budget
                .time_limit
                .is_some_and(|t| ctx.elapsed() >= t.as_secs_f64());
            // a best that meets the model's floor is optimal: nothing is left to do
            if (late || ctx.solved()) && best.is_some() {
                break;
            }
            // an extra round (`until`) runs only while the rounds before it left the time
            // (`budget` is the context's own: without one, the default limit was set on both)
            if ph.until.is_some_and(|u| ctx.used_share() > u) {
                continue;
            }
            let b = share(budget, ctx.evaluations(), ctx.elapsed(), ph.share);
            let start = match ph.start {
                Start::Fresh => None,
                Start::Best => best.as_ref(),
                Start::Previous => last.as_ref(),
            };
            // how often this solver ran before in the plan: its seed's repeat index
            let repeat = plan[..i].iter().filter(|p| p.solver == ph.solver).count() as u64;
            if ph.reversed && twin.is_none() {
                twin = Some(ctx.instance.reversed_matrix().map(|i| {
                    let m = CostModel::new(&i, ctx.model.objective());
                    (i, m)
                }));
            }
            let on = if ph.reversed {
                twin.as_ref().and_then(|t| t.as_ref())
            } else {
                None
            };
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
            if o.proven_optimal && !ph.reversed {
                return Ok(o);
            }
            keep(&mut best, o.clone());
            last = Some(o);
        }
        let mut out = best.expect("at least one phase ran");
        out.proven_optimal = false;
        Ok(out)
    }
}

/// What `auto` runs on one instance, for `cellseq solve --explain` (text or JSON).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Explanation {
    /// The portfolio: `built-in` or the file's path.
    pub portfolio: String,
    /// The rule chosen (`PLAN_RULE` when the `plan` parameter replaced the selection).
    pub rule: String,
    /// The instance's features.
    pub features: Features,
    /// The beam phase's share of the budget.
    pub beam_share: f64,
    /// Largest instance that gets the beam phase (cells).
    pub beam_max_cells: usize,
    /// Shortest wall-clock budget that gets the beam phase (seconds).
    pub beam_min_seconds: f64,
    /// Up to how many times its share the beam phase's widest bounded pass may take.
    pub beam_stretch: f64,
    /// The phases, in plan syntax.
    pub phases: String,
    /// The phases after a beam phase that ran, when they differ.
    pub after_beam: Option<String>,
    /// The phases for long budgets, when the rule has them (`long` of the portfolio file).
    pub long: Option<String>,
    /// Shortest wall-clock budget (seconds) that gets the `long` phases.
    pub long_min_seconds: Option<f64>,
    /// Smallest evaluation budget, without a time limit, that gets the `long` phases.
    pub long_min_evals: Option<u64>,
    /// Wall-clock seconds the features and the rule selection took on their own (the model
    /// built, before any phase; `auto` spends the same at the start of its budget).
    pub features_seconds: f64,
    /// The same as lines of text.
    #[serde(skip)]
    pub lines: Vec<String>,
}

/// What `auto` with parameters `given` would run on `instance` under `objective`: the
/// portfolio, the rule, the features, the beam settings and the phases.
pub fn explain(
    instance: &Instance,
    objective: crate::model::Objective,
    given: &BTreeMap<String, String>,
) -> Result<Explanation> {
    let params = Params::new(INFO.name, INFO.params, given)?;
    let auto = Auto::from_params(&params)?;
    let model = CostModel::new(instance, objective);
    let clock = std::time::Instant::now();
    let c = auto.choose(&model);
    let features_seconds = clock.elapsed().as_secs_f64();
    let mut lines = c.lines(&auto.portfolio.source);
    lines.push(format!(
        "feature time {features_seconds:.3} s (features and rule selection alone)"
    ));
    Ok(Explanation {
        portfolio: auto.portfolio.source.clone(),
        rule: c.rule.to_string(),
        features: c.features.clone(),
        beam_share: c.beam.share,
        beam_max_cells: c.beam.max_cells,
        beam_min_seconds: c.beam.min_seconds,
        beam_stretch: c.beam.stretch,
        phases: plan_text(c.phases),
        after_beam: c.after_beam.map(plan_text),
        long: c.long.map(|l| plan_text(&l.phases)),
        long_min_seconds: c.long.map(|l| l.min_seconds),
        long_min_evals: c.long.map(|l| l.min_evals),
        features_seconds,
        lines,
    })
}

/// Validates an `auto` portfolio file as `solve` and `run` would read it: the names of its
/// rules, in order (`cellseq check FILE`).
pub fn validate_portfolio(path: &str) -> Result<Vec<String>> {
    let p = Portfolio::load(path)?;
    Ok(p.rules.iter().map(|r| r.name.clone()).collect())
}

/// True when `path` looks like a portfolio file (TOML with `[[rule]]` tables) rather than an
/// experiment plan.
pub fn is_portfolio_file(path: &std::path::Path) -> bool {
    portfolio::is_portfolio_file(path)
}

/// The name `--param portfolio=` takes for the built-in portfolio.
pub const BUILT_IN_PORTFOLIO: &str = portfolio::BUILT_IN_NAME;


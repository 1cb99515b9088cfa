//! The portfolio: rules that map instance [`Features`] to the plan `auto` runs, read from a
//! TOML file (`portfolio.toml` beside this module is built in) into typed structures and
//! validated as a whole before anything runs.
//!
//! A file has a `[beam]` table (the beam phase's default limits) and an ordered list of
//! `[[rule]]` tables, each with a `name`, optional `when` conditions on features, the beam
//! phase's `beam = { share, max_cells?, min_seconds?, stretch? }`, `phases`, optional `after_beam`
//! phases and an optional `long = { min_seconds, min_evals, phases }` plan for long budgets.
//! The first rule whose conditions all hold applies; the last must have none.
//! The format is described for users in `docs/portfolio.md`.

use super::features::Features;
use super::phases::{Phase, Start, check_phase};
use crate::context::Budget;
use crate::error::{Error, Result};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

/// The built-in portfolio's text.
pub const BUILT_IN: &str = include_str!("portfolio.toml");

/// The name that selects the built-in portfolio (the `portfolio` parameter's default).
pub const BUILT_IN_NAME: &str = "built-in";

/// Largest portfolio file read (bytes).
pub const MAX_FILE_BYTES: u64 = 1 << 20;

/// A validated portfolio.
#[derive(Debug, Clone, PartialEq)]
pub struct Portfolio {
    /// Where it came from: [`BUILT_IN_NAME`] or the file's path.
    pub source: String,
    /// Its rules in order; the last one has no conditions.
    pub rules: Vec<Rule>,
}

/// One rule: when it applies and what runs.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    /// Its name (unique in the portfolio), reported with the features.
    pub name: String,
    /// The conditions on features; all must hold.
    pub when: When,
    /// The beam phase's settings.
    pub beam: Beam,
    /// The phases after the beam.
    pub phases: Vec<Phase>,
    /// The phases after a beam phase that ran and did not prove the optimum, if not `phases`.
    pub after_beam: Option<Vec<Phase>>,
    /// The phases that replace `phases` under a long budget, if any.
    pub long: Option<Long>,
}

/// A rule's plan for long budgets: it replaces the rule's `phases` wherever they would run
/// (also after a beam phase that ran, when the rule has no `after_beam` phases, which keep
/// precedence) when the run's budget reaches `min_seconds` of wall clock, or, with an
/// evaluation budget and no time limit, `min_evals` evaluations.
#[derive(Debug, Clone, PartialEq)]
pub struct Long {
    /// Shortest wall-clock budget (seconds) that gets these phases.
    pub min_seconds: f64,
    /// Smallest evaluation budget, without a time limit, that gets these phases.
    pub min_evals: u64,
    /// The phases.
    pub phases: Vec<Phase>,
}

impl Long {
    /// True when a run under `budget` gets these phases: its time limit is at least
    /// `min_seconds`, or, without one, its evaluation budget at least `min_evals` (a run
    /// without either has no end the plan could be sized for, and keeps `phases`).
    pub fn applies(&self, budget: Budget) -> bool {
        match (budget.time_limit, budget.max_evals) {
            (Some(t), _) => t.as_secs_f64() >= self.min_seconds,
            (None, Some(m)) => m >= self.min_evals,
            (None, None) => false,
        }
    }
}

/// The beam proof attempt of a rule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Share of the budget (0: no beam phase).
    pub share: f64,
    /// Largest instance (cells) that gets it.
    pub max_cells: usize,
    /// Shortest wall-clock budget (seconds) that gets it; evaluation budgets always do.
    pub min_seconds: f64,
    /// The beam's widest bounded pass may run up to `stretch` times the share when the pass
    /// before it predicts that it fits (the beam's `soft`); 1: every pass within the share.
    pub stretch: f64,
}

/// Conditions on features: each given one must hold.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct When {
    /// Number of cells.
    pub cells: Option<Range>,
    /// Mean modes per cell.
    pub modes: Option<Range>,
    /// Geometric (true) or cost matrix (false).
    pub geometric: Option<bool>,
    /// Costs that read the same backwards.
    pub symmetric: Option<bool>,
    /// Precedence closure density.
    pub closure_density: Option<Range>,
    /// Closure density among the cells not pinned to the ends.
    pub free_density: Option<Range>,
    /// Share of the cells in the widest precedence level.
    pub widest_level: Option<Range>,
    /// Share of zero-cost arcs.
    pub zero_arcs: Option<Range>,
    /// Coefficient of variation of the arc costs.
    pub cost_spread: Option<Range>,
}

/// A numeric condition: any of `min` (>=), `max` (<=), `above` (>), `below` (<).
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// Lower bound, included.
    pub min: Option<f64>,
    /// Upper bound, included.
    pub max: Option<f64>,
    /// Lower bound, excluded.
    pub above: Option<f64>,
    /// Upper bound, excluded.
    pub below: Option<f64>,
}

/// A bound as (value, strict): −∞/+∞ when absent.
type Bound = (f64, bool);

impl Range {
    /// True when `v` lies in the range.
    pub fn holds(&self, v: f64) -> bool {
        self.min.is_none_or(|m| v >= m)
            && self.max.is_none_or(|m| v <= m)
            && self.above.is_none_or(|m| v > m)
            && self.below.is_none_or(|m| v < m)
    }

    /// The tighter lower and upper bounds.
    fn bounds(&self) -> (Bound, Bound) {
        let lo = match (self.min, self.above) {
            (Some(a), Some(b)) if b >= a => (b, true),
            (Some(a), _) => (a, false),
            (None, Some(b)) => (b, true),
            (None, None) => (f64::NEG_INFINITY, false),
        };
        let hi = match (self.max, self.below) {
            (Some(a), Some(b)) if b <= a => (b, true),
            (Some(a), _) => (a, false),
            (None, Some(b)) => (b, true),
            (None, None) => (f64::INFINITY, false),
        };
        (lo, hi)
    }

    /// True when no value lies in the range.
    fn is_empty(&self) -> bool {
        let ((lo, ls), (hi, hs)) = self.bounds();
        lo > hi || (lo == hi && (ls || hs))
    }

    /// True when every value in `self` lies in `outer`.
    fn within(&self, outer: &Range) -> bool {
        let ((lo, ls), (hi, hs)) = self.bounds();
        let ((olo, ols), (ohi, ohs)) = outer.bounds();
        let lower = lo > olo || (lo == olo && (ls || !ols));
        let upper = hi < ohi || (hi == ohi && (hs || !ohs));
        lower && upper
    }

    /// The bounds that are not finite numbers, by key.
    fn non_finite(&self) -> Option<&'static str> {
        [
            ("min", self.min),
            ("max", self.max),
            ("above", self.above),
            ("below", self.below),
        ]
        .into_iter()
        .find(|(_, v)| v.is_some_and(|x| !x.is_finite()))
        .map(|(k, _)| k)
    }
}

impl When {
    /// The numeric conditions with their feature names.
    fn ranges(&self) -> [(&'static str, Option<&Range>); 7] {
        [
            ("cells", self.cells.as_ref()),
            ("modes", self.modes.as_ref()),
            ("closure_density", self.closure_density.as_ref()),
            ("free_density", self.free_density.as_ref()),
            ("widest_level", self.widest_level.as_ref()),
            ("zero_arcs", self.zero_arcs.as_ref()),
            ("cost_spread", self.cost_spread.as_ref()),
        ]
    }

    /// The boolean conditions with their feature names.
    fn flags(&self) -> [(&'static str, Option<bool>); 2] {
        [("geometric", self.geometric), ("symmetric", self.symmetric)]
    }

    /// True when every condition holds for `f`.
    pub fn holds(&self, f: &Features) -> bool {
        let flags = self
            .flags()
            .into_iter()
            .all(|(k, want)| want.is_none_or(|w| f.value(k) == Some(if w { 1.0 } else { 0.0 })));
        flags
            && self
                .ranges()
                .into_iter()
                .all(|(k, r)| r.is_none_or(|r| f.value(k).is_some_and(|v| r.holds(v))))
    }

    /// True when there are no conditions (a catch-all).
    pub fn is_empty(&self) -> bool {
        self == &When::default()
    }

    /// True when every instance that meets `self` meets `outer` as well.
    fn within(&self, outer: &When) -> bool {
        let flags = self
            .flags()
            .into_iter()
            .zip(outer.flags())
            .all(|((_, mine), (_, theirs))| theirs.is_none() || mine == theirs);
        flags
            && self
                .ranges()
                .into_iter()
                .zip(outer.ranges())
                .all(|((_, mine), (_, theirs))| match (mine, theirs) {
                    (_, None) => true,
                    (None, Some(_)) => false,
                    (Some(m), Some(t)) => m.within(t),
                })
    }
}

// ---- the file as written ----

/// Largest `beam.stretch`.
pub const MAX_STRETCH: f64 = 10.0;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileText {
    beam: BeamDefaults,
    #[serde(default)]
    rule: Vec<RuleText>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BeamDefaults {
    max_cells: usize,
    min_seconds: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RuleText {
    name: String,
    #[serde(default)]
    when: When,
    beam: BeamText,
    phases: Vec<PhaseText>,
    #[serde(default)]
    after_beam: Option<Vec<PhaseText>>,
    #[serde(default)]
    long: Option<LongText>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LongText {
    min_seconds: f64,
    min_evals: f64,
    phases: Vec<PhaseText>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BeamText {
    share: f64,
    max_cells: Option<usize>,
    min_seconds: Option<f64>,
    stretch: Option<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PhaseText {
    solver: String,
    share: f64,
    #[serde(default)]
    start: Start,
    #[serde(default)]
    backwards: bool,
    #[serde(default)]
    params: BTreeMap<String, toml::Value>,
    #[serde(default)]
    until: Option<f64>,
}

/// 1-based line of byte offset `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// True when the file at `path` reads as a portfolio rather than an experiment plan: a
/// regular file of at most [`MAX_FILE_BYTES`] with a `[[rule]]` table (how `cellseq check`
/// tells the two apart).
pub fn is_portfolio_file(path: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(path) else {
        return false;
    };
    let mut text = String::new();
    meta.is_file()
        && meta.len() <= MAX_FILE_BYTES
        && std::fs::File::open(path)
            .and_then(|f| f.take(MAX_FILE_BYTES).read_to_string(&mut text))
            .is_ok()
        && text.lines().any(|l| l.trim_start().starts_with("[[rule]]"))
}

impl Portfolio {
    /// The built-in portfolio.
    pub fn built_in() -> Result<Portfolio> {
        Portfolio::parse(BUILT_IN_NAME, BUILT_IN)
    }

    /// The portfolio named by the `portfolio` parameter: [`BUILT_IN_NAME`] or a file path.
    pub fn load(spec: &str) -> Result<Portfolio> {
        if spec == BUILT_IN_NAME {
            return Portfolio::built_in();
        }
        let path = Path::new(spec);
        let meta = std::fs::metadata(path).map_err(|e| Error::io(spec, e))?;
        if !meta.is_file() {
            return Err(Error::invalid(spec, "a portfolio must be a regular file"));
        }
        let mut text = String::new();
        std::fs::File::open(path)
            .and_then(|f| f.take(MAX_FILE_BYTES + 1).read_to_string(&mut text))
            .map_err(|e| Error::io(spec, e))?;
        if text.len() as u64 > MAX_FILE_BYTES {
            return Err(Error::invalid(
                spec,
                format!("a portfolio file may hold at most {MAX_FILE_BYTES} bytes"),
            ));
        }
        Portfolio::parse(spec, &text)
    }

    /// Parses and validates the portfolio `text` read from `file` (named in every error).
    pub fn parse(file: &str, text: &str) -> Result<Portfolio> {
        let raw: FileText = toml::from_str(text).map_err(|e| match e.span() {
            Some(s) => Error::parse(file, line_of(text, s.start), e.message().trim()),
            None => Error::invalid(file, e.message().trim()),
        })?;
        let bad = |m: String| Error::invalid(file, m);
        let d = &raw.beam;
        seconds("[beam] min_seconds", d.min_seconds).map_err(bad)?;
        if raw.rule.is_empty() {
            return Err(bad(
                "no [[rule]]: a portfolio needs at least a catch-all rule".into(),
            ));
        }
        let mut rules: Vec<Rule> = Vec::new();
        for (i, r) in raw.rule.iter().enumerate() {
            let what = format!("rule {} '{}'", i + 1, r.name);
            let rule = rule_of(r, d).map_err(|m| bad(format!("{what}: {m}")))?;
            if let Some(prev) = rules.iter().find(|p| p.name == rule.name) {
                return Err(bad(format!(
                    "{what}: the name is used by an earlier rule ('{}')",
                    prev.name
                )));
            }
            if let Some(prev) = rules.iter().find(|p| rule.when.within(&p.when)) {
                return Err(bad(format!(
                    "{what} is never reached: every instance it matches is taken by the earlier rule '{}'",
                    prev.name
                )));
            }
            rules.push(rule);
        }
        let last = rules.last().expect("at least one rule");
        if !last.when.is_empty() {
            return Err(bad(format!(
                "the last rule ('{}') has conditions; the last rule must have none (a \
                 catch-all), so that every instance gets a plan",
                last.name
            )));
        }
        Ok(Portfolio {
            source: file.to_string(),
            rules,
        })
    }

    /// The rule that applies to an instance with features `f`: the first whose conditions
    /// hold (the last one always does).
    pub fn select(&self, f: &Features) -> &Rule {
        self.rules
            .iter()
            .find(|r| r.when.holds(f))
            .unwrap_or_else(|| self.catch_all())
    }

    /// The last rule, which has no conditions.
    pub fn catch_all(&self) -> &Rule {
        self.rules.last().expect("a validated portfolio has rules")
    }
}

/// A validated [`Rule`] from its text; `Err` is the message (the caller names the rule).
fn rule_of(r: &RuleText, d: &BeamDefaults) -> std::result::Result<Rule, String> {
    if r.name.trim().is_empty() || r.name.chars().any(char::is_control) {
        return Err("a rule needs a name (printable, not empty)".into());
    }
    for (k, range) in r.when.ranges() {
        if let Some(range) = range {
            if let Some(b) = range.non_finite() {
                return Err(format!("when.{k}.{b} must be a finite number"));
            }
            if *range == Range::default() {
                return Err(format!(
                    "when.{k} gives no bound (min, max, above or below)"
                ));
            }
            if range.is_empty() {
                return Err(format!("when.{k} is empty: no value satisfies it"));
            }
        }
    }
    let b = &r.beam;
    if !(b.share.is_finite() && (0.0..=1.0).contains(&b.share)) {
        return Err(format!("beam.share must be in [0, 1], got {}", b.share));
    }
    let min_seconds = seconds("beam.min_seconds", b.min_seconds.unwrap_or(d.min_seconds))?;
    let stretch = b.stretch.unwrap_or(1.0);
    if !(stretch.is_finite() && (1.0..=MAX_STRETCH).contains(&stretch)) {
        return Err(format!(
            "beam.stretch must be in [1, {MAX_STRETCH}], got {stretch}"
        ));
    }
    let beam = Beam {
        share: b.share,
        max_cells: b.max_cells.unwrap_or(d.max_cells),
        min_seconds,
        stretch,
    };
    let phases = phases_of(&r.phases).map_err(|m| format!("phases: {m}"))?;
    let after_beam = match &r.after_beam {
        Some(p) => Some(phases_of(p).map_err(|m| format!("after_beam: {m}"))?),
        None => None,
    };
    if after_beam.is_some() && beam.share == 0.0 {
        return Err("after_beam is never used: beam.share is 0".into());
    }
    let long = match &r.long {
        Some(l) => Some(long_of(l)?),
        None => None,
    };
    Ok(Rule {
        name: r.name.clone(),
        when: r.when.clone(),
        beam,
        phases,
        after_beam,
        long,
    })
}

/// `v` when it is a number of seconds a portfolio may give (finite, at least 0); else the
/// message naming `key`.
fn seconds(key: &str, v: f64) -> std::result::Result<f64, String> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{key} must be a number >= 0, got {v}"))
    }
}

/// Largest `long.min_evals` a portfolio may give.
pub const MAX_LONG_EVALS: f64 = 1e15;

/// A validated [`Long`] plan from its text.
fn long_of(l: &LongText) -> std::result::Result<Long, String> {
    let min_seconds = seconds("long.min_seconds", l.min_seconds)?;
    if !(l.min_evals.is_finite() && (0.0..=MAX_LONG_EVALS).contains(&l.min_evals)) {
        return Err(format!(
            "long.min_evals must be a number in [0, {MAX_LONG_EVALS:e}], got {}",
            l.min_evals
        ));
    }
    let phases = phases_of(&l.phases).map_err(|m| format!("long.phases: {m}"))?;
    Ok(Long {
        min_seconds,
        min_evals: l.min_evals as u64,
        phases,
    })
}

/// Validated phases from their text.
fn phases_of(list: &[PhaseText]) -> std::result::Result<Vec<Phase>, String> {
    if list.is_empty() {
        return Err("no phases".into());
    }
    let mut out = Vec::new();
    for (i, p) in list.iter().enumerate() {
        let mut params = BTreeMap::new();
        for (k, v) in &p.params {
            let v = crate::params::toml_text(v).ok_or_else(|| {
                format!(
                    "phase {} ({}): parameter '{k}' is not a single value",
                    i + 1,
                    p.solver
                )
            })?;
            params.insert(k.clone(), v);
        }
        let ph = Phase {
            solver: p.solver.clone(),
            share: p.share,
            start: p.start,
            reversed: p.backwards,
            params,
            until: p.until,
        };
        check_phase(&ph, i).map_err(|m| format!("phase {} ({}): {m}", i + 1, p.solver))?;
        out.push(ph);
    }
    Ok(out)
}

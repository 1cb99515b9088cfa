//! Phases of a plan: the typed [`Phase`], the checks every phase passes, and the compact plan
//! syntax of the `plan` parameter (`solver[key=value;...]:share,...`).

use crate::error::{Error, Result};
use serde::Deserialize;
use std::collections::BTreeMap;

/// Where a plan phase starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Start {
    /// From scratch (the solver's own construction).
    #[default]
    Fresh,
    /// From the best sequence so far (`*` after the name; gls, ils, eacs, reopt and corridor only).
    Best,
    /// From the sequence of the phase just before (`+`; gls, ils, eacs, reopt and corridor only): polishes one
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
    /// The phase is skipped once more than this share of the plan's budget is used (`@U`
    /// after the share; `None`: it always runs). Extra rounds of a plan so run only when the
    /// rounds before them ended early, and never take the time of the phases after them.
    pub until: Option<f64>,
}

impl Phase {
    /// The phase in plan syntax (`~eacs[key=value]*:0.5`), for traces and explanations.
    pub fn text(&self) -> String {
        let params = if self.params.is_empty() {
            String::new()
        } else {
            let kv: Vec<String> = self
                .params
                .iter()
                .map(|(k, v)| format!("{k}={v}"))
                .collect();
            format!("[{}]", kv.join(";"))
        };
        let start = match self.start {
            Start::Fresh => "",
            Start::Best => "*",
            Start::Previous => "+",
        };
        let until = self.until.map(|u| format!("@{u}")).unwrap_or_default();
        format!(
            "{}{}{params}{start}:{}{until}",
            if self.reversed { "~" } else { "" },
            self.solver,
            self.share
        )
    }
}

/// A list of phases in plan syntax, comma-separated.
pub fn plan_text(phases: &[Phase]) -> String {
    phases.iter().map(Phase::text).collect::<Vec<_>>().join(",")
}

/// Checks phase `ph`, the `index`-th of its plan (0-based): a registered solver other than
/// `auto` whose parameters build it, a share in (0, 1], a start the solver can take, and a
/// `previous` start only after another phase. The message names what is wrong.
pub fn check_phase(ph: &Phase, index: usize) -> std::result::Result<(), String> {
    if !(ph.share.is_finite() && ph.share > 0.0 && ph.share <= 1.0) {
        return Err(format!("share must be in (0, 1], got {}", ph.share));
    }
    if let Some(u) = ph.until
        && !(u.is_finite() && u > 0.0 && u <= 1.0)
    {
        return Err(format!("until must be in (0, 1], got {u}"));
    }
    if ph.solver == "auto" {
        return Err("a plan cannot contain auto itself".to_string());
    }
    let info = super::super::find(&ph.solver).map_err(|e| e.to_string())?;
    info.check_params(&ph.params).map_err(|e| e.to_string())?;
    if ph.start != Start::Fresh && !info.starts_from() {
        return Err(format!(
            "only {} can start from an earlier sequence",
            startable()
        ));
    }
    if ph.start == Start::Previous && index == 0 {
        return Err("the first phase has no phase before it to follow".to_string());
    }
    Ok(())
}

/// Parses a plan `[~]solver[key=value;...][*|+]:share[@until],...` (parameters in brackets
/// and `@until` are optional; parameters are checked against the solver's declared ones).
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
        let (share, until) = match share.split_once('@') {
            Some((s, u)) => {
                let u: f64 = u.trim().parse().map_err(|_| {
                    bad(format!(
                        "plan phase '{part}': until (after @) must be a number in (0, 1]"
                    ))
                })?;
                (s, Some(u))
            }
            None => (share, None),
        };
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
        let phase = Phase {
            solver,
            share,
            start,
            reversed,
            params,
            until,
        };
        check_phase(&phase, out.len()).map_err(|e| bad(format!("plan phase '{part}': {e}")))?;
        out.push(phase);
    }
    if out.is_empty() {
        return Err(bad("empty plan".to_string()));
    }
    Ok(out)
}

/// The solvers a plan phase can start from an earlier sequence (`*`, `+`): those whose
/// capabilities say `starts_from`, as "gls, ils, eacs, reopt and corridor".
fn startable() -> String {
    let mut names: Vec<&str> = super::super::registry()
        .into_iter()
        .filter(|i| i.starts_from())
        .map(|i| i.name)
        .collect();
    names.sort_by_key(|n| (n.len(), *n));
    match names.split_last() {
        Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
        Some((last, _)) => last.to_string(),
        None => "no solver".to_string(),
    }
}

/// The seed of a plan phase: the run's own seed for the first phase of each solver, so
/// that a plan naming each solver once draws the streams it always drew, and a different
/// seed for each repeat (`eacs:0.4,eacs:0.6` runs two independent colonies).
pub fn phase_seed(seed: u64, repeat: u64) -> u64 {
    seed.wrapping_add(repeat.wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

//! The G-code pipeline: groups of cells in their required order → one instance per group →
//! solver (with the group's share of the command's budget) → the group's original order kept
//! where the solver's is not better → write → verify (state-tagged cutting moves, events, no
//! new motion) → never worse than the input on air, lifts and time, else the original order.

use super::{Allowance, Timings, solve_group};
use crate::error::Result;
use crate::io::gcode::{self, Figures, Parsed, reverse, verify_with, write};
use crate::model::Objective;
use crate::solvers;
use std::time::Instant;

/// Options of [`optimize`].
#[derive(Debug, Clone)]
pub struct Options {
    /// Solver from the registry.
    pub solver: String,
    /// Time limit (s) of the whole command (parse, solve, verify, write).
    pub time_limit: Option<f64>,
    /// Evaluation budget shared among groups by size (deterministic).
    pub max_evals: Option<u64>,
    /// Seed.
    pub seed: u64,
    /// Merge blocks of the same tool.
    pub merge: bool,
    /// XY margin (mm) added to footprints for the overlap rule.
    pub margin: f64,
    /// Allow cutting reversible cells backwards: `Some(true)` (`--reversible`), `Some(false)`
    /// (`--no-reversible`), or `None`: on for 2-D programs (laser, plasma, plotter), off for
    /// programs with Z (milling, where reversal swaps climb and conventional milling).
    pub reversible: Option<bool>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            solver: solvers::DEFAULT_SOLVER.to_string(),
            time_limit: None,
            max_evals: None,
            seed: 1,
            merge: false,
            margin: 0.5,
            reversible: None,
        }
    }
}

/// Where the original order was kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Kept {
    /// The solver's order was used in every group.
    Nothing,
    /// The original order was kept in this many groups (the solver did not improve them).
    Groups(usize),
    /// The whole program was kept as it is: the new order was worse on air, lifts or time.
    Whole,
}

/// The result of [`optimize`].
#[derive(Debug, Clone)]
pub struct Optimized {
    /// The new order (indices into the layout's cells).
    pub order: Vec<usize>,
    /// Parallel to `order`: true where the cell is cut backwards.
    pub reversed: Vec<bool>,
    /// Cells that could have been reversed (reversal on and the cell qualifies).
    pub reversible_cells: usize,
    /// True when reversal was on.
    pub reversal_on: bool,
    /// The new program text.
    pub text: String,
    /// Figures of the original.
    pub before: Figures,
    /// Figures of the new program.
    pub after: Figures,
    /// Cutting moves compared.
    pub cuts: usize,
    /// Non-motion events compared (dwells, pauses, tool changes).
    pub events: usize,
    /// Groups sequenced independently.
    pub groups: usize,
    /// Groups where the inner-first rule was dropped.
    pub inner_first_dropped: usize,
    /// Where the original order was kept.
    pub kept: Kept,
    /// Where the time went (parse is filled in by the caller).
    pub timings: Timings,
    /// Why the whole program was kept as it is, when it was.
    pub note: Option<String>,
}

/// The figures on which `after` is worse than `before`.
fn worse_on(after: &Figures, before: &Figures) -> String {
    let mut v = Vec::new();
    if after.air_length > before.air_length + 1e-9 {
        v.push(format!(
            "air travel ({:.1} > {:.1} mm)",
            after.air_length, before.air_length
        ));
    }
    if after.lifts > before.lifts {
        v.push(format!("lifts ({} > {})", after.lifts, before.lifts));
    }
    if after.est_time_s > before.est_time_s + 1e-9 {
        v.push(format!(
            "estimated time ({:.1} > {:.1} s)",
            after.est_time_s, before.est_time_s
        ));
    }
    v.join(", ")
}

impl Optimized {
    /// True when any original order was kept (in a group or the whole program).
    pub fn kept_original(&self) -> bool {
        self.kept != Kept::Nothing
    }
}

/// [`optimize_within`] with an allowance starting now, from the options' budget.
pub fn optimize(p: &Parsed, opts: &Options) -> Result<Optimized> {
    optimize_within(p, opts, &Allowance::new(opts.time_limit, opts.max_evals))
}

/// Sequences the cells group by group with a registry solver, writes the program, verifies it
/// against the original and keeps the original order where the new one is not better. The
/// allowance's time limit covers what is left of the whole command.
pub fn optimize_within(p: &Parsed, opts: &Options, allowance: &Allowance) -> Result<Optimized> {
    let l = &p.layout;
    let on = gcode::reversal_on(p, opts.reversible);
    let pl = gcode::plans(p, on);
    let gs = gcode::groups(p, opts.merge);
    let total: usize = l.cells.len();
    let mut timings = Timings::default();
    // keep time for writing and verifying: both are linear in the program, about twice a parse
    let reserve_s =
        0.02 * allowance.time_limit.unwrap_or(0.0) + 1e-6 * p.program.lines.len() as f64 * 4.0;
    let t_solve = Instant::now();
    let mut order = Vec::with_capacity(total);
    let mut rev: Vec<Option<reverse::Plan>> = Vec::with_capacity(total);
    let mut home = l.start.unwrap_or(l.cells[0].entry);
    let mut dropped = 0;
    let mut kept_groups = 0;
    let mut left = total;
    let mut spans: Vec<(usize, usize)> = Vec::with_capacity(gs.len());
    for g in &gs {
        let (inst, d) = gcode::group_instance(p, g, home, opts.margin, &pl);
        dropped += d as usize;
        let budget = allowance.share(g.len(), left, total, reserve_s);
        left -= g.len();
        let r = if g.len() == 1 {
            None
        } else {
            Some(solve_group(
                &inst,
                Objective::Air,
                &opts.solver,
                &Default::default(),
                opts.seed,
                budget,
            )?)
        };
        let seq = match &r {
            Some(r) => r.sequence.clone(),
            None => super::original_order(&inst),
        };
        if r.as_ref().is_some_and(|r| r.kept_original) {
            kept_groups += 1;
        }
        let from = order.len();
        for v in &seq {
            order.push(g[v.cell]);
            rev.push(if v.mode == 1 { pl[g[v.cell]] } else { None });
        }
        spans.push((from, order.len()));
        if let Some(v) = seq.last() {
            home = match rev.last().copied().flatten() {
                Some(x) => x.exit,
                None => l.cells[g[v.cell]].exit,
            };
        }
    }
    timings.solve_s = t_solve.elapsed().as_secs_f64();
    let given: Vec<usize> = (0..total).collect();
    let mut kept = if kept_groups > 0 {
        Kept::Groups(kept_groups)
    } else {
        Kept::Nothing
    };
    let mut note = None;
    let mut result = None;
    // the groups whose order changed, reverted one by one (at most 64 tries) while the
    // program is worse than the input on any figure
    let changed: Vec<usize> = (0..gs.len())
        .filter(|&k| {
            let (a, b) = spans[k];
            order[a..b] != gs[k][..] || rev[a..b].iter().any(Option::is_some)
        })
        .collect();
    let any_changed = !changed.is_empty();
    let mut changed = changed.into_iter();
    for attempt in 0..=64 {
        let t = Instant::now();
        let written = write::write_checked(&p.program, &p.layout, &order, &rev, opts.merge);
        timings.write_s += t.elapsed().as_secs_f64();
        match written {
            Ok(text) => {
                let t = Instant::now();
                let verified = verify_with(p, "<optimized>", &text, on);
                timings.verify_s += t.elapsed().as_secs_f64();
                match verified {
                    // never worse than the input on air, lifts and time, each one
                    Ok(check) if check.after.not_worse_than(&check.before) || order == given => {
                        result = Some((text, check));
                        break;
                    }
                    Ok(check) => {
                        note.get_or_insert(format!(
                            "the new order was worse on {}",
                            worse_on(&check.after, &check.before)
                        ));
                    }
                    // when in doubt, keep the original: a failed check reverts groups too
                    Err(e) => {
                        note.get_or_insert(format!("the new order failed the built-in check: {e}"));
                    }
                }
            }
            Err(m) => {
                note.get_or_insert(m);
            }
        }
        let Some(k) = changed.next().filter(|_| attempt < 64) else {
            break;
        };
        let (a, b) = spans[k];
        order[a..b].copy_from_slice(&gs[k]);
        rev[a..b].iter_mut().for_each(|r| *r = None);
        kept_groups += 1;
        kept = Kept::Groups(kept_groups);
    }
    if any_changed && order == given && rev.iter().all(Option::is_none) && result.is_some() {
        // every changed group had to be reverted: the program is the input as it is
        kept = Kept::Whole;
    }
    let (text, check) = match result {
        Some(r) => r,
        None => {
            // the input's own order: every cell next to its original neighbours, so the
            // program is written as it is
            let t = Instant::now();
            let text = write::write_checked(&p.program, &p.layout, &given, &[], false)
                .map_err(|m| crate::Error::invalid(&p.file, m))?;
            timings.write_s += t.elapsed().as_secs_f64();
            let t = Instant::now();
            let check = verify_with(p, "<optimized>", &text, false)?;
            timings.verify_s += t.elapsed().as_secs_f64();
            order = given;
            rev.clear();
            kept = Kept::Whole;
            (text, check)
        }
    };
    let mut reversed: Vec<bool> = rev.iter().map(Option::is_some).collect();
    reversed.resize(order.len(), false);
    Ok(Optimized {
        kept,
        reversible_cells: pl.iter().filter(|x| x.is_some()).count(),
        reversal_on: on,
        reversed,
        order,
        text,
        before: check.before,
        after: check.after,
        cuts: check.cuts,
        events: check.events,
        groups: gs.len(),
        inner_first_dropped: dropped,
        timings,
        note,
    })
}

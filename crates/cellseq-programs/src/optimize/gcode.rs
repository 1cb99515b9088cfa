//! The G-code pipeline: groups of cells in their required order → one instance per group →
//! solver (with the group's share of the command's budget) → the group's original order kept
//! where the solver's is not better → write → verify (state-tagged cutting moves, events, no
//! new motion) → never worse than the input on air, lifts and time, else the original order.

use super::{Allowance, Timings, solve_group};
use crate::gcode::{self, Figures, Parsed, Verification, Verifier, reverse, write};
use cellseq::SolverKind;
use cellseq::error::Result;
use cellseq::model::Objective;
use std::time::Instant;

/// Options of [`optimize`].
#[derive(Debug, Clone)]
pub struct Options {
    /// The solver.
    pub solver: SolverKind,
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
            solver: SolverKind::default(),
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
    optimize_within(p, opts, &Allowance::new(opts.time_limit, opts.max_evals)?)
}

/// Sequences the cells group by group with a registry solver, writes the program, verifies it
/// against the original and keeps the original order where the new one is not better. The
/// allowance's time limit covers what is left of the whole command.
pub fn optimize_within(p: &Parsed, opts: &Options, allowance: &Allowance) -> Result<Optimized> {
    let on = gcode::reversal_on(p, opts.reversible);
    let pl = gcode::plans(p, on);
    let gs = gcode::groups(p, opts.merge);
    let mut timings = Timings::default();
    let reserve_s = reserve_s(p, allowance);
    let t_solve = Instant::now();
    let mut s = solve_groups(p, opts, allowance, reserve_s, &gs, &pl)?;
    timings.solve_s = t_solve.elapsed().as_secs_f64();
    let t_verify = Instant::now();
    let verifier = Verifier::new(p, on)?;
    timings.verify_s += t_verify.elapsed().as_secs_f64();
    let (result, note) = write_verified(p, opts, allowance, &verifier, &gs, &mut s, &mut timings);
    let given: Vec<usize> = (0..p.layout.cells.len()).collect();
    let mut kept = match s.kept_groups {
        0 => Kept::Nothing,
        k => Kept::Groups(k),
    };
    if s.any_changed && s.order == given && s.rev.iter().all(Option::is_none) && result.is_some() {
        // every changed group had to be reverted: the program is the input as it is
        kept = Kept::Whole;
    }
    let (text, check) = match result {
        Some(r) => r,
        None => {
            let r = write_original(p, &mut timings)?;
            s.order = given;
            s.rev.clear();
            kept = Kept::Whole;
            r
        }
    };
    let mut reversed: Vec<bool> = s.rev.iter().map(Option::is_some).collect();
    reversed.resize(s.order.len(), false);
    Ok(Optimized {
        kept,
        reversible_cells: pl.iter().filter(|x| x.is_some()).count(),
        reversal_on: on,
        reversed,
        order: s.order,
        text,
        before: check.before,
        after: check.after,
        cuts: check.cuts,
        events: check.events,
        groups: gs.len(),
        inner_first_dropped: s.dropped,
        timings,
        note,
    })
}

/// The groups' orders as the solver left them.
struct Solved {
    /// The new order (layout cell indices).
    order: Vec<usize>,
    /// Parallel to `order`: the reversal plan of a cell cut backwards.
    rev: Vec<Option<reverse::Plan>>,
    /// Per group, its positions in `order`.
    spans: Vec<(usize, usize)>,
    /// Groups where the solver's order was not better (or that were reverted since).
    kept_groups: usize,
    /// Groups where the inner-first rule was dropped.
    dropped: usize,
    /// True when any group's order or direction changed.
    any_changed: bool,
}

/// Seconds of the time limit kept for writing and verifying. Both are linear in the program
/// and together cost a little more than reading it (1.2–1.8× on generated programs of 10^5
/// cells with 1–10 moves each, `scripts/gcode-scale.sh`), so the reserve is twice the time
/// spent before solving (reading and parsing, measured on this machine under its current
/// load), at least 4 µs per line, plus 2 % of the limit.
fn reserve_s(p: &Parsed, allowance: &Allowance) -> f64 {
    let before = allowance.started.elapsed().as_secs_f64();
    let per_line = 4e-6 * p.program.lines.len() as f64;
    0.02 * allowance.time_limit.unwrap_or(0.0) + per_line.max(2.0 * before)
}

/// Solves every group in its fixed order with its share of the allowance (less `reserve_s`
/// for writing and verifying), each group starting where the previous one ended.
fn solve_groups(
    p: &Parsed,
    opts: &Options,
    allowance: &Allowance,
    reserve_s: f64,
    gs: &[Vec<usize>],
    pl: &[Option<reverse::Plan>],
) -> Result<Solved> {
    let l = &p.layout;
    let total: usize = l.cells.len();
    let mut s = Solved {
        order: Vec::with_capacity(total),
        rev: Vec::with_capacity(total),
        spans: Vec::with_capacity(gs.len()),
        kept_groups: 0,
        dropped: 0,
        any_changed: false,
    };
    let mut home = l.start.unwrap_or(l.cells[0].entry);
    let mut left = total;
    let mut prev_block = l.cells[0].block;
    for g in gs {
        // a block whose tool change goes to a fixed place starts from there
        let b = l.cells[g[0]].block;
        if b != prev_block
            && let Some(h) = gcode::cells::preamble_home(&p.program, &l.blocks[b])
        {
            home = h;
        }
        let (inst, d) = gcode::group_instance(p, g, home, opts.margin, pl);
        s.dropped += d as usize;
        let budget = allowance.share(g.len(), left, total, reserve_s);
        left -= g.len();
        let r = if g.len() == 1 {
            None
        } else {
            Some(solve_group(
                &inst,
                Objective::Air,
                opts.solver,
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
            s.kept_groups += 1;
        }
        let from = s.order.len();
        for v in &seq {
            s.order.push(g[v.cell]);
            s.rev.push(if v.mode == 1 { pl[g[v.cell]] } else { None });
        }
        s.spans.push((from, s.order.len()));
        if let Some(v) = seq.last() {
            prev_block = l.cells[g[v.cell]].block;
            home = match s.rev.last().copied().flatten() {
                Some(x) => x.exit,
                None => l.cells[g[v.cell]].exit,
            };
        }
    }
    s.any_changed = (0..gs.len()).any(|k| group_changed(&s, gs, k));
    Ok(s)
}

/// True when group `k`'s order or direction differs from the program's.
fn group_changed(s: &Solved, gs: &[Vec<usize>], k: usize) -> bool {
    let (a, b) = s.spans[k];
    s.order[a..b] != gs[k][..] || s.rev[a..b].iter().any(Option::is_some)
}

/// Writes and verifies the new program; while it fails the check or is worse than the input
/// on any figure, reverts the changed groups one by one (at most 64 tries). Returns the
/// program and its check, or none (with why) when no try passed.
fn write_verified(
    p: &Parsed,
    opts: &Options,
    allowance: &Allowance,
    verifier: &Verifier,
    gs: &[Vec<usize>],
    s: &mut Solved,
    timings: &mut Timings,
) -> (Option<(String, Verification)>, Option<String>) {
    let given: Vec<usize> = (0..p.layout.cells.len()).collect();
    let mut note = None;
    let changed: Vec<usize> = (0..gs.len()).filter(|&k| group_changed(s, gs, k)).collect();
    let mut changed = changed.into_iter();
    for attempt in 0..=64 {
        let t_attempt = Instant::now();
        let t = Instant::now();
        let written = write::write_checked(&p.program, &p.layout, &s.order, &s.rev, opts.merge);
        timings.write_s += t.elapsed().as_secs_f64();
        match written {
            Ok(text) => {
                let t = Instant::now();
                let verified = verifier.check("<optimized>", &text);
                timings.verify_s += t.elapsed().as_secs_f64();
                match verified {
                    // never worse than the input on air, lifts and time, each one
                    Ok(check) if check.after.not_worse_than(&check.before) || s.order == given => {
                        return (Some((text, check)), note);
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
        // another try costs about as much as this one: past the time limit, stop reverting
        // group by group and let the caller write the original
        let attempt_s = t_attempt.elapsed().as_secs_f64();
        if allowance.remaining_s().is_some_and(|r| r < attempt_s) {
            note = Some(format!(
                "{}; the time limit ran out while reverting groups one by one",
                note.unwrap_or_default()
            ));
            break;
        }
        let Some(k) = changed.next().filter(|_| attempt < 64) else {
            break;
        };
        let (a, b) = s.spans[k];
        s.order[a..b].copy_from_slice(&gs[k]);
        s.rev[a..b].iter_mut().for_each(|r| *r = None);
        s.kept_groups += 1;
    }
    (None, note)
}

/// The input's own order: every cell next to its original neighbours, so the program is
/// written as it is; checked in the original direction.
fn write_original(p: &Parsed, timings: &mut Timings) -> Result<(String, Verification)> {
    let given: Vec<usize> = (0..p.layout.cells.len()).collect();
    let t = Instant::now();
    let text = write::write_checked(&p.program, &p.layout, &given, &[], false)
        .map_err(|m| cellseq::Error::invalid(&p.file, m))?;
    timings.write_s += t.elapsed().as_secs_f64();
    let t = Instant::now();
    let check = Verifier::new(p, false)?.check("<optimized>", &text)?;
    timings.verify_s += t.elapsed().as_secs_f64();
    Ok((text, check))
}

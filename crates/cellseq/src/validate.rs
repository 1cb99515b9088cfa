//! Structural validation of instances: everything a solver may rely on.
//!
//! An instance that passes [`validate`] can be handed to every solver: its precedence,
//! together with the fixed first and last cells, is acyclic; every number is finite and
//! within the [limits](self#limits) below, so no cost any sequence can have overflows; and
//! every reference (tool, cell, mode) resolves. `cellseq validate` and `cellseq solve` run the
//! same checks, so they agree.
//!
//! # Limits
//!
//! The bounds keep every cost of every sequence finite (and far from `f64` overflow) while
//! leaving room for anything a machine or a benchmark file holds:
//!
//! - coordinates, depths and the clearance height: |v| ≤ [`MAX_COORD`] = 10⁹ mm (1000 km), so
//!   any distance is below 3.5·10⁹ mm and one move's air path below 1.4·10¹⁰ mm;
//! - feeds ≥ [`MIN_FEED`] = 10⁻³ mm/min, so no rate exceeds 6·10⁴ s/mm and one move takes
//!   at most about 10¹⁵ s;
//! - lift and tool-change times ≤ [`MAX_TIME`] = 10⁹ s; cut lengths ≤ [`MAX_LENGTH`] = 10¹² mm;
//! - matrix entries in 0..=[`MAX_MATRIX_COST`] = 10¹² (TSPLIB's forbidden arcs are stored as
//!   10⁹); negative entries are refused.
//!
//! With at most 2³² nodes a path therefore costs below 10²⁹, nowhere near 1.8·10³⁰⁸; on top of
//! the limits, [`cost_bound`] computes an upper bound on the cost of any sequence from the
//! instance's own numbers and validation refuses the instance if it is not finite.

use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{CostMatrix, Instance};
use crate::precedence::{Dag, topological_order};
use std::collections::HashMap;

/// Largest magnitude of a coordinate, depth or clearance height (mm).
pub const MAX_COORD: f64 = 1.0e9;
/// Smallest feed (mm/min).
pub const MIN_FEED: f64 = 1.0e-3;
/// Largest lift or tool-change time (s).
pub const MAX_TIME: f64 = 1.0e9;
/// Largest cut length of a cell and largest link distance (mm).
pub const MAX_LENGTH: f64 = 1.0e12;
/// Largest explicit matrix cost.
pub const MAX_MATRIX_COST: f64 = 1.0e12;

type Check = std::result::Result<(), String>;

/// A number for a message: plain, or in exponent form when very large or very small.
pub fn show(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-6..1e15).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// Validates `inst`; `file` names the source in error messages.
///
/// Checks: at least one cell; unique cell and tool ids; every cell has a mode; numbers finite
/// and within the [limits](self#limits); tools exist (geometric instances); clearance above
/// every point; precedence edges in range, no self-loops, and acyclic (the cycle is named);
/// fixed first and last cells that exist and agree with the precedence (the first cell has no
/// predecessor, the last no successor, and they differ when there are two cells or more);
/// closed tours only on matrix instances, from a single-mode first cell; the as-given order is
/// a permutation with valid modes; the matrix matches the modes, with entries in
/// 0..=[`MAX_MATRIX_COST`]; and [`cost_bound`] is finite.
pub fn validate(inst: &Instance, file: &str) -> Result<()> {
    let run = || -> Check {
        if inst.n() == 0 {
            return Err("instance has no cells".into());
        }
        cells(inst)?;
        if !inst.is_matrix() {
            machine(inst)?;
            tools(inst)?;
        }
        precedence(inst)?;
        ends(inst)?;
        as_given(inst)?;
        if let Some(m) = &inst.matrix {
            matrix(inst, m)?;
        }
        let b = cost_bound(inst);
        if !b.is_finite() {
            return Err(format!(
                "the cost of a sequence could overflow (upper bound {b}); see the limits in docs/bad-input.md"
            ));
        }
        Ok(())
    };
    run().map_err(|msg| Error::invalid(file, msg))
}

fn coord(v: f64) -> bool {
    v.is_finite() && v.abs() <= MAX_COORD
}

fn point(p: &Point3) -> bool {
    coord(p.x) && coord(p.y) && coord(p.z)
}

fn feed_ok(f: f64) -> bool {
    f.is_finite() && f >= MIN_FEED
}

fn cells(inst: &Instance) -> Check {
    let n = inst.n();
    let mut ids: HashMap<&str, usize> = HashMap::with_capacity(n);
    let mut nodes: u64 = 0;
    for (i, c) in inst.cells.iter().enumerate() {
        if c.id.is_empty() {
            return Err(format!("cell #{} has an empty id", i + 1));
        }
        if let Some(j) = ids.insert(c.id.as_str(), i) {
            return Err(format!(
                "duplicate cell id '{}' (cells #{} and #{})",
                c.id,
                j + 1,
                i + 1
            ));
        }
        if c.modes.is_empty() {
            return Err(format!("cell '{}' has no modes", c.id));
        }
        nodes += c.modes.len() as u64;
        if !(c.cut_length.is_finite() && (0.0..=MAX_LENGTH).contains(&c.cut_length)) {
            return Err(format!(
                "cell '{}' has an invalid cut_length {} (0 to {MAX_LENGTH:e} mm)",
                c.id,
                show(c.cut_length)
            ));
        }
        if !coord(c.z) {
            return Err(format!(
                "cell '{}' has a z that is not finite or beyond ±{MAX_COORD:e} mm ({})",
                c.id,
                show(c.z)
            ));
        }
        if let Some(f) = c.feed
            && !feed_ok(f)
        {
            return Err(format!(
                "cell '{}' has an invalid feed {} (at least {MIN_FEED} mm/min)",
                c.id,
                show(f)
            ));
        }
        if inst.is_matrix() {
            continue;
        }
        if inst.tool(&c.tool).is_none() {
            return Err(format!("cell '{}' uses unknown tool '{}'", c.id, c.tool));
        }
        for (k, m) in c.modes.iter().enumerate() {
            if !point(&m.entry) || !point(&m.exit) {
                return Err(format!(
                    "cell '{}' mode {k} has a coordinate that is not finite or beyond \
                     ±{MAX_COORD:e} mm",
                    c.id
                ));
            }
            let top = m.entry.z.max(m.exit.z);
            if top > inst.machine.clearance + 1e-9 {
                return Err(format!(
                    "cell '{}' mode {k} lies at z = {top}, above the clearance height {}",
                    c.id, inst.machine.clearance
                ));
            }
        }
    }
    if nodes >= u32::MAX as u64 {
        return Err(format!(
            "the cells have {nodes} modes in all; at most {} are supported",
            u32::MAX - 1
        ));
    }
    Ok(())
}

fn machine(inst: &Instance) -> Check {
    let m = &inst.machine;
    for (name, v) in [("rapid_feed", m.rapid_feed), ("cut_feed", m.cut_feed)] {
        if !feed_ok(v) {
            return Err(format!(
                "machine {name} must be a number of at least {MIN_FEED} mm/min, got {}",
                show(v)
            ));
        }
    }
    if !coord(m.clearance) {
        return Err(format!(
            "machine clearance must be finite and within ±{MAX_COORD:e} mm, got {}",
            show(m.clearance)
        ));
    }
    for (name, v) in [
        ("tool_change_time", m.tool_change_time),
        ("lift_time", m.lift_time),
    ] {
        if !(v.is_finite() && (0.0..=MAX_TIME).contains(&v)) {
            return Err(format!(
                "machine {name} must be between 0 and {MAX_TIME:e} s, got {}",
                show(v)
            ));
        }
    }
    if !(m.link_distance.is_finite() && (0.0..=MAX_LENGTH).contains(&m.link_distance)) {
        return Err(format!(
            "machine link_distance must be between 0 and {MAX_LENGTH:e} mm, got {}",
            show(m.link_distance)
        ));
    }
    for (name, p) in [("home", &m.home), ("tool_change", &m.tool_change)] {
        if !point(p) {
            return Err(format!(
                "machine {name} point has a coordinate that is not finite or beyond \
                 ±{MAX_COORD:e} mm"
            ));
        }
    }
    for (i, k) in m.keep_out.iter().enumerate() {
        if ![k.x0, k.y0, k.x1, k.y1, k.top].into_iter().all(coord) || k.x0 > k.x1 || k.y0 > k.y1 {
            return Err(format!(
                "machine keep_out {i}: x0 <= x1, y0 <= y1 and finite values within \
                 ±{MAX_COORD:e} mm expected"
            ));
        }
    }
    Ok(())
}

fn tools(inst: &Instance) -> Check {
    let mut seen: HashMap<&str, usize> = HashMap::with_capacity(inst.tools.len());
    for (i, t) in inst.tools.iter().enumerate() {
        if let Some(j) = seen.insert(t.id.as_str(), i) {
            return Err(format!(
                "tool id '{}' is listed twice (tools #{} and #{})",
                t.id,
                j + 1,
                i + 1
            ));
        }
        if !(t.diameter.is_finite() && t.diameter > 0.0 && t.diameter <= MAX_COORD) {
            return Err(format!(
                "tool '{}' has an invalid diameter {}",
                t.id,
                show(t.diameter)
            ));
        }
        if let Some(f) = t.feed
            && !feed_ok(f)
        {
            return Err(format!(
                "tool '{}' has an invalid feed {} (at least {MIN_FEED} mm/min)",
                t.id,
                show(f)
            ));
        }
    }
    Ok(())
}

fn precedence(inst: &Instance) -> Check {
    let n = inst.n();
    for &(a, b) in &inst.precedence {
        if a >= n || b >= n {
            return Err(format!(
                "precedence edge ({a}, {b}) refers to a cell that does not exist"
            ));
        }
        if a == b {
            return Err(format!(
                "cell '{}' is required to precede itself",
                inst.cells[a].id
            ));
        }
    }
    let dag = Dag::new(n, &inst.precedence);
    if let Err(cycle) = topological_order(&dag) {
        let names: Vec<&str> = cycle.iter().map(|&i| inst.cells[i].id.as_str()).collect();
        return Err(format!(
            "precedence has a cycle: {} -> {}",
            names.join(" -> "),
            names[0]
        ));
    }
    Ok(())
}

/// The fixed first and last cells against the precedence. With the precedence acyclic, no
/// edge into the first cell, none out of the last and first ≠ last, the precedence together
/// with "first before every other cell" and "every other cell before last" (what the cost
/// model adds) is acyclic too: a cycle would have to enter the first cell or leave the last.
fn ends(inst: &Instance) -> Check {
    let n = inst.n();
    for (which, v) in [("first", inst.first), ("last", inst.last)] {
        if let Some(c) = v
            && c >= n
        {
            return Err(format!("fixed {which} cell index {c} does not exist"));
        }
    }
    let id = |c: usize| inst.cells[c].id.as_str();
    if let (Some(f), Some(l)) = (inst.first, inst.last)
        && f == l
        && n > 1
    {
        return Err(format!(
            "cell '{}' is fixed both first and last, but there are {n} cells",
            id(f)
        ));
    }
    for &(a, b) in &inst.precedence {
        if Some(b) == inst.first {
            return Err(format!(
                "cell '{}' is fixed first, but precedence puts '{}' before it",
                id(b),
                id(a)
            ));
        }
        if Some(a) == inst.last {
            return Err(format!(
                "cell '{}' is fixed last, but precedence puts '{}' after it",
                id(a),
                id(b)
            ));
        }
    }
    if inst.closed {
        if !inst.is_matrix() {
            return Err(
                "closed tours apply to matrix instances only (a geometric path returns home \
                 with machine.return_home)"
                    .into(),
            );
        }
        match inst.first {
            Some(f) if inst.cells[f].modes.len() == 1 => {}
            _ => return Err("a closed tour needs a fixed first cell with exactly one mode".into()),
        }
    }
    Ok(())
}

fn as_given(inst: &Instance) -> Check {
    let n = inst.n();
    let Some(order) = &inst.as_given else {
        return Ok(());
    };
    let mut seen = vec![false; n];
    for v in order {
        if v.cell >= n || seen[v.cell] {
            return Err("as_given order is not a permutation of the cells".into());
        }
        seen[v.cell] = true;
        if v.mode >= inst.cells[v.cell].modes.len() {
            return Err(format!(
                "as_given order uses mode {} of cell '{}', which does not exist",
                v.mode, inst.cells[v.cell].id
            ));
        }
    }
    if order.len() != n {
        return Err(format!(
            "as_given order has {} cells, the instance {n}",
            order.len()
        ));
    }
    Ok(())
}

fn matrix(inst: &Instance, m: &CostMatrix) -> Check {
    let nodes = inst.total_modes();
    if m.size != nodes || m.costs.len() != nodes.saturating_mul(nodes) {
        return Err(format!(
            "cost matrix is {}x{} but the cells have {nodes} modes in all",
            m.size,
            m.costs.len() / m.size.max(1)
        ));
    }
    if let Some(i) = m
        .costs
        .iter()
        .position(|c| !(c.is_finite() && (0.0..=MAX_MATRIX_COST).contains(c)))
    {
        let v = m.costs[i];
        let what = if !v.is_finite() {
            "is not finite".to_string()
        } else if v < 0.0 {
            format!("is negative ({})", show(v))
        } else {
            format!("is {}, above the limit {MAX_MATRIX_COST:e}", show(v))
        };
        return Err(format!(
            "cost matrix entry ({}, {}) {what}",
            i / m.size + 1,
            i % m.size + 1
        ));
    }
    Ok(())
}

/// An upper bound on the cost of any sequence of `inst` under either objective (time or air
/// for geometric instances, the matrix cost otherwise), computed from the instance's numbers:
/// (cells + 1) × the dearest possible move, plus the cutting time. Infinite (or NaN) exactly
/// when some cost could overflow; [`validate`] refuses such instances.
pub fn cost_bound(inst: &Instance) -> f64 {
    let steps = inst.n() as f64 + 1.0;
    if let Some(m) = &inst.matrix {
        let top = m.costs.iter().fold(0.0f64, |a, &c| a.max(c.abs()));
        return steps * top;
    }
    let mc = &inst.machine;
    let mut reach = mc.clearance.abs().max(mc.home.x.abs());
    for p in [mc.home, mc.tool_change] {
        reach = reach.max(p.x.abs()).max(p.y.abs()).max(p.z.abs());
    }
    let mut slowest = mc.cut_feed.min(mc.rapid_feed);
    let mut cut_time = 0.0;
    for c in &inst.cells {
        for md in &c.modes {
            for p in [md.entry, md.exit] {
                reach = reach.max(p.x.abs()).max(p.y.abs()).max(p.z.abs());
            }
        }
        let feed = c
            .feed
            .or_else(|| inst.tool(&c.tool).and_then(|t| t.feed))
            .unwrap_or(mc.cut_feed);
        slowest = slowest.min(feed);
        cut_time += c.cut_length * 60.0 / feed;
    }
    // any distance between points within `reach` of the origin in every axis is at most
    // 2·√3·reach; a move is at most four such legs (retract, two travels, plunge)
    let air = 4.0 * 2.0 * 3f64.sqrt() * reach;
    let rate = 60.0 / slowest;
    let mv = air * rate.max(1.0) + mc.lift_time.abs() + mc.tool_change_time.abs();
    steps * mv + cut_time.abs()
}

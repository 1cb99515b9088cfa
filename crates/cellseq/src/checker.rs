//! The independent checker: feasibility and a from-scratch report of a sequence.
//!
//! Deliberately shares no code with `crate::cost::CostModel` (the solvers' evaluator): it
//! walks the raw instance, re-derives every move from the machine description, and so catches
//! any disagreement between what a solver believes and what the sequence really costs.

use crate::model::{Instance, Machine, Objective, Sequence};
use serde::{Deserialize, Serialize};
use thiserror::Error;

/// Everything a sequence costs. Always complete, whatever the objective.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Report {
    /// The objective value (`time`: seconds, `air`: mm, `matrix`: matrix units).
    pub cost: f64,
    /// Length cut inside cells (mm).
    pub cut_length: f64,
    /// Non-cutting (air) length (mm), including at-depth links.
    pub air_length: f64,
    /// Cut + air.
    pub path_length: f64,
    /// Number of retract/plunge cycles between cells.
    pub lifts: u64,
    /// Number of tool changes.
    pub tool_changes: u64,
    /// Machining time (s): cutting + rapids + lifts × lift time + changes × change time.
    pub machining_time: f64,
}

/// Why a sequence is not a feasible solution.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Violation {
    /// A visit names a cell index that does not exist.
    #[error("position {position}: cell index {cell} does not exist (instance has {n} cells)")]
    UnknownCell {
        /// Position in the sequence.
        position: usize,
        /// The bad index.
        cell: usize,
        /// Number of cells.
        n: usize,
    },
    /// A cell appears twice.
    #[error("cell '{cell}' appears more than once (positions {first} and {second})")]
    Duplicate {
        /// Cell id.
        cell: String,
        /// First position.
        first: usize,
        /// Second position.
        second: usize,
    },
    /// A cell never appears.
    #[error("cell '{cell}' is missing from the sequence")]
    Missing {
        /// Cell id.
        cell: String,
    },
    /// A mode index out of range.
    #[error("cell '{cell}' has no mode {mode} (it has {modes})")]
    BadMode {
        /// Cell id.
        cell: String,
        /// The bad mode.
        mode: usize,
        /// Number of modes.
        modes: usize,
    },
    /// A precedence pair is broken.
    #[error("precedence broken: '{before}' must come before '{after}'")]
    Precedence {
        /// The cell that must come first.
        before: String,
        /// The cell that came too early.
        after: String,
    },
    /// The fixed first or last cell is elsewhere.
    #[error("cell '{cell}' must be {which}")]
    Fixed {
        /// Cell id.
        cell: String,
        /// `first` or `last`.
        which: &'static str,
    },
}

/// Checks `seq` against `inst` and recomputes its report for `objective`.
///
/// ```
/// use cellseq::prelude::*;
///
/// // three cells, cell 0 before cell 2
/// let inst = Instance::from_matrix("three", 3, vec![0.0, 1.0, 5.0, 1.0, 0.0, 2.0, 5.0, 2.0, 0.0], &[(0, 2)])?;
/// let good = vec![Visit::new(0, 0), Visit::new(1, 0), Visit::new(2, 0)];
/// assert_eq!(cellseq::check(&inst, &good, Objective::Matrix).unwrap().cost, 3.0);
/// let bad = vec![Visit::new(2, 0), Visit::new(1, 0), Visit::new(0, 0)];
/// assert!(cellseq::check(&inst, &bad, Objective::Matrix).is_err());
/// # Ok::<(), cellseq::Error>(())
/// ```
pub fn check(inst: &Instance, seq: &Sequence, objective: Objective) -> Result<Report, Violation> {
    let n = inst.cells.len();
    let mut position = vec![usize::MAX; n];
    for (p, v) in seq.iter().enumerate() {
        if v.cell >= n {
            return Err(Violation::UnknownCell {
                position: p,
                cell: v.cell,
                n,
            });
        }
        let cell = &inst.cells[v.cell];
        if position[v.cell] != usize::MAX {
            return Err(Violation::Duplicate {
                cell: cell.id.clone(),
                first: position[v.cell],
                second: p,
            });
        }
        position[v.cell] = p;
        if v.mode >= cell.modes.len() {
            return Err(Violation::BadMode {
                cell: cell.id.clone(),
                mode: v.mode,
                modes: cell.modes.len(),
            });
        }
    }
    if let Some(i) = position.iter().position(|&p| p == usize::MAX) {
        return Err(Violation::Missing {
            cell: inst.cells[i].id.clone(),
        });
    }
    if let Some(f) = inst.first
        && position[f] != 0
    {
        return Err(Violation::Fixed {
            cell: inst.cells[f].id.clone(),
            which: "first",
        });
    }
    if let Some(l) = inst.last
        && position[l] != n - 1
    {
        return Err(Violation::Fixed {
            cell: inst.cells[l].id.clone(),
            which: "last",
        });
    }
    // first broken pair in sequence order: the earliest cell placed before one of its predecessors
    let mut broken: Option<(usize, usize)> = None;
    for &(a, b) in &inst.precedence {
        if position[a] > position[b] {
            let key = (position[b], position[a]);
            if broken.is_none_or(|(pb, pa)| key < (position[pb], position[pa])) {
                broken = Some((b, a));
            }
        }
    }
    if let Some((b, a)) = broken {
        return Err(Violation::Precedence {
            before: inst.cells[a].id.clone(),
            after: inst.cells[b].id.clone(),
        });
    }
    Ok(match &inst.matrix {
        Some(m) => {
            let mut first_node = Vec::with_capacity(n);
            let mut count = 0;
            for c in &inst.cells {
                first_node.push(count);
                count += c.modes.len();
            }
            let node = |c: usize, md: usize| first_node[c] + md;
            let mut total = 0.0;
            for w in seq.windows(2) {
                total += m.costs[node(w[0].cell, w[0].mode) * m.size + node(w[1].cell, w[1].mode)];
            }
            if inst.closed
                && let (Some(a), Some(b)) = (seq.last(), seq.first())
            {
                total += m.costs[node(a.cell, a.mode) * m.size + node(b.cell, b.mode)];
            }
            Report {
                cost: total,
                cut_length: 0.0,
                air_length: total,
                path_length: total,
                lifts: 0,
                tool_changes: 0,
                machining_time: total,
            }
        }
        None => geometric_report(inst, seq, objective),
    })
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The length of a same-depth move from `from` to `to` that stays at depth: the straight line
/// when no keep-out area stands in its way, else an axis-parallel dog-leg (x first or y first)
/// that passes them, else `None` (the cutter must lift).
pub fn at_depth_length(m: &Machine, from: [f64; 3], to: [f64; 3]) -> Option<f64> {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    if !link_blocked(m, from, to) {
        return Some((dx * dx + dy * dy).sqrt());
    }
    for corner in [[to[0], from[1], from[2]], [from[0], to[1], from[2]]] {
        if !link_blocked(m, from, corner) && !link_blocked(m, corner, to) {
            return Some(dx.abs() + dy.abs());
        }
    }
    None
}

/// Whether a same-depth move from `from` to `to` crosses material of one of the machine's
/// keep-out areas standing above that depth, so that the cutter must lift. Separating-axis
/// test of the segment against each area shrunk by 1 µm (touching the boundary is free).
pub fn link_blocked(m: &Machine, from: [f64; 3], to: [f64; 3]) -> bool {
    const EPS: f64 = 1e-6;
    m.keep_out.iter().any(|k| {
        if k.top <= from[2] + 1e-9 {
            return false;
        }
        let (x0, x1, y0, y1) = (k.x0 + EPS, k.x1 - EPS, k.y0 + EPS, k.y1 - EPS);
        if x0 >= x1 || y0 >= y1 {
            return false;
        }
        // the box's own axes
        if from[0].max(to[0]) <= x0 || from[0].min(to[0]) >= x1 {
            return false;
        }
        if from[1].max(to[1]) <= y0 || from[1].min(to[1]) >= y1 {
            return false;
        }
        // the segment's normal: every corner on one side (or on the line) separates
        let (nx, ny) = (from[1] - to[1], to[0] - from[0]);
        if nx == 0.0 && ny == 0.0 {
            return true; // a point strictly inside the box
        }
        let side = |x: f64, y: f64| nx * (x - from[0]) + ny * (y - from[1]);
        let c = [side(x0, y0), side(x0, y1), side(x1, y0), side(x1, y1)];
        !(c.iter().all(|&v| v >= 0.0) || c.iter().all(|&v| v <= 0.0))
    })
}

fn geometric_report(inst: &Instance, seq: &Sequence, objective: Objective) -> Report {
    let m = &inst.machine;
    let h = m.clearance;
    let home: [f64; 3] = m.home.into();
    let tc: [f64; 3] = m.tool_change.into();
    let mut r = Report::default();
    let mut rapid = 0.0; // mm at rapid feed
    let mut link_time = 0.0; // s spent on at-depth links
    let mut cut_time = 0.0;
    let mut prev: Option<([f64; 3], &str)> = None;
    for v in seq {
        let cell = &inst.cells[v.cell];
        let md = cell.modes[v.mode];
        let entry: [f64; 3] = md.entry.into();
        let exit: [f64; 3] = md.exit.into();
        let feed = match cell.feed {
            Some(f) => f,
            None => inst
                .tools
                .iter()
                .find(|t| t.id == cell.tool)
                .and_then(|t| t.feed)
                .unwrap_or(m.cut_feed),
        };
        let above_entry = [entry[0], entry[1], h];
        match prev {
            None => {
                let first_change = match &m.initial_tool {
                    Some(t) => *t != cell.tool,
                    None => false,
                };
                let travel = if first_change {
                    r.tool_changes += 1;
                    dist3(home, tc) + dist3(tc, above_entry)
                } else {
                    dist3(home, above_entry)
                };
                rapid += travel + (h - entry[2]);
            }
            Some((pexit, ptool)) => {
                if ptool != cell.tool {
                    r.tool_changes += 1;
                    r.lifts += 1;
                    let above_exit = [pexit[0], pexit[1], h];
                    rapid += (h - pexit[2])
                        + dist3(above_exit, tc)
                        + dist3(tc, above_entry)
                        + (h - entry[2]);
                } else {
                    let planar =
                        ((pexit[0] - entry[0]).powi(2) + (pexit[1] - entry[1]).powi(2)).sqrt();
                    let same_depth = (pexit[2] - entry[2]).abs() <= 1e-9;
                    let link = if same_depth && planar <= m.link_distance + 1e-9 {
                        at_depth_length(m, pexit, entry).filter(|&d| d <= m.link_distance + 1e-9)
                    } else {
                        None
                    };
                    if let Some(d) = link {
                        r.air_length += d;
                        link_time += d * 60.0 / feed;
                    } else {
                        r.lifts += 1;
                        rapid += (h - pexit[2]) + planar + (h - entry[2]);
                    }
                }
            }
        }
        r.cut_length += cell.cut_length;
        cut_time += cell.cut_length * 60.0 / feed;
        prev = Some((exit, cell.tool.as_str()));
    }
    if m.return_home
        && let Some((pexit, _)) = prev
    {
        rapid += (h - pexit[2]) + dist3([pexit[0], pexit[1], h], home);
    }
    r.air_length += rapid;
    r.path_length = r.cut_length + r.air_length;
    r.machining_time = cut_time
        + link_time
        + rapid * 60.0 / m.rapid_feed
        + r.lifts as f64 * m.lift_time
        + r.tool_changes as f64 * m.tool_change_time;
    r.cost = match objective {
        Objective::Air => r.air_length,
        _ => r.machining_time,
    };
    r
}

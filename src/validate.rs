//! Structural validation of instances: everything a solver may rely on.

use crate::error::{Error, Result};
use crate::model::Instance;
use crate::precedence::{Dag, topological_order};
use std::collections::HashMap;

/// Validates `inst`; `file` names the source in error messages.
///
/// Checks: at least one cell; unique cell ids; every cell has a mode; finite coordinates and
/// lengths; tools exist (geometric instances); positive feeds; clearance above every point;
/// precedence edges in range, no self-loops, and acyclic (the cycle is named); the as-given
/// order is a permutation with valid modes; the matrix matches the modes and is finite.
pub fn validate(inst: &Instance, file: &str) -> Result<()> {
    let bad = |msg: String| Err(Error::invalid(file, msg));
    let n = inst.n();
    if n == 0 {
        return bad("instance has no cells".into());
    }
    let mut ids: HashMap<&str, usize> = HashMap::with_capacity(n);
    for (i, c) in inst.cells.iter().enumerate() {
        if c.id.is_empty() {
            return bad(format!("cell #{} has an empty id", i + 1));
        }
        if let Some(j) = ids.insert(c.id.as_str(), i) {
            return bad(format!(
                "duplicate cell id '{}' (cells #{} and #{})",
                c.id,
                j + 1,
                i + 1
            ));
        }
        if c.modes.is_empty() {
            return bad(format!("cell '{}' has no modes", c.id));
        }
        if !c.cut_length.is_finite() || c.cut_length < 0.0 {
            return bad(format!(
                "cell '{}' has an invalid cut_length {}",
                c.id, c.cut_length
            ));
        }
        if !c.z.is_finite() {
            return bad(format!("cell '{}' has a non-finite z", c.id));
        }
        if let Some(f) = c.feed
            && !(f.is_finite() && f > 0.0)
        {
            return bad(format!("cell '{}' has an invalid feed {f}", c.id));
        }
        if !inst.is_matrix() {
            if inst.tool(&c.tool).is_none() {
                return bad(format!("cell '{}' uses unknown tool '{}'", c.id, c.tool));
            }
            for (k, m) in c.modes.iter().enumerate() {
                if !m.entry.is_finite() || !m.exit.is_finite() {
                    return bad(format!(
                        "cell '{}' mode {k} has a non-finite (NaN or infinite) coordinate",
                        c.id
                    ));
                }
                let top = m.entry.z.max(m.exit.z);
                if top > inst.machine.clearance + 1e-9 {
                    return bad(format!(
                        "cell '{}' mode {k} lies at z = {top}, above the clearance height {}",
                        c.id, inst.machine.clearance
                    ));
                }
            }
        }
    }
    if !inst.is_matrix() {
        let m = &inst.machine;
        for (name, v) in [("rapid_feed", m.rapid_feed), ("cut_feed", m.cut_feed)] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("machine {name} must be a positive number, got {v}"));
            }
        }
        for (name, v) in [
            ("clearance", m.clearance),
            ("tool_change_time", m.tool_change_time),
            ("lift_time", m.lift_time),
            ("link_distance", m.link_distance),
        ] {
            if !v.is_finite() {
                return bad(format!("machine {name} is not finite"));
            }
        }
        if m.tool_change_time < 0.0 || m.lift_time < 0.0 || m.link_distance < 0.0 {
            return bad("machine times and link_distance must not be negative".into());
        }
        if !m.home.is_finite() || !m.tool_change.is_finite() {
            return bad("machine home or tool-change point is not finite".into());
        }
        for (i, k) in m.keep_out.iter().enumerate() {
            if ![k.x0, k.y0, k.x1, k.y1, k.top]
                .iter()
                .all(|v| v.is_finite())
                || k.x0 > k.x1
                || k.y0 > k.y1
            {
                return bad(format!(
                    "machine keep_out {i}: x0 <= x1, y0 <= y1 and finite values expected"
                ));
            }
        }
        for t in &inst.tools {
            if !(t.diameter.is_finite() && t.diameter > 0.0) {
                return bad(format!(
                    "tool '{}' has an invalid diameter {}",
                    t.id, t.diameter
                ));
            }
            if let Some(f) = t.feed
                && !(f.is_finite() && f > 0.0)
            {
                return bad(format!("tool '{}' has an invalid feed {f}", t.id));
            }
        }
    }
    for &(a, b) in &inst.precedence {
        if a >= n || b >= n {
            return bad(format!(
                "precedence edge ({a}, {b}) refers to a cell that does not exist"
            ));
        }
        if a == b {
            return bad(format!(
                "cell '{}' is required to precede itself",
                inst.cells[a].id
            ));
        }
    }
    let dag = Dag::new(n, &inst.precedence);
    if let Err(cycle) = topological_order(&dag) {
        let names: Vec<&str> = cycle.iter().map(|&i| inst.cells[i].id.as_str()).collect();
        return bad(format!(
            "precedence has a cycle: {} -> {}",
            names.join(" -> "),
            names[0]
        ));
    }
    for (which, v) in [("first", inst.first), ("last", inst.last)] {
        if let Some(c) = v
            && c >= n
        {
            return bad(format!("fixed {which} cell index {c} does not exist"));
        }
    }
    if inst.closed {
        match inst.first {
            Some(f) if inst.cells[f].modes.len() == 1 => {}
            _ => return bad("a closed tour needs a fixed first cell with exactly one mode".into()),
        }
    }
    if let Some(order) = &inst.as_given {
        let mut seen = vec![false; n];
        for v in order {
            if v.cell >= n || seen[v.cell] {
                return bad("as_given order is not a permutation of the cells".into());
            }
            seen[v.cell] = true;
            if v.mode >= inst.cells[v.cell].modes.len() {
                return bad(format!(
                    "as_given order uses mode {} of cell '{}', which does not exist",
                    v.mode, inst.cells[v.cell].id
                ));
            }
        }
        if order.len() != n {
            return bad(format!(
                "as_given order has {} cells, the instance {n}",
                order.len()
            ));
        }
    }
    if let Some(m) = &inst.matrix {
        let nodes = inst.total_modes();
        if m.size != nodes || m.costs.len() != nodes * nodes {
            return bad(format!(
                "cost matrix is {}x{} but the cells have {nodes} modes in all",
                m.size,
                m.costs.len() / m.size.max(1)
            ));
        }
        if let Some(i) = m.costs.iter().position(|c| !c.is_finite()) {
            return bad(format!(
                "cost matrix entry ({}, {}) is not finite",
                i / m.size + 1,
                i % m.size + 1
            ));
        }
    }
    Ok(())
}

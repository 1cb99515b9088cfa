//! Writing an SOP-shaped matrix instance as a TSPLIB SOP file, the form LKH-3 and the other
//! peers read (`TYPE: SOP`, `EDGE_WEIGHT_SECTION` with the dimension repeated, then the full
//! matrix; entry (i, j) = −1 when node j must precede node i).

use crate::error::{Error, Result};
use crate::model::{CostMatrix, Instance};
use std::collections::HashSet;
use std::fmt::Write;

/// The instance as TSPLIB SOP text, or why it cannot be one: it must be a matrix instance
/// with one mode per cell, not a closed tour, with the first cell fixed at index 0 and the
/// last at the last index, and every cost an integer (LKH-3 reads integers). Every precedence
/// edge (a, b) is written as −1 at (b, a); other arcs keep their cost (an arc stored as
/// forbidden that no edge explains is written as 1 000 000, TSPLIB's "never" cost).
pub fn to_sop_text(inst: &Instance) -> Result<String> {
    let bad = |m: &str| {
        Err(Error::Param(format!(
            "cannot write {} as TSPLIB SOP: {m}",
            inst.name
        )))
    };
    let Some(m) = &inst.matrix else {
        return bad("it is not a matrix instance");
    };
    let n = inst.n();
    if inst.cells.iter().any(|c| c.modes.len() != 1) || m.size != n {
        return bad("its cells have several modes (write JSON instead)");
    }
    if inst.closed || inst.first != Some(0) || n < 2 || inst.last != Some(n - 1) {
        return bad("SOP files fix the first cell at 1 and the last at n, as an open path");
    }
    let edges: HashSet<(usize, usize)> = inst.precedence.iter().copied().collect();
    let mut rows = Vec::with_capacity(n);
    let mut width = 2;
    for i in 0..n {
        let mut row = Vec::with_capacity(n);
        for j in 0..n {
            let v = if edges.contains(&(j, i)) {
                -1
            } else {
                let c = m.get(i, j);
                if c >= CostMatrix::FORBIDDEN {
                    1_000_000
                } else if c.fract() != 0.0 || c > 9.0e15 {
                    return bad(&format!(
                        "cost ({}, {}) = {c} is not an integer",
                        i + 1,
                        j + 1
                    ));
                } else {
                    c as i64
                }
            };
            width = width.max(v.to_string().len() + 1);
            row.push(v);
        }
        rows.push(row);
    }
    let mut s = String::with_capacity(n * n * (width + 1) + 256);
    let _ = writeln!(s, "NAME: {}", inst.name);
    let _ = writeln!(s, "TYPE: SOP");
    if let Some(g) = &inst.meta.generator {
        let params: Vec<String> = inst
            .meta
            .params
            .iter()
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        let seed = inst
            .meta
            .seed
            .map(|s| format!(" seed={s}"))
            .unwrap_or_default();
        let _ = writeln!(
            s,
            "COMMENT: cellseq generate {g} {}{seed}",
            params.join(" ")
        );
    }
    let _ = writeln!(s, "DIMENSION: {n}");
    let _ = writeln!(s, "EDGE_WEIGHT_TYPE: EXPLICIT");
    let _ = writeln!(s, "EDGE_WEIGHT_FORMAT: FULL_MATRIX");
    let _ = writeln!(s, "EDGE_WEIGHT_SECTION");
    let _ = writeln!(s, "{n}");
    for row in rows {
        for v in row {
            let _ = write!(s, "{v:>width$}");
        }
        s.push('\n');
    }
    s.push_str("EOF\n");
    Ok(s)
}

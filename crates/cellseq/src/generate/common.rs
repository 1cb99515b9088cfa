//! Helpers shared by the part generators: the as-programmed order of a CAM programmer and
//! small geometric conveniences.

use super::toolsel::{ToolLibrary, ToolSpec};
use crate::geom::Point3;
use crate::model::{Cell, Mode, Visit};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use std::collections::{BTreeMap, BTreeSet};

/// A uniformly random permutation of `0..n` (Fisher–Yates from the back, one
/// `random_range(0..=i)` per position): every generator that draws a hidden order uses this one
/// sequence of draws, so the same seed gives the same instance as before it was shared.
pub fn random_permutation(n: usize, rng: &mut ChaCha8Rng) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng.random_range(0..=i);
        order.swap(i, j);
    }
    order
}

/// The library's tools that `cells` use, larger first (ties by id), and every cell's rank in
/// that list: the procedure order of the as-programmed sequence ("larger tool first").
pub fn tools_larger_first<'a>(
    lib: &'a ToolLibrary,
    cells: &[Cell],
) -> (Vec<&'a ToolSpec>, Vec<u32>) {
    let mut used: Vec<&ToolSpec> = lib
        .tools
        .iter()
        .filter(|t| cells.iter().any(|c| c.tool == t.id))
        .collect();
    used.sort_by(|a, c| {
        c.diameter
            .total_cmp(&a.diameter)
            .then_with(|| a.id.cmp(&c.id))
    });
    let rank = cells
        .iter()
        .map(|c| {
            used.iter()
                .position(|t| t.id == c.tool)
                .expect("a used tool") as u32
        })
        .collect();
    (used, rank)
}

/// The order a CAM programmer would write without optimization: procedure by procedure
/// (a procedure = the cells cut with one tool; `tool_rank` 0 is programmed first), inside a
/// procedure by `key` (feature numbering, then layer), always respecting `precedence`.
///
/// It is a list schedule: the current tool is kept while it has a ready cell (the one with the
/// smallest key is taken); otherwise the ready cell with the smallest (tool rank, key) is
/// taken. Every cell is visited in mode 0. Panics only if `precedence` has a cycle (callers
/// build acyclic precedence).
pub fn programmed_order(
    n: usize,
    precedence: &[(usize, usize)],
    tool_rank: &[u32],
    key: &[(u64, u64)],
) -> Vec<Visit> {
    let mut indeg = vec![0u32; n];
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    for &(a, b) in precedence {
        indeg[b] += 1;
        succ[a].push(b);
    }
    let mut ready: BTreeMap<u32, BTreeSet<(u64, u64, usize)>> = BTreeMap::new();
    for c in 0..n {
        if indeg[c] == 0 {
            ready
                .entry(tool_rank[c])
                .or_default()
                .insert((key[c].0, key[c].1, c));
        }
    }
    let mut order = Vec::with_capacity(n);
    let mut current: Option<u32> = None;
    while order.len() < n {
        let tool = match current {
            Some(t) if ready.get(&t).is_some_and(|s| !s.is_empty()) => t,
            _ => *ready
                .iter()
                .find(|(_, s)| !s.is_empty())
                .map(|(t, _)| t)
                .expect("precedence is acyclic"),
        };
        let set = ready.get_mut(&tool).expect("tool has ready cells");
        let (_, _, c) = set.pop_first().expect("non-empty");
        current = Some(tool);
        order.push(Visit::new(c, 0));
        for &s in &succ[c] {
            indeg[s] -= 1;
            if indeg[s] == 0 {
                ready
                    .entry(tool_rank[s])
                    .or_default()
                    .insert((key[s].0, key[s].1, s));
            }
        }
    }
    order
}

/// Rounds to 1 µm so that generated files stay short and identical across platforms.
pub fn r3(x: f64) -> f64 {
    let v = (x * 1000.0).round() / 1000.0;
    if v == 0.0 { 0.0 } else { v }
}

/// A point rounded to 1 µm.
pub fn pt(x: f64, y: f64, z: f64) -> Point3 {
    Point3::new(r3(x), r3(y), r3(z))
}

/// An open stroke from `a` to `b`, with its reverse as a second mode when `reversible`.
pub fn stroke_modes(a: Point3, b: Point3, reversible: bool) -> Vec<Mode> {
    let m = Mode::new(a, b);
    if reversible {
        vec![m, m.reversed()]
    } else {
        vec![m]
    }
}

/// Closed-contour modes: one start point per given point.
pub fn closed_modes(points: &[Point3]) -> Vec<Mode> {
    points.iter().map(|p| Mode::closed(*p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn programmed_order_keeps_tool_and_precedence() {
        // cells 0,1 tool 0; 2,3 tool 1; 3 must precede 1
        let order = programmed_order(
            4,
            &[(3, 1)],
            &[0, 0, 1, 1],
            &[(0, 0), (1, 0), (0, 0), (1, 0)],
        );
        let cells: Vec<usize> = order.iter().map(|v| v.cell).collect();
        assert_eq!(cells, vec![0, 2, 3, 1]);
    }
}

//! The assignment bound of large geometric instances from a sparse candidate graph, in
//! O(n K log n) time and O(n K) memory (issue 51).
//!
//! Rows are the cells as predecessors plus home (the path's start), columns the cells as
//! successors plus home (its end); arc costs are minimised over mode pairs and the arcs the
//! precedence forbids are left out, as in the dense [`super::assignment`] bound. Any duals
//! with `u_i + v_j ≤ c_ij` on **every** arc give `Σu + Σv ≤` the assignment optimum `≤` the
//! optimum path.
//!
//! Each cell's row lists its `k` nearest cells (centroids of exit and entry points, k-d
//! tree) that the precedence allows, every cell with an entry point within the link
//! distance of one of its exit points, and home if it may come last; home's row lists every
//! cell that may come first. The arcs left out are covered by floors proven below their cost
//! ([`super::auction`] solves the assignment on listed arcs plus these floors):
//! - to a cell of the row's tool: `lift_floor + r · rate` — such a move is not a link (no
//!   entry point within the link distance was left out), so it retracts, travels at least
//!   `r` at rapid and plunges, with `r` the planar distance every left-out entry point is
//!   known to lie beyond (the last centroid distance found, less the spread of both cells'
//!   points around their centroids, and at least the link distance);
//! - to a cell of another tool t (listed or not): `change_offset` of the row plus the least
//!   [`CostModel::change_tail`] over t's entry points.
//!
//! Modes enter as the cheapest mode pair per arc and the least floor over the row's modes.
//! Lowering costs only lowers the assignment optimum, so the auction's dual value on these
//! costs, taken after any phase, is a lower bound of the instance.

use super::auction::{NO_GROUP, Problem, auction};
use crate::clock::{Deadline, Ticker};
use crate::cost::CostModel;
use crate::geom::xy_tree;
use crate::model::Objective;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use std::num::NonZero;

/// Most cells within the link distance listed per row besides the nearest.
const LINKS_LISTED: usize = 32;

/// Most cells the precedence search of [`barred`] visits each way from one cell.
const BARRED_VISITS: usize = 64;

/// Per cell, the centroid of its entry (or exit) points and each point's distance from it.
fn centroids(m: &CostModel, exit: bool) -> (Vec<[f64; 2]>, Vec<Vec<f64>>) {
    let mut at = Vec::with_capacity(m.n());
    let mut off = Vec::with_capacity(m.n());
    for c in 0..m.n() {
        let pts: Vec<_> = (0..m.modes(c))
            .map(|md| {
                let nd = m.node(c, md);
                if exit { m.exit(nd) } else { m.entry(nd) }
            })
            .collect();
        let k = pts.len() as f64;
        let cx = pts.iter().map(|p| p.x).sum::<f64>() / k;
        let cy = pts.iter().map(|p| p.y).sum::<f64>() / k;
        at.push([cx, cy]);
        off.push(pts.iter().map(|p| (p.x - cx).hypot(p.y - cy)).collect());
    }
    (at, off)
}

/// The candidate graph of `m` (cells `0..n`, home `n`) and the floors of its unlisted arcs,
/// or `None` once `deadline` passes.
///
/// A k-d tree holds the centroids of the cells' entry points; row i lists the `k` nearest
/// cells to the centroid of its exit points that the precedence allows. A cell left out
/// lies at centroid distance `R` (the last found) or more, so each of its entry points lies
/// at least `R − ρ − s` from exit point `x` of i, with `ρ` the largest distance of an entry
/// point from its cell's centroid and `s` that of `x` from i's.
fn candidates(m: &CostModel, k: usize, deadline: Deadline) -> Option<Problem> {
    let n = m.n();
    let (entry_at, entry_off) = centroids(m, false);
    let rho = entry_off.iter().flatten().copied().fold(0.0, f64::max);
    let (exit_at, exit_off) = centroids(m, true);
    let tree = xy_tree(entry_at.iter().copied());
    let nodes = xy_tree((0..m.nodes()).map(|nd| {
        let p = m.entry(nd);
        [p.x, p.y]
    }));
    let time = m.objective() == Objective::Time;
    let rapid = if time { m.rapid_rate() } else { 1.0 };
    let link_rate = if time {
        (0..n).map(|c| m.cut_rate(c)).fold(f64::INFINITY, f64::min)
    } else {
        1.0
    };
    let mut g = Problem {
        size: n + 1,
        first: Vec::with_capacity(n + 2),
        group: (0..n).map(|c| m.tool(c)).chain([NO_GROUP]).collect(),
        same: vec![f64::INFINITY; n + 1],
        other: vec![f64::INFINITY; n + 1],
        tail: tool_tails(m),
        ..Problem::default()
    };
    g.first.push(0);
    let mut clock = Ticker::new(deadline, 64);
    let mut barred_cells: Vec<u32> = Vec::new();
    for i in 0..n {
        if clock.passed() {
            return None;
        }
        barred(m, i, &mut barred_cells);
        let want = (k + 1 + barred_cells.len()).min(n);
        let res = tree
            .query(&exit_at[i])
            .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(want).expect("n > 0"))
            .execute();
        // the centroid distance from which cells are left out: the first allowed cell past
        // the k listed, else past the last found (results come nearest first)
        let mut listed = 0;
        let mut far = None;
        for r in &res {
            let j = r.item;
            if j as usize == i || barred_cells.contains(&j) {
                continue;
            }
            if listed == k {
                far = Some(r.distance.sqrt());
                break;
            }
            let c = m.cheapest_arc(i, j as usize);
            if c.is_finite() {
                g.col.push(j);
                g.cost.push(c);
                listed += 1;
            }
        }
        if far.is_none() && res.len() < n {
            far = Some(res.last().map(|r| r.distance.sqrt()).unwrap_or(0.0));
        }
        let row = g.first[i];
        let links = list_links(m, &nodes, i, &barred_cells, &mut g, row);
        if let Some(far) = far {
            for (mi, s) in exit_off[i].iter().enumerate() {
                let r = (far - rho - s).max(0.0);
                // with `links`, every unlisted entry lies beyond the link distance too
                let reach = if links { r.max(m.link_distance()) } else { r };
                let lift = m.lift_floor(i, mi) + reach * rapid;
                let same = if links { lift } else { lift.min(r * link_rate) };
                g.same[i] = g.same[i].min(same);
                g.other[i] = g.other[i].min(m.change_offset(i, mi));
            }
        }
        if m.dag.succs[i].is_empty() {
            let f = (0..m.modes(i)).map(|md| m.finish(i, md)).fold(f64::INFINITY, f64::min);
            g.col.push(n as u32);
            g.cost.push(f);
        }
        g.first.push(g.col.len());
    }
    for j in (0..n).filter(|&j| m.dag.preds[j].is_empty()) {
        let s = (0..m.modes(j)).map(|md| m.start(j, md)).fold(f64::INFINITY, f64::min);
        g.col.push(j as u32);
        g.cost.push(s);
    }
    g.first.push(g.col.len());
    Some(g)
}

/// Lists in row `i` (arcs from `row` on) every cell with an entry point within the link
/// distance of an exit point of `i` that is not listed yet; true when all are listed, false
/// when more than [`LINKS_LISTED`] were found (links to unlisted cells stay possible).
fn list_links(
    m: &CostModel,
    nodes: &ImmutableKdTree<f64, 2>,
    i: usize,
    barred_cells: &[u32],
    g: &mut Problem,
    row: usize,
) -> bool {
    let reach = m.link_distance() + 1e-6;
    let want = NonZero::new(LINKS_LISTED + 1).expect("> 0");
    let mut added = 0;
    for mi in 0..m.modes(i) {
        let ex = m.exit(m.node(i, mi));
        let res = nodes
            .query(&[ex.x, ex.y])
            .nearest_n::<SquaredEuclidean<f64>>(want)
            .within::<SquaredEuclidean<f64>>(reach * reach)
            .execute();
        if res.len() > LINKS_LISTED {
            return false;
        }
        for r in &res {
            let j = m.cell_mode(r.item as usize).0 as u32;
            if j as usize == i || barred_cells.contains(&j) || g.col[row..].contains(&j) {
                continue;
            }
            if added == LINKS_LISTED {
                return false;
            }
            let c = m.cheapest_arc(i, j as usize);
            if c.is_finite() {
                g.col.push(j);
                g.cost.push(c);
                added += 1;
            }
        }
    }
    true
}

/// Per tool, the least [`CostModel::change_tail`] over the entry points of its cells (the
/// part of a tool change that depends on the target); `INFINITY` for unused tools.
fn tool_tails(m: &CostModel) -> Vec<f64> {
    let tools = (0..m.n()).map(|c| m.tool(c) as usize + 1).max().unwrap_or(0);
    let mut tail = vec![f64::INFINITY; tools];
    for c in 0..m.n() {
        for md in 0..m.modes(c) {
            let t = &mut tail[m.tool(c) as usize];
            *t = t.min(m.change_tail(m.node(c, md)));
        }
    }
    tail
}

/// Cells `j` for which the arc `i → j` breaks the precedence, as far as a search of at most
/// [`BARRED_VISITS`] cells each way finds them: ancestors of `i`, and cells after some
/// successor of `i` (fewer found only leaves more arcs in, which keeps the bound valid).
fn barred(m: &CostModel, i: usize, out: &mut Vec<u32>) {
    out.clear();
    out.extend_from_slice(&m.dag.preds[i]);
    let direct = out.clone();
    reach(&m.dag.preds, &direct, out);
    reach(&m.dag.succs, &m.dag.succs[i], out);
}

/// Appends to `out` the cells reached from `start` by one or more steps along `adj`, until
/// [`BARRED_VISITS`] are appended.
fn reach(adj: &[Vec<u32>], start: &[u32], out: &mut Vec<u32>) {
    let from = out.len();
    let mut stack: Vec<u32> = start.to_vec();
    while let Some(c) = stack.pop() {
        for &x in &adj[c as usize] {
            if out.len() - from >= BARRED_VISITS {
                return;
            }
            if !out[from..].contains(&x) {
                out.push(x);
                stack.push(x);
            }
        }
    }
}

/// The sparse assignment bound of a geometric model (without the model's constant): the
/// best dual value over the auction's phases, `None` when the deadline passes before the
/// first. `k` entry points are searched per exit point.
pub fn assignment_knn_until(m: &CostModel, k: usize, deadline: Deadline) -> Option<f64> {
    if m.n() == 0 {
        return Some(0.0);
    }
    let g = candidates(m, k, deadline)?;
    let mut best: Option<f64> = None;
    auction(&g, deadline, |p| {
        if let Some(v) = g.dual_value(p) {
            best = Some(best.map_or(v, |b: f64| b.max(v)));
        }
    });
    best
}

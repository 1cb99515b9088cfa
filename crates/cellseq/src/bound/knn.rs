//! The degree bound for large geometric instances, in O(n K log n) time and O(n) memory.
//!
//! For every (cell, mode) the cheapest way in is searched among the K nearest exit points
//! (k-d tree on the xy plane). Every other predecessor lies at a planar distance of at least
//! the K-th distance `r`, and any move of planar length `r` costs at least `r · rate` (links
//! run at cutting feed, lifted moves and tool changes travel at least the planar distance at
//! rapid), so `min(best found, r · rate)` is a valid lower bound on the cheapest entry.

use crate::clock::{Deadline, Ticker};
use crate::cost::CostModel;
use crate::geom::xy_tree;
use crate::model::Objective;
use kiddo::SquaredEuclidean;
use std::num::NonZero;

/// Σ over cells of a lower bound on the cheapest way into the cell, plus a lower bound on
/// the final move home; excludes the model's constant.
pub fn knn_in_bound(m: &CostModel, k: usize) -> f64 {
    knn_in_bound_until(m, k, Deadline::NONE)
}

/// Like [`knn_in_bound`], with the cells whose turn comes after `deadline` left out of the
/// sum (every term is a cost ≥ 0, so the partial sum is a bound too).
pub fn knn_in_bound_until(m: &CostModel, k: usize, deadline: Deadline) -> f64 {
    let n = m.n();
    let nodes = m.nodes();
    if n == 0 {
        return 0.0;
    }
    let tree = xy_tree((0..nodes).map(|nd| {
        let p = m.exit(nd);
        [p.x, p.y]
    }));
    let max_modes = (0..n).map(|c| m.modes(c)).max().unwrap_or(1);
    let want = (k + max_modes).min(nodes).max(1);
    let rate = |cell: usize| match m.objective() {
        Objective::Time => m.rapid_rate().min(m.cut_rate(cell)),
        _ => 1.0,
    };
    let mut total = 0.0;
    let mut clock = Ticker::new(deadline, 256);
    for j in 0..n {
        if clock.passed() {
            break;
        }
        let mut cell_best = f64::INFINITY;
        let first_ok = m.dag.preds[j].is_empty();
        for mj in 0..m.modes(j) {
            let nb = m.node(j, mj);
            let en = m.entry(nb);
            let mut best = if first_ok {
                m.start(j, mj)
            } else {
                f64::INFINITY
            };
            let res = tree
                .query(&[en.x, en.y])
                .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(want).expect("want > 0"))
                .execute();
            for r in &res {
                let na = r.item as usize;
                let (i, mi) = m.cell_mode(na);
                if i == j || m.dag.preds[i].binary_search(&(j as u32)).is_ok() {
                    continue;
                }
                best = best.min(m.arc(i, mi, j, mj));
            }
            if res.len() < nodes {
                let far = res.last().map(|r| r.distance.sqrt()).unwrap_or(0.0);
                best = best.min(far * rate(j));
            }
            cell_best = cell_best.min(best);
        }
        if cell_best.is_finite() {
            total += cell_best;
        }
    }
    // the final move home, from some cell that may be last
    let fin = (0..n)
        .filter(|&c| m.dag.succs[c].is_empty())
        .flat_map(|c| (0..m.modes(c)).map(move |md| (c, md)))
        .map(|(c, md)| m.finish(c, md))
        .fold(f64::INFINITY, f64::min);
    if fin.is_finite() {
        total += fin;
    }
    total
}

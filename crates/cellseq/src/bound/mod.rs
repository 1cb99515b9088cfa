//! Lower bounds on the optimum of any instance, through [`CostModel`].
//!
//! All bounds use arc costs minimised over modes and remove every arc that the transitive
//! closure of the precedence forbids (j ≺ i, or some k with i ≺ k ≺ j). The open path is closed
//! into a cycle through a home node (start arcs out of it, finish arcs into it).
//!
//! - `degree`: Σ cheapest in-arc, and Σ cheapest out-arc, over cells and home; the max.
//! - `degree_knn`: the in-degree bound of large geometric instances from K nearest
//!   neighbours only (memory linear in n).
//! - `assignment_knn`: the assignment bound of the same large geometric instances, by an
//!   auction on a sparse candidate graph whose left-out arcs are covered by proven floors
//!   ([`assignment_knn`], O(n K) memory).
//! - `assignment`: the assignment problem on the cell graph (the dense Hungarian method, and
//!   [`lap`] above order [`assignment::DENSE_MAX_ORDER`]).
//! - `lagrangian`: minimum spanning 1-arborescence with subgradient out-degree penalties.
//! - `sec`: assignment with Lagrangian subtour-elimination multipliers ([`sec`]).
//! - `qpath`: position-indexed path relaxation (precedence windows, no 2-cycles) with
//!   subgradient multipliers per cell ([`qpath`]).
//!
//! [`compute`] runs what is affordable for the instance size and reports each with its time.

pub mod arborescence;
pub mod assignment;
pub mod assignment_knn;
pub mod auction;
pub mod cells;
pub mod knn;
pub mod lap;
pub mod qpath;
pub mod sec;

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::precedence::Closure;
use cells::CellGraph;
use std::time::Instant;

/// Which bounds to compute and the size limits of the dense ones.
#[derive(Debug, Clone, Copy)]
pub struct BoundOptions {
    /// Largest n for the dense cell graph (O(n²) memory); larger geometric instances get the
    /// K-nearest-neighbour degree and sparse assignment bounds only.
    pub dense_max_cells: usize,
    /// Largest n for the assignment bound (the dense Hungarian method, O(n³), up to order
    /// 512; shortest augmenting paths on sparse row lists above).
    pub assignment_max_cells: usize,
    /// Largest n for the Lagrangian arborescence bound.
    pub lagrangian_max_cells: usize,
    /// Subgradient iterations of the Lagrangian bound.
    pub lagrangian_iterations: usize,
    /// Work budget of the `qpath` bound in arc evaluations (0 = skip it); it runs only when
    /// at least 10 subgradient iterations fit.
    pub qpath_work: f64,
    /// Work budget of the `sec` bound (d³ per subgradient iteration; 0 = skip it); it runs
    /// only when at least 10 iterations fit.
    pub sec_work: f64,
    /// Neighbours per node in the K-nearest-neighbour degree bound, and cells per row in the
    /// sparse assignment bound.
    pub knn: usize,
    /// A known solution cost (with the constant), used to size subgradient steps.
    pub upper: Option<f64>,
    /// When to stop: a bound not started by then is skipped, one under way stops (the
    /// subgradient bounds keep their best iterate; the assignment is dropped).
    pub deadline: Deadline,
}

impl Default for BoundOptions {
    fn default() -> Self {
        BoundOptions {
            dense_max_cells: 3000,
            assignment_max_cells: 1500,
            lagrangian_max_cells: 400,
            lagrangian_iterations: 300,
            qpath_work: 1e8,
            sec_work: 1e8,
            knn: 8,
            upper: None,
            deadline: Deadline::NONE,
        }
    }
}

/// One computed bound.
#[derive(Debug, Clone, PartialEq)]
pub struct BoundValue {
    /// Bound name (`degree`, `degree_knn`, `assignment_knn`, `assignment`, `lagrangian`, …).
    pub name: &'static str,
    /// Its value, in objective units, constant included.
    pub value: f64,
    /// Seconds it took (the shared cell graph is charged to the first dense bound).
    pub seconds: f64,
}

/// All bounds computed for an instance and the best of them.
#[derive(Debug, Clone, PartialEq)]
pub struct Bounds {
    /// Each bound in the order computed.
    pub parts: Vec<BoundValue>,
    /// The largest of them (rounded up when all costs are integers).
    pub best: f64,
    /// Name of the largest.
    pub best_name: &'static str,
}

/// Computes every affordable lower bound of the model's optimum, within `opt.deadline`.
pub fn compute(m: &CostModel, opt: &BoundOptions) -> Bounds {
    let n = m.n();
    let mut parts = Vec::new();
    let constant = m.constant();
    let t0 = Instant::now();
    let dl = opt.deadline;
    let closure = (n <= opt.dense_max_cells && !dl.passed())
        .then(|| Closure::new(&m.dag))
        .flatten();
    if let Some(cl) = closure {
        if let Some(g) = CellGraph::new_until(m, &cl, dl) {
            dense_bounds(m, opt, &cl, &g, t0, &mut parts);
        }
    } else if m.is_geometric() && !dl.passed() {
        let k = opt.knn.max(1);
        // the sparse assignment first: it is the stronger; under a deadline the degree
        // bound runs only when the assignment gave nothing
        let t = Instant::now();
        let a = assignment_knn::assignment_knn_until(m, k, dl);
        if let Some(v) = a {
            parts.push(BoundValue {
                name: "assignment_knn",
                value: constant + v,
                seconds: t.elapsed().as_secs_f64(),
            });
        }
        if (a.is_none() || !dl.is_set()) && !dl.passed() {
            let t = Instant::now();
            let v = knn::knn_in_bound_until(m, k, dl);
            parts.push(BoundValue {
                name: "degree_knn",
                value: constant + v,
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }
    if parts.is_empty() {
        parts.push(BoundValue {
            name: "constant",
            value: constant,
            seconds: 0.0,
        });
    }
    let best = parts
        .iter()
        .fold(&parts[0], |a, b| if b.value > a.value { b } else { a })
        .clone();
    Bounds {
        parts,
        best: best.value,
        best_name: best.name,
    }
}

/// The bounds on the dense cell graph `g`, each started only before `opt.deadline`.
fn dense_bounds(
    m: &CostModel,
    opt: &BoundOptions,
    cl: &Closure,
    g: &CellGraph,
    t0: Instant,
    parts: &mut Vec<BoundValue>,
) {
    let n = m.n();
    let constant = m.constant();
    let dl = opt.deadline;
    let integral = g.integral() && constant.fract() == 0.0;
    let round = |v: f64| {
        // `+ 0.0`: a bound of zero is 0, not the -0 that ceil(-1e-6) gives
        if integral { (v - 1e-6).ceil() + 0.0 } else { v }
    };
    let mi: f64 = g.min_in().iter().filter(|c| c.is_finite()).sum();
    let mo: f64 = g.min_out().iter().filter(|c| c.is_finite()).sum();
    parts.push(BoundValue {
        name: "degree",
        value: round(constant + mi.max(mo)),
        seconds: t0.elapsed().as_secs_f64(),
    });
    let upper = opt.upper.map(|u| u - constant);
    if n <= opt.assignment_max_cells && !dl.passed() {
        let t = Instant::now();
        if let Some(a) = assignment::hungarian_duals_until(g.size(), |i, j| g.c(i, j), dl) {
            parts.push(BoundValue {
                name: "assignment",
                value: round(constant + a.value),
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }
    if n <= opt.lagrangian_max_cells && opt.lagrangian_iterations > 0 && !dl.passed() {
        let t = Instant::now();
        if let Some(l) = arborescence::lagrangian_bound(g, opt.lagrangian_iterations, upper, dl) {
            parts.push(BoundValue {
                name: "lagrangian",
                value: round(constant + l.bound),
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }
    let iters = sec::affordable_iterations(n, opt.sec_work, 300);
    if n <= opt.assignment_max_cells && iters >= 10 && !dl.passed() {
        let t = Instant::now();
        if let Some(s) = sec::sec_bound_until(g, Some(cl), upper, iters, 4 * n + 16, dl) {
            parts.push(BoundValue {
                name: "sec",
                value: round(constant + s.value),
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }
    let iters = qpath::affordable_iterations(m, opt.qpath_work, 300);
    if iters >= 10 && !dl.passed() {
        let t = Instant::now();
        if let Some(q) = qpath::QPath::shifted(m, opt.upper, iters, None, dl) {
            parts.push(BoundValue {
                name: "qpath",
                value: round(q.root),
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }
}

/// Certified gap of a solution cost against a lower bound, in percent of the bound.
pub fn certified_gap_percent(cost: f64, lower: f64) -> Option<f64> {
    (lower > 0.0)
        .then(|| 100.0 * (cost - lower).max(0.0) / lower)
        .filter(|g| g.is_finite())
}

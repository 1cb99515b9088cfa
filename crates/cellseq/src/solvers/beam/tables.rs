//! The static tables of the incremental bound: potentials (root assignment duals, or the
//! subtour-elimination Lagrangian with its set multipliers), per-cell and per-node cheapest
//! reduced arcs, sorted arc lists, precedence masks (with twin symmetry breaking) and clusters.

use super::clusters::choose_clusters;
use super::twins::{TWIN_MAX_CELLS, twin_order};
use crate::bound::assignment::{self, Assignment};
use crate::bound::cells::CellGraph;
use crate::bound::sec::{self, SecBound};
use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::error::{Error, Result};
use crate::precedence::Closure;

/// Static data of the incremental bound.
///
/// All bound terms are written with the dual potentials `u`, `v` of the root assignment
/// problem (cells plus home = index n): every arc cost splits as `c(i, j) = u_i + v_j +
/// r(i, j)` with reduced cost `r`, so the rest of a path from the last cell `l` through the
/// unvisited set `U` to home costs exactly `u_l + v_home + Σ_{U} (u + v) + Σ r` over its arcs,
/// and `Σ r` is bounded below by degree arguments on reduced costs (valid for any potentials;
/// the assignment duals make them strong).
///
/// With `sec` the split is `c(i, j) = u_i + v_j + μ(i, j) + r(i, j)` where `μ(i, j)` sums
/// the multipliers `μ_S ≥ 0` of the sets `S` that the arc leaves ([`crate::bound::sec`]):
/// the rest of the path leaves every set that holds an unvisited cell or the last cell, so it
/// pays at least Σ μ_S over those on top of `Σ r` (and dropping `μ(i, j) ≥ 0` keeps the
/// O(1) incremental terms valid).
pub(super) struct Tables {
    pub(super) pred_mask: Vec<Vec<u64>>,
    /// per cell: u + v + cheapest reduced in-arc
    pub(super) cell_in: Vec<f64>,
    /// per cell: u + v + cheapest reduced out-arc
    pub(super) cell_out: Vec<f64>,
    /// per node: u(cell) + v(home) + cheapest reduced arc out of the node (μ excluded: the
    /// sets' multipliers are charged separately)
    pub(super) node_out: Vec<f64>,
    /// per node: u(cell) + v(home) + cheapest reduced arc into home
    pub(super) node_in: Vec<f64>,
    /// row potentials (cells, then home)
    pub(super) u: Vec<f64>,
    /// column potentials (cells, then home)
    pub(super) v: Vec<f64>,
    /// per cell: reduced cost of the cheapest finish (∞ when the cell cannot be last)
    pub(super) r_home: Vec<f64>,
    pub(super) integral: bool,
    /// per cell: allowed predecessor cells by increasing reduced cost
    pub(super) in_list: Vec<Vec<(f64, u32)>>,
    /// per cell: allowed successor cells (and home = n when it may be last) by increasing
    /// reduced cost
    pub(super) out_list: Vec<Vec<(f64, u32)>>,
    /// cluster index of each cell (`u32::MAX`: none); clusters are the subtours of the root
    /// assignment, which any path must enter and leave at least once
    pub(super) cluster: Vec<u32>,
    /// the clusters' cells
    pub(super) clusters: Vec<Vec<u32>>,
    /// Σ cell_in, Σ cell_out over all cells
    pub(super) total_in: f64,
    pub(super) total_out: f64,
    /// `μ(i, j)` over cells and home, row-major with n + 1 columns (empty: all zero)
    pub(super) mu_arc: Vec<f64>,
    /// subtour-elimination sets as cell bitsets (words of 64) with their multipliers
    pub(super) sec_sets: Vec<(Vec<u64>, f64)>,
    /// per cell: the indices of the subtour-elimination sets that hold it
    pub(super) sets_of: Vec<Vec<u32>>,
}

impl Tables {
    /// Σ μ_S over the subtour-elimination sets that the rest of a path must still leave:
    /// those holding the last cell `l` or an unvisited cell (`bits`: the visited set).
    #[inline]
    pub(super) fn active_mu(&self, bits: &[u64], l: usize) -> f64 {
        let mut sum = 0.0;
        for (set, mu) in &self.sec_sets {
            if set[l / 64] >> (l % 64) & 1 == 1 || set.iter().zip(bits).any(|(s, b)| s & !b != 0) {
                sum += mu;
            }
        }
        sum
    }

    /// Σ μ_S over the sets that hold `l` and lie inside `bits`: a prefix (`bits`, last `l`)
    /// must still leave them, each of its children no longer (they are visited and the child's
    /// last cell lies outside them); every other set keeps its status. So every child of the
    /// prefix has `active_mu` = the prefix's minus this.
    #[inline]
    pub(super) fn closing_mu(&self, bits: &[u64], l: usize) -> f64 {
        let mut sum = 0.0;
        for &k in &self.sets_of[l] {
            let (set, mu) = &self.sec_sets[k as usize];
            if set.iter().zip(bits).all(|(s, b)| s & !b == 0) {
                sum += mu;
            }
        }
        sum
    }

    /// `μ(i, j)`: Σ multipliers of the sets that the arc i → j leaves (home = n).
    #[inline]
    pub(super) fn mu(&self, n: usize, i: usize, j: usize) -> f64 {
        arc_mu(&self.mu_arc, n, i, j)
    }
}

/// `μ(i, j)` read from the dense multiplier matrix `mu_arc` (n + 1 columns; empty: all zero).
#[inline]
fn arc_mu(mu_arc: &[f64], n: usize, i: usize, j: usize) -> f64 {
    if mu_arc.is_empty() {
        0.0
    } else {
        mu_arc[i * (n + 1) + j]
    }
}

/// Largest instance for which the root assignment (O(n³)) gives the potentials.
const POTENTIAL_MAX_CELLS: usize = 600;

/// Work budget (d³ per iteration) of the subtour-elimination multipliers' subgradient steps.
const SEC_WORK: f64 = 2e8;

/// `upper`: cost of a known solution (constant included), for the subgradient steps.
/// `Ok(None)` when `deadline` passes before the tables are built (the root relaxation cut off
/// by it leaves weaker potentials, not none).
pub(super) fn tables(
    m: &CostModel,
    use_potentials: bool,
    use_sec: bool,
    twins: bool,
    upper: Option<f64>,
    deadline: Deadline,
) -> Result<Option<Tables>> {
    let n = m.n();
    let words = n.div_ceil(64).max(1);
    let cl = Closure::new(&m.dag).ok_or_else(|| Error::Solver {
        solver: "beam".into(),
        msg: "precedence has a cycle".into(),
    })?;
    let Some(g) = CellGraph::new_until(m, &cl, deadline) else {
        return Ok(None);
    };
    let with_potentials = use_potentials && n <= POTENTIAL_MAX_CELLS;
    let (sec, asg) = root_duals(m, &g, &cl, with_potentials, use_sec, upper, deadline);
    if deadline.passed() {
        return Ok(None);
    }
    let (u, v) = match (&sec, &asg) {
        (Some(s), _) => (s.u.clone(), s.v.clone()),
        (None, Some(a)) => (a.u.clone(), a.v.clone()),
        _ => (vec![0.0; n + 1], vec![0.0; n + 1]),
    };
    let mu_arc = sec
        .as_ref()
        .map(|s| s.arc_multipliers(n))
        .unwrap_or_default();
    let sec_sets = sec.as_ref().map(|s| set_bits(s, words)).unwrap_or_default();
    let red = Reduced {
        g: &g,
        u: &u,
        v: &v,
        mu_arc: &mu_arc,
    };
    let pred_mask = pred_masks(m, &cl, twins, words, deadline);
    let Some((node_out, node_in)) = node_terms(m, &cl, &red, deadline) else {
        return Ok(None);
    };
    let (in_list, out_list) = arc_lists(&red);
    let first = |l: &Vec<(f64, u32)>| l.first().map(|e| e.0).unwrap_or(0.0);
    let clusters = if asg.is_some() || sec.is_some() {
        choose_clusters(&g, &|i, j| red.r(i, j), deadline)
    } else {
        Vec::new()
    };
    if deadline.passed() {
        return Ok(None);
    }
    if crate::solvers::trace_enabled() {
        trace_root(m, sec.as_ref(), asg.as_ref(), &clusters);
    }
    let mut cluster = vec![u32::MAX; n];
    for (k, cs) in clusters.iter().enumerate() {
        for &c in cs {
            cluster[c as usize] = k as u32;
        }
    }
    let cell_in: Vec<f64> = (0..n).map(|c| u[c] + v[c] + first(&in_list[c])).collect();
    let cell_out: Vec<f64> = (0..n).map(|c| u[c] + v[c] + first(&out_list[c])).collect();
    let r_home: Vec<f64> = (0..n).map(|i| red.r(i, n)).collect();
    Ok(Some(Tables {
        total_in: cell_in.iter().sum(),
        total_out: cell_out.iter().sum(),
        cell_in,
        cell_out,
        sets_of: (0..n)
            .map(|c| {
                (0..sec_sets.len() as u32)
                    .filter(|&k| sec_sets[k as usize].0[c / 64] >> (c % 64) & 1 == 1)
                    .collect()
            })
            .collect(),
        sec_sets,
        r_home,
        in_list,
        out_list,
        pred_mask,
        node_out,
        node_in,
        mu_arc,
        u,
        v,
        integral: g.integral() && m.constant().fract() == 0.0,
        cluster,
        clusters,
    }))
}

/// The root relaxation whose duals give the potentials (`with_potentials`: wanted and
/// affordable): the subtour-elimination Lagrangian with `use_sec`, else (or when it fails)
/// the assignment problem; results with a non-finite dual are dropped.
fn root_duals(
    m: &CostModel,
    g: &CellGraph,
    cl: &Closure,
    with_potentials: bool,
    use_sec: bool,
    upper: Option<f64>,
    deadline: Deadline,
) -> (Option<SecBound>, Option<Assignment>) {
    let n = m.n();
    let sec: Option<SecBound> = (with_potentials && use_sec)
        .then(|| {
            let iters = sec::affordable_iterations(n, SEC_WORK, 1000);
            let upper = upper.map(|x| x - m.constant());
            sec::sec_bound_until(g, Some(cl), upper, iters, 4 * n + 16, deadline)
        })
        .flatten()
        .filter(|s| s.u.iter().chain(&s.v).chain(&s.mu).all(|x| x.is_finite()));
    let asg = if sec.is_some() {
        None
    } else {
        with_potentials
            .then(|| assignment::hungarian_duals_until(g.size(), |i, j| g.c(i, j), deadline))
            .flatten()
            .filter(|a| a.u.iter().chain(&a.v).all(|x| x.is_finite()))
    };
    (sec, asg)
}

/// The subtour-elimination sets of `s` as cell bitsets of `words` words, with their
/// multipliers.
fn set_bits(s: &SecBound, words: usize) -> Vec<(Vec<u64>, f64)> {
    s.sets
        .iter()
        .zip(&s.mu)
        .map(|(cells, &mu)| {
            let mut w = vec![0u64; words];
            for &c in cells {
                w[c as usize / 64] |= 1 << (c % 64);
            }
            (w, mu)
        })
        .collect()
}

/// Reduced costs over cells and home (index n): `r(i, j) = c(i, j) − u_i − v_j − μ(i, j)`.
struct Reduced<'a> {
    g: &'a CellGraph,
    u: &'a [f64],
    v: &'a [f64],
    /// `μ(i, j)`, row-major with n + 1 columns (empty: all zero)
    mu_arc: &'a [f64],
}

impl Reduced<'_> {
    /// `μ(i, j)`: Σ multipliers of the sets that the arc i → j leaves.
    fn mu(&self, i: usize, j: usize) -> f64 {
        arc_mu(self.mu_arc, self.g.n, i, j)
    }

    /// The reduced cost of the cell-graph arc i → j.
    fn r(&self, i: usize, j: usize) -> f64 {
        self.g.c(i, j) - self.u[i] - self.v[j] - self.mu(i, j)
    }
}

/// Per cell: its predecessors as a bitset of `words` words; with `twins`, each twin also
/// waits for the twin that leads it (symmetry breaking, up to [`TWIN_MAX_CELLS`] cells; the
/// pairs found before `deadline`).
fn pred_masks(
    m: &CostModel,
    cl: &Closure,
    twins: bool,
    words: usize,
    deadline: Deadline,
) -> Vec<Vec<u64>> {
    let n = m.n();
    let mut pred_mask: Vec<Vec<u64>> = (0..n)
        .map(|c| {
            let mut v = vec![0u64; words];
            for &p in &m.dag.preds[c] {
                v[p as usize / 64] |= 1 << (p % 64);
            }
            v
        })
        .collect();
    if twins && n <= TWIN_MAX_CELLS {
        for (a, b) in twin_order(m, cl, deadline) {
            pred_mask[b][a / 64] |= 1 << (a % 64);
        }
    }
    pred_mask
}

/// Per node: `Tables::node_out` and `Tables::node_in` (the last node's terms of the
/// incremental bound); `None` once `deadline` passes (checked per node: O(nodes) work each).
fn node_terms(
    m: &CostModel,
    cl: &Closure,
    red: &Reduced,
    deadline: Deadline,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let n = m.n();
    let (u, v) = (red.u, red.v);
    let fin = |x: f64| if x.is_finite() { x } else { 0.0 };
    let mut node_out = vec![0.0; m.nodes()];
    let mut node_in = vec![0.0; m.nodes()];
    let home_in = fin((0..n).map(|i| red.r(i, n)).fold(f64::INFINITY, f64::min));
    for (nd, slot) in node_out.iter_mut().enumerate() {
        if deadline.passed() {
            return None;
        }
        let (a, ma) = m.cell_mode(nd);
        let mut best = if cl.can_be_last(a) {
            m.finish(a, ma) - u[a] - v[n] - red.mu(a, n)
        } else {
            f64::INFINITY
        };
        for b in 0..n {
            if cl.arc_allowed(a, b) {
                for mb in 0..m.modes(b) {
                    best = best.min(m.arc(a, ma, b, mb) - u[a] - v[b] - red.mu(a, b));
                }
            }
        }
        *slot = u[a] + v[n] + fin(best);
        node_in[nd] = u[a] + v[n] + home_in;
    }
    Some((node_out, node_in))
}

/// Per cell: the allowed predecessor cells, and the allowed successors (home = n when it
/// may be last), each by increasing reduced cost (ties: index).
#[allow(clippy::type_complexity)]
fn arc_lists(red: &Reduced) -> (Vec<Vec<(f64, u32)>>, Vec<Vec<(f64, u32)>>) {
    let (g, n) = (red.g, red.g.n);
    let mut in_list = vec![Vec::new(); n];
    let mut out_list = vec![Vec::new(); n];
    #[allow(clippy::needless_range_loop)]
    for i in 0..n {
        for j in 0..=n {
            if g.c(i, j).is_finite() {
                out_list[i].push((red.r(i, j), j as u32));
                if j < n {
                    in_list[j].push((red.r(i, j), i as u32));
                }
            }
        }
    }
    for l in in_list.iter_mut().chain(out_list.iter_mut()) {
        l.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
    }
    (in_list, out_list)
}

/// Prints the root relaxation and the chosen clusters (with `CELLSEQ_TRACE`).
fn trace_root(
    m: &CostModel,
    sec: Option<&SecBound>,
    asg: Option<&Assignment>,
    clusters: &[Vec<u32>],
) {
    eprintln!(
        "beam: assignment {:?}, clusters {:?}",
        asg.map(|a| a.value),
        clusters
    );
    if let Some(s) = sec {
        eprintln!(
            "beam: sec bound {} after {} iterations, {} sets with a multiplier",
            s.value + m.constant(),
            s.iterations,
            s.sets.len()
        );
    }
}

//! The assignment bound: a minimum-cost assignment (Hungarian method: dense, or
//! [`super::lap`] above [`DENSE_MAX_ORDER`]) on the cell graph closed into a cycle through
//! home. Every feasible sequence plus its return to home is a cyclic permutation, hence an
//! assignment, so the optimum assignment is a lower bound.

use super::cells::CellGraph;
use crate::clock::Deadline;

/// Solves the assignment problem on a dense square matrix (`INFINITY` = forbidden).
/// Returns the optimal value and the column of each row, or `None` if no finite assignment
/// exists.
pub fn hungarian(d: usize, cost: impl Fn(usize, usize) -> f64) -> Option<(f64, Vec<usize>)> {
    hungarian_duals(d, cost).map(|a| (a.value, a.col))
}

/// An optimal assignment with its dual potentials.
#[derive(Debug, Clone)]
pub struct Assignment {
    /// Optimal value.
    pub value: f64,
    /// Column assigned to each row.
    pub col: Vec<usize>,
    /// Row potentials: `cost(i, j) - u[i] - v[j] >= 0` for every finite entry (up to rounding).
    pub u: Vec<f64>,
    /// Column potentials.
    pub v: Vec<f64>,
}

/// Like [`hungarian`], and also returns the dual potentials `u`, `v` (reduced costs
/// `cost(i, j) - u[i] - v[j]` are non-negative; `Σu + Σv` = the optimal value).
pub fn hungarian_duals(d: usize, cost: impl Fn(usize, usize) -> f64) -> Option<Assignment> {
    hungarian_duals_until(d, cost, Deadline::NONE)
}

/// Up to this order the dense method runs ([`dense_until`]), above it the sparse one
/// ([`super::lap`]). Both are exact but reach different optimal duals, and the beam's
/// reduced-cost bounds were tuned on the dense method's; its O(d³) worst case (all costs
/// equal) stays under about 0.3 s here.
pub const DENSE_MAX_ORDER: usize = 512;

/// Like [`hungarian_duals`], or `None` once `deadline` passes (checked before each
/// augmenting search).
pub fn hungarian_duals_until(
    d: usize,
    cost: impl Fn(usize, usize) -> f64,
    deadline: Deadline,
) -> Option<Assignment> {
    if d <= DENSE_MAX_ORDER {
        dense_until(d, cost, deadline)
    } else {
        super::lap::solve(d, cost, deadline)
    }
}

/// The dense Hungarian method (the e-maxx formulation), O(d³): each of the d augmentations
/// scans every column per step. `None` once `deadline` passes (checked before each
/// augmentation) or when no finite assignment exists.
///
/// `cost` is read once per entry into a row-major matrix (forbidden entries replaced by a
/// penalty larger than any finite assignment), so the O(d³) scans read memory, not the
/// caller's closure.
pub fn dense_until(
    d: usize,
    cost: impl Fn(usize, usize) -> f64,
    deadline: Deadline,
) -> Option<Assignment> {
    if d == 0 {
        return Some(Assignment {
            value: 0.0,
            col: Vec::new(),
            u: Vec::new(),
            v: Vec::new(),
        });
    }
    let mut m = Vec::with_capacity(d * d);
    let mut finite_max = 0.0f64;
    let mut forbidden = false;
    for i in 0..d {
        for j in 0..d {
            let c = cost(i, j);
            if c.is_finite() {
                finite_max = finite_max.max(c.abs());
            } else {
                forbidden = true;
            }
            m.push(c);
        }
    }
    if forbidden {
        let big = (finite_max + 1.0) * (d as f64 + 1.0) * 4.0;
        for c in m.iter_mut().filter(|c| !c.is_finite()) {
            *c = big;
        }
    }
    let Potentials { u, v, p } = augment_all(d, &m, deadline)?;
    let mut col = vec![0usize; d];
    for j in 1..=d {
        col[p[j] - 1] = j - 1;
    }
    let mut total = 0.0;
    for (i, &j) in col.iter().enumerate() {
        let c = cost(i, j);
        if !c.is_finite() {
            return None;
        }
        total += c;
    }
    Some(Assignment {
        value: total,
        col,
        u: u[1..].to_vec(),
        v: v[1..].to_vec(),
    })
}

/// The result of [`augment_all`], 1-based with a virtual column 0.
struct Potentials {
    /// Row potentials.
    u: Vec<f64>,
    /// Column potentials.
    v: Vec<f64>,
    /// The row matched to each column.
    p: Vec<usize>,
}

/// The e-maxx augmentations on the row-major `d × d` matrix `m`. `None` once `deadline`
/// passes (checked before each augmentation).
fn augment_all(d: usize, m: &[f64], deadline: Deadline) -> Option<Potentials> {
    let inf = f64::INFINITY;
    let mut u = vec![0.0; d + 1];
    let mut v = vec![0.0; d + 1];
    let mut p = vec![0usize; d + 1];
    let mut way = vec![0usize; d + 1];
    let mut minv = vec![inf; d + 1];
    let mut used = vec![false; d + 1];
    for i in 1..=d {
        if deadline.passed() {
            return None;
        }
        p[0] = i;
        let mut j0 = 0usize;
        minv.fill(inf);
        used.fill(false);
        loop {
            used[j0] = true;
            let i0 = p[j0];
            let row = &m[(i0 - 1) * d..i0 * d];
            let ui = u[i0];
            let mut delta = inf;
            let mut j1 = 0usize;
            for j in 1..=d {
                if !used[j] {
                    let cur = row[j - 1] - ui - v[j];
                    if cur < minv[j] {
                        minv[j] = cur;
                        way[j] = j0;
                    }
                    if minv[j] < delta {
                        delta = minv[j];
                        j1 = j;
                    }
                }
            }
            for j in 0..=d {
                if used[j] {
                    u[p[j]] += delta;
                    v[j] -= delta;
                } else {
                    minv[j] -= delta;
                }
            }
            j0 = j1;
            if p[j0] == 0 {
                break;
            }
        }
        loop {
            let j1 = way[j0];
            p[j0] = p[j1];
            j0 = j1;
            if j0 == 0 {
                break;
            }
        }
    }
    Some(Potentials { u, v, p })
}

/// The assignment bound on the arc part of the cost (without the model's constant).
pub fn assignment_bound(g: &CellGraph) -> Option<f64> {
    hungarian(g.size(), |i, j| g.c(i, j)).map(|r| r.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn hungarian_small_matrix() {
        let m = [[4.0, 1.0, 3.0], [2.0, 0.0, 5.0], [3.0, 2.0, 2.0]];
        let (v, col) = hungarian(3, |i, j| m[i][j]).unwrap();
        assert_eq!(v, 5.0);
        assert_eq!(col, vec![1, 0, 2]);
        let a = hungarian_duals(3, |i, j| m[i][j]).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                assert!(m[i][j] - a.u[i] - a.v[j] >= -1e-9);
            }
        }
        let dual: f64 = a.u.iter().chain(&a.v).sum();
        assert!((dual - 5.0).abs() < 1e-9);
    }

    #[test]
    fn hungarian_forbidden() {
        let inf = f64::INFINITY;
        let m = [[inf, 1.0], [inf, 2.0]];
        assert!(hungarian(2, |i, j| m[i][j]).is_none());
        let m = [[inf, 7.0], [3.0, inf]];
        assert_eq!(hungarian(2, |i, j| m[i][j]).unwrap().0, 10.0);
    }

    /// Random d × d matrices: value equal to the dense oracle's, duals feasible on every
    /// finite arc and tight on the chosen ones, a permutation; over wide and tiny cost ranges
    /// (many ties), negative costs and forbidden arcs (also rows with fewer finite arcs than
    /// a list holds, and instances with no finite assignment).
    #[test]
    fn sparse_method_matches_the_dense_oracle() {
        let mut infeasible = 0;
        for seed in 0..300u64 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let d = 1 + rng.random_range(0..60usize);
            let range = [1u64, 3, 20, 1000][seed as usize % 4];
            let forbid = [0.0, 0.2, 0.6, 0.9][(seed as usize / 4) % 4];
            let shift = if seed % 7 == 0 { -5.0 } else { 0.0 };
            let m: Vec<f64> = (0..d * d)
                .map(|_| {
                    if rng.random_bool(forbid) {
                        f64::INFINITY
                    } else {
                        rng.random_range(0..=range) as f64 + shift
                    }
                })
                .collect();
            let c = |i: usize, j: usize| m[i * d + j];
            let want = dense_until(d, c, Deadline::NONE);
            let got = super::super::lap::solve(d, c, Deadline::NONE);
            match (&want, &got) {
                (None, None) => infeasible += 1,
                (Some(w), Some(g)) => {
                    assert!((w.value - g.value).abs() < 1e-9, "seed {seed}: {} vs {}", w.value, g.value);
                    let mut seen = vec![false; d];
                    for (i, &j) in g.col.iter().enumerate() {
                        assert!(!seen[j], "seed {seed}: column {j} twice");
                        seen[j] = true;
                        assert!((c(i, j) - g.u[i] - g.v[j]).abs() < 1e-9, "seed {seed}: not tight");
                    }
                    for i in 0..d {
                        for j in 0..d {
                            if c(i, j).is_finite() {
                                assert!(c(i, j) - g.u[i] - g.v[j] >= -1e-9, "seed {seed}: dual ({i},{j})");
                            }
                        }
                    }
                    let dual: f64 = g.u.iter().chain(&g.v).sum();
                    assert!((dual - g.value).abs() < 1e-6, "seed {seed}: dual {dual}");
                }
                _ => panic!("seed {seed}: oracle {:?}, sparse {:?}", want.map(|a| a.value), got.map(|a| a.value)),
            }
        }
        assert!(infeasible > 0 && infeasible < 150, "{infeasible} infeasible cases");
    }

    /// A matrix of equal costs (every assignment optimal) of the size where the dense method
    /// took its O(d³): solved, with feasible duals.
    #[test]
    fn all_ties() {
        let d = 400;
        let a = super::super::lap::solve(d, |i, j| if i == j { 5.0 } else { 0.0 }, Deadline::NONE).unwrap();
        assert_eq!(a.value, 0.0);
        assert!(a.col.iter().enumerate().all(|(i, &j)| i != j));
    }

    /// Above [`DENSE_MAX_ORDER`] the sparse method answers: on an order-600 matrix whose
    /// cheap arcs (costs 0–5) all go to one column in seven, the others costing 10 more, with
    /// forbidden arcs (many ties; most rows lose the race for a cheap column) its value is
    /// the dense method's.
    #[test]
    fn large_orders_take_the_sparse_method_with_the_same_value() {
        let d = DENSE_MAX_ORDER + 88;
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let m: Vec<f64> = (0..d * d)
            .map(|k| {
                if rng.random_bool(0.3) {
                    f64::INFINITY
                } else {
                    let dear = if (k % d).is_multiple_of(7) { 0 } else { 10 };
                    (rng.random_range(0..=5u64) + dear) as f64
                }
            })
            .collect();
        let c = |i: usize, j: usize| m[i * d + j];
        let sparse = hungarian_duals(d, c).unwrap();
        let dense = dense_until(d, c, Deadline::NONE).unwrap();
        assert_eq!(sparse.value, dense.value);
        assert!(sparse.value >= 10.0 * (d - d.div_ceil(7)) as f64, "{}", sparse.value);
        let lap = super::super::lap::solve(d, c, Deadline::NONE).unwrap();
        assert_eq!(lap.col, sparse.col, "hungarian_duals did not take the sparse method");
    }
}

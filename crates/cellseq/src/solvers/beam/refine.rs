//! The refined node bound of one prefix (degree sums over the arcs still possible, cluster
//! surcharges, subtour-elimination multipliers), and the bounds built on it.

use super::prefix::{Prefix, first_prefixes, open_cells};
use super::tables::Tables;
use crate::cost::CostModel;

/// The dynamic bound of a prefix, in reduced costs (see [`Tables`]): every unvisited cell is
/// entered from an unvisited cell or the last one, and left to an unvisited cell or home; the
/// last node is left to an unvisited cell; and every root-assignment cluster's unvisited part
/// must be entered from outside it and left to outside it at least once, which adds the
/// cheapest surcharge of doing so over its members' own cheapest arcs.
/// O(|unvisited| · scan) with the sorted arc lists; `scratch` holds n + clusters entries.
pub(super) fn refined<const W: usize>(
    m: &CostModel,
    t: &Tables,
    p: &Prefix<W>,
    scratch: &mut [(f64, f64)],
) -> f64 {
    let n = m.n();
    let (l, lm) = m.cell_mode(p.node as usize);
    let view = View { t, p, n, l };
    let (io, dd) = scratch.split_at_mut(n);
    let mut d = match degree_sums(m, &view, lm, io) {
        Ok(d) => d,
        Err(bound) => return bound,
    };
    let Some(any_cluster) = cluster_surcharges(&view, io, dd, &mut d) else {
        return f64::INFINITY;
    };
    if any_cluster {
        cluster_links(&view, io, dd, &mut d);
    }
    // every set holding the last cell or an unvisited one must still be left
    d.pot += t.active_mu(&p.bits, l);
    p.g + d.pot + (d.h_in + d.home_in).max(d.h_out + d.last_out)
}

/// A prefix as the refined bound reads it: the tables, the prefix, the number of cells and
/// the last cell.
struct View<'a, const W: usize> {
    t: &'a Tables,
    p: &'a Prefix<W>,
    n: usize,
    l: usize,
}

impl<const W: usize> View<'_, W> {
    /// Whether `c` is a cell (not home) that the prefix has not visited.
    #[inline]
    fn open(&self, c: usize) -> bool {
        c < self.n && self.p.bits[c / 64] >> (c % 64) & 1 == 0
    }
}

/// The running terms of the refined bound, in reduced costs.
struct Degrees {
    /// potentials: the last cell's row, home's column, both of every unvisited cell
    pot: f64,
    /// Σ cheapest allowed reduced in-arc over the unvisited cells (plus surcharges)
    h_in: f64,
    /// Σ cheapest allowed reduced out-arc over the unvisited cells (plus surcharges)
    h_out: f64,
    /// cheapest reduced finish from an unvisited cell (0 when none is finite)
    home_in: f64,
    /// cheapest reduced arc out of the last node into an unvisited cell
    last_out: f64,
}

/// The degree sums over the unvisited cells, each cell's cheapest in- and out-arc kept in
/// `io`; `Err` holds the bound outright: the finish when no cell is left, infinite when some
/// cell can no longer be entered or left.
fn degree_sums<const W: usize>(
    m: &CostModel,
    view: &View<W>,
    lm: usize,
    io: &mut [(f64, f64)],
) -> std::result::Result<Degrees, f64> {
    let (t, n, l) = (view.t, view.n, view.l);
    let mut pot = t.u[l] + t.v[n];
    let mut h_in = 0.0;
    let mut h_out = 0.0;
    let mut home_in = f64::INFINITY;
    let mut last_out = f64::INFINITY;
    let mut any = false;
    for j in open_cells(&view.p.bits, n) {
        any = true;
        pot += t.u[j] + t.v[j];
        let Some(i) = t.in_list[j]
            .iter()
            .find(|&&(_, i)| view.open(i as usize) || i as usize == l)
            .map(|e| e.0)
        else {
            return Err(f64::INFINITY);
        };
        h_in += i;
        let Some(o) = t.out_list[j]
            .iter()
            .find(|&&(_, k)| view.open(k as usize) || k as usize == n)
            .map(|e| e.0)
        else {
            return Err(f64::INFINITY);
        };
        h_out += o;
        io[j] = (i, o);
        home_in = home_in.min(t.r_home[j]);
        let mu = t.mu(n, l, j);
        for mj in 0..m.modes(j) {
            last_out = last_out.min(m.arc(l, lm, j, mj) - t.u[l] - t.v[j] - mu);
        }
    }
    if !any {
        return Err(view.p.g + m.finish(l, lm));
    }
    if !last_out.is_finite() {
        return Err(f64::INFINITY);
    }
    Ok(Degrees {
        pot,
        h_in,
        h_out,
        home_in: if home_in.is_finite() { home_in } else { 0.0 },
        last_out,
    })
}

/// Pass 1: the entering and leaving surcharge of each cluster's open part over its members'
/// own cheapest arcs (`io`), added to the degree sums and kept in `dd` (NaN: the cluster has
/// no open cell). Returns whether some cluster is open; `None` when one can no longer be
/// entered or left.
fn cluster_surcharges<const W: usize>(
    view: &View<W>,
    io: &[(f64, f64)],
    dd: &mut [(f64, f64)],
    d: &mut Degrees,
) -> Option<bool> {
    let (t, n, l) = (view.t, view.n, view.l);
    let mut any_cluster = false;
    for (s, cells) in t.clusters.iter().enumerate() {
        let s = s as u32;
        let mut d_in = f64::INFINITY;
        let mut d_out = f64::INFINITY;
        let mut touched = false;
        for &j in cells {
            let j = j as usize;
            if !view.open(j) {
                continue;
            }
            touched = true;
            let (i0, o0) = io[j];
            if let Some(&(c, _)) = t.in_list[j].iter().find(|&&(_, i)| {
                let i = i as usize;
                i == l || (view.open(i) && t.cluster[i] != s)
            }) {
                d_in = d_in.min(c - i0);
            }
            if let Some(&(c, _)) = t.out_list[j].iter().find(|&&(_, k)| {
                let k = k as usize;
                k == n || (view.open(k) && t.cluster[k] != s)
            }) {
                d_out = d_out.min(c - o0);
            }
        }
        if !touched {
            dd[s as usize] = (f64::NAN, f64::NAN);
            continue;
        }
        if !d_in.is_finite() || !d_out.is_finite() {
            return None;
        }
        any_cluster = true;
        dd[s as usize] = (d_in.max(0.0), d_out.max(0.0));
        d.h_in += d_in.max(0.0);
        d.h_out += d_out.max(0.0);
    }
    Some(any_cluster)
}

/// Pass 2: a cluster's leaving arc enters some cell k (or home); in the in-degree sum it
/// costs at least min_in(k) plus, when k's cluster is entered by it, that cluster's entering
/// surcharge: the rest is an extra surcharge on top (and symmetrically for entering arcs in
/// the out-degree sum). Each arc is charged at most one entering and one leaving surcharge,
/// so the sums stay valid.
fn cluster_links<const W: usize>(
    view: &View<W>,
    io: &[(f64, f64)],
    dd: &[(f64, f64)],
    d: &mut Degrees,
) {
    let (t, n, l) = (view.t, view.n, view.l);
    let (home_in, last_out) = (d.home_in, d.last_out);
    let open_d = |k: usize| -> (f64, f64) {
        let c = t.cluster[k];
        if c == u32::MAX || dd[c as usize].0.is_nan() {
            (0.0, 0.0)
        } else {
            dd[c as usize]
        }
    };
    let mut max_in = home_in;
    let mut max_out = last_out;
    for j in open_cells(&view.p.bits, n) {
        let d = open_d(j);
        max_in = max_in.max(io[j].0 + d.0);
        max_out = max_out.max(io[j].1 + d.1);
    }
    for (s, cells) in t.clusters.iter().enumerate() {
        if dd[s].0.is_nan() {
            continue;
        }
        let s = s as u32;
        let mut e_out = f64::INFINITY;
        let mut e_in = f64::INFINITY;
        for &j in cells {
            let j = j as usize;
            if !view.open(j) {
                continue;
            }
            for &(c, k) in &t.out_list[j] {
                if c - max_in >= e_out {
                    break;
                }
                let k = k as usize;
                let base = if k == n {
                    home_in
                } else if view.open(k) && t.cluster[k] != s {
                    io[k].0 + open_d(k).0
                } else {
                    continue;
                };
                e_out = e_out.min(c - base);
            }
            for &(c, i) in &t.in_list[j] {
                if c - max_out >= e_in {
                    break;
                }
                let i = i as usize;
                let base = if i == l {
                    last_out
                } else if view.open(i) && t.cluster[i] != s {
                    io[i].1 + open_d(i).1
                } else {
                    continue;
                };
                e_in = e_in.min(c - base);
            }
        }
        if e_out.is_finite() {
            d.h_in += e_out.max(0.0);
        }
        if e_in.is_finite() {
            d.h_out += e_in.max(0.0);
        }
    }
}

/// The bounds the tests read, compiled for them only.
#[cfg(any(test, feature = "internals"))]
mod for_tests {
    use super::*;
    use crate::error::{Error, Result};
    use crate::model::Visit;
    use crate::solvers::beam::MAX_CELLS;
    use crate::solvers::beam::tables::tables;
    use crate::clock::Deadline;

    /// The node bound (`refined`: potentials, subtour-elimination multipliers, degree sums and
    /// cluster surcharges) of every prefix of `seq`, in order, with the tables built as the beam
    /// builds them (`upper`: a known solution cost for the subgradient steps; no symmetry
    /// breaking). For tests: along an optimal sequence every value is at most the optimum.
    pub fn prefix_bounds(m: &CostModel, seq: &[Visit], upper: Option<f64>) -> Result<Vec<f64>> {
        fn go<const W: usize>(m: &CostModel, seq: &[Visit], upper: Option<f64>) -> Result<Vec<f64>> {
            let t = tables(m, true, true, false, upper, Deadline::NONE)?.expect("no deadline");
            let mut scratch = vec![(0.0, 0.0); m.n() + t.clusters.len()];
            let mut out = Vec::with_capacity(seq.len());
            let Some(v0) = seq.first() else {
                return Ok(out);
            };
            let mut p = Prefix::<W>::first(m, &t, v0.cell, v0.mode, 0.0);
            out.push(refined(m, &t, &p, &mut scratch));
            for w in seq.windows(2) {
                let (a, b) = (w[0], w[1]);
                p.bits[b.cell / 64] |= 1 << (b.cell % 64);
                p.node = m.node(b.cell, b.mode) as u32;
                p.g += m.arc(a.cell, a.mode, b.cell, b.mode);
                out.push(refined(m, &t, &p, &mut scratch));
            }
            Ok(out)
        }
        match m.n().div_ceil(64) {
            0 | 1 => go::<1>(m, seq, upper),
            2 => go::<2>(m, seq, upper),
            3 | 4 => go::<4>(m, seq, upper),
            5..=8 => go::<8>(m, seq, upper),
            9..=16 => go::<16>(m, seq, upper),
            _ => Err(Error::Solver {
                solver: "beam".into(),
                msg: format!(
                    "instance has {} cells; beam accepts at most {MAX_CELLS}",
                    m.n()
                ),
            }),
        }
    }
}
#[cfg(any(test, feature = "internals"))]
pub use for_tests::prefix_bounds;

/// The smallest refined bound over all one-cell prefixes: a lower bound on the optimum.
pub(super) fn first_level_bound<const W: usize>(m: &CostModel, t: &Tables) -> f64 {
    let n = m.n();
    let mut scratch = vec![(0.0, 0.0); n + t.clusters.len()];
    first_prefixes::<W>(m, t, 0.0, |_| 0.0)
        .iter()
        .map(|p| refined(m, t, p, &mut scratch))
        .fold(f64::INFINITY, f64::min)
}

//! Stored prefixes of the beam (visited set, last node, cost so far, the incremental bound
//! terms) and the ranking that keeps a level's best.

use super::tables::Tables;
use crate::cost::CostModel;

/// One stored prefix.
#[derive(Clone, Copy)]
pub(super) struct Prefix<const W: usize> {
    pub(super) bits: [u64; W],
    pub(super) node: u32,
    pub(super) parent: u32,
    pub(super) g: f64,
    /// Σ cheapest in-arc over unvisited cells
    pub(super) rem_in: f64,
    /// Σ cheapest out-arc over unvisited cells
    pub(super) rem_out: f64,
    /// Σ qpath multipliers over unvisited cells
    pub(super) lam_open: f64,
    /// Σ μ_S over the sets the rest must still leave ([`Tables::active_mu`], kept
    /// incrementally: a child has its parent's less [`Tables::closing_mu`] of the parent)
    pub(super) act: f64,
    pub(super) f: f64,
}

impl<const W: usize> Prefix<W> {
    /// The one-cell prefix of cell `c` in mode `md` with its incremental bound terms
    /// (`lam_open`: Σ qpath multipliers over the other cells); `f` is left at 0.
    pub(super) fn first(m: &CostModel, t: &Tables, c: usize, md: usize, lam_open: f64) -> Self {
        let mut bits = [0u64; W];
        bits[c / 64] |= 1 << (c % 64);
        Prefix {
            bits,
            node: m.node(c, md) as u32,
            parent: u32::MAX,
            g: m.constant() + m.start(c, md),
            rem_in: t.total_in - t.cell_in[c],
            rem_out: t.total_out - t.cell_out[c],
            lam_open,
            act: t.active_mu(&bits, c),
            f: 0.0,
        }
    }
}

/// The cells below `n` that are not in the set `bits`, in increasing order (a word of the
/// set at a time: the visited cells cost nothing to skip).
#[inline]
pub(super) fn open_cells<const W: usize>(bits: &[u64; W], n: usize) -> impl Iterator<Item = usize> + '_ {
    bits.iter().enumerate().flat_map(move |(w, &have)| {
        let below = n.saturating_sub(w * 64);
        let valid = if below >= 64 { u64::MAX } else { (1u64 << below) - 1 };
        let mut open = !have & valid;
        std::iter::from_fn(move || {
            (open != 0).then(|| {
                let b = open.trailing_zeros() as usize;
                open &= open - 1;
                w * 64 + b
            })
        })
    })
}

/// Every one-cell prefix: each cell that may come first (no predecessor, twins included), in
/// each mode; `lam_total` = Σ qpath multipliers, `lam(c)` the multiplier of cell `c`.
pub(super) fn first_prefixes<const W: usize>(
    m: &CostModel,
    t: &Tables,
    lam_total: f64,
    lam: impl Fn(usize) -> f64,
) -> Vec<Prefix<W>> {
    (0..m.n())
        .filter(|&c| t.pred_mask[c].iter().all(|&w| w == 0))
        .flat_map(|c| (0..m.modes(c)).map(move |md| (c, md)))
        .map(|(c, md)| Prefix::first(m, t, c, md, lam_total - lam(c)))
        .collect()
}

/// Order by bound, then cost, last node and visited set (a total order on distinct prefixes).
pub(super) fn rank<const W: usize>(a: &Prefix<W>, b: &Prefix<W>) -> std::cmp::Ordering {
    a.f.total_cmp(&b.f)
        .then(a.g.total_cmp(&b.g))
        .then(a.node.cmp(&b.node))
        .then(a.bits.cmp(&b.bits))
}

/// Keeps the `width` candidates with the smallest bound (ties: cost, then last node and visited
/// set, so the choice is deterministic). Returns true when some were discarded.
pub(super) fn keep_best<const W: usize>(
    c: &mut Vec<Prefix<W>>,
    width: usize,
    by_cost: bool,
) -> bool {
    if c.len() <= width {
        return false;
    }
    let key = |a: &Prefix<W>, b: &Prefix<W>| {
        let (x, y) = if by_cost { (a.g, b.g) } else { (a.f, b.f) };
        x.total_cmp(&y)
            .then(a.f.total_cmp(&b.f))
            .then(a.g.total_cmp(&b.g))
            .then(a.node.cmp(&b.node))
            .then(a.bits.cmp(&b.bits))
    };
    c.select_nth_unstable_by(width - 1, key);
    c.truncate(width);
    true
}

#[cfg(test)]
mod tests {
    use super::open_cells;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn open_cells_are_the_cells_below_n_not_in_the_set_in_order() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for n in [0, 1, 5, 63, 64, 65, 100, 127, 128] {
            for _ in 0..50 {
                let mut bits = [0u64; 2];
                for v in 0..n {
                    if rng.random_bool(0.5) {
                        bits[v / 64] |= 1 << (v % 64);
                    }
                }
                let want: Vec<usize> =
                    (0..n).filter(|&v| bits[v / 64] >> (v % 64) & 1 == 0).collect();
                assert_eq!(open_cells(&bits, n).collect::<Vec<_>>(), want, "n = {n}");
            }
        }
    }
}

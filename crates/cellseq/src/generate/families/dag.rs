//! Random precedence DAGs with a target **closure** density, over a hidden random order.
//!
//! Pairs `(a, b)` with `a` before `b` in a hidden random order are drawn uniformly at random;
//! a pair already implied by the edges drawn so far is skipped, and a pair whose transitive
//! consequences would carry the closure more than a tolerance past the target is skipped too.
//! Drawing stops once the closure holds the target share of the n(n−1)/2 pairs. The edges
//! returned are the drawn ones, not their closure, so the relation is usually not transitively
//! closed. The closure is kept as bitsets of descendants and ancestors (n²/4 bytes).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// Transitive closure of a growing DAG as bitsets.
struct Closure {
    words: usize,
    /// `desc[x * words ..]`: the cells after x.
    desc: Vec<u64>,
    /// `anc[x * words ..]`: the cells before x.
    anc: Vec<u64>,
    pairs: usize,
}

impl Closure {
    fn new(n: usize) -> Self {
        let words = n.div_ceil(64).max(1);
        Closure {
            words,
            desc: vec![0; n * words],
            anc: vec![0; n * words],
            pairs: 0,
        }
    }
    fn has(&self, a: usize, b: usize) -> bool {
        self.desc[a * self.words + b / 64] >> (b % 64) & 1 == 1
    }
    /// `row` of `set` with `x` itself added.
    fn with_self(&self, set: &[u64], x: usize) -> Vec<u64> {
        let mut v = set[x * self.words..(x + 1) * self.words].to_vec();
        v[x / 64] |= 1 << (x % 64);
        v
    }
    fn members(bits: &[u64]) -> impl Iterator<Item = usize> + '_ {
        bits.iter().enumerate().flat_map(|(w, &word)| {
            let mut m = word;
            std::iter::from_fn(move || {
                if m == 0 {
                    return None;
                }
                let t = m.trailing_zeros() as usize;
                m &= m - 1;
                Some(w * 64 + t)
            })
        })
    }
    /// New closure pairs that the edge a → b would add.
    fn gain(&self, a: usize, b: usize) -> usize {
        let down = self.with_self(&self.desc, b);
        let up = self.with_self(&self.anc, a);
        Self::members(&up)
            .map(|x| {
                let row = &self.desc[x * self.words..(x + 1) * self.words];
                down.iter()
                    .zip(row)
                    .map(|(d, r)| (d & !r).count_ones() as usize)
                    .sum::<usize>()
            })
            .sum()
    }
    fn add(&mut self, a: usize, b: usize, gain: usize) {
        let down = self.with_self(&self.desc, b);
        let up = self.with_self(&self.anc, a);
        let w = self.words;
        for x in Self::members(&up) {
            for (r, d) in self.desc[x * w..(x + 1) * w].iter_mut().zip(&down) {
                *r |= d;
            }
        }
        for y in Self::members(&down) {
            for (r, u) in self.anc[y * w..(y + 1) * w].iter_mut().zip(&up) {
                *r |= u;
            }
        }
        self.pairs += gain;
    }
}

/// A random DAG on `n` cells whose transitive closure holds about `density` (0..=1) of the
/// n(n−1)/2 pairs: at least the target, and at most max(n, 0.5 % of the pairs) above it.
/// Returns edges `(a, b)`, a before b, in the order drawn. Deterministic for a given `rng`
/// state. Gives up adding edges (and returns what it has) after 64·n² + 1000 draws, which
/// only a density near 1 on very small n can reach.
pub fn random_dag(n: usize, density: f64, rng: &mut ChaCha8Rng) -> Vec<(usize, usize)> {
    if n < 2 || density <= 0.0 {
        return Vec::new();
    }
    let all = n * (n - 1) / 2;
    let target = ((density.min(1.0) * all as f64).round() as usize).min(all);
    let slack = n.max(all / 200);
    let ceiling = (target + slack).min(all);
    let hidden = crate::generate::common::random_permutation(n, rng);
    let mut clo = Closure::new(n);
    let mut edges = Vec::new();
    let max_draws = 64 * n * n + 1000;
    let mut draws = 0usize;
    while clo.pairs < target && draws < max_draws {
        draws += 1;
        let i = rng.random_range(0..n);
        let j = rng.random_range(0..n);
        if i == j {
            continue;
        }
        let (a, b) = (hidden[i.min(j)], hidden[i.max(j)]);
        if clo.has(a, b) {
            continue;
        }
        let g = clo.gain(a, b);
        if clo.pairs + g > ceiling {
            continue;
        }
        clo.add(a, b, g);
        edges.push((a, b));
    }
    edges
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::precedence::{Dag, closure_density, topological_order};
    use rand::SeedableRng;

    #[test]
    fn closure_density_is_on_target() {
        for (n, p) in [(50, 0.01), (200, 0.05), (200, 0.15), (300, 0.3), (200, 0.6)] {
            let mut rng = ChaCha8Rng::seed_from_u64(7);
            let e = random_dag(n, p, &mut rng);
            let dag = Dag::new(n, &e);
            assert!(topological_order(&dag).is_ok(), "acyclic");
            let d = closure_density(&dag);
            let all = (n * (n - 1) / 2) as f64;
            let tol = (n as f64).max(all / 200.0) / all;
            assert!(
                d >= p - 1e-9 && d <= p + tol + 1e-9,
                "n={n} p={p}: closure density {d}"
            );
        }
    }

    #[test]
    fn counted_pairs_match_the_closure() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let e = random_dag(120, 0.2, &mut rng);
        let d = closure_density(&Dag::new(120, &e));
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let e2 = random_dag(120, 0.2, &mut rng);
        assert_eq!(e, e2, "same seed, same edges");
        assert!(d >= 0.2);
    }

    #[test]
    fn zero_density_has_no_edges() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        assert!(random_dag(100, 0.0, &mut rng).is_empty());
    }
}

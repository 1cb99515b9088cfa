//! Transitive closure of the precedence DAG as bitsets, and the arc-elimination rule it gives.

use super::{Dag, topological_order};

/// Ancestor and descendant bitsets of every cell (strict).
#[derive(Debug, Clone)]
pub struct Closure {
    n: usize,
    words: usize,
    desc: Vec<u64>,
    anc: Vec<u64>,
}

impl Closure {
    /// Computes the closure in O(n · e / 64). Returns `None` when the DAG has a cycle.
    pub fn new(dag: &Dag) -> Option<Closure> {
        let n = dag.n();
        let order = topological_order(dag).ok()?;
        let words = n.div_ceil(64).max(1);
        let mut desc = vec![0u64; n * words];
        let mut anc = vec![0u64; n * words];
        for &v in order.iter().rev() {
            let v = v as usize;
            for &s in &dag.succs[v] {
                let s = s as usize;
                desc[v * words + s / 64] |= 1 << (s % 64);
                for w in 0..words {
                    desc[v * words + w] |= desc[s * words + w];
                }
            }
        }
        for &v in order.iter() {
            let v = v as usize;
            for &p in &dag.preds[v] {
                let p = p as usize;
                anc[v * words + p / 64] |= 1 << (p % 64);
                for w in 0..words {
                    anc[v * words + w] |= anc[p * words + w];
                }
            }
        }
        Some(Closure {
            n,
            words,
            desc,
            anc,
        })
    }

    /// Number of cells.
    pub fn n(&self) -> usize {
        self.n
    }

    /// True when `a` must come (transitively) before `b`.
    #[inline]
    pub fn before(&self, a: usize, b: usize) -> bool {
        self.desc[a * self.words + b / 64] >> (b % 64) & 1 == 1
    }

    /// Words per bitset row.
    pub fn words(&self) -> usize {
        self.words
    }

    /// Bitset of the strict descendants of `v` (bit `b` of word `b / 64`).
    #[inline]
    pub fn desc_row(&self, v: usize) -> &[u64] {
        &self.desc[v * self.words..(v + 1) * self.words]
    }

    /// Bitset of the strict ancestors of `v`.
    #[inline]
    pub fn anc_row(&self, v: usize) -> &[u64] {
        &self.anc[v * self.words..(v + 1) * self.words]
    }

    /// Number of strict ancestors of a cell.
    pub fn ancestors(&self, v: usize) -> usize {
        self.anc[v * self.words..(v + 1) * self.words]
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// Number of strict descendants of a cell.
    pub fn descendants(&self, v: usize) -> usize {
        self.desc[v * self.words..(v + 1) * self.words]
            .iter()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// Whether the arc a → b can occur in a feasible sequence: not when b ≺ a, and not when
    /// some k satisfies a ≺ k ≺ b (k would have to lie between them).
    #[inline]
    pub fn arc_allowed(&self, a: usize, b: usize) -> bool {
        if a == b || self.before(b, a) {
            return false;
        }
        let d = &self.desc[a * self.words..(a + 1) * self.words];
        let an = &self.anc[b * self.words..(b + 1) * self.words];
        d.iter().zip(an).all(|(x, y)| x & y == 0)
    }

    /// Whether `v` can be the first cell (no ancestors).
    pub fn can_be_first(&self, v: usize) -> bool {
        self.ancestors(v) == 0
    }

    /// Whether `v` can be the last cell (no descendants).
    pub fn can_be_last(&self, v: usize) -> bool {
        self.descendants(v) == 0
    }
}

//! A path as a cyclic doubly linked list with order labels (order maintenance).
//!
//! Cells are linked through a sentinel (index n: before the first cell and after the last),
//! so moving or inserting a cell is O(1) and needs no positions. Each cell also carries a
//! label that grows along the path, so "is a before b?" is one comparison — what precedence
//! checks need. A cell put between a and b takes the middle of their labels; when that gap
//! is used up, the smallest run of cells around it (doubling on each side) whose label range
//! leaves gaps of at least max(run length, 32) is spread out evenly, so a relabelling of w
//! cells buys at least log2(w) further insertions in any of its gaps.

/// The linked list with labels. The sentinel's label is 0; cells have labels ≥ 1.
#[derive(Debug, Clone)]
pub struct OrderList {
    /// Successor of each cell (the sentinel after the last).
    pub next: Vec<u32>,
    /// Predecessor of each cell (the sentinel before the first).
    pub prev: Vec<u32>,
    label: Vec<u64>,
}

/// Label distance between consecutive cells appended at the end of the path.
const STEP: u64 = 1 << 24;

impl OrderList {
    /// An empty path over `n` cells (none linked yet).
    pub fn new(n: usize) -> Self {
        let d = n as u32;
        let mut next = vec![u32::MAX; n + 1];
        let mut prev = vec![u32::MAX; n + 1];
        next[n] = d;
        prev[n] = d;
        OrderList {
            next,
            prev,
            label: vec![0; n + 1],
        }
    }

    /// The path `order` (cells `0..n`, each at most once; others stay unlinked).
    pub fn from_order(n: usize, order: &[u32]) -> Self {
        let mut l = OrderList::new(n);
        let mut label = 0u64;
        for &x in order {
            label += STEP;
            l.link_after(l.last(), x);
            l.label[x as usize] = label;
        }
        l
    }

    /// The sentinel's index (n).
    #[inline]
    pub fn sentinel(&self) -> u32 {
        (self.next.len() - 1) as u32
    }

    /// The last cell (the sentinel when the path is empty).
    #[inline]
    pub fn last(&self) -> u32 {
        self.prev[self.sentinel() as usize]
    }

    /// The label of x read as a place *after which* something goes: the sentinel is 0.
    #[inline]
    pub fn after(&self, x: u32) -> u64 {
        self.label[x as usize]
    }

    /// The label of x read as a place *before which* something goes: the sentinel is the
    /// end of the path (u64::MAX).
    #[inline]
    pub fn before(&self, x: u32) -> u64 {
        if x == self.sentinel() {
            u64::MAX
        } else {
            self.label[x as usize]
        }
    }

    fn link_after(&mut self, a: u32, c: u32) {
        let b = self.next[a as usize];
        self.next[a as usize] = c;
        self.prev[c as usize] = a;
        self.next[c as usize] = b;
        self.prev[b as usize] = c;
    }

    /// Takes c out of the path (its label is stale until it is put back).
    pub fn unlink(&mut self, c: u32) {
        let (p, q) = (self.prev[c as usize], self.next[c as usize]);
        self.next[p as usize] = q;
        self.prev[q as usize] = p;
    }

    /// Puts the unlinked cell c right after a (a may be the sentinel: c becomes first).
    pub fn insert_after(&mut self, a: u32, c: u32) {
        self.link_after(a, c);
        let lo = self.after(a);
        let b = self.next[c as usize];
        let hi = self.before(b);
        let gap = hi - lo;
        if gap >= 2 {
            let step = if b == self.sentinel() {
                (gap / 2).min(STEP)
            } else {
                gap / 2
            };
            self.label[c as usize] = lo + step;
        } else {
            self.spread(c);
        }
    }

    /// Relabels the smallest run of cells around c whose label range leaves gaps of at least
    /// max(run length, 32) between its cells (or the whole path).
    fn spread(&mut self, c: u32) {
        let d = self.sentinel();
        let (mut first, mut last, mut count) = (c, c, 1u64);
        let mut w = 1;
        loop {
            for _ in 0..w {
                let p = self.prev[first as usize];
                if p != d {
                    first = p;
                    count += 1;
                }
                let q = self.next[last as usize];
                if q != d {
                    last = q;
                    count += 1;
                }
            }
            let lo = self.after(self.prev[first as usize]);
            let hi = self.before(self.next[last as usize]);
            let gap = (hi - lo) / (count + 1);
            let whole = self.prev[first as usize] == d && self.next[last as usize] == d;
            if gap >= count.max(32) || whole {
                let mut x = first;
                for i in 1..=count {
                    self.label[x as usize] = lo + gap * i;
                    x = self.next[x as usize];
                }
                return;
            }
            w *= 2;
        }
    }

    /// The cells from first to last.
    pub fn cells(&self) -> impl Iterator<Item = u32> + '_ {
        let d = self.sentinel();
        std::iter::successors(Some(self.next[d as usize]), move |&x| {
            Some(self.next[x as usize])
        })
        .take_while(move |&x| x != d)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Labels strictly increase along the list, which holds `count` cells.
    fn ordered(l: &OrderList, count: usize) {
        let mut last = 0;
        let mut seen = 0;
        for x in l.cells() {
            assert!(l.after(x) > last, "labels must increase along the path");
            last = l.after(x);
            seen += 1;
        }
        assert_eq!(seen, count);
    }

    #[test]
    fn labels_stay_ordered_when_gaps_run_out() {
        let n = 5000;
        // always at the front, always right after the first cell, always at the end, at
        // random places, and moves of random cells (unlink and insert elsewhere): the first
        // two use a gap up every ~60 insertions
        for pattern in 0..5u64 {
            let mut l = OrderList::new(n);
            let d = l.sentinel();
            let mut rng = ChaCha8Rng::seed_from_u64(pattern);
            l.insert_after(d, 0);
            for c in 1..n as u32 {
                let a = match pattern {
                    0 => d,
                    1 => 0,
                    2 => l.last(),
                    _ => rng.random_range(0..c),
                };
                l.insert_after(a, c);
            }
            if pattern == 4 {
                for _ in 0..20 * n {
                    let c = rng.random_range(0..n as u32);
                    let a = rng.random_range(0..n as u32);
                    if a != c {
                        l.unlink(c);
                        l.insert_after(a, c);
                    }
                }
            }
            ordered(&l, n);
        }
        let l = OrderList::from_order(4, &[2, 0, 3]);
        assert_eq!(l.cells().collect::<Vec<_>>(), vec![2, 0, 3]);
        ordered(&l, 3);
        assert!(l.before(l.sentinel()) > l.after(3) && l.after(l.sentinel()) < l.after(2));
    }
}

//! The order of a drawing's free blocks (plain top-level groups, each drawn as one contiguous
//! run of strokes): an open path from a start point through every block, entering a block at
//! its entry point and leaving it at its exit point, optionally ending at a fixed point (the
//! next block that keeps its place). [`order`] is exact (dynamic programming over subsets)
//! for up to [`EXACT_MAX`] blocks, and nearest neighbour followed by block moves (Or-opt) to a
//! local optimum beyond: both on R-trees and candidate lists, so 10^5 blocks take well under
//! a second, and both stop at a deadline ([`order_until`]).

use crate::drawing::dist;
use rstar::RTree;
use rstar::primitives::GeomWithData;
use std::collections::HashMap;
use std::time::Instant;

/// Most blocks ordered exactly (2^n · n² work: 12 blocks are about 600 000 steps).
pub const EXACT_MAX: usize = 12;

/// Travel of visiting `blocks` (entry, exit) in `order` from `start`, then to `finish`.
pub fn travel(
    start: [f64; 2],
    blocks: &[([f64; 2], [f64; 2])],
    order: &[usize],
    finish: Option<[f64; 2]>,
) -> f64 {
    let mut at = start;
    let mut t = 0.0;
    for &b in order {
        t += dist(at, blocks[b].0);
        at = blocks[b].1;
    }
    t + finish.map_or(0.0, |f| dist(at, f))
}

/// The order of `blocks` (entry, exit) with the least [`travel`] from `start` (and to
/// `finish`). Exact up to [`EXACT_MAX`] blocks; ties go to the order found first, which for
/// the exact method favours the file's order (lower indices first). Deterministic.
pub fn order(
    start: [f64; 2],
    blocks: &[([f64; 2], [f64; 2])],
    finish: Option<[f64; 2]>,
) -> Vec<usize> {
    order_until(start, blocks, finish, None)
}

/// [`order`] that stops searching at `deadline`: beyond [`EXACT_MAX`] blocks, the nearest
/// neighbour order is given up for the file's order, and block moves stop where they are
/// (the clock is read every few hundred steps). Without a deadline, deterministic.
pub fn order_until(
    start: [f64; 2],
    blocks: &[([f64; 2], [f64; 2])],
    finish: Option<[f64; 2]>,
    deadline: Option<Instant>,
) -> Vec<usize> {
    let n = blocks.len();
    if n <= 1 {
        return (0..n).collect();
    }
    let best = if n <= EXACT_MAX {
        exact(start, blocks, finish)
    } else {
        match nearest(start, blocks, deadline) {
            Some(first) => OrOpt::new(start, blocks, finish, &first).run(deadline),
            None => (0..n).collect(),
        }
    };
    // never worse than the file's order on this measure
    let file: Vec<usize> = (0..n).collect();
    if travel(start, blocks, &best, finish) < travel(start, blocks, &file, finish) {
        best
    } else {
        file
    }
}

/// Held–Karp over subsets: `cost[set][last]` is the least travel from `start` through `set`
/// ending with block `last`.
fn exact(start: [f64; 2], blocks: &[([f64; 2], [f64; 2])], finish: Option<[f64; 2]>) -> Vec<usize> {
    let n = blocks.len();
    let full = (1usize << n) - 1;
    let mut cost = vec![f64::INFINITY; (full + 1) * n];
    let mut from = vec![usize::MAX; (full + 1) * n];
    for b in 0..n {
        cost[(1 << b) * n + b] = dist(start, blocks[b].0);
    }
    for set in 1..=full {
        for last in 0..n {
            let c = cost[set * n + last];
            if set & (1 << last) == 0 || !c.is_finite() {
                continue;
            }
            for next in 0..n {
                if set & (1 << next) != 0 {
                    continue;
                }
                let s2 = set | (1 << next);
                let c2 = c + dist(blocks[last].1, blocks[next].0);
                if c2 < cost[s2 * n + next] {
                    cost[s2 * n + next] = c2;
                    from[s2 * n + next] = last;
                }
            }
        }
    }
    let end_cost =
        |last: usize| cost[full * n + last] + finish.map_or(0.0, |f| dist(blocks[last].1, f));
    let mut last = (0..n)
        .min_by(|&a, &b| end_cost(a).total_cmp(&end_cost(b)))
        .expect("at least two blocks");
    let mut set = full;
    let mut out = Vec::with_capacity(n);
    loop {
        out.push(last);
        let prev = from[set * n + last];
        set &= !(1 << last);
        if set == 0 {
            break;
        }
        last = prev;
    }
    out.reverse();
    out
}

/// True once `deadline` has passed.
fn past(deadline: Option<Instant>) -> bool {
    deadline.is_some_and(|d| Instant::now() >= d)
}

type Site = GeomWithData<[f64; 2], usize>;

/// A block's entry and exit.
type Block = ([f64; 2], [f64; 2]);

/// Nearest neighbour by entry point, from `start`: an R-tree over the distinct entry points,
/// each with its blocks (lowest first, so coincident entries cost no search). `None` when
/// the deadline passes first.
fn nearest(
    start: [f64; 2],
    blocks: &[([f64; 2], [f64; 2])],
    deadline: Option<Instant>,
) -> Option<Vec<usize>> {
    let n = blocks.len();
    let mut at_point: HashMap<[u64; 2], usize> = HashMap::new();
    let mut points: Vec<[f64; 2]> = Vec::new();
    let mut queue: Vec<std::collections::VecDeque<usize>> = Vec::new();
    for (b, blk) in blocks.iter().enumerate() {
        let p = blk.0;
        let id = *at_point
            .entry([p[0].to_bits(), p[1].to_bits()])
            .or_insert_with(|| {
                points.push(p);
                queue.push(Default::default());
                points.len() - 1
            });
        queue[id].push_back(b);
    }
    let mut tree: RTree<Site> = RTree::bulk_load(
        points
            .iter()
            .enumerate()
            .map(|(i, &p)| Site::new(p, i))
            .collect(),
    );
    let mut at = start;
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        if out.len() % 1024 == 1023 && past(deadline) {
            return None;
        }
        let site = *tree.nearest_neighbor(at).expect("a block is left");
        let b = queue[site.data]
            .pop_front()
            .expect("a live site has a block");
        if queue[site.data].is_empty() {
            tree.remove(&site);
        }
        at = blocks[b].1;
        out.push(b);
    }
    Some(out)
}

/// Candidate blocks per block.
const CANDIDATES: usize = 8;

/// Or-opt on blocks: runs of 1–3 consecutive blocks moved between two others that a
/// candidate list names (a block whose exit is near the run's entry, or whose entry is near
/// its exit), while that shortens the travel; the order is a linked list with the start
/// (node `n`) and the finish (node `n + 1`) as fixed ends.
struct OrOpt<'a> {
    start: [f64; 2],
    blocks: &'a [([f64; 2], [f64; 2])],
    finish: Option<[f64; 2]>,
    next: Vec<usize>,
    prev: Vec<usize>,
    /// blocks whose exit is near this block's entry
    before: Vec<Vec<usize>>,
    /// blocks whose entry is near this block's exit
    after: Vec<Vec<usize>>,
}

impl<'a> OrOpt<'a> {
    fn new(
        start: [f64; 2],
        blocks: &'a [([f64; 2], [f64; 2])],
        finish: Option<[f64; 2]>,
        order: &[usize],
    ) -> Self {
        let n = blocks.len();
        let (head, tail) = (n, n + 1);
        let mut next = vec![usize::MAX; n + 2];
        let mut prev = vec![usize::MAX; n + 2];
        let mut last = head;
        for &b in order {
            next[last] = b;
            prev[b] = last;
            last = b;
        }
        next[last] = tail;
        prev[tail] = last;
        let tree = |pick: fn(&Block) -> [f64; 2]| -> RTree<Site> {
            RTree::bulk_load(
                blocks
                    .iter()
                    .enumerate()
                    .map(|(i, b)| Site::new(pick(b), i))
                    .collect(),
            )
        };
        let (exits, entries) = (tree(|b| b.1), tree(|b| b.0));
        let near = |t: &RTree<Site>, p: [f64; 2], me: usize| -> Vec<usize> {
            t.nearest_neighbor_iter(p)
                .map(|s| s.data)
                .filter(|&x| x != me)
                .take(CANDIDATES)
                .collect()
        };
        let before = (0..n).map(|b| near(&exits, blocks[b].0, b)).collect();
        let after = (0..n).map(|b| near(&entries, blocks[b].1, b)).collect();
        OrOpt {
            start,
            blocks,
            finish,
            next,
            prev,
            before,
            after,
        }
    }

    /// Travel from node `a` (a block, or the start) to node `b` (a block, or the finish).
    fn link(&self, a: usize, b: usize) -> f64 {
        let n = self.blocks.len();
        let from = if a == n { self.start } else { self.blocks[a].1 };
        if b == n + 1 {
            self.finish.map_or(0.0, |f| dist(from, f))
        } else {
            dist(from, self.blocks[b].0)
        }
    }

    /// Block moves from a queue of blocks (each run starting at a queued block), until none
    /// shortens the travel or the deadline passes. Returns the order.
    fn run(mut self, deadline: Option<Instant>) -> Vec<usize> {
        let n = self.blocks.len();
        let mut queue: std::collections::VecDeque<usize> = (0..n).collect();
        let mut queued = vec![true; n];
        let mut pops = 0usize;
        while let Some(a) = queue.pop_front() {
            queued[a] = false;
            pops += 1;
            if pops.is_multiple_of(256) && past(deadline) {
                break;
            }
            if let Some(touched) = self.improve_at(a) {
                for x in touched {
                    if x < n && !queued[x] {
                        queued[x] = true;
                        queue.push_back(x);
                    }
                }
            }
        }
        let mut out = Vec::with_capacity(n);
        let mut at = self.next[n];
        while at != n + 1 {
            out.push(at);
            at = self.next[at];
        }
        out
    }

    /// The best move of a run of 1–3 blocks starting at `a`, applied when it saves travel;
    /// returns the nodes around the run's old and new places.
    fn improve_at(&mut self, a: usize) -> Option<[usize; 6]> {
        let n = self.blocks.len();
        let mut best: Option<(f64, usize, usize)> = None; // (saving, run end, insert after)
        let mut b = a;
        for _ in 0..3 {
            if b >= n {
                break;
            }
            let (p, q) = (self.prev[a], self.next[b]);
            let removed = self.link(p, a) + self.link(b, q) - self.link(p, q);
            let in_run = |x: usize, s: &Self| {
                let mut y = a;
                loop {
                    if y == x {
                        return true;
                    }
                    if y == b {
                        return false;
                    }
                    y = s.next[y];
                }
            };
            // places: after a block whose exit is near a's entry, before a block whose entry
            // is near b's exit, at the front and at the end
            let mut places: Vec<usize> = self.before[a].clone();
            places.extend(self.after[b].iter().map(|&y| self.prev[y]));
            places.push(n);
            places.push(self.prev[n + 1]);
            for x in places {
                if x == p || x == n + 1 || in_run(x, self) {
                    continue;
                }
                let y = self.next[x];
                let added = self.link(x, a) + self.link(b, y) - self.link(x, y);
                let saving = removed - added;
                if saving > 1e-12 && best.is_none_or(|(s, _, _)| saving > s) {
                    best = Some((saving, b, x));
                }
            }
            b = self.next[b];
        }
        let (_, b, x) = best?;
        let (p, q, y) = (self.prev[a], self.next[b], self.next[x]);
        // unlink a..=b, relink it between x and y
        self.next[p] = q;
        self.prev[q] = p;
        self.next[x] = a;
        self.prev[a] = x;
        self.next[b] = y;
        self.prev[y] = b;
        Some([p, q, x, y, a, b])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every permutation of `n` items (Heap's algorithm), for the brute-force check.
    fn perms(n: usize) -> Vec<Vec<usize>> {
        let mut out = Vec::new();
        let mut a: Vec<usize> = (0..n).collect();
        let mut c = vec![0; n];
        out.push(a.clone());
        let mut i = 0;
        while i < n {
            if c[i] < i {
                if i % 2 == 0 {
                    a.swap(0, i);
                } else {
                    a.swap(c[i], i);
                }
                out.push(a.clone());
                c[i] += 1;
                i = 0;
            } else {
                c[i] = 0;
                i += 1;
            }
        }
        out
    }

    fn blocks(seed: u64, n: usize) -> Vec<([f64; 2], [f64; 2])> {
        let mut x = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let mut r = || {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((x >> 33) % 1000) as f64 / 10.0
        };
        (0..n).map(|_| ([r(), r()], [r(), r()])).collect()
    }

    #[test]
    fn exact_order_equals_brute_force() {
        for seed in 0..20 {
            for n in 2..=6 {
                let b = blocks(seed, n);
                let fin = (seed % 2 == 0).then_some([50.0, 50.0]);
                let got = travel([0.0, 0.0], &b, &order([0.0, 0.0], &b, fin), fin);
                let best = perms(n)
                    .iter()
                    .map(|p| travel([0.0, 0.0], &b, p, fin))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    (got - best).abs() < 1e-9,
                    "seed {seed} n {n}: {got} vs {best}"
                );
            }
        }
    }

    #[test]
    fn heuristic_order_is_a_permutation_never_worse_than_the_file() {
        for seed in 0..5 {
            let b = blocks(seed, 30);
            let o = order([0.0, 0.0], &b, None);
            let mut s = o.clone();
            s.sort_unstable();
            assert_eq!(s, (0..30).collect::<Vec<_>>());
            let file: Vec<usize> = (0..30).collect();
            assert!(travel([0.0, 0.0], &b, &o, None) <= travel([0.0, 0.0], &b, &file, None));
        }
    }

    #[test]
    fn file_order_kept_on_ties() {
        // two blocks at the same point: either order travels the same
        let b = vec![([1.0, 0.0], [1.0, 0.0]), ([1.0, 0.0], [1.0, 0.0])];
        assert_eq!(order([0.0, 0.0], &b, None), vec![0, 1]);
    }
}

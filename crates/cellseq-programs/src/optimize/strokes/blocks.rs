//! The order of a drawing's free blocks (plain top-level groups, each drawn as one contiguous
//! run of strokes): an open path from a start point through every block, entering a block at
//! its entry point and leaving it at its exit point, optionally ending at a fixed point (the
//! next block that keeps its place). [`order`] is exact (dynamic programming over subsets)
//! for up to [`EXACT_MAX`] blocks, and nearest neighbour followed by block moves (Or-opt) to a
//! local optimum beyond.

use crate::drawing::dist;

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
    let n = blocks.len();
    if n <= 1 {
        return (0..n).collect();
    }
    let best = if n <= EXACT_MAX {
        exact(start, blocks, finish)
    } else {
        improve(start, blocks, finish, nearest(start, blocks))
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

/// Nearest neighbour by entry point, from `start`.
fn nearest(start: [f64; 2], blocks: &[([f64; 2], [f64; 2])]) -> Vec<usize> {
    let n = blocks.len();
    let mut used = vec![false; n];
    let mut at = start;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let b = (0..n)
            .filter(|&b| !used[b])
            .min_by(|&a, &b| dist(at, blocks[a].0).total_cmp(&dist(at, blocks[b].0)))
            .expect("an unused block");
        used[b] = true;
        at = blocks[b].1;
        out.push(b);
    }
    out
}

/// Or-opt on blocks: moves a run of 1–3 blocks to the best other position while that
/// shortens the travel (first improvement, at most `n²` passes).
fn improve(
    start: [f64; 2],
    blocks: &[([f64; 2], [f64; 2])],
    finish: Option<[f64; 2]>,
    mut cur: Vec<usize>,
) -> Vec<usize> {
    let n = cur.len();
    let mut best = travel(start, blocks, &cur, finish);
    for _ in 0..n * n {
        let mut better = false;
        'moves: for len in 1..=3.min(n - 1) {
            for i in 0..=n - len {
                for j in 0..=n - len {
                    if j == i {
                        continue;
                    }
                    let mut cand = cur.clone();
                    let run: Vec<usize> = cand.drain(i..i + len).collect();
                    cand.splice(j..j, run);
                    let t = travel(start, blocks, &cand, finish);
                    if t < best - 1e-12 {
                        best = t;
                        cur = cand;
                        better = true;
                        break 'moves;
                    }
                }
            }
        }
        if !better {
            break;
        }
    }
    cur
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

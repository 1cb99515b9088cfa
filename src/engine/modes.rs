//! The mode pass: for a fixed cell order, the best mode of every cell by a layered
//! shortest path, O(n·k²).

use super::{Costs, Solution};

/// Re-chooses every cell's mode optimally for the current order; returns the number of
/// arc evaluations made. The solution's cost is updated (never increases).
pub fn mode_dp(c: &Costs, s: &mut Solution) -> u64 {
    let n = s.n();
    if n == 0 {
        return 0;
    }
    let m = c.m;
    let mut evals = 0u64;
    // dist[k] for the current layer, back-pointers per layer
    let first = s.order[0] as usize;
    let mut dist: Vec<f64> = (0..m.modes(first))
        .map(|k| c.link(None, Some((first, k))))
        .collect();
    let mut back: Vec<Vec<u32>> = Vec::with_capacity(n);
    back.push(Vec::new());
    for p in 1..n {
        let (a, b) = (s.order[p - 1] as usize, s.order[p] as usize);
        let mut nd = vec![f64::INFINITY; m.modes(b)];
        let mut bp = vec![0u32; m.modes(b)];
        for (mb, slot) in nd.iter_mut().enumerate() {
            for (ma, &d) in dist.iter().enumerate() {
                let v = d + c.link(Some((a, ma)), Some((b, mb)));
                if v < *slot {
                    *slot = v;
                    bp[mb] = ma as u32;
                }
            }
        }
        evals += (dist.len() * nd.len()) as u64;
        dist = nd;
        back.push(bp);
    }
    let last = s.order[n - 1] as usize;
    let (mut best, mut bm) = (f64::INFINITY, 0usize);
    for (k, &d) in dist.iter().enumerate() {
        let v = d + c.link(Some((last, k)), None);
        if v < best {
            best = v;
            bm = k;
        }
    }
    if best < s.cost - 1e-9 * s.cost.abs().max(1.0) {
        let mut k = bm;
        for p in (0..n).rev() {
            let cell = s.order[p] as usize;
            s.mode[cell] = k as u32;
            if p > 0 {
                k = back[p][k] as usize;
            }
        }
        s.cost = s.evaluate(c);
    }
    evals
}

//! Drawing sequencer: an exact nearest-neighbour greedy on a uniform grid (robust to many
//! coincident endpoints, precedence-aware) followed, when every stroke may be reversed and
//! there is no precedence, by 2-opt with neighbour lists (reversing a block of the order also
//! reverses each stroke in it). Pure air-travel objective in the plane; deterministic.

use crate::model::{Instance, Sequence, Visit};
use std::time::Instant;

struct Grid {
    x0: f64,
    y0: f64,
    size: f64,
    nx: usize,
    ny: usize,
    buckets: Vec<Vec<u32>>,
    live: usize,
}

impl Grid {
    fn new(pts: &[(u32, [f64; 2])]) -> Grid {
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for (_, p) in pts {
            b[0] = b[0].min(p[0]);
            b[1] = b[1].min(p[1]);
            b[2] = b[2].max(p[0]);
            b[3] = b[3].max(p[1]);
        }
        if pts.is_empty() {
            b = [0.0, 0.0, 1.0, 1.0];
        }
        let (w, h) = ((b[2] - b[0]).max(1e-9), (b[3] - b[1]).max(1e-9));
        let cells = (pts.len() as f64 / 2.0).max(1.0);
        let size = ((w * h) / cells).sqrt().max(w.max(h) / 2048.0).max(1e-9);
        let nx = ((w / size) as usize + 1).min(4096);
        let ny = ((h / size) as usize + 1).min(4096);
        let mut g = Grid {
            x0: b[0],
            y0: b[1],
            size,
            nx,
            ny,
            buckets: vec![Vec::new(); nx * ny],
            live: 0,
        };
        for &(id, p) in pts {
            g.insert(id, p);
        }
        g
    }
    fn key(&self, p: [f64; 2]) -> (usize, usize) {
        let i = (((p[0] - self.x0) / self.size).floor().max(0.0) as usize).min(self.nx - 1);
        let j = (((p[1] - self.y0) / self.size).floor().max(0.0) as usize).min(self.ny - 1);
        (i, j)
    }
    fn insert(&mut self, id: u32, p: [f64; 2]) {
        let (i, j) = self.key(p);
        self.buckets[j * self.nx + i].push(id);
        self.live += 1;
    }
    fn remove(&mut self, id: u32, p: [f64; 2]) {
        let (i, j) = self.key(p);
        let b = &mut self.buckets[j * self.nx + i];
        if let Some(k) = b.iter().position(|&x| x == id) {
            b.swap_remove(k);
            self.live -= 1;
        }
    }
    /// Nearest id by `dist(id)`, which must be >= the planar distance to the id's point.
    fn nearest(&self, q: [f64; 2], mut dist: impl FnMut(u32) -> f64) -> Option<(f64, u32)> {
        if self.live == 0 {
            return None;
        }
        let (ci, cj) = self.key(q);
        let mut best: Option<(f64, u32)> = None;
        let maxr = self.nx.max(self.ny);
        for r in 0..=maxr {
            // lower bound of any point in ring r: distance from q to the ring's inner edge
            if let Some((d, _)) = best {
                let lb = (r as f64 - 1.0).max(0.0) * self.size;
                if d <= lb {
                    break;
                }
            }
            let (i0, i1) = (ci as isize - r as isize, ci as isize + r as isize);
            let (j0, j1) = (cj as isize - r as isize, cj as isize + r as isize);
            let mut visit = |i: isize, j: isize, best: &mut Option<(f64, u32)>| {
                if i < 0 || j < 0 || i >= self.nx as isize || j >= self.ny as isize {
                    return;
                }
                for &id in &self.buckets[j as usize * self.nx + i as usize] {
                    let d = dist(id);
                    if best.is_none_or(|(bd, bid)| d < bd || (d == bd && id < bid)) {
                        *best = Some((d, id));
                    }
                }
            };
            if r == 0 {
                visit(i0, j0, &mut best);
                continue;
            }
            for i in i0..=i1 {
                visit(i, j0, &mut best);
                visit(i, j1, &mut best);
            }
            for j in (j0 + 1)..j1 {
                visit(i0, j, &mut best);
                visit(i1, j, &mut best);
            }
        }
        best
    }
}

fn d2(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// Sequences a drawing instance (single tool, z = 0) starting at the machine's home.
/// `time_limit` bounds the 2-opt phase. Returns the sequence.
pub fn solve(inst: &Instance, time_limit: Option<f64>) -> Sequence {
    let n = inst.n();
    let mut offs = Vec::with_capacity(n + 1);
    let mut entry: Vec<[f64; 2]> = Vec::new();
    let mut exit: Vec<[f64; 2]> = Vec::new();
    let mut node_cell: Vec<u32> = Vec::new();
    for (i, c) in inst.cells.iter().enumerate() {
        offs.push(entry.len());
        for m in &c.modes {
            entry.push([m.entry.x, m.entry.y]);
            exit.push([m.exit.x, m.exit.y]);
            node_cell.push(i as u32);
        }
    }
    offs.push(entry.len());
    let mut missing = vec![0u32; n];
    let mut succs: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &(a, b) in &inst.precedence {
        missing[b] += 1;
        succs[a].push(b as u32);
    }
    let ready_nodes = |c: usize| (offs[c]..offs[c + 1]).map(|nd| (nd as u32, entry[nd]));
    let init: Vec<(u32, [f64; 2])> = (0..n)
        .filter(|&c| missing[c] == 0)
        .flat_map(ready_nodes)
        .collect();
    let mut grid = Grid::new(&init);
    let mut built = grid.live;
    let mut in_grid = vec![false; n];
    for c in 0..n {
        in_grid[c] = missing[c] == 0;
    }
    let home = [inst.machine.home.x, inst.machine.home.y];
    let mut at = home;
    let mut seq: Sequence = Vec::with_capacity(n);
    while seq.len() < n {
        let Some((_, nd)) = grid.nearest(at, |id| d2(at, entry[id as usize])) else {
            break; // precedence cycle: validated instances have none
        };
        let c = node_cell[nd as usize] as usize;
        seq.push(Visit::new(c, nd as usize - offs[c]));
        at = exit[nd as usize];
        for (k, &p) in entry.iter().enumerate().take(offs[c + 1]).skip(offs[c]) {
            grid.remove(k as u32, p);
        }
        in_grid[c] = false;
        for &s in &succs[c] {
            let s = s as usize;
            missing[s] -= 1;
            if missing[s] == 0 {
                for (k, &p) in entry.iter().enumerate().take(offs[s + 1]).skip(offs[s]) {
                    grid.insert(k as u32, p);
                }
                in_grid[s] = true;
            }
        }
        if grid.live > 0 && grid.live * 8 < built && built > 64 {
            let pts: Vec<(u32, [f64; 2])> = (0..n)
                .filter(|&c| in_grid[c])
                .flat_map(ready_nodes)
                .collect();
            grid = Grid::new(&pts);
            built = grid.live;
        }
    }
    // 2-opt needs every stroke reversible (open: a flipped mode; closed: entry = exit) and
    // no precedence
    let flip: Option<Vec<usize>> = if inst.precedence.is_empty() {
        (0..entry.len())
            .map(|nd| {
                let c = node_cell[nd] as usize;
                if entry[nd] == exit[nd] {
                    return Some(nd);
                }
                (offs[c]..offs[c + 1]).find(|&k| entry[k] == exit[nd] && exit[k] == entry[nd])
            })
            .collect()
    } else {
        None
    };
    if let Some(flip) = flip
        && seq.len() == n
        && n > 3
    {
        {
            let nodes: Vec<usize> = seq.iter().map(|v| offs[v.cell] + v.mode).collect();
            let nodes = two_opt(nodes, &entry, &exit, &flip, home, time_limit);
            seq = nodes
                .into_iter()
                .map(|nd| {
                    let c = node_cell[nd] as usize;
                    Visit::new(c, nd - offs[c])
                })
                .collect();
        }
    }
    seq
}

/// 2-opt on an open path from `home` with neighbour lists over stroke endpoints: replacing
/// the moves (a→b) and (c→d) by (a→c') and (b'→d) reverses the block b..c and flips each
/// stroke in it. First improvement, repeated until no move improves or time runs out.
fn two_opt(
    mut tour: Vec<usize>,
    entry: &[[f64; 2]],
    exit: &[[f64; 2]],
    flip: &[usize],
    home: [f64; 2],
    time_limit: Option<f64>,
) -> Vec<usize> {
    let n = tour.len();
    let t0 = Instant::now();
    let limit = time_limit.unwrap_or(f64::INFINITY);
    // position of each cell's node in the tour, via node -> position for the current node
    let nn = entry.len();
    let mut pos = vec![usize::MAX; nn];
    for (i, &nd) in tour.iter().enumerate() {
        pos[nd] = i;
        pos[flip[nd]] = i;
    }
    // neighbour lists: for each tour position's stroke, the K nearest strokes by any endpoint
    const K: usize = 8;
    let pts: Vec<(u32, [f64; 2])> = tour
        .iter()
        .flat_map(|&nd| [(nd as u32, entry[nd]), (nd as u32, exit[nd])])
        .collect();
    let grid = Grid::new(&pts);
    let neigh = |p: [f64; 2], own: usize| -> Vec<usize> {
        // K nearest distinct nodes by endpoint, collected by growing rings
        let mut found: Vec<(f64, usize)> = Vec::new();
        let (ci, cj) = grid.key(p);
        let maxr = grid.nx.max(grid.ny);
        for r in 0..=maxr {
            if found.len() >= K {
                let lb = (r as f64 - 1.0).max(0.0) * grid.size;
                if found[K - 1].0 <= lb {
                    break;
                }
            }
            let (i0, i1) = (ci as isize - r as isize, ci as isize + r as isize);
            let (j0, j1) = (cj as isize - r as isize, cj as isize + r as isize);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    if !(i == i0 || i == i1 || j == j0 || j == j1) {
                        continue;
                    }
                    if i < 0 || j < 0 || i >= grid.nx as isize || j >= grid.ny as isize {
                        continue;
                    }
                    for &id in &grid.buckets[j as usize * grid.nx + i as usize] {
                        let id = id as usize;
                        if id == own || found.iter().any(|f| f.1 == id) {
                            continue;
                        }
                        let d = d2(p, entry[id]).min(d2(p, exit[id]));
                        found.push((d, id));
                    }
                }
            }
            found.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            found.truncate(K);
        }
        found.into_iter().map(|f| f.1).collect()
    };
    let neighbours: Vec<Vec<usize>> = tour
        .iter()
        .map(|&nd| {
            let mut v = neigh(exit[nd], nd);
            for x in neigh(entry[nd], nd) {
                if !v.contains(&x) {
                    v.push(x);
                }
            }
            v
        })
        .collect();
    // map original node ids to neighbour lists (by the node placed at build time)
    let mut nb_of = vec![usize::MAX; nn];
    for (i, &nd) in tour.iter().enumerate() {
        nb_of[nd] = i;
        nb_of[flip[nd]] = i;
    }
    // gain of reversing (and flipping) the block i..=j
    let gain_of = |tour: &[usize], i: usize, j: usize| -> f64 {
        let a = if i == 0 { home } else { exit[tour[i - 1]] };
        let b_start = entry[tour[i]];
        let c_end = exit[tour[j]];
        let (old_cd, new_bd) = if j + 1 < n {
            let d = entry[tour[j + 1]];
            (d2(c_end, d), d2(b_start, d))
        } else {
            (0.0, 0.0)
        };
        d2(a, b_start) + old_cd - d2(a, c_end) - new_bd
    };
    let apply = |tour: &mut Vec<usize>, pos: &mut Vec<usize>, i: usize, j: usize| {
        tour[i..=j].reverse();
        for k in i..=j {
            tour[k] = flip[tour[k]];
            pos[tour[k]] = k;
            pos[flip[tour[k]]] = k;
        }
    };
    let ex = |tour: &[usize], k: usize| -> [f64; 2] {
        if k == usize::MAX { home } else { exit[tour[k]] }
    };
    let or_move =
        |tour: &mut Vec<usize>, pos: &mut Vec<usize>, k: usize, cands: &[usize]| -> bool {
            let s = tour[k];
            let prev = if k == 0 { usize::MAX } else { k - 1 };
            let pe = ex(tour, prev);
            let removed = d2(pe, entry[s])
                + if k + 1 < n {
                    d2(exit[s], entry[tour[k + 1]]) - d2(pe, entry[tour[k + 1]])
                } else {
                    0.0
                };
            // best insertion between positions q-1 and q (q != k, k+1), orientation o
            let mut best = (1e-9, usize::MAX, 0usize);
            for &m in cands {
                let qm = pos[m];
                if qm == usize::MAX {
                    continue;
                }
                for q in [qm, qm + 1] {
                    if q == k || q == k + 1 || q > n {
                        continue;
                    }
                    let u = ex(tour, if q == 0 { usize::MAX } else { q - 1 });
                    for o in [s, flip[s]] {
                        let add = d2(u, entry[o])
                            + if q < n {
                                d2(exit[o], entry[tour[q]]) - d2(u, entry[tour[q]])
                            } else {
                                0.0
                            };
                        let g = removed - add;
                        if g > best.0 {
                            best = (g, q, o);
                        }
                    }
                }
            }
            if best.1 == usize::MAX {
                return false;
            }
            let (_, q, o) = best;
            if q < k {
                tour[q..=k].rotate_right(1);
                tour[q] = o;
                for (i, &nd) in tour.iter().enumerate().take(k + 1).skip(q) {
                    pos[nd] = i;
                    pos[flip[nd]] = i;
                }
            } else {
                tour[k..q].rotate_left(1);
                tour[q - 1] = o;
                for (i, &nd) in tour.iter().enumerate().take(q).skip(k) {
                    pos[nd] = i;
                    pos[flip[nd]] = i;
                }
            }
            true
        };
    let mut improved = true;
    while improved && t0.elapsed().as_secs_f64() < limit {
        improved = false;
        for p in 0..n {
            // blocks starting at p: the new first stroke ends near the predecessor's exit
            let around = if p == 0 { tour[0] } else { tour[p - 1] };
            let mut best = (1e-9, usize::MAX, usize::MAX);
            for &m in &neighbours[nb_of[around]] {
                let j = pos[m];
                if j != usize::MAX && j >= p {
                    let g = gain_of(&tour, p, j);
                    if g > best.0 {
                        best = (g, p, j);
                    }
                }
            }
            // blocks ending at p: the new last stroke starts near the successor's entry
            if p + 1 < n {
                for &m in &neighbours[nb_of[tour[p + 1]]] {
                    let i = pos[m];
                    if i != usize::MAX && i <= p {
                        let g = gain_of(&tour, i, p);
                        if g > best.0 {
                            best = (g, i, p);
                        }
                    }
                }
            }
            if best.1 != usize::MAX {
                apply(&mut tour, &mut pos, best.1, best.2);
                improved = true;
            }
            // or-opt: move the stroke at p (either way round) next to a neighbour
            let nbi = nb_of[tour[p]];
            if or_move(&mut tour, &mut pos, p, &neighbours[nbi]) {
                improved = true;
            }
            if p % 1024 == 0 && t0.elapsed().as_secs_f64() >= limit {
                break;
            }
        }
    }
    tour
}

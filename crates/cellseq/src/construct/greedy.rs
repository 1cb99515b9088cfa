//! `greedy`: precedence-aware nearest neighbour.
//!
//! From the current (cell, mode) it moves to the cheapest (cell, mode) among cells whose
//! predecessors are all done. Geometric instances keep one k-d tree (kiddo) per tool over the
//! entry points of ready cells and grow the nearest-k query until no farther point can beat
//! the best exact arc cost found, so each step is exact and costs O(log n) in practice.
//! Matrix instances scan the ready cells.

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::model::{Objective, Sequence, Visit};
use kiddo::{MutableKdTree, SquaredEuclidean};
use std::cmp::Reverse;
use std::collections::BinaryHeap;
use std::num::NonZero;

/// Tracks which cells are ready (all predecessors done).
struct Fringe {
    missing: Vec<u32>,
}

impl Fringe {
    fn new(m: &CostModel) -> Self {
        Fringe {
            missing: m.dag.preds.iter().map(|p| p.len() as u32).collect(),
        }
    }
    /// Marks `c` done and calls `ready` for each successor that became ready.
    fn done(&mut self, m: &CostModel, c: usize, mut ready: impl FnMut(usize)) {
        for &s in &m.dag.succs[c] {
            let s = s as usize;
            self.missing[s] -= 1;
            if self.missing[s] == 0 {
                ready(s);
            }
        }
    }
}

/// Greedy over an explicit matrix: scans every ready (cell, mode).
pub fn matrix(m: &CostModel, count: &mut dyn FnMut(u64)) -> Sequence {
    matrix_until(m, count, Deadline::NONE)
}

/// Like [`matrix`]; once `deadline` passes, the rest of the cells follow in a quick feasible
/// order ([`super::complete`]).
pub fn matrix_until(m: &CostModel, count: &mut dyn FnMut(u64), deadline: Deadline) -> Sequence {
    let n = m.n();
    let mut fringe = Fringe::new(m);
    let mut ready: Vec<usize> = (0..n).filter(|&c| fringe.missing[c] == 0).collect();
    let mut seq: Sequence = Vec::with_capacity(n);
    let mut clock = super::ticker(deadline);
    while !ready.is_empty() {
        if clock.passed() {
            super::complete(m, &mut seq);
            return seq;
        }
        let mut best = (f64::INFINITY, usize::MAX, 0usize, 0usize);
        for (i, &c) in ready.iter().enumerate() {
            for md in 0..m.modes(c) {
                let cost = match seq.last() {
                    None => m.start(c, md),
                    Some(p) => m.arc(p.cell, p.mode, c, md),
                };
                if cost < best.0 || (cost == best.0 && c < best.1) {
                    best = (cost, c, md, i);
                }
            }
        }
        count(ready.len() as u64);
        let (_, c, md, i) = best;
        ready.swap_remove(i);
        seq.push(Visit::new(c, md));
        fringe.done(m, c, |s| ready.push(s));
    }
    seq
}

type Tree = MutableKdTree<f64, 2>;

/// One k-d tree per tool over the distinct entry points ("sites") of ready, unvisited cells.
/// Coincident entry points share one site (a k-d tree bucket cannot split identical points).
/// The nodes of a site are split into classes of equal cost from any node (the same entry
/// height and cutting rate; the tool is the site's), and each class keeps its live nodes in a
/// min-heap, so a site offers its cheapest lowest-numbered node without walking all of them
/// (40 000 coincident strokes made every step walk 40 000 nodes). kiddo's mutable tree does
/// not prune emptied leaves, so a tree is rebuilt from its live sites once more sites have
/// left it than remain.
struct ToolTrees {
    trees: Vec<Tree>,
    /// sites the tree refused (never expected with jittered points; scanned linearly)
    overflow: Vec<Vec<u32>>,
    /// tree coordinates: the site's point moved by a tiny deterministic jitter, so that no
    /// two sites share a coordinate (kiddo's mutable tree cannot split a bucket of points
    /// equal along its split axis)
    tree_xy: Vec<[f64; 2]>,
    /// bound on |tree_xy - site_xy| per axis, for the exact stopping rule
    jitter: f64,
    /// live sites per tool tree
    live: Vec<u32>,
    removed: Vec<u32>,
    site_of_node: Vec<u32>,
    site_tool: Vec<u32>,
    sites_of_tool: Vec<Vec<u32>>,
    /// live nodes at each site
    live_at: Vec<u32>,
    /// the classes of each site's nodes
    classes_at: Vec<Vec<u32>>,
    class_of_node: Vec<u32>,
    /// per class, its nodes added so far (lowest first); the top is always live
    heaps: Vec<BinaryHeap<Reverse<u32>>>,
    /// visited nodes
    dead: Vec<bool>,
}

impl ToolTrees {
    fn new(m: &CostModel) -> Self {
        let n = m.n();
        let ntools = (0..n).map(|c| m.tool(c) as usize + 1).max().unwrap_or(1);
        let mut index: std::collections::HashMap<(u32, u64, u64), u32> = Default::default();
        let mut class_index: std::collections::HashMap<(u32, u64, u64), u32> = Default::default();
        let mut site_of_node = vec![0u32; m.nodes()];
        let mut class_of_node = vec![0u32; m.nodes()];
        let mut classes_at: Vec<Vec<u32>> = Vec::new();
        let mut site_xy = Vec::new();
        let mut site_tool = Vec::new();
        let mut sites_of_tool = vec![Vec::new(); ntools];
        for c in 0..n {
            let t = m.tool(c);
            for md in 0..m.modes(c) {
                let nd = m.node(c, md);
                let p = m.entry(nd);
                let key = (t, p.x.to_bits(), p.y.to_bits());
                let id = *index.entry(key).or_insert_with(|| {
                    site_xy.push([p.x, p.y]);
                    site_tool.push(t);
                    classes_at.push(Vec::new());
                    sites_of_tool[t as usize].push(site_xy.len() as u32 - 1);
                    site_xy.len() as u32 - 1
                });
                site_of_node[nd] = id;
                // what else a move into the node costs by: its height and cutting rate
                let ckey = (id, p.z.to_bits(), m.cut_rate(c).to_bits());
                let next = class_index.len() as u32;
                let class = *class_index.entry(ckey).or_insert(next);
                if class == next {
                    classes_at[id as usize].push(class);
                }
                class_of_node[nd] = class;
            }
        }
        let nsites = site_xy.len();
        let scale = site_xy
            .iter()
            .map(|p| p[0].abs().max(p[1].abs()))
            .fold(1.0f64, f64::max);
        let jitter = scale * 1e-9;
        let tree_xy = site_xy
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let h = (i as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
                let u = |v: u64| ((v >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0;
                [
                    p[0] + jitter * u(h),
                    p[1] + jitter * u(h.rotate_left(29) ^ 0xD1B5_4A32_D192_ED03),
                ]
            })
            .collect();
        ToolTrees {
            overflow: vec![Vec::new(); ntools],
            tree_xy,
            jitter,
            trees: (0..ntools).map(|_| Tree::default()).collect(),
            live: vec![0; ntools],
            removed: vec![0; ntools],
            site_of_node,
            site_tool,
            sites_of_tool,
            live_at: vec![0; nsites],
            classes_at,
            heaps: (0..class_index.len()).map(|_| BinaryHeap::new()).collect(),
            class_of_node,
            dead: vec![false; m.nodes()],
        }
    }
    fn add(&mut self, m: &CostModel, c: usize) {
        for md in 0..m.modes(c) {
            let nd = m.node(c, md);
            let site = self.site_of_node[nd] as usize;
            if self.live_at[site] == 0 {
                let t = self.site_tool[site] as usize;
                if self.trees[t].add(&self.tree_xy[site], site as u32).is_ok() {
                    self.live[t] += 1;
                } else {
                    self.overflow[t].push(site as u32);
                }
            }
            self.live_at[site] += 1;
            self.heaps[self.class_of_node[nd] as usize].push(Reverse(nd as u32));
        }
    }
    fn remove(&mut self, m: &CostModel, c: usize) {
        let t = m.tool(c) as usize;
        for md in 0..m.modes(c) {
            let nd = m.node(c, md);
            let site = self.site_of_node[nd] as usize;
            self.dead[nd] = true;
            let heap = &mut self.heaps[self.class_of_node[nd] as usize];
            while heap.peek().is_some_and(|x| self.dead[x.0 as usize]) {
                heap.pop();
            }
            self.live_at[site] -= 1;
            if self.live_at[site] == 0 {
                if let Some(k) = self.overflow[t].iter().position(|&x| x as usize == site) {
                    self.overflow[t].swap_remove(k);
                } else {
                    self.trees[t].remove(&self.tree_xy[site], site as u32);
                    self.live[t] -= 1;
                    self.removed[t] += 1;
                }
            }
        }
        if self.removed[t] > self.live[t].max(64) {
            self.overflow[t].clear();
            let entries: Vec<(u32, [f64; 2])> = self.sites_of_tool[t]
                .iter()
                .filter(|&&site| self.live_at[site as usize] > 0)
                .map(|&site| (site, self.tree_xy[site as usize]))
                .collect();
            self.trees[t] = if entries.is_empty() {
                Tree::default()
            } else {
                Tree::new_from_entries(&entries).expect("k-d tree build")
            };
            self.live[t] = entries.len() as u32;
            self.removed[t] = 0;
        }
    }
    /// The live nodes of `site` that may be the cheapest: the lowest-numbered of each class
    /// (every node of a class costs the same from any node).
    fn candidates(&self, site: usize) -> impl Iterator<Item = usize> + '_ {
        self.classes_at[site]
            .iter()
            .filter_map(|&k| self.heaps[k as usize].peek().map(|x| x.0 as usize))
    }
}

/// Greedy over a geometric instance with one k-d tree per tool.
pub fn geometric(m: &CostModel, count: &mut dyn FnMut(u64)) -> Sequence {
    geometric_until(m, count, Deadline::NONE)
}

/// Like [`geometric`]; once `deadline` passes, the rest of the cells follow in a quick
/// feasible order ([`super::complete`]).
pub fn geometric_until(m: &CostModel, count: &mut dyn FnMut(u64), deadline: Deadline) -> Sequence {
    if deadline.passed() {
        return super::fastest(m);
    }
    let n = m.n();
    let mut clock = super::ticker(deadline);
    let mut trees = ToolTrees::new(m);
    let ntools = trees.trees.len();
    let mut fringe = Fringe::new(m);
    for c in 0..n {
        if fringe.missing[c] == 0 {
            trees.add(m, c);
        }
    }
    // lower bound on any move cost given its planar length d
    let rr = m.rapid_rate();
    let (lb_rate, link_rate) = match m.objective() {
        Objective::Time => (rr, rr.min(min_cut_rate(m))),
        _ => (1.0, 1.0),
    };
    let link = m.link_distance();
    let mut seq: Sequence = Vec::with_capacity(n);
    let mut done = vec![false; n];
    let mut order: Vec<usize> = Vec::with_capacity(ntools);
    while seq.len() < n {
        if clock.passed() {
            super::complete(m, &mut seq);
            return seq;
        }
        let prev = seq.last().copied();
        let mut best = (f64::INFINITY, usize::MAX);
        let cost_to = |nd: usize| -> f64 {
            let (c, md) = m.cell_mode(nd);
            match prev {
                None => m.start(c, md),
                Some(p) => m.arc(p.cell, p.mode, c, md),
            }
        };
        let cur_tool = prev.map(|p| m.tool(p.cell) as usize);
        // Where to query tree t, and a lower bound on the cost of any move into t whose
        // planar length is at least d: `offset + d * rate` (links only within link distance).
        let query_at = |t: usize| -> ([f64; 2], f64, bool) {
            match prev {
                Some(p) if Some(t) == cur_tool => {
                    let e = m.exit(m.node(p.cell, p.mode));
                    ([e.x, e.y], m.lift_floor(p.cell, p.mode), true)
                }
                Some(p) => {
                    let tc = m.tool_change_point();
                    ([tc.x, tc.y], m.change_offset(p.cell, p.mode), false)
                }
                None => {
                    let h = m.home_point();
                    ([h.x, h.y], 0.0, false)
                }
            }
        };
        order.clear();
        order.extend((0..ntools).filter(|&t| trees.live[t] > 0 || !trees.overflow[t].is_empty()));
        if let Some(ct) = cur_tool {
            order.sort_by_key(|&t| (t != ct, t));
        }
        for &t in &order {
            let (q, offset, same_tool) = query_at(t);
            let lower = |d: f64| -> f64 {
                if same_tool && d <= link + 1e-9 {
                    d * link_rate
                } else {
                    offset + d * lb_rate
                }
            };
            if best.0 <= lower(0.0) {
                continue;
            }
            for &site in &trees.overflow[t] {
                for nd in trees.candidates(site as usize) {
                    let c = cost_to(nd);
                    if c < best.0 || (c == best.0 && nd < best.1) {
                        best = (c, nd);
                    }
                }
            }
            let mut k = 8usize;
            let live = trees.live[t] as usize;
            if live == 0 {
                continue;
            }
            loop {
                let kk = k.min(live);
                let res = trees.trees[t]
                    .query(&q)
                    .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(kk).expect("k > 0"))
                    .execute();
                count(res.len() as u64);
                for r in &res {
                    for nd in trees.candidates(r.item as usize) {
                        let c = cost_to(nd);
                        if c < best.0 || (c == best.0 && nd < best.1) {
                            best = (c, nd);
                        }
                    }
                }
                let exhausted = res.len() < kk || kk == live;
                // tree points sit within `jitter` of the true points on each axis
                let far = res.last().map(|r| r.distance.sqrt()).unwrap_or(0.0);
                let far = (far - 3.0 * trees.jitter).max(0.0);
                if exhausted || best.0 <= lower(far) {
                    break;
                }
                k *= 4;
            }
        }
        let (c, md) = m.cell_mode(best.1);
        seq.push(Visit::new(c, md));
        done[c] = true;
        let mut newly = Vec::new();
        fringe.done(m, c, |s| newly.push(s));
        trees.remove(m, c);
        for s in newly {
            trees.add(m, s);
        }
    }
    seq
}

fn min_cut_rate(m: &CostModel) -> f64 {
    (0..m.n())
        .map(|c| m.cut_rate(c))
        .fold(f64::INFINITY, f64::min)
}

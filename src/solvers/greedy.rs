//! `greedy`: precedence-aware nearest neighbour.
//!
//! From the current (cell, mode) it moves to the cheapest (cell, mode) among cells whose
//! predecessors are all done. Geometric instances keep one k-d tree (kiddo) per tool over the
//! entry points of ready cells and grow the nearest-k query until no farther point can beat
//! the best exact arc cost found, so each step is exact and costs O(log n) in practice.
//! Matrix instances scan the ready cells.

use super::{Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo, outcome_of};
use crate::cost::CostModel;
use crate::error::Result;
use crate::model::{Objective, Sequence, Visit};
use kiddo::{MutableKdTree, SquaredEuclidean};
use std::num::NonZero;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "greedy",
    summary: "precedence-aware nearest neighbour (k-d tree per tool on geometric instances)",
    params: &[ParamSpec {
        name: "randomize",
        default: "0",
        kind: ParamKind::Float,
        help: "probability of taking the second-best candidate at a step (0 = pure greedy)",
    }],
    make: |p: &Params| {
        Box::new(Greedy {
            randomize: p.float("randomize"),
        })
    },
};

/// The greedy solver.
pub struct Greedy {
    /// Probability of taking the second-best candidate.
    pub randomize: f64,
}

impl Solver for Greedy {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let seq = if ctx.model.is_geometric() {
            geometric(ctx.model, &mut |k| ctx.count(k))
        } else {
            matrix(ctx.model, &mut |k| ctx.count(k))
        };
        let out = outcome_of(ctx.model, seq);
        ctx.report(out.cost);
        Ok(out)
    }
}

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
    let n = m.n();
    let mut fringe = Fringe::new(m);
    let mut ready: Vec<usize> = (0..n).filter(|&c| fringe.missing[c] == 0).collect();
    let mut seq: Sequence = Vec::with_capacity(n);
    while !ready.is_empty() {
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

/// One k-d tree per tool over the entry points of ready, unvisited cells. kiddo's mutable
/// tree does not prune emptied leaves, so a tree is rebuilt from its live points once more
/// points have been removed from it than remain.
struct ToolTrees<'a> {
    m: &'a CostModel,
    trees: Vec<Tree>,
    live: Vec<u32>,
    removed: Vec<u32>,
    cells_of_tool: Vec<Vec<u32>>,
}

impl<'a> ToolTrees<'a> {
    fn new(m: &'a CostModel) -> Self {
        let n = m.n();
        let ntools = (0..n).map(|c| m.tool(c) as usize + 1).max().unwrap_or(1);
        let mut cells_of_tool = vec![Vec::new(); ntools];
        for c in 0..n {
            cells_of_tool[m.tool(c) as usize].push(c as u32);
        }
        ToolTrees {
            m,
            trees: (0..ntools).map(|_| Tree::default()).collect(),
            live: vec![0; ntools],
            removed: vec![0; ntools],
            cells_of_tool,
        }
    }
    fn add(&mut self, c: usize) {
        let t = self.m.tool(c) as usize;
        for md in 0..self.m.modes(c) {
            let nd = self.m.node(c, md);
            let p = self.m.entry(nd);
            self.trees[t]
                .add(&[p.x, p.y], nd as u32)
                .expect("k-d tree insert");
            self.live[t] += 1;
        }
    }
    fn remove(&mut self, c: usize, in_tree: impl Fn(usize) -> bool) {
        let t = self.m.tool(c) as usize;
        for md in 0..self.m.modes(c) {
            let nd = self.m.node(c, md);
            let p = self.m.entry(nd);
            self.trees[t].remove(&[p.x, p.y], nd as u32);
            self.live[t] -= 1;
            self.removed[t] += 1;
        }
        if self.removed[t] > self.live[t].max(64) {
            let mut entries = Vec::with_capacity(self.live[t] as usize);
            for &cc in &self.cells_of_tool[t] {
                let cc = cc as usize;
                if in_tree(cc) {
                    for md in 0..self.m.modes(cc) {
                        let nd = self.m.node(cc, md);
                        let p = self.m.entry(nd);
                        entries.push((nd as u32, [p.x, p.y]));
                    }
                }
            }
            self.trees[t] = if entries.is_empty() {
                Tree::default()
            } else {
                Tree::new_from_entries(&entries).expect("k-d tree build")
            };
            self.live[t] = entries.len() as u32;
            self.removed[t] = 0;
        }
    }
}

/// Greedy over a geometric instance with one k-d tree per tool.
pub fn geometric(m: &CostModel, count: &mut dyn FnMut(u64)) -> Sequence {
    let n = m.n();
    let mut trees = ToolTrees::new(m);
    let ntools = trees.trees.len();
    let mut fringe = Fringe::new(m);
    for c in 0..n {
        if fringe.missing[c] == 0 {
            trees.add(c);
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
        order.extend((0..ntools).filter(|&t| trees.live[t] > 0));
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
            let mut k = 8usize;
            loop {
                let kk = k.min(trees.live[t] as usize);
                let res = trees.trees[t]
                    .query(&q)
                    .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(kk).expect("k > 0"))
                    .execute();
                count(res.len() as u64);
                for r in &res {
                    let nd = r.item as usize;
                    let c = cost_to(nd);
                    if c < best.0 || (c == best.0 && nd < best.1) {
                        best = (c, nd);
                    }
                }
                let exhausted = res.len() < kk || kk == trees.live[t] as usize;
                let far = res.last().map(|r| r.distance.sqrt()).unwrap_or(0.0);
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
        let missing = &fringe.missing;
        trees.remove(c, |x| !done[x] && missing[x] == 0);
        for s in newly {
            trees.add(s);
        }
    }
    seq
}

fn min_cut_rate(m: &CostModel) -> f64 {
    (0..m.n())
        .map(|c| m.cut_rate(c))
        .fold(f64::INFINITY, f64::min)
}

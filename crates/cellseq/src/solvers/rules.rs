//! `rules`: paper 002's knowledge rules 1–5 as an ordering procedure.
//!
//! Each cell gets a priority key and a precedence-respecting list schedule always takes the
//! ready cell with the smallest key; the mode DP then picks entry/exit points.
//! - Rule 1: procedures (tool groups) ordered by precedence between them, else larger tool first.
//! - Rule 2: outer contour before inner features.
//! - Rule 3: topologically related cells (same feature) upper before lower (larger z first).
//! - Rule 4: step types in the order wall groove, pocket, flange/edge, rib (then the rest).
//! - Rule 5: cells with no other priority ordered symmetrically about the part's centre
//!   (mirror pairs left/right of the centre cut one after the other) to limit deformation.

use super::Build;
use super::start::outcome;
use super::{Caps, Context, Outcome, ParamSpec, Params, Solver, SolverInfo};
use crate::engine::modes::mode_dp;
use crate::engine::{Costs, Solution};
use crate::error::Result;
use crate::model::{Instance, StepKind, Visit};
use crate::precedence::Dag;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "rules",
    summary: "knowledge rules 1-5 of paper 002 (tool size, outer before inner, upper before lower, step order, symmetry)",
    description: "The knowledge rules 1–5 of paper 002 (tool size, outer before inner, upper before lower, \
step order, symmetry) applied in turn, with no search: the papers' rule-based baseline.",
    params: &[] as &[ParamSpec],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|_p: &Params| Ok(Box::new(Rules))),
};

/// The rule-based solver.
pub struct Rules;

/// Rule-1 key of a tool group: larger diameter first, then index.
type GroupKey = (Reverse<i64>, usize);

/// Priority of a cell: tool rank, outer flag, step rank, −z, symmetry ring, offset, side, index.
type CellKey = (u32, u32, u32, i64, i64, i64, bool, usize);

/// Rule-4 rank of a step kind (smaller first).
fn step_rank(k: StepKind) -> u32 {
    match k {
        StepKind::Face => 0,
        StepKind::OuterContour => 1,
        StepKind::WallGroove => 2,
        StepKind::PocketRough => 3,
        StepKind::PocketFinish => 4,
        StepKind::Flange => 5,
        StepKind::Rib => 6,
        StepKind::Hole => 7,
        StepKind::Engrave => 8,
        StepKind::Other => 9,
    }
}

/// Rank of every tool group: topological over the group precedence graph, larger diameter
/// first among ready groups (rule 1). Returns the rank per cell.
pub fn tool_rank(inst: &Instance, dag: &Dag) -> Vec<u32> {
    let tools = inst.used_tools();
    let t = tools.len();
    let group: Vec<usize> = inst
        .cells
        .iter()
        .map(|c| tools.iter().position(|x| *x == c.tool).unwrap_or(0))
        .collect();
    let dia = |g: usize| inst.tool(tools[g]).map(|x| x.diameter).unwrap_or(0.0);
    let mut edges = vec![Vec::new(); t];
    let mut indeg = vec![0u32; t];
    for (a, ss) in dag.succs.iter().enumerate() {
        for &b in ss {
            let (ga, gb) = (group[a], group[b as usize]);
            if ga != gb && !edges[ga].contains(&gb) {
                edges[ga].push(gb);
                indeg[gb] += 1;
            }
        }
    }
    let key = |g: usize| (Reverse((dia(g) * 1000.0) as i64), g);
    let mut heap: BinaryHeap<Reverse<(GroupKey, usize)>> = (0..t)
        .filter(|&g| indeg[g] == 0)
        .map(|g| Reverse((key(g), g)))
        .collect();
    let mut rank = vec![u32::MAX; t];
    let mut r = 0;
    while let Some(Reverse((_, g))) = heap.pop() {
        rank[g] = r;
        r += 1;
        for &h in &edges[g] {
            indeg[h] -= 1;
            if indeg[h] == 0 {
                heap.push(Reverse((key(h), h)));
            }
        }
    }
    if rank.contains(&u32::MAX) {
        // cyclic between groups: diameter order only
        let mut gs: Vec<usize> = (0..t).collect();
        gs.sort_by_key(|&g| key(g));
        for (i, g) in gs.into_iter().enumerate() {
            rank[g] = i as u32;
        }
    }
    group.iter().map(|&g| rank[g]).collect()
}

/// Precedence-respecting list schedule by smallest key.
pub fn list_schedule<K: Ord + Copy>(dag: &Dag, key: &[K]) -> Vec<usize> {
    let n = dag.n();
    let mut missing: Vec<u32> = dag.preds.iter().map(|p| p.len() as u32).collect();
    let mut heap: BinaryHeap<Reverse<(K, usize)>> = (0..n)
        .filter(|&c| missing[c] == 0)
        .map(|c| Reverse((key[c], c)))
        .collect();
    let mut out = Vec::with_capacity(n);
    while let Some(Reverse((_, c))) = heap.pop() {
        out.push(c);
        for &s in &dag.succs[c] {
            missing[s as usize] -= 1;
            if missing[s as usize] == 0 {
                heap.push(Reverse((key[s as usize], s as usize)));
            }
        }
    }
    out
}

impl Solver for Rules {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let inst = ctx.instance;
        let m = ctx.model;
        let n = inst.n();
        let trank = tool_rank(inst, &m.dag);
        // part centre and symmetric key (rule 5)
        let pts: Vec<(f64, f64)> = inst
            .cells
            .iter()
            .map(|c| {
                c.modes
                    .first()
                    .map(|md| (md.entry.x, md.entry.y))
                    .unwrap_or((0.0, 0.0))
            })
            .collect();
        let (cx, cy) = pts.iter().fold((0.0, 0.0), |a, p| {
            (a.0 + p.0 / n as f64, a.1 + p.1 / n as f64)
        });
        let span = pts
            .iter()
            .map(|p| (p.0 - cx).abs().max((p.1 - cy).abs()))
            .fold(0.0, f64::max)
            .max(1e-9);
        let key: Vec<CellKey> = (0..n)
            .map(|c| {
                let cell = &inst.cells[c];
                let outer = (cell.step != StepKind::OuterContour) as u32; // rule 2
                let z = -(cell.z * 1000.0) as i64; // rule 3: upper first
                let (dx, dy) = (pts[c].0 - cx, pts[c].1 - cy);
                // rule 5: mirror pairs about the centre share the first two parts of the key
                let ring = -((dx.abs().max(dy.abs()) / span * 64.0) as i64);
                let along = (if dx.abs() >= dy.abs() {
                    dy.abs()
                } else {
                    dx.abs()
                } / span
                    * 64.0) as i64;
                (
                    trank[c],
                    outer,
                    step_rank(cell.step),
                    z,
                    ring,
                    along,
                    dx < 0.0 || (dx == 0.0 && dy < 0.0),
                    c,
                )
            })
            .collect();
        let order = list_schedule(&m.dag, &key);
        ctx.count(n as u64);
        let c = Costs::open(m);
        let seq: Vec<Visit> = order.iter().map(|&x| Visit::new(x, 0)).collect();
        let mut s = Solution::new(&c, &seq);
        let e = mode_dp(&c, &mut s);
        ctx.count(e);
        let out = outcome(m, &s);
        ctx.report(out.cost);
        Ok(out)
    }
}

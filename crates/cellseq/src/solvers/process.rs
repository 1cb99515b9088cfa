//! `process`: paper 000's process-based sequencing of machining cells.
//!
//! Cells are grouped on four levels: cutter (in the process scheme's tool order, taken as the
//! instance's tool library order) → target vs supplementary cells (target = the cutter's main
//! working-step type, the one with most cells) → supplementary cells by working-step type →
//! layer. Groups are ordered by the cutter order (the depth-first traversal of the scheme) and
//! the cutter-layer rule: supplementary groups in the order of the preceding working steps
//! (step-type process order), then the target group; layers top-down. A precedence-respecting
//! list schedule by group rank gives the macro sequence; simulated annealing (paper 000's
//! Markov chains, Metropolis, stagnation stop) then reorders cells only inside each level-4
//! group (contiguous run of the same group).

use super::Build;
use super::sa::{Anneal, SPECS};
use super::start::outcome;
use super::{Caps, Context, Outcome, Params, Solver, SolverInfo};
use crate::engine::{Costs, Solution};
use crate::error::Result;
use crate::model::{StepKind, Visit};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "process",
    summary: "process-based sequencing (paper 000): 4-level grouping, process-scheme group order, SA inside level-4 groups",
    description: "Process-based sequencing as in paper 000: cells are grouped on four levels (cutter; the \
cutter's main working-step type against the supplementary ones; working-step type; layer), \
groups are ordered by the process scheme (cutter order, supplementary steps before the \
target group, layers top-down), and simulated annealing (the parameters of `sa`) reorders \
the cells inside each level-4 group.",
    params: SPECS,
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Process {
            anneal: Anneal::from_params(p),
        }))
    }),
};

/// The process-based solver.
pub struct Process {
    /// Annealing inside groups.
    pub anneal: Anneal,
}

impl Solver for Process {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let inst = ctx.instance;
        let m = ctx.model;
        let n = inst.n();
        if !m.acyclic() {
            return Err(crate::error::Error::Solver {
                solver: "process".into(),
                msg: "the precedence has a cycle".into(),
            });
        }
        // level 1: cutter in process-scheme order (tool library order, then first use)
        let mut tool_order: Vec<&str> = inst.tools.iter().map(|t| t.id.as_str()).collect();
        for t in inst.used_tools() {
            if !tool_order.contains(&t) {
                tool_order.push(t);
            }
        }
        let tool_of = |c: usize| {
            tool_order
                .iter()
                .position(|t| *t == inst.cells[c].tool)
                .unwrap_or(0)
        };
        // level 2: target step per cutter = most frequent step kind
        let mut target = vec![StepKind::Other; tool_order.len()];
        for (t, tg) in target.iter_mut().enumerate() {
            let mut counts = [0usize; 10];
            for c in (0..n).filter(|&c| tool_of(c) == t) {
                counts[StepKind::ALL
                    .iter()
                    .position(|k| *k == inst.cells[c].step)
                    .unwrap_or(9)] += 1;
            }
            let best = (0..10)
                .max_by_key(|&i| (counts[i], std::cmp::Reverse(i)))
                .unwrap_or(9);
            *tg = StepKind::ALL[best];
        }
        // group key: (cutter, supplementary before target, step type, layer)
        let key: Vec<(usize, bool, usize, u32)> = (0..n)
            .map(|c| {
                let cell = &inst.cells[c];
                let t = tool_of(c);
                let is_target = cell.step == target[t];
                let step = StepKind::ALL
                    .iter()
                    .position(|k| *k == cell.step)
                    .unwrap_or(9);
                (t, is_target, if is_target { 0 } else { step }, cell.layer)
            })
            .collect();
        let with_index: Vec<((usize, bool, usize, u32), usize)> =
            (0..n).map(|c| (key[c], c)).collect();
        let order = super::rules::list_schedule(&m.dag, &with_index);
        ctx.count(n as u64);
        // blocks: maximal runs of one group in the macro sequence
        let mut block = vec![(0u32, 0u32); n];
        let mut start = 0usize;
        for p in 0..=n {
            if p == n || (p > start && key[order[p]] != key[order[start]]) {
                for b in block.iter_mut().take(p).skip(start) {
                    *b = (start as u32, p as u32 - 1);
                }
                start = p;
            }
        }
        let c = Costs {
            m,
            closed: self.anneal.closed,
        };
        let seq: Vec<Visit> = order.iter().map(|&x| Visit::new(x, 0)).collect();
        let mut s = Solution::new(&c, &seq);
        let e = crate::engine::modes::mode_dp(&c, &mut s);
        ctx.count(e);
        ctx.report(m.evaluate(&s.sequence()));
        let mut rng = ChaCha8Rng::seed_from_u64(ctx.seed);
        let before = s.clone();
        self.anneal.run(ctx, &c, &mut s, Some(&block), &mut rng);
        let mut out = outcome(m, &s);
        let base = outcome(m, &before);
        if base.cost < out.cost {
            out = base;
        }
        ctx.report(out.cost);
        Ok(out)
    }
}

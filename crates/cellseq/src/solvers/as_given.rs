//! `as-given`: the instance's own programmed order (the papers' "unoptimized" baseline),
//! else file order, repaired to respect precedence.

use super::Build;
use super::{Caps, Context, Outcome, Params, Solver, SolverInfo, outcome_of};
use crate::error::Result;
use crate::model::Visit;
use crate::precedence::ranked_topological_order;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "as-given",
    summary: "the instance's as-programmed order (else file order), repaired to respect precedence",
    description: "The order the instance was programmed in (its `as_given` order; else file \
order), repaired to respect precedence: the \"unoptimized\" baseline the papers compare \
against.",
    params: &[],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|_p: &Params| Ok(Box::new(AsGiven))),
};

/// The as-given solver.
pub struct AsGiven;

impl Solver for AsGiven {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let inst = ctx.instance;
        let n = inst.n();
        let wished: Vec<Visit> = inst
            .as_given
            .clone()
            .unwrap_or_else(|| (0..n).map(|c| Visit::new(c, 0)).collect());
        let mut rank = vec![0usize; n];
        let mut mode = vec![0usize; n];
        for (p, v) in wished.iter().enumerate() {
            rank[v.cell] = p;
            mode[v.cell] = v.mode;
        }
        let order =
            ranked_topological_order(&ctx.model.dag, &rank).unwrap_or_else(|_| (0..n).collect());
        ctx.count(n as u64);
        let out = outcome_of(
            ctx.model,
            order.into_iter().map(|c| Visit::new(c, mode[c])).collect(),
        );
        ctx.report(out.cost);
        Ok(out)
    }
}

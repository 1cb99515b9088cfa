//! `greedy`: precedence-aware nearest neighbour, the registry entry of
//! [`crate::construct::greedy`].

use super::Build;
use super::{Caps, Context, Outcome, Params, Solver, SolverInfo, outcome_of};
use crate::error::Result;

pub use crate::construct::greedy::{geometric, matrix};

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "greedy",
    summary: "precedence-aware nearest neighbour (k-d tree per tool on geometric instances)",
    description: "Precedence-aware nearest neighbour: from the current cell, the cheapest next cell whose \
predecessors are all done. On geometric instances the candidates come from a k-d tree per \
tool, so 10^5 cells take well under a second. Deterministic; the multi-start solvers draw \
their randomized starts from a randomized fringe construction instead (`start.rs`).",
    params: &[],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|_: &Params| Ok(Box::new(Greedy))),
};

/// The greedy solver.
pub struct Greedy;

impl Solver for Greedy {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let seq = super::start::greedy_start(ctx);
        let out = outcome_of(ctx.model, seq);
        ctx.report(out.cost);
        Ok(out)
    }
}

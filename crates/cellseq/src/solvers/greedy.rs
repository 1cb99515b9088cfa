//! `greedy`: precedence-aware nearest neighbour, the registry entry of
//! [`crate::construct::greedy`].

use super::Build;
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo, outcome_of};
use crate::error::Result;

pub use crate::construct::greedy::{geometric, matrix};

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "greedy",
    summary: "precedence-aware nearest neighbour (k-d tree per tool on geometric instances)",
    description: "Precedence-aware nearest neighbour: from the current cell, the cheapest next cell whose \
predecessors are all done. On geometric instances the candidates come from a k-d tree per \
tool, so 10^5 cells take well under a second. `randomize` makes it a randomized start for \
multi-start solvers.",
    params: &[ParamSpec {
        name: "randomize",
        default: "0",
        kind: ParamKind::float(0.0, 1.0),
        help: "probability of taking the second-best candidate at a step (0 = pure greedy)",
    }],
    caps: Caps { ..Caps::NONE },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(Greedy {
            randomize: p.float("randomize"),
        }))
    }),
};

/// The greedy solver.
pub struct Greedy {
    /// Probability of taking the second-best candidate.
    pub randomize: f64,
}

impl Solver for Greedy {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let seq = super::start::greedy_start(ctx);
        let out = outcome_of(ctx.model, seq);
        ctx.report(out.cost);
        Ok(out)
    }
}

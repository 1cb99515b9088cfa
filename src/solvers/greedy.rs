//! `greedy`: precedence-aware nearest neighbour, the registry entry of
//! [`crate::construct::greedy`].

use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo, outcome_of};
use crate::error::Result;

pub use crate::construct::greedy::{geometric, matrix};

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
    caps: Caps { ..Caps::NONE },
    make: |p: &Params| {
        Ok(Box::new(Greedy {
            randomize: p.float("randomize"),
        }))
    },
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

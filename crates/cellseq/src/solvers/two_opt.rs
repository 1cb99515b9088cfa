//! `two-opt`: greedy start, then 2-opt with mode flip to a local optimum.

use super::Build;
use super::start::{greedy_solution, outcome};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::engine::Costs;
use crate::engine::vnd::Search;
use crate::error::Result;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "two-opt",
    summary: "greedy, then 2-opt with mode flip (reversal of precedence-free reversible segments) to a local optimum",
    description: "`greedy`, then 2-opt with mode flip to a local optimum: a segment is reversed only when \
no precedence pair lies inside it and every cell in it may be cut backwards (reversed cells \
change mode).",
    params: &[ParamSpec {
        name: "k",
        default: "10",
        kind: ParamKind::int(1, crate::params::MAX_NEIGHBOURS),
        help: "candidate neighbours per cell",
    }],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::Fresh(|p: &Params| {
        Ok(Box::new(TwoOpt {
            k: p.int("k") as usize,
        }))
    }),
};

/// The 2-opt solver.
pub struct TwoOpt {
    /// Candidate neighbours per cell.
    pub k: usize,
}

impl Solver for TwoOpt {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs::open(m);
        let mut s = greedy_solution(ctx, &c);
        if ctx.deadline().passed() {
            return Ok(outcome(m, &s));
        }
        let mut search = Search::new_until(c, self.k, ctx.deadline());
        while search.two_opt(&mut s, ctx) {
            ctx.report(s.cost + m.constant());
        }
        Ok(outcome(m, &s))
    }
}

//! `local-search`: greedy start, then variable neighbourhood descent over every move of the
//! engine (Or-opt, 2-opt with mode flip, single-cell mode change, SOP-3-exchange, mode DP).

use super::start::{greedy_start, outcome};
use super::{Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::engine::search::Search;
use crate::engine::{Costs, Solution};
use crate::error::Result;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "local-search",
    summary: "greedy, then VND over Or-opt, 2-opt with mode flip, mode change, SOP-3-exchange and the mode DP",
    params: &[
        ParamSpec {
            name: "k",
            default: "10",
            kind: ParamKind::Int,
            help: "candidate neighbours per cell",
        },
        ParamSpec {
            name: "max-block",
            default: "0",
            kind: ParamKind::Int,
            help: "longest block of SOP-3-exchange (0 = n up to 1000 cells, else 50)",
        },
    ],
    make: |p: &Params| {
        Box::new(LocalSearch {
            k: p.int("k").max(1) as usize,
            max_block: p.int("max-block") as usize,
        })
    },
};

/// The VND solver.
pub struct LocalSearch {
    /// Candidate neighbours per cell.
    pub k: usize,
    /// SOP-3-exchange block limit (0 = automatic).
    pub max_block: usize,
}

impl Solver for LocalSearch {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs::open(m);
        let seq = greedy_start(ctx);
        let mut s = Solution::new(&c, &seq);
        ctx.report(s.cost + m.constant());
        let mut search = Search::new(c, self.k);
        if self.max_block > 0 {
            search.max_block = self.max_block;
        }
        search.vnd(&mut s, ctx);
        ctx.report(s.cost + m.constant());
        Ok(outcome(m, &s))
    }
}

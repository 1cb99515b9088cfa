//! `corridor`: the corridor search of [`crate::engine::corridor`] run again and again from
//! the best sequence, wider after each pass that finds nothing, each gain polished by the VND.

use super::Build;
use super::StartsFrom;
use super::start::{POLISH_K, given_or_polished, outcome};
use super::{Caps, Context, Outcome, ParamKind, ParamSpec, Params, SolverInfo};
use crate::engine::corridor::{self, Corridor as Shape, MAX_DIFF, MAX_REACH};
use crate::engine::{Costs, Solution};
use crate::error::Result;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "corridor",
    summary: "corridor search: the cheapest reorder within a corridor around the best sequence, by a beam over prefixes guided by the best sequence's own finish",
    description: "Corridor search (the corridor method of Sniedovich and Voß). The sequences it \
looks at differ from the best one, at every length of prefix, by at most `diff` cells, and \
move no cell more than `reach` places. A beam over prefixes (two prefixes with the same cells \
and last cell are one state) keeps, at each length, the `width` states of lowest cost plus the \
cost of finishing them in the best sequence's order; so it is never worse than the best \
sequence, and with a width that holds the whole corridor it is the corridor's optimum. A gain \
is polished by the VND and searched again; a pass without one doubles the width, up to \
`max-width`. Reorders of 60 cells in which 20 move up to 30 places, which no kick or exchange \
makes at once, lie in a corridor of five. Alone it starts from `greedy`.",
    params: &[
        ParamSpec {
            name: "diff",
            default: "5",
            kind: ParamKind::int(1, MAX_DIFF as u64),
            help: "most cells by which a prefix may differ from the best sequence's prefix of the same length",
        },
        ParamSpec {
            name: "reach",
            default: "30",
            kind: ParamKind::int(1, MAX_REACH as u64),
            help: "most places a cell may move",
        },
        ParamSpec {
            name: "width",
            default: "2000",
            kind: ParamKind::int(1, 1 << 24),
            help: "states kept per prefix length at the first pass",
        },
        ParamSpec {
            name: "max-width",
            default: "65536",
            kind: ParamKind::int(1, 1 << 24),
            help: "passes without a gain double the width up to this; a pass at it without a gain ends the run",
        },
        POLISH_K,
    ],
    caps: Caps {
        improves: true,
        ..Caps::NONE
    },
    build: Build::StartsFrom(|p: &Params| Ok(Box::new(from_params(p)))),
};

/// Builds the solver from validated parameters.
pub fn from_params(p: &Params) -> Corridor {
    Corridor {
        diff: p.int("diff") as usize,
        reach: p.int("reach") as usize,
        width: p.int("width") as usize,
        max_width: p.int("max-width") as usize,
        k: p.int("k") as usize,
    }
}

/// Corridor search from the best sequence, repeated.
pub struct Corridor {
    /// Most cells a prefix may differ by.
    pub diff: usize,
    /// Most places a cell may move.
    pub reach: usize,
    /// States per prefix length at the first pass.
    pub width: usize,
    /// Widest pass.
    pub max_width: usize,
    /// Candidate neighbours of the polishing VND.
    pub k: usize,
}

impl StartsFrom for Corridor {
    /// Runs the passes from `start` (evaluated with open-loop costs), or from the greedy
    /// sequence polished by the VND when `start` is `None`.
    fn run_from(&self, ctx: &mut Context, start: Option<Solution>) -> Result<Outcome> {
        let m = ctx.model;
        let c = Costs::open(m);
        let (mut s, search) = given_or_polished(ctx, c, start, self.k);
        let Some(mut search) = search else {
            return Ok(outcome(m, &s));
        };
        let mut width = self.width.min(self.max_width);
        let (mut passes, mut gains) = (0u64, 0u64);
        while !ctx.exhausted() {
            let shape = Shape {
                diff: self.diff,
                reach: self.reach,
                width,
            };
            passes += 1;
            match corridor::improve(&c, &s, ctx, shape) {
                Some((order, _)) => {
                    gains += 1;
                    s = s.reordered(&c, &order);
                    search.vnd(&mut s, ctx);
                    ctx.report(s.cost + m.constant());
                    if super::trace_enabled() {
                        eprintln!(
                            "corridor: {} at width {width}, {:.2} s",
                            s.cost + m.constant(),
                            ctx.elapsed()
                        );
                    }
                }
                None if width >= self.max_width => break,
                None => width = (width * 2).min(self.max_width),
            }
        }
        if super::trace_enabled() {
            eprintln!("corridor: {passes} passes, {gains} gains, last width {width}");
        }
        Ok(outcome(m, &s))
    }
}

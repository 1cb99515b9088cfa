//! `time-window`: jobs of a storage-and-retrieval crane, each released in a time window.
//!
//! Each job picks a load up at one rack slot and sets it down at another. A job must come
//! before another when its window closes before the other's opens, so the precedence is an
//! interval order: transitively closed, and dense when windows are short against the
//! horizon (about 1 − 2w/n of the pairs are ordered). The cost of doing job `j` right after
//! job `i` is the crane's empty move from `i`'s drop-off to `j`'s pick-up plus `j`'s loaded
//! move, both in the Chebyshev metric (the two axes drive at once) with the vertical axis half
//! as fast: asymmetric, with the triangle inequality on the empty moves. Unlike
//! `random-sop`, whose dense precedence is a random DAG over uniform costs, the orders here
//! come in overlapping windows of about `w` jobs, and nearby jobs are cheap to chain.
//!
//! `io` sends a share of the jobs through the input/output station (storage: picked up
//! there; retrieval: set down there), so that a retrieval followed by a storage links for
//! nothing: the zero-cost links and ties of TSPLIB's stacker-crane instances. `loaded=false`
//! leaves the loaded moves out of the costs, as those instances do, and `setup` charges every
//! move between two different slots a fixed time to start and stop (their costs are 0 or at
//! least 10). `windows=exponential` draws window lengths with a long tail, so that a few
//! jobs may go almost anywhere, as a few of theirs do, and `bursts` releases the jobs in
//! bursts, which gives the wide levels of mutually unordered jobs theirs have.

use super::{C_SPEC, sop_shaped};
use crate::error::{Error, Result};
use crate::model::Instance;
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `time-window` parameters.
pub static SPECS: &[ParamSpec] = &[
    super::n_spec("200", super::MAX_N),
    C_SPEC,
    ParamSpec {
        name: "w",
        default: "10",
        kind: ParamKind::float_above(0.0, super::MAX_N as f64),
        help: "mean window length in jobs: releases are uniform over a horizon of n jobs, \
               window lengths uniform in [0, 2w] (0 < w <= n)",
    },
    ParamSpec {
        name: "windows",
        default: "uniform",
        kind: ParamKind::Choice(&["uniform", "exponential"]),
        help: "window lengths: uniform in [0, 2w], or exponential with mean w (a long tail: a \
               few jobs may go almost anywhere, as in TSPLIB's stacker-crane instances)",
    },
    ParamSpec {
        name: "bursts",
        default: "0",
        kind: ParamKind::int(0, super::MAX_N),
        help: "releases come in this many bursts at random times over the horizon, each job \
               released within one job's time after its burst (wide levels of mutually \
               unordered jobs, as in TSPLIB's stacker-crane instances); 0: releases uniform \
               over the horizon",
    },
    ParamSpec {
        name: "io",
        default: "0",
        kind: ParamKind::float(0.0, 1.0),
        help: "share of jobs that pass through the input/output station at the rack's \
               corner: half of them store a load (picked up there), half retrieve one (set \
               down there); a retrieval followed by a storage moves the crane empty for \
               nothing (0 <= io <= 1; 0: every pick-up and drop-off is a random slot)",
    },
    ParamSpec {
        name: "loaded",
        default: "true",
        kind: ParamKind::Bool,
        help: "the cost of a job includes its loaded move (false: only the empty move to its \
               pick-up, as in TSPLIB's stacker-crane instances; the loaded moves add to a \
               sequence the sum over all jobs but the first, so among sequences that start \
               with the same job the order by cost is the same)",
    },
    ParamSpec {
        name: "setup",
        default: "0",
        kind: ParamKind::int(0, 1_000_000),
        help: "time the crane takes to start and stop: a move between two different slots \
               costs this much on top of its travel, a move that stays put nothing (TSPLIB's \
               stacker-crane costs are 0 or at least 10)",
    },
];

/// The input/output station: column 0, level 0.
const STATION: Slot = (0, 0);

/// A rack slot: column and level.
type Slot = (i64, i64);

/// The crane's travel time between two slots: both axes at once, the vertical one half as fast.
fn travel(a: Slot, b: Slot) -> i64 {
    (a.0 - b.0).abs().max(2 * (a.1 - b.1).abs())
}

/// Checks the parameters together (`w` ≤ `n`); the number of cells.
pub fn check(p: &Params) -> Result<u64> {
    let (n, w) = (p.int("n"), p.float("w"));
    if w > n as f64 {
        return Err(Error::Param(format!(
            "time-window: w must lie in (0, n] = (0, {n}], got {w}"
        )));
    }
    Ok(n + 2)
}

/// `time-window`: n crane jobs in a rack `c` columns wide and `c / 4` levels high, windows of
/// mean length `w` jobs; job `i` precedes job `j` when `i`'s window closes before `j`'s opens.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    check(p)?;
    let n = p.int("n") as usize;
    let c = p.int("c");
    let w = p.float("w");
    let io = p.float("io");
    let loaded = p.bool("loaded");
    let exponential = p.word("windows") == "exponential";
    let setup = p.int("setup") as i64;
    // a crane move: nothing when it stays put, else its travel and the start and stop
    let crane_move = |a: Slot, b: Slot| {
        if a == b { 0 } else { travel(a, b) + setup }
    };
    let (cols, levels) = (c as i64, (c as i64 / 4).max(1));
    let bursts = p.int("bursts") as usize;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // burst times, drawn only with bursts, so bursts = 0 keeps the draws of before
    let times: Vec<f64> = (0..bursts)
        .map(|_| rng.random_range(0.0..n as f64))
        .collect();
    let mut jobs: Vec<(f64, f64, Slot, Slot)> = (0..n)
        .map(|_| {
            let open = if bursts > 0 {
                times[rng.random_range(0..bursts)] + rng.random_range(0.0..1.0)
            } else {
                rng.random_range(0.0..n as f64)
            };
            let close = open
                + if exponential {
                    -w * (1.0 - rng.random_range(0.0..1.0f64)).ln()
                } else {
                    rng.random_range(0.0..=2.0 * w)
                };
            // drawn only when the station is used, so io = 0 keeps the draws of before
            let kind = if io > 0.0 {
                rng.random_range(0.0..1.0)
            } else {
                1.0
            };
            let mut pick = (rng.random_range(0..=cols), rng.random_range(0..=levels));
            let mut drop = (rng.random_range(0..=cols), rng.random_range(0..=levels));
            if kind < io / 2.0 {
                pick = STATION;
            } else if kind < io {
                drop = STATION;
            }
            (open, close, pick, drop)
        })
        .collect();
    // cells numbered by release, so the numbering is a schedule
    jobs.sort_by(|a, b| a.0.total_cmp(&b.0));
    // job i precedes exactly the jobs released after its window closes: a suffix of the order
    let mut edges = Vec::new();
    for (i, a) in jobs.iter().enumerate() {
        let first = jobs.partition_point(|b| b.0 <= a.1);
        edges.extend((first..n).map(|j| (i, j)));
    }
    let cost = |u: usize, v: usize| {
        let (_, _, _, drop_u) = jobs[u];
        let (_, _, pick_v, drop_v) = jobs[v];
        let load = if loaded {
            crane_move(pick_v, drop_v)
        } else {
            0
        };
        (crane_move(drop_u, pick_v) + load) as f64
    };
    let mut name = format!("time-window-n{n}-c{c}-w{w}");
    if bursts > 0 {
        name += &format!("-b{bursts}");
    }
    if exponential {
        name += "-exp";
    }
    if io > 0.0 {
        name += &format!("-io{io}");
    }
    if !loaded {
        name += "-empty";
    }
    if setup > 0 {
        name += &format!("-setup{setup}");
    }
    name += &format!("-s{seed}");
    Ok(sop_shaped(name, &vec![1; n], cost, &edges))
}

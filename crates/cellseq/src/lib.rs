//! cellseq: sequencing of CNC machining cells — an open, precedence-constrained, generalized
//! asymmetric TSP (with one mode per cell, TSPLIB's Sequential Ordering Problem) — with file
//! formats, generators, lower bounds, solvers and an independent checker.
//!
//! From a file to a verified, written result:
//!
//! ```no_run
//! use cellseq::prelude::*;
//! use std::path::Path;
//! use std::time::Duration;
//!
//! let inst = cellseq::load(Path::new("instances/tsplib-sop/ESC07.sop"))?;
//! let solved = Solve::new(SolverKind::Auto)
//!     .time_limit(Duration::from_secs(10))
//!     .seed(1)
//!     .lower_bound(true)
//!     .run(&inst)?;
//! println!("cost {} (lower bound {:?})", solved.cost(), solved.lower_bound);
//! solved.save(&inst, Path::new("solution.json"))?;
//! # Ok::<(), cellseq::Error>(())
//! ```
//!
//! And in memory, deterministically (an evaluation budget gives the same result on any
//! machine), with a solver parameter and the independent checker:
//!
//! ```
//! use cellseq::prelude::*;
//!
//! // a TSPLIB SOP instance: node 1 first, node 3 last, arcs 1->2 = 1 and 2->3 = 2
//! let text = "TYPE: SOP\nDIMENSION: 3\nEDGE_WEIGHT_SECTION\n3\n0 1 9\n-1 0 2\n-1 -1 0\nEOF\n";
//! let inst = cellseq::parse("tiny.sop", text, Format::Sop)?;
//! let solved = Solve::new(SolverKind::Ils)
//!     .param("k", 4)
//!     .max_evals(100_000)
//!     .run(&inst)?;
//! assert_eq!(solved.cost(), 3.0);
//! let report = cellseq::check(&inst, &solved.sequence, solved.objective).expect("feasible");
//! assert_eq!(report.cost, 3.0);
//! // a misspelled solver or parameter is an error, never a panic
//! assert!("ilss".parse::<SolverKind>().is_err());
//! assert!(Solve::new(SolverKind::Ils).param("kk", 4).run(&inst).is_err());
//! # Ok::<(), cellseq::Error>(())
//! ```
//!
//! The pieces: [`model`] (instances, cells, modes, sequences), [`formats`] (TSPLIB SOP,
//! PCGLNS, PCGTSP and cellseq JSON; [`load`], [`parse`], [`save_instance`]), [`generate`]
//! (seeded instance families), [`Solve`]/[`Solved`] (running a [`SolverKind`] of the
//! [`registry`]), [`check`] (the independent checker, sharing no code with the solvers' cost
//! model), [`lower_bounds`]. Real machine programs (G-code, SVG, DXF) are the
//! `cellseq-programs` crate; experiment plans, statistics and plots the `cellseq-lab` crate.
//!
//! The engine, the cost model and the solvers' own types are internal; the `internals`
//! feature makes them public for this workspace's benches and tests, with no stability promise.

// No unsafe code in the library. Unit tests may use it only where allowed by name (one helper
// in `files`' tests makes a FIFO through libc), so tests are built with `deny`.
#![cfg_attr(not(test), forbid(unsafe_code))]
#![cfg_attr(test, deny(unsafe_code))]
// Every public item has a doc comment (CI turns this warning into an error).
#![warn(missing_docs)]
// Index loops are the clearest form for the graph and DP code here.
#![allow(clippy::needless_range_loop)]

/// Declares modules that are internal, or public (and hidden from the documentation) with the
/// `internals` feature, for this workspace's benches and tests.
macro_rules! internal {
    ($($module:ident),* $(,)?) => {$(
        #[cfg(feature = "internals")]
        #[doc(hidden)]
        pub mod $module;
        // what only the tests and benches call (through `internals`) is not dead code
        #[cfg(not(feature = "internals"))]
        #[allow(dead_code, unused_imports)]
        mod $module;
    )*};
}

internal!(bound, construct, context, cost, engine, solvers);

pub mod checker;
pub mod clock;
pub mod error;
pub mod files;
pub mod formats;
pub mod generate;
pub mod geom;
pub mod model;
pub mod params;
pub mod precedence;
pub mod solve;
pub mod validate;

/// The solver registry: every [`SolverKind`], what each declares ([`SolverInfo`]), the
/// generated `docs/solvers.md`, and what the `auto` portfolio would run on an instance.
pub mod registry {
    pub use crate::solvers::{
        BUILT_IN_PORTFOLIO, Caps, DEFAULT_SOLVER, Explanation, Features, Needs, SolverInfo,
        SolverKind, explain, find, is_portfolio_file, kind_label, markdown, registry as all,
        validate_portfolio,
    };
    /// Largest portfolio file read, in bytes.
    pub const PORTFOLIO_MAX_BYTES: u64 = crate::solvers::auto::portfolio::MAX_FILE_BYTES;
    /// Largest `beam.stretch` of a portfolio rule (the least is 1).
    pub const PORTFOLIO_MAX_STRETCH: f64 = crate::solvers::auto::portfolio::MAX_STRETCH;
    /// Largest `long.min_evals` of a portfolio rule (the least is 0).
    pub const PORTFOLIO_MAX_LONG_EVALS: f64 = crate::solvers::auto::portfolio::MAX_LONG_EVALS;
}

/// What most programs need, in one `use cellseq::prelude::*;`.
pub mod prelude {
    pub use crate::checker::{Report, Violation, check};
    pub use crate::error::{Error, Result};
    pub use crate::formats::Format;
    pub use crate::model::{Cell, Instance, Mode, Objective, Sequence, Visit};
    pub use crate::solve::{Budget, Observer, Progress, Solve, Solved};
    pub use crate::solvers::SolverKind;
}

pub use bound::{BoundOptions, BoundValue, Bounds, certified_gap_percent};
pub use checker::{Report, Violation, check};
pub use error::{Error, Result};
pub use formats::{Format, load_instance as load, parse_instance as parse, save_instance};
pub use model::{Cell, Instance, Machine, Mode, Objective, Sequence, StepKind, Tool, Visit};
pub use solve::{
    Budget, NoObserver, Observer, Progress, Solve, Solved, Trace, lower_bounds, save_solution,
};
pub use solvers::{SolverInfo, SolverKind};

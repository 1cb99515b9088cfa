//! cellseq: sequencing of CNC machining cells — an open, precedence-constrained, generalized
//! asymmetric TSP — with an independent checker, file formats, generators and solvers.
//!
//! Data flow: a file or generator gives an [`model::Instance`]; [`cost::CostModel`] flattens it
//! for search; a [`solvers::Solver`] returns a [`model::Sequence`]; [`check::check`] verifies it
//! and recomputes the [`check::Report`] from scratch.
//!
//! ```
//! use cellseq::solvers::{self, Budget, NoObserver};
//! use std::collections::BTreeMap;
//!
//! // a TSPLIB SOP instance: node 1 first, node 3 last, arcs 1->2 = 1 and 2->3 = 2
//! let text = "TYPE: SOP\nDIMENSION: 3\nEDGE_WEIGHT_SECTION\n3\n0 1 9\n-1 0 2\n-1 -1 0\nEOF\n";
//! let inst = cellseq::formats::parse_instance("tiny.sop", text, cellseq::formats::Format::Sop)?;
//! let obj = inst.default_objective();
//! let run = solvers::run("exact", &inst, obj, &BTreeMap::new(), 1, Budget::default(), &mut NoObserver)?;
//! assert_eq!(run.report.cost, 3.0);
//! assert!(run.outcome.proven_optimal);
//! # Ok::<(), cellseq::Error>(())
//! ```

// No unsafe code in the library. Unit tests may use it only where allowed by name (one helper
// in `formats::write`'s tests makes a FIFO through libc), so tests are built with `deny`.
#![cfg_attr(not(test), forbid(unsafe_code))]
#![cfg_attr(test, deny(unsafe_code))]
// Every public item has a doc comment (CI turns this warning into an error).
#![warn(missing_docs)]
// Index loops are the clearest form for the graph and DP code here.
#![allow(clippy::needless_range_loop)]

pub mod bound;
pub mod check;
pub mod clock;
pub mod construct;
pub mod cost;
pub mod engine;
pub mod error;
pub mod formats;
pub mod generate;
pub mod geom;
pub mod harness;
pub mod io;
pub mod model;
pub mod params;
pub mod pipeline;
pub mod plot;
pub mod precedence;
pub mod search;
pub mod solvers;
pub mod validate;

pub use check::{Report, Violation, check};
pub use error::{Error, Result};
pub use model::{Cell, Instance, Machine, Mode, Objective, Sequence, StepKind, Tool, Visit};

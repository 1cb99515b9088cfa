//! cellseq: sequencing of CNC machining cells — an open, precedence-constrained, generalized
//! asymmetric TSP — with an independent checker, file formats, generators and solvers.
//!
//! Data flow: a file or generator gives an [`model::Instance`]; [`cost::CostModel`] flattens it
//! for search; a [`solvers::Solver`] returns a [`model::Sequence`]; [`check::check`] verifies it
//! and recomputes the [`check::Report`] from scratch.

pub mod check;
pub mod engine;
pub mod cost;
pub mod error;
pub mod formats;
pub mod generate;
pub mod geom;
pub mod model;
pub mod params;
pub mod precedence;
pub mod solvers;
pub mod validate;

pub use check::{check, Report, Violation};
pub use error::{Error, Result};
pub use model::{Cell, Instance, Machine, Mode, Objective, Sequence, StepKind, Tool, Visit};

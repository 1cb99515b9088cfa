//! cellseq-lab: the research harness of [`cellseq`]: experiment plans, seeded parallel trials with resumable results,
//! statistics, plots and reports.
//!
//! Data flow: [`plan::Plan`] (a validated `experiments/*.toml`) expands into trials;
//! [`run::run_plan`] runs them with rayon and appends one row per finished trial to
//! `results.csv` (plus anytime points to `traces.csv` and a `manifest.json`);
//! [`report::report`] turns a results directory into Markdown/CSV tables and PNG/SVG plots.
//! Everything goes through the solver and generator registries, so new entries just work.

// No unsafe code.
#![forbid(unsafe_code)]
// Every public item has a doc comment (CI turns this warning into an error).
#![warn(missing_docs)]
#![allow(clippy::needless_range_loop)]

pub mod estimate;
pub mod figures;
pub mod hash;
pub mod latex;
pub mod layers;
pub mod manifest;
pub mod paper;
pub mod plan;
pub mod plot;
pub mod provenance;
pub mod report;
pub mod results;
pub mod run;
pub mod stats;

/// The plan of `cellseq demo` (also shipped as `experiments/demo.toml`).
pub const DEMO_PLAN: &str = include_str!("../../../experiments/demo.toml");

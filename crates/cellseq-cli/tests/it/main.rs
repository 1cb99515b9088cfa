//! The integration tests, one binary (each test binary links the whole crate, so one binary
//! builds and links once). Every former `tests/<name>.rs` is a module here; shared helpers
//! (paths of instances and fixtures, the `cellseq` binary, small instances) live in
//! `common.rs`. Run one module with `cargo test --release --test it <module>::`.
//!
//! To add tests: put them in `tests/it/<topic>.rs` (use `crate::common::*` for every path to
//! a repository file, so that no test depends on the working directory), add `mod <topic>;`
//! below, and keep proptest regression files in `tests/proptest-regressions/<topic>.txt`
//! (where proptest looks for a module of this binary). A file that needs a process of its
//! own — a `#[global_allocator]`, a global setting of the process — stays a binary of its own
//! in `tests/` (as `tests/mutations.rs`, whose counting allocator would otherwise account for
//! every test of this binary).

mod common;

mod atsp_free;
mod bad_instances;
mod bounds;
mod cli;
mod conformance;
mod core;
mod docs_solvers;
mod drawing_scale;
mod drawing_semantics;
mod dxf;
mod dxf_arcs;
mod edge;
mod engine_props;
mod figure_fonts;
mod gcode;
mod gcode_reverse;
mod gcode_shopfloor;
mod gcode_touch_off;
mod generated_suite;
mod generators;
mod golden;
mod harness;
mod hostile;
mod insertion;
mod keep_out;
mod pcgtsp;
mod plot;
mod portfolio;
mod props;
mod ranges;
mod reader_regressions;
mod records;
mod report_outputs;
mod rs274;
mod safe_writes;
mod safety_outputs;
mod svg;
mod svg_layers;
mod time_limits;
mod two_level;

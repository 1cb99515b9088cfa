//! Seeded instance generators. The same kind, parameters and seed give the same instance
//! (and the same bytes once saved). Every generated instance records its generator,
//! parameters and seed in its metadata and carries an as-programmed order.
//!
//! To add a generator: write a module with a `SPECS` parameter list and a
//! `generate(&Params, seed) -> Result<Instance>` function, and list it in [`KINDS`].

pub mod cabin;
pub mod casing;
pub mod common;
pub mod families;
pub mod panel;
pub mod toolsel;
pub mod uniform;

use crate::error::{Error, Result};
use crate::model::Instance;
use crate::params::{ParamSpec, Params};
use std::collections::BTreeMap;

/// A generator kind.
pub struct GeneratorInfo {
    /// Name used on the command line.
    pub name: &'static str,
    /// One-line description.
    pub summary: &'static str,
    /// Parameters with defaults.
    pub params: &'static [ParamSpec],
    /// Checks what the parameters' declared ranges cannot (their combination, a tool library
    /// file) without generating anything; about how many cells the instance will have, at
    /// most. [`generate`] calls it first.
    pub check: fn(&Params) -> Result<u64>,
    /// The generator.
    pub generate: fn(&Params, u64) -> Result<Instance>,
}

/// All generator kinds.
pub static KINDS: &[GeneratorInfo] = &[
    GeneratorInfo {
        name: "panel",
        summary: "aircraft integral panel: pockets on a grid, ribs, flange, outer contour, holes (paper 002)",
        params: panel::SPECS,
        check: panel::check,
        generate: panel::generate,
    },
    GeneratorInfo {
        name: "casing",
        summary: "layered casing: annular regions split into fan-shaped sub-regions over 5 layers (paper 004)",
        params: casing::SPECS,
        check: casing::check,
        generate: casing::generate,
    },
    GeneratorInfo {
        name: "cabin",
        summary: "large cabin part: open/closed features, hole groups, several tools (patent 003)",
        params: cabin::SPECS,
        check: cabin::check,
        generate: cabin::generate,
    },
    GeneratorInfo {
        name: "uniform",
        summary: "cells at random in a box (n, modes, tools, precedence density) for scaling studies",
        params: uniform::SPECS,
        check: uniform::check,
        generate: uniform::generate,
    },
    GeneratorInfo {
        name: "random-sop",
        summary: "SOP with asymmetric integer costs uniform in [0, c] and precedence of closure density p % (training family)",
        params: families::matrix::RANDOM_SOP_SPECS,
        check: |p| families::cells_of(p, 2),
        generate: families::matrix::random_sop,
    },
    GeneratorInfo {
        name: "atsp",
        summary: "asymmetric costs without precedence, open path (class amat: uniform; tmat: shortest-path closure)",
        params: families::matrix::ATSP_SPECS,
        check: families::matrix::atsp_check,
        generate: families::matrix::atsp,
    },
    GeneratorInfo {
        name: "symmetric",
        summary: "symmetric integer costs uniform in [0, c], precedence of closure density p % or disjoint pairs (pairs)",
        params: families::matrix::SYMMETRIC_SPECS,
        check: families::matrix::symmetric_check,
        generate: families::matrix::symmetric,
    },
    GeneratorInfo {
        name: "near-symmetric",
        summary: "symmetric costs plus an asymmetric part of up to asym % of c, precedence density p %",
        params: families::matrix::NEAR_SYMMETRIC_SPECS,
        check: |p| families::cells_of(p, 2),
        generate: families::matrix::near_symmetric,
    },
    GeneratorInfo {
        name: "time-window",
        summary: "storage crane jobs in time windows: interval-order precedence (dense when windows are short), asymmetric Chebyshev travel costs",
        params: families::time_window::SPECS,
        check: families::time_window::check,
        generate: families::time_window::generate,
    },
    GeneratorInfo {
        name: "compiler-dag",
        summary: "instruction block: Hamming switching costs of 32-bit words, register/flag/memory dependences (sparse, not closed)",
        params: families::compiler::SPECS,
        check: families::compiler::check,
        generate: families::compiler::generate,
    },
    GeneratorInfo {
        name: "geometric-sparse",
        summary: "CNC part: pockets roughed in layers then finished, holes spot-drilled then drilled; sparse precedence, 10^3-10^5 cells",
        params: families::geometric::GEOMETRIC_SPECS,
        check: |p| families::cells_of(p, 0),
        generate: families::geometric::geometric_sparse,
    },
    GeneratorInfo {
        name: "generalized",
        summary: "matrix instance whose cells have 1..=modes nodes near each other, precedence density p %",
        params: families::geometric::GENERALIZED_SPECS,
        check: families::geometric::generalized_check,
        generate: families::geometric::generalized,
    },
];

/// Checks `KEY=VALUE` parameters of generator `kind` without generating anything: each in its
/// declared range, and their combination ([`GeneratorInfo::check`]). About how many cells
/// the instance would have, at most.
pub fn check(kind: &str, given: &BTreeMap<String, String>) -> Result<u64> {
    let info = find(kind)?;
    let params = Params::new(kind, info.params, given)?;
    (info.check)(&params)
}

/// The generator named `kind`; an unknown name is an error listing the known ones.
pub fn find(kind: &str) -> Result<&'static GeneratorInfo> {
    KINDS.iter().find(|k| k.name == kind).ok_or_else(|| {
        Error::Param(format!(
            "unknown generator '{kind}' (known: {})",
            KINDS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
        ))
    })
}

/// Generates an instance of `kind` from `KEY=VALUE` parameters and a seed: the same seed and
/// parameters give the same instance on any machine. [`KINDS`] lists every kind with its
/// parameters; an unknown kind or parameter is an error listing the known ones.
///
/// ```
/// use std::collections::BTreeMap;
///
/// let params = BTreeMap::from([("rows".to_string(), "2".to_string())]);
/// let a = cellseq::generate::generate("panel", &params, 7)?;
/// let b = cellseq::generate::generate("panel", &params, 7)?;
/// assert_eq!(a, b);
/// assert!(cellseq::generate::generate("nosuch", &params, 7).is_err());
/// # Ok::<(), cellseq::Error>(())
/// ```
pub fn generate(kind: &str, given: &BTreeMap<String, String>, seed: u64) -> Result<Instance> {
    let info = find(kind)?;
    let params = Params::new(kind, info.params, given)?;
    (info.check)(&params)?;
    let mut inst = (info.generate)(&params, seed)?;
    inst.meta.generator = Some(kind.to_string());
    inst.meta.params = params.values().clone();
    inst.meta.seed = Some(seed);
    crate::validate::validate(&inst, &format!("<generated {kind}>"))?;
    Ok(inst)
}

//! Seeded instance generators. The same kind, parameters and seed give the same instance
//! (and the same bytes once saved). Every generated instance records its generator,
//! parameters and seed in its metadata and carries an as-programmed order.
//!
//! To add a generator: write a module with a `SPECS` parameter list and a
//! `generate(&Params, seed) -> Result<Instance>` function, and list it in [`KINDS`].

pub mod cabin;
pub mod casing;
pub mod common;
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
    /// The generator.
    pub generate: fn(&Params, u64) -> Result<Instance>,
}

/// All generator kinds.
pub static KINDS: &[GeneratorInfo] = &[
    GeneratorInfo {
        name: "panel",
        summary: "aircraft integral panel: pockets on a grid, ribs, flange, outer contour, holes (paper 002)",
        params: panel::SPECS,
        generate: panel::generate,
    },
    GeneratorInfo {
        name: "casing",
        summary: "layered casing: annular regions split into fan-shaped sub-regions over 5 layers (paper 004)",
        params: casing::SPECS,
        generate: casing::generate,
    },
    GeneratorInfo {
        name: "cabin",
        summary: "large cabin part: open/closed features, hole groups, several tools (patent 003)",
        params: cabin::SPECS,
        generate: cabin::generate,
    },
    GeneratorInfo {
        name: "uniform",
        summary: "cells at random in a box (n, modes, tools, precedence density) for scaling studies",
        params: uniform::SPECS,
        generate: uniform::generate,
    },
];

/// Generates an instance of `kind` from `KEY=VALUE` parameters and a seed.
pub fn generate(kind: &str, given: &BTreeMap<String, String>, seed: u64) -> Result<Instance> {
    let info = KINDS.iter().find(|k| k.name == kind).ok_or_else(|| {
        Error::Param(format!(
            "unknown generator '{kind}' (known: {})",
            KINDS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
        ))
    })?;
    let params = Params::new(kind, info.params, given)?;
    let mut inst = (info.generate)(&params, seed)?;
    inst.meta.generator = Some(kind.to_string());
    inst.meta.params = params.values().clone();
    inst.meta.seed = Some(seed);
    crate::validate::validate(&inst, &format!("<generated {kind}>"))?;
    Ok(inst)
}

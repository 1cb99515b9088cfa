//! `bound`: lower bounds on the optimum of an instance.

use super::solve::{best_known, load, objective_of};
use anyhow::Result;
use cellseq::{BoundOptions, Solve, SolverKind, certified_gap_percent, lower_bounds};
use clap::Args;
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Args, Debug)]
pub struct BoundArgs {
    /// Instance file.
    file: PathBuf,
    /// Objective: time (default), air, or matrix.
    #[arg(long)]
    objective: Option<String>,
    /// Subgradient iterations of the Lagrangian arborescence bound (0 = skip it).
    #[arg(long, default_value_t = 300, value_parser = super::ranges::iterations)]
    iterations: usize,
    /// Print one JSON object.
    #[arg(long)]
    json: bool,
}

pub fn bound(a: BoundArgs) -> Result<()> {
    let inst = load(&a.file)?;
    let objective = objective_of(&inst, a.objective.as_deref())?;
    let t = Instant::now();
    // a greedy solution sizes the subgradient steps (only needed where the Lagrangian runs)
    let defaults = BoundOptions::default();
    let upper = (inst.n() <= defaults.lagrangian_max_cells && a.iterations > 0)
        .then(|| {
            Solve::new(SolverKind::Greedy)
                .objective(objective)
                .run(&inst)
                .ok()
                .map(|r| r.cost())
        })
        .flatten();
    let opts = BoundOptions {
        lagrangian_iterations: a.iterations,
        upper,
        ..defaults
    };
    let b = lower_bounds(&inst, objective, &opts)?;
    let total = t.elapsed().as_secs_f64();
    let bk = best_known(&a.file).map(|x| x.0);
    if a.json {
        let parts: Vec<_> = b
            .parts
            .iter()
            .map(|p| json!({"name": p.name, "value": p.value, "seconds": p.seconds}))
            .collect();
        say!(
            "{}",
            json!({
                "instance": inst.name,
                "cells": inst.n(),
                "objective": objective.name(),
                "bounds": parts,
                "lower_bound": b.best,
                "best_bound": b.best_name,
                "upper_bound": upper,
                "best_known": bk,
                "certified_gap_percent": upper.and_then(|u| certified_gap_percent(u, b.best)),
                "elapsed_s": total,
            })
        );
    } else {
        say!("instance        {} ({} cells)", inst.name, inst.n());
        say!("objective       {}", objective.name());
        for p in &b.parts {
            say!("{:<15} {}  ({:.3} s)", p.name, fmt(p.value), p.seconds);
        }
        say!("lower bound     {}  ({})", fmt(b.best), b.best_name);
        if let Some(u) = upper {
            say!("greedy          {}", fmt(u));
        }
        if let Some(k) = bk {
            let g = certified_gap_percent(k, b.best).unwrap_or(0.0);
            say!(
                "best known      {}  (bound is {:.3} % below)",
                fmt(k),
                100.0 * g / (100.0 + g)
            );
        }
        say!("elapsed         {total:.3} s");
    }
    Ok(())
}

fn fmt(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{x:.0}")
    } else {
        format!("{x:.3}")
    }
}

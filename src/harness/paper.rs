//! Report sections of paper reproductions: the per-layer table (paper 004, from `layers.csv`)
//! and the tool table with per-solver totals (paper 002, from `instances.csv`). A plan asks for
//! them with `layers = true` / `tools = true` in its `[paper]` section.

use super::results::{InstanceRow, LayerRow, Row, read_lenient};
use super::stats::mean;
use crate::error::Result;
use serde::Serialize;
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

fn fmt(x: f64) -> String {
    if x.is_nan() {
        "–".into()
    } else {
        format!("{x:.2}")
    }
}

/// `100 (base - x) / base` of two sums (the reduction of the means).
fn reduction(base: f64, x: f64) -> f64 {
    if base.abs() > 0.0 {
        100.0 * (base - x) / base
    } else {
        f64::NAN
    }
}

/// One row of `layers_summary.csv`: a solver's means over its feasible trials in one layer
/// (`layer` = "total" for the whole sequence, from `results.csv`).
#[derive(Debug, Clone, Serialize)]
pub struct LayerSummary {
    /// Solver id.
    pub solver: String,
    /// Layer index, or `total`.
    pub layer: String,
    /// Trials averaged.
    pub trials: usize,
    /// Mean path length (mm).
    pub path_length: f64,
    /// Path reduction of the means against the as-given order, %.
    pub path_reduction_pct: f64,
    /// Mean lifts.
    pub lifts: f64,
    /// Mean lifts of the as-given order.
    pub as_given_lifts: f64,
    /// Mean machining time (s).
    pub machining_time: f64,
    /// Machining-time reduction of the means against the as-given order, %.
    pub time_reduction_pct: f64,
}

/// The per-layer section (Markdown) and `layers_summary.csv`; `None` without `layers.csv`.
pub fn layer_section(
    dir: &Path,
    out: &Path,
    rows: &[Row],
    solvers: &[String],
) -> Result<Option<(String, PathBuf)>> {
    let (layers, _) = read_lenient::<LayerRow>(&dir.join("layers.csv"))?;
    if layers.is_empty() {
        return Ok(None);
    }
    let ids: BTreeSet<u32> = layers.iter().map(|l| l.layer).collect();
    let mut table = Vec::new();
    for s in solvers {
        for &layer in &ids {
            let g: Vec<&LayerRow> = layers
                .iter()
                .filter(|l| &l.solver_id == s && l.layer == layer)
                .collect();
            if g.is_empty() {
                continue;
            }
            let f = |h: fn(&LayerRow) -> f64| g.iter().map(|l| h(l)).collect::<Vec<f64>>();
            let path = mean(&f(|l| l.path_length));
            let base_path = mean(&f(|l| l.as_given_path_length.unwrap_or(f64::NAN)));
            let time = mean(&f(|l| l.machining_time));
            let base_time = mean(&f(|l| l.as_given_machining_time.unwrap_or(f64::NAN)));
            table.push(LayerSummary {
                solver: s.clone(),
                layer: layer.to_string(),
                trials: g.len(),
                path_length: path,
                path_reduction_pct: reduction(base_path, path),
                lifts: mean(&f(|l| l.lifts as f64)),
                as_given_lifts: mean(&f(|l| l.as_given_lifts.map_or(f64::NAN, |x| x as f64))),
                machining_time: time,
                time_reduction_pct: reduction(base_time, time),
            });
        }
        // total, from the results of the same (feasible) trials
        let keys: BTreeSet<&str> = layers
            .iter()
            .filter(|l| &l.solver_id == s)
            .map(|l| l.run_key.as_str())
            .collect();
        let g: Vec<&Row> = rows
            .iter()
            .filter(|r| keys.contains(r.run_key.as_str()))
            .collect();
        if g.is_empty() {
            continue;
        }
        let base_lifts: Vec<f64> = g
            .iter()
            .map(|r| {
                layers
                    .iter()
                    .filter(|l| l.run_key == r.run_key)
                    .map(|l| l.as_given_lifts.map_or(f64::NAN, |x| x as f64))
                    .sum()
            })
            .collect();
        let pick = |h: fn(&Row) -> Option<f64>| {
            mean(
                &g.iter()
                    .map(|r| h(r).unwrap_or(f64::NAN))
                    .collect::<Vec<_>>(),
            )
        };
        table.push(LayerSummary {
            solver: s.clone(),
            layer: "total".into(),
            trials: g.len(),
            path_length: pick(|r| r.path_length),
            path_reduction_pct: pick(|r| r.path_reduction_pct),
            lifts: pick(|r| r.lifts.map(|x| x as f64)),
            as_given_lifts: mean(&base_lifts),
            machining_time: pick(|r| r.machining_time),
            time_reduction_pct: pick(|r| r.time_reduction_pct),
        });
    }
    let p = out.join("layers_summary.csv");
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in &table {
        let _ = w.serialize(r);
    }
    crate::formats::write_atomic(&p, &w.into_inner().unwrap_or_default())?;
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Per layer\n\nMeans over each solver's feasible trials (all instances). Each move is \
         charged to the layer of the cell it enters; the total row also holds the final return \
         home. Reductions compare the means with the as-given order's on the same trials' \
         instances (`layers.csv`, `layers_summary.csv`).\n"
    );
    let _ = writeln!(
        md,
        "| solver | layer | trials | path mm | path red. % | lifts | as-given lifts | mach. time s | time red. % |\n|---|---|---|---|---|---|---|---|---|"
    );
    for r in &table {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            r.solver,
            r.layer,
            r.trials,
            fmt(r.path_length),
            fmt(r.path_reduction_pct),
            fmt(r.lifts),
            fmt(r.as_given_lifts),
            fmt(r.machining_time),
            fmt(r.time_reduction_pct)
        );
    }
    let _ = writeln!(md);
    Ok(Some((md, p)))
}

/// The tool section: tools and cells per tool per instance (from `instances.csv`) and each
/// solver's mean reductions and tool changes over all instances.
pub fn tools_section(dir: &Path, rows: &[Row], solvers: &[String]) -> Result<String> {
    let (insts, _) = read_lenient::<InstanceRow>(&dir.join("instances.csv"))?;
    let mut md = String::new();
    let _ = writeln!(md, "## Tools and reduction per solver\n");
    if !insts.is_empty() {
        let _ = writeln!(
            md,
            "| instance | tools | cells per tool | tool-group choice |\n|---|---|---|---|"
        );
        for i in &insts {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                i.instance,
                i.tools,
                i.cells_per_tool,
                if i.comment.is_empty() {
                    "–"
                } else {
                    &i.comment
                }
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "| solver | ok/runs | reduction % | path red. % | time red. % | lifts | tool changes |\n|---|---|---|---|---|---|---|"
    );
    for s in solvers {
        let g: Vec<&Row> = rows.iter().filter(|r| &r.solver_id == s).collect();
        let ok: Vec<&&Row> = g.iter().filter(|r| r.feasible).collect();
        let m =
            |h: fn(&Row) -> Option<f64>| mean(&ok.iter().filter_map(|r| h(r)).collect::<Vec<_>>());
        let _ = writeln!(
            md,
            "| {} | {}/{} | {} | {} | {} | {} | {} |",
            s,
            ok.len(),
            g.len(),
            fmt(m(|r| r.reduction_pct)),
            fmt(m(|r| r.path_reduction_pct)),
            fmt(m(|r| r.time_reduction_pct)),
            fmt(m(|r| r.lifts.map(|x| x as f64))),
            fmt(m(|r| r.tool_changes.map(|x| x as f64)))
        );
    }
    let _ = writeln!(md);
    Ok(md)
}

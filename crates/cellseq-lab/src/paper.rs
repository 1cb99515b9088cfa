//! Report sections of paper reproductions: for paper 004 (`layers = true` in a plan's
//! `[paper]` section) the direction table (the paper's three figures — path, lifts, time — of
//! the as-programmed order against `tabu` and `auto` on every casing of the paper's
//! configuration), the sensitivity table (casings whose generator parameters differ from the
//! defaults: cutting share, link distance, lift time, region order; it explains our magnitudes
//! against the paper's) and the per-layer table (from `layers.csv`); for paper 002
//! (`tools = true`) the tool table with per-solver totals (from `instances.csv`).

use super::results::{InstanceRow, LayerRow, Row, read_lenient};
use super::stats::mean;
use cellseq::error::Result;
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
    let (mut layers, _) = read_lenient::<LayerRow>(&dir.join("layers.csv"))?;
    if layers.is_empty() {
        return Ok(None);
    }
    // the per-layer table is the paper's configuration (sensitivity variants stay out) when
    // the plan has it, else every instance
    let main: BTreeSet<&str> = rows
        .iter()
        .filter(|r| in_figures(r))
        .map(|r| r.run_key.as_str())
        .collect();
    if layers.iter().any(|l| main.contains(l.run_key.as_str())) {
        layers.retain(|l| main.contains(l.run_key.as_str()));
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
    cellseq::files::write_atomic(&p, &w.into_inner().unwrap_or_default())?;
    let mut md = direction_section(rows);
    md.push_str(&sensitivity_section(rows));
    let _ = writeln!(
        md,
        "## Per layer\n\nMeans over each solver's feasible trials (the casings of the paper's \
         configuration: generator defaults). Each move is \
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

/// The generator parameters of a row that differ from the generator's defaults, `k=v, …`
/// (empty for the paper's own configuration or a row without a known generator).
pub fn variant(r: &Row) -> String {
    let Some(kind) = cellseq::generate::KINDS
        .iter()
        .find(|k| k.name == r.generator)
    else {
        return String::new();
    };
    let same = |a: &str, b: &str| match (a.parse::<f64>(), b.parse::<f64>()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    };
    r.gen_params
        .split(';')
        .filter_map(|kv| kv.split_once('='))
        .filter(|(k, v)| {
            kind.params
                .iter()
                .find(|p| p.name == *k)
                .is_some_and(|p| !same(p.default, v))
        })
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Whether a row counts towards a paper's figures: every row except those of generated
/// casings whose parameters differ from the defaults (the sensitivity variants of paper 004,
/// which have a table of their own).
pub fn in_figures(r: &Row) -> bool {
    r.generator != "casing" || variant(r).is_empty()
}

/// Means of one solver's feasible rows on one instance: path, lifts, time, air, cut.
#[derive(Debug, Clone, Copy)]
struct Means {
    path: f64,
    lifts: f64,
    time: f64,
    air: f64,
}

fn means(rows: &[&Row]) -> Option<Means> {
    let ok: Vec<&&Row> = rows.iter().filter(|r| r.feasible).collect();
    if ok.is_empty() {
        return None;
    }
    let m = |h: fn(&Row) -> Option<f64>| {
        mean(
            &ok.iter()
                .map(|r| h(r).unwrap_or(f64::NAN))
                .collect::<Vec<_>>(),
        )
    };
    Some(Means {
        path: m(|r| r.path_length),
        lifts: m(|r| r.lifts.map(|x| x as f64)),
        time: m(|r| r.machining_time),
        air: m(|r| r.air_length),
    })
}

/// The solvers the paper-004 tables compare with the as-programmed order.
const COMPARED: [&str; 2] = ["tabu", "auto"];

/// One instance: its id, the as-given means and the compared solvers' means.
type Entry = (String, Means, Vec<(&'static str, Means)>);

/// Instances in plan order.
type Table = Vec<Entry>;

fn by_instance(rows: &[Row], keep: impl Fn(&Row) -> bool) -> Table {
    let mut names: Vec<&str> = Vec::new();
    for r in rows.iter().filter(|r| r.generator == "casing" && keep(r)) {
        if !names.contains(&r.instance.as_str()) {
            names.push(&r.instance);
        }
    }
    let pick = |inst: &str, solver: &str| {
        let g: Vec<&Row> = rows
            .iter()
            .filter(|r| r.instance == inst && r.solver_id == solver)
            .collect();
        means(&g)
    };
    names
        .into_iter()
        .filter_map(|i| {
            let base = pick(i, "as-given")?;
            let ours = COMPARED
                .iter()
                .filter_map(|s| pick(i, s).map(|m| (*s, m)))
                .collect();
            Some((i.to_string(), base, ours))
        })
        .collect()
}

/// The direction table: per casing of the paper's configuration, the as-programmed order's
/// path, lifts and time against those of `tabu` and `auto`, with whether all three go the
/// paper's way; then the paper's own totals. Empty without casings.
pub fn direction_section(rows: &[Row]) -> String {
    let table = by_instance(rows, in_figures);
    let mut md = String::new();
    if table.is_empty() {
        return md;
    }
    let _ = writeln!(
        md,
        "## Paper 004: direction on every casing\n\nThe paper's three figures per casing \
         (means over replicates): total tool-path length (cutting + moves between regions, at \
         depth or lifted), cutter lifts, machining time, against the as-programmed order \
         (layer by layer, regions in numbering order, each from its advance point). \
         `direction` is `yes` when the solver has fewer lifts, a shorter path and less time \
         than the as-programmed order.\n"
    );
    let _ = writeln!(
        md,
        "| casing | solver | path mm | path red. % | lifts | as-given lifts | mach. time s | time red. % | direction |\n|---|---|---|---|---|---|---|---|---|"
    );
    let mut held: Vec<(&str, usize, usize)> = COMPARED.iter().map(|s| (*s, 0, 0)).collect();
    for (inst, base, ours) in &table {
        let _ = writeln!(
            md,
            "| {inst} | as-given | {} | 0.00 | {} | {} | {} | 0.00 | – |",
            fmt(base.path),
            fmt(base.lifts),
            fmt(base.lifts),
            fmt(base.time)
        );
        for (s, m) in ours {
            let ok = m.lifts < base.lifts && m.path < base.path && m.time < base.time;
            if let Some(h) = held.iter_mut().find(|h| h.0 == *s) {
                h.1 += ok as usize;
                h.2 += 1;
            }
            let _ = writeln!(
                md,
                "| {inst} | {s} | {} | {} | {} | {} | {} | {} | {} |",
                fmt(m.path),
                fmt(reduction(base.path, m.path)),
                fmt(m.lifts),
                fmt(base.lifts),
                fmt(m.time),
                fmt(reduction(base.time, m.time)),
                if ok { "yes" } else { "**no**" }
            );
        }
    }
    let _ = writeln!(
        md,
        "| paper 004 (one casing, 5 layers) | tabu | – | 16.7 | 26 | – | 4946 (1:22:26) | 21.62 | yes |\n"
    );
    for (s, ok, n) in held {
        if n > 0 {
            let _ = writeln!(md, "Direction holds for `{s}` on {ok} of {n} casings.\n");
        }
    }
    md
}

/// The sensitivity table: per generator configuration (the defaults first, then each variant
/// of the plan), the shares that bound the reductions and the reductions `tabu` and `auto`
/// reach, means over the configuration's casings.
pub fn sensitivity_section(rows: &[Row]) -> String {
    let all = by_instance(rows, |_| true);
    if all.is_empty() {
        return String::new();
    }
    let variant_of = |inst: &str| {
        rows.iter()
            .find(|r| r.instance == inst)
            .map(variant)
            .unwrap_or_default()
    };
    let mut configs: Vec<String> = Vec::new();
    for (inst, _, _) in &all {
        let v = variant_of(inst);
        if !configs.contains(&v) {
            configs.push(v);
        }
    }
    configs.sort_by_key(|v| !v.is_empty());
    let mut md = String::new();
    let _ = writeln!(
        md,
        "## Paper 004: sensitivity\n\nEach row: casings of one generator configuration (seeds \
         as in the plan), means over casings. `cut share` = cutting length / as-programmed \
         path; `air share` = the rest, the most any order can take off the path; `air red.` = \
         the part of it `auto` removes, so path red. ≈ air share × air red.; `cut time share` \
         = cutting time / as-programmed time, so no order can cut the time by more than \
         100 − that. Lifts: as-given → tabu / auto.\n"
    );
    let _ = writeln!(
        md,
        "| configuration | casings | cut share % | air share % | air red. % (auto) | cut time share % | lifts as-given → tabu / auto | path red. % tabu / auto | time red. % tabu / auto |\n|---|---|---|---|---|---|---|---|---|"
    );
    for v in &configs {
        let group: Vec<&Entry> = all.iter().filter(|(i, _, _)| &variant_of(i) == v).collect();
        let avg = |f: &dyn Fn(&Entry) -> f64| mean(&group.iter().map(|g| f(g)).collect::<Vec<_>>());
        let solver = |g: &Entry, s: &str| g.2.iter().find(|(n, _)| *n == s).map(|x| x.1);
        let cut_rate = cut_rate_of(rows, v);
        let cut_share = avg(&|g| 100.0 * (g.1.path - g.1.air) / g.1.path);
        let air_share = avg(&|g| 100.0 * g.1.air / g.1.path);
        let air_red = avg(&|g| solver(g, "auto").map_or(f64::NAN, |m| reduction(g.1.air, m.air)));
        let cut_time = avg(&|g| 100.0 * (g.1.path - g.1.air) * cut_rate / g.1.time);
        let lifts = |s: &str| avg(&|g| solver(g, s).map_or(f64::NAN, |m| m.lifts));
        let red = |s: &str, f: fn(&Means) -> f64| {
            avg(&|g| solver(g, s).map_or(f64::NAN, |m| reduction(f(&g.1), f(&m))))
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} → {} / {} | {} / {} | {} / {} |",
            if v.is_empty() {
                "defaults (the paper's)"
            } else {
                v
            },
            group.len(),
            fmt(cut_share),
            fmt(air_share),
            fmt(air_red),
            fmt(cut_time),
            fmt(avg(&|g| g.1.lifts)),
            fmt(lifts("tabu")),
            fmt(lifts("auto")),
            fmt(red("tabu", |m| m.path)),
            fmt(red("auto", |m| m.path)),
            fmt(red("tabu", |m| m.time)),
            fmt(red("auto", |m| m.time)),
        );
    }
    let _ = writeln!(
        md,
        "\nReading it against the paper: a path reduction of 16.7 % needs at least 16.7 % of the \
         as-programmed path to be non-cutting (our `air share`). With the paper's two feeds \
         alone (cutting 500, non-cutting 2000 mm/min, nothing per lift) every millimetre saved \
         is non-cutting and costs a quarter of a cutting one, so the time reduction is always \
         smaller than the path reduction; the paper's 21.62 % time against 16.7 % path needs \
         time that the path does not carry (per lift, plunge feed, acceleration: the \
         `lift_time` rows). See notes/paper004.md.\n"
    );
    md
}

/// Seconds per mm of cutting of a configuration's casings: 60 / `cut_feed` (500 mm/min unless
/// the configuration sets it).
fn cut_rate_of(rows: &[Row], v: &str) -> f64 {
    let feed = rows
        .iter()
        .find(|r| r.generator == "casing" && variant(r) == v)
        .and_then(|r| {
            r.gen_params
                .split(';')
                .find_map(|kv| kv.strip_prefix("cut_feed="))
                .and_then(|x| x.parse::<f64>().ok())
        })
        .unwrap_or(500.0);
    60.0 / feed
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(instance: &str, params: &str, solver: &str, path: f64, lifts: u64, time: f64) -> Row {
        Row {
            run_key: format!("{instance}/{solver}"),
            instance: instance.into(),
            generator: "casing".into(),
            gen_params: params.into(),
            solver: solver.into(),
            solver_id: solver.into(),
            feasible: true,
            path_length: Some(path),
            air_length: Some(path - 900.0),
            lifts: Some(lifts),
            machining_time: Some(time),
            ..Row::default()
        }
    }

    #[test]
    fn direction_and_sensitivity_tables() {
        let rows = vec![
            row(
                "casing-s1",
                "link_distance=60;regions=3",
                "as-given",
                1000.0,
                10,
                200.0,
            ),
            row(
                "casing-s1",
                "link_distance=60;regions=3",
                "tabu",
                950.0,
                8,
                190.0,
            ),
            // more lifts than the as-programmed order: not the paper's direction
            row(
                "casing-s1",
                "link_distance=60;regions=3",
                "auto",
                940.0,
                11,
                189.0,
            ),
            row(
                "casing-x-s1",
                "link_distance=0;regions=3",
                "as-given",
                1000.0,
                10,
                200.0,
            ),
            row(
                "casing-x-s1",
                "link_distance=0;regions=3",
                "tabu",
                990.0,
                10,
                199.0,
            ),
        ];
        assert!(in_figures(&rows[0]) && !in_figures(&rows[3]));
        assert_eq!(variant(&rows[3]), "link_distance=0");
        let d = direction_section(&rows);
        assert!(
            d.contains("| casing-s1 | tabu | 950.00 | 5.00 | 8.00 | 10.00 | 190.00 | 5.00 | yes |"),
            "{d}"
        );
        assert!(
            d.contains("| casing-s1 | auto |") && d.contains("| **no** |"),
            "{d}"
        );
        assert!(!d.contains("casing-x-s1"), "{d}");
        assert!(
            d.contains("`tabu` on 1 of 1") && d.contains("`auto` on 0 of 1"),
            "{d}"
        );
        let s = sensitivity_section(&rows);
        // defaults first: cut 900 of 1000 mm; air 100 mm of which tabu... auto removes 60 %
        assert!(
            s.contains("| defaults (the paper's) | 1 | 90.00 | 10.00 | 60.00 |"),
            "{s}"
        );
        // cutting time 900 mm at 500 mm/min = 108 s of 200 s
        assert!(
            s.contains("| 54.00 | 10.00 → 8.00 / 11.00 | 5.00 / 6.00 | 5.00 / 5.50 |"),
            "{s}"
        );
        assert!(s.contains("| link_distance=0 | 1 |"), "{s}");
    }
}

//! The report's figures, computed from `results.csv` and `traces.csv` and drawn by
//! [`crate::plot::charts`]: box plots of the reduction and the lifts, runtime against size, fixed-budget
//! convergence (the best few solvers on one plot, every solver in a panel of its own with its
//! quartile band), the ECDF of the time to reach the best found within 1 %, and the Dolan–Moré
//! performance profile on a log₂ τ axis with a detail near τ = 1.
//!
//! Under evaluation budgets (every trial's `budget` names `evals=`) the anytime figures count
//! evaluations on their x axis, so they are the same on any machine; otherwise wall seconds,
//! labelled so. Solver `i` of the results (in order of first appearance) has look `i` in every
//! figure.

use super::results::{Row, TraceRow};
use super::stats::{mean, quantile};
use crate::plot::charts::{self, Axis, Curve, CurveSpec, Scale};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Relative gap to the best found cost that counts as reaching the target (ECDF).
pub const TARGET_GAP: f64 = 0.01;
/// Solvers on the single-plot convergence figure (the reference is added when not among them).
pub const CONVERGENCE_TOP: usize = 8;
/// Points of the fixed-budget grid.
const GRID: usize = 80;

/// What the anytime figures count on their x axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// Counted evaluations (evaluation budgets).
    Evaluations,
    /// Wall seconds (time budgets).
    Seconds,
}

impl Clock {
    /// Evaluations when every trial ran under an evaluation budget, else seconds.
    pub fn of_rows(rows: &[Row]) -> Clock {
        if !rows.is_empty() && rows.iter().all(|r| r.budget.contains("evals=")) {
            Clock::Evaluations
        } else {
            Clock::Seconds
        }
    }
    fn trace(self, t: &TraceRow) -> f64 {
        match self {
            // a point found before the first counted evaluation sits at 1 on the log axis
            Clock::Evaluations => (t.evaluations as f64).max(1.0),
            Clock::Seconds => t.wall_elapsed_s.max(1e-7),
        }
    }
    fn row(self, r: &Row) -> f64 {
        match self {
            Clock::Evaluations => (r.evaluations as f64).max(1.0),
            Clock::Seconds => r.wall_elapsed_s.max(1e-7),
        }
    }
    /// The x-axis title.
    pub fn label(self) -> &'static str {
        match self {
            Clock::Evaluations => "evaluations",
            Clock::Seconds => "wall seconds (machine-dependent)",
        }
    }
}

/// The data of the figures.
pub struct FigureData<'a> {
    /// Trials.
    pub rows: &'a [Row],
    /// Anytime points.
    pub traces: &'a [TraceRow],
    /// Instances in order of first appearance.
    pub instances: &'a [String],
    /// Solvers in order of first appearance (look `i` for solver `i`).
    pub solvers: &'a [String],
    /// The reference solver, always on the convergence figure.
    pub reference: &'a str,
}

type Files = std::result::Result<Vec<PathBuf>, String>;

/// Writes every figure into `dir` (PNG, SVG and PDF); returns the files in order.
pub fn write_figures(dir: &Path, d: &FigureData) -> Files {
    let clock = Clock::of_rows(d.rows);
    let mut out = Vec::new();
    out.extend(boxes(dir, d)?);
    out.extend(scaling(dir, d)?);
    out.extend(convergence(dir, d, clock)?);
    out.extend(ecdf(dir, d, clock)?);
    out.extend(profile(dir, d)?);
    Ok(out)
}

fn feasible<'a>(d: &'a FigureData, s: &'a str) -> impl Iterator<Item = &'a Row> + 'a {
    d.rows
        .iter()
        .filter(move |r| r.solver_id == s && r.feasible)
}

fn boxes(dir: &Path, d: &FigureData) -> Files {
    let groups = |f: fn(&Row) -> Option<f64>| -> Vec<charts::Group> {
        d.solvers
            .iter()
            .enumerate()
            .map(|(i, s)| (s.clone(), i, feasible(d, s).filter_map(f).collect()))
            .collect()
    };
    let mut out = charts::box_plot(
        dir,
        "reduction_box",
        "Reduction of the objective against the as-given order, per trial",
        "reduction %",
        &groups(|r| r.reduction_pct),
    )?;
    let lifts = groups(|r| r.lifts.map(|x| x as f64));
    if lifts.iter().any(|g| !g.2.is_empty()) {
        out.extend(charts::box_plot(
            dir,
            "lifts_box",
            "Lifts per trial (geometric instances)",
            "lifts",
            &lifts,
        )?);
    }
    Ok(out)
}

fn scaling(dir: &Path, d: &FigureData) -> Files {
    let data: Vec<charts::ScalingSeries> = d
        .solvers
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let pts = d
                .instances
                .iter()
                .filter_map(|inst| {
                    // feasible trials only: a quick refusal says nothing about scaling
                    let g: Vec<&Row> = feasible(d, s).filter(|r| &r.instance == inst).collect();
                    let t: Vec<f64> = g.iter().map(|r| r.wall_elapsed_s).collect();
                    (!t.is_empty()).then(|| (g[0].n as f64, mean(&t)))
                })
                .collect();
            (s.clone(), i, pts)
        })
        .collect();
    charts::scaling_plot(dir, &data)
}

/// Best found cost per instance over every feasible trial.
fn best_found<'a>(d: &'a FigureData) -> BTreeMap<&'a str, f64> {
    let mut b: BTreeMap<&str, f64> = BTreeMap::new();
    for r in d.rows.iter().filter(|r| r.feasible) {
        if let Some(c) = r.cost {
            let e = b.entry(r.instance.as_str()).or_insert(f64::INFINITY);
            *e = e.min(c);
        }
    }
    b
}

/// A trial's row and its anytime points (clock, best so far).
type Run<'a> = (&'a Row, Vec<(f64, f64)>);

/// Each trial's anytime points, in clock order, with the trial's row.
fn runs<'a>(d: &'a FigureData, clock: Clock) -> BTreeMap<&'a str, Run<'a>> {
    let mut m: BTreeMap<&str, Run> = d
        .rows
        .iter()
        .map(|r| (r.run_key.as_str(), (r, Vec::new())))
        .collect();
    for t in d.traces {
        if let Some(e) = m.get_mut(t.run_key.as_str()) {
            e.1.push((clock.trace(t), t.best));
        }
    }
    for e in m.values_mut() {
        e.1.sort_by(|a, b| a.0.total_cmp(&b.0));
        // a feasible trial's final cost is reached at its end even if no trace point says so
        if e.0.feasible
            && let Some(c) = e.0.cost
            && e.1.last().is_none_or(|p| p.1 > c)
        {
            e.1.push((clock.row(e.0), c));
        }
    }
    m
}

/// Median and quartiles of gaps where runs without a solution yet count as +∞; `None` when
/// fewer than half of the runs have one.
fn gap_quartiles(mut g: Vec<f64>) -> Option<(f64, f64, f64)> {
    let n = g.len();
    let finite = g.iter().filter(|x| x.is_finite()).count();
    if n == 0 || 2 * finite < n + 1 {
        return None;
    }
    for x in &mut g {
        if !x.is_finite() {
            *x = f64::MAX;
        }
    }
    // an upper quartile among the runs without a solution is unbounded
    let unbounded = |q: f64| if q > 1e300 { f64::INFINITY } else { q };
    Some((
        quantile(&g, 0.5),
        quantile(&g, 0.25),
        unbounded(quantile(&g, 0.75)),
    ))
}

fn convergence(dir: &Path, d: &FigureData, clock: Clock) -> Files {
    let bf = best_found(d);
    let runs = runs(d, clock);
    let lo = runs
        .values()
        .filter_map(|r| r.1.first().map(|p| p.0))
        .fold(f64::INFINITY, f64::min);
    let hi = d.rows.iter().map(|r| clock.row(r)).fold(0.0, f64::max);
    if !lo.is_finite() || hi <= 0.0 {
        return Ok(Vec::new());
    }
    let hi = hi.max(lo * 10.0);
    let grid: Vec<f64> = (0..GRID)
        .map(|k| lo * (hi / lo).powf(k as f64 / (GRID - 1) as f64))
        .collect();
    let mut curves = Vec::new();
    for (i, s) in d.solvers.iter().enumerate() {
        let mine: Vec<&Run> = runs.values().filter(|r| &r.0.solver_id == s).collect();
        let pts = grid
            .iter()
            .filter_map(|&t| {
                let gaps = mine
                    .iter()
                    .map(|(r, tr)| {
                        let b = tr
                            .iter()
                            .take_while(|p| p.0 <= t)
                            .map(|p| p.1)
                            .fold(f64::INFINITY, f64::min);
                        match bf.get(r.instance.as_str()) {
                            Some(&f) if b.is_finite() && f.abs() > 0.0 => 100.0 * (b - f) / f.abs(),
                            Some(&f) if b.is_finite() && f == 0.0 => 0.0,
                            _ => f64::INFINITY,
                        }
                    })
                    .collect();
                gap_quartiles(gaps).map(|(m, q1, q3)| (t, m.max(0.0), q1.max(0.0), q3))
            })
            .collect();
        curves.push(Curve {
            name: s.clone(),
            look: i,
            points: pts,
        });
    }
    // rank: final median gap, then the mean of the median over the grid (+∞ where undefined)
    let score = |c: &Curve| {
        let last = c
            .points
            .last()
            .filter(|p| p.0 >= grid[GRID - 1] * 0.999)
            .map_or(f64::INFINITY, |p| p.1);
        let area = grid
            .iter()
            .map(|&t| {
                c.points
                    .iter()
                    .take_while(|p| p.0 <= t)
                    .last()
                    .map_or(1e300, |p| p.1.min(1e300))
            })
            .sum::<f64>();
        (last, area)
    };
    let mut order: Vec<usize> = (0..curves.len()).collect();
    order.sort_by(|&a, &b| {
        let (sa, sb) = (score(&curves[a]), score(&curves[b]));
        sa.0.total_cmp(&sb.0).then(sa.1.total_cmp(&sb.1))
    });
    let mut top: Vec<Curve> = order
        .iter()
        .take(CONVERGENCE_TOP)
        .map(|&k| curves[k].clone())
        .collect();
    let reference = curves.iter().find(|c| c.name == d.reference).cloned();
    if let Some(r) = &reference
        && !top.iter().any(|c| c.name == r.name)
    {
        top.push(r.clone());
    }
    for c in &mut top {
        if c.name == d.reference {
            c.name = format!("{} (reference)", c.name);
        }
    }
    let y = Axis::linear("median gap to best found, %").with_scale(Scale::LogWithZero);
    let x = Axis::log(clock.label());
    let n = curves.len();
    let title = if n > top.len() {
        format!(
            "Convergence: median gap to the best found, best {} of {n} solvers (all: convergence_facets)",
            top.len().min(CONVERGENCE_TOP)
        )
    } else {
        "Convergence: median gap to the best found".to_string()
    };
    let spec = CurveSpec {
        title,
        x: x.clone(),
        y: y.clone(),
        step: true,
    };
    let mut out = charts::curve_plot(dir, "convergence", &spec, &top)?;
    let ordered: Vec<Curve> = order.iter().map(|&k| curves[k].clone()).collect();
    let facets = CurveSpec {
        title: format!(
            "Median gap to the best found, % (band: quartiles) against {}; grey dashed: {}",
            clock.label(),
            d.reference
        ),
        x,
        y,
        step: true,
    };
    out.extend(charts::facet_plot(
        dir,
        "convergence_facets",
        &facets,
        &ordered,
        reference.as_ref(),
    )?);
    Ok(out)
}

fn ecdf(dir: &Path, d: &FigureData, clock: Clock) -> Files {
    let bf = best_found(d);
    let runs = runs(d, clock);
    let end = d.rows.iter().map(|r| clock.row(r)).fold(0.0, f64::max);
    let mut curves = Vec::new();
    for (i, s) in d.solvers.iter().enumerate() {
        let mine: Vec<_> = runs.values().filter(|r| &r.0.solver_id == s).collect();
        let mut hits: Vec<f64> = mine
            .iter()
            .filter_map(|(r, tr)| {
                let f = *bf.get(r.instance.as_str())?;
                let target = f + TARGET_GAP * f.abs();
                tr.iter().find(|p| p.1 <= target).map(|p| p.0)
            })
            .collect();
        hits.sort_by(f64::total_cmp);
        let total = mine.len().max(1) as f64;
        // the curve rises from 0 at the first hit
        let points = hits
            .first()
            .map(|&t| (t, 0.0, 0.0, 0.0))
            .into_iter()
            .chain(hits.iter().enumerate().map(|(k, &t)| {
                let y = (k + 1) as f64 / total;
                (t, y, y, y)
            }))
            .collect::<Vec<_>>();
        // ... and holds its final value to the end of the longest trial
        let mut points = points;
        if let Some(&(t, y, _, _)) = points.last()
            && end > t
        {
            points.push((end, y, y, y));
        }
        curves.push(Curve {
            name: format!("{s} ({}/{})", hits.len(), mine.len()),
            look: i,
            points,
        });
    }
    let spec = CurveSpec {
        title: format!(
            "ECDF of the {} to reach the best found within {} % (legend: runs that did)",
            if clock == Clock::Evaluations {
                "evaluations"
            } else {
                "time"
            },
            TARGET_GAP * 100.0
        ),
        x: Axis::log(clock.label()),
        y: Axis::linear("fraction of runs").with_range(0.0, 1.0),
        step: true,
    };
    charts::curve_plot(dir, "ecdf_time_to_target", &spec, &curves)
}

/// Performance ratios per solver over (instance, replicate) problems (+∞ where it failed).
fn ratios(d: &FigureData) -> Vec<Vec<f64>> {
    let mut problems: BTreeMap<(&str, u32), BTreeMap<&str, f64>> = BTreeMap::new();
    for r in d.rows {
        let c = if r.feasible {
            r.cost.unwrap_or(f64::INFINITY)
        } else {
            f64::INFINITY
        };
        problems
            .entry((r.instance.as_str(), r.replicate))
            .or_default()
            .insert(r.solver_id.as_str(), c);
    }
    let mut out = vec![Vec::new(); d.solvers.len()];
    for costs in problems.values() {
        let best = costs.values().copied().fold(f64::INFINITY, f64::min);
        for (i, s) in d.solvers.iter().enumerate() {
            let c = costs.get(s.as_str()).copied().unwrap_or(f64::INFINITY);
            out[i].push(if best > 0.0 && best.is_finite() {
                c / best
            } else if c == best && c.is_finite() {
                1.0
            } else {
                f64::INFINITY
            });
        }
    }
    out
}

fn profile(dir: &Path, d: &FigureData) -> Files {
    let rs = ratios(d);
    let finite: Vec<f64> = rs
        .iter()
        .flatten()
        .copied()
        .filter(|r| r.is_finite())
        .collect();
    let tau_max = finite.iter().copied().fold(1.0, f64::max).max(1.001);
    let problems = rs.first().map_or(0, Vec::len);
    // a solver's profile as a step function of x = f(τ) from τ = 1 to τ_max
    let curves = |f: &dyn Fn(f64) -> f64, with_share: bool| -> Vec<Curve> {
        d.solvers
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let mut r: Vec<f64> = rs[i].iter().copied().filter(|x| x.is_finite()).collect();
                r.sort_by(f64::total_cmp);
                let n = rs[i].len().max(1) as f64;
                let at1 = r.iter().filter(|&&x| x <= 1.0 + 1e-12).count();
                let mut pts = vec![(f(1.0), at1 as f64 / n, 0.0, 0.0)];
                for (k, &x) in r.iter().enumerate() {
                    if x > 1.0 + 1e-12 {
                        let y = (k + 1) as f64 / n;
                        pts.push((f(x), y, y, y));
                    }
                }
                let last = pts.last().map_or(0.0, |p| p.1);
                pts.push((f(tau_max), last, last, last));
                let name = if with_share {
                    format!("{s} (best on {:.0} %)", 100.0 * at1 as f64 / n)
                } else {
                    s.clone()
                };
                Curve {
                    name,
                    look: i,
                    points: pts,
                }
            })
            .collect()
    };
    let spec = CurveSpec {
        title: format!(
            "Performance profile (Dolan–Moré) over {problems} problems (instance × replicate)"
        ),
        x: Axis::linear("log₂ τ   (τ = cost / best cost on the problem)")
            .with_range(0.0, tau_max.log2()),
        y: Axis::linear("fraction of problems with ratio ≤ τ").with_range(0.0, 1.0),
        step: true,
    };
    let mut out = charts::curve_plot(
        dir,
        "performance_profile",
        &spec,
        &curves(&|t: f64| t.log2(), true),
    )?;
    // the detail near τ = 1, where close solvers part: up to the median ratio above 1
    let above: Vec<f64> = finite
        .iter()
        .copied()
        .filter(|&r| r > 1.0 + 1e-12)
        .collect();
    if !above.is_empty() {
        let edge = quantile(&above, 0.5).max(1.0005).min(tau_max);
        let detail = CurveSpec {
            title: format!(
                "Performance profile, detail for τ ≤ {edge:.4} (half of the ratios above 1 are below it)"
            ),
            x: Axis::linear("τ = cost / best cost on the problem").with_range(1.0, edge),
            y: Axis::linear("fraction of problems with ratio ≤ τ").with_range(0.0, 1.0),
            step: true,
        };
        out.extend(charts::curve_plot(
            dir,
            "performance_profile_detail",
            &detail,
            &curves(&|t: f64| t, true),
        )?);
    }
    Ok(out)
}

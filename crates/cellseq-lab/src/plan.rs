//! Experiment plans (`experiments/*.toml`): parsing, validation and expansion into trials.
//!
//! A plan lists instances (files, globs, or generator specs with parameter grids), solvers with
//! parameters (a list value is a grid), replicates, a budget, an objective and a reference
//! solver. [`Plan::load`] / [`Plan::parse`] validate everything that can be validated without
//! running: unknown solvers, generators or parameters, malformed values, missing files, globs
//! that match nothing, empty grids, duplicate ids and a reference that is not in the plan.
//!
//! Hostile or mistaken plans are refused before anything runs: the `name` must be a name (it
//! becomes the directory `results/<name>`), file patterns stay inside the plan's directory tree
//! and are capped ([`files`]), and the number of trials is capped ([`Limits`]), counted without
//! listing them, so `check` and `run` refuse the same plans.

pub mod files;

use super::hash::{hex, stable_hash, trial_seed};
use cellseq::SolverKind;
use cellseq::error::{Error, Result};
use cellseq::generate::KINDS;
use cellseq::model::Objective;
use cellseq::params::{FloatRange, IntRange, ParamKind, ParamSpec, Params};
use cellseq::registry as solvers;
use serde::Deserialize;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Default cap on the trials of a plan (plan key `max_trials`, flag `--max-trials`).
pub const DEFAULT_MAX_TRIALS: u64 = 100_000;

/// What `max_trials` (and `--max-trials`, `--shards`) may be: a plan's trials are listed in
/// memory, about 0.6 KB each with their result rows, so 10⁷ trials take about 6 GB.
pub const MAX_TRIALS: IntRange = IntRange::new(1, 10_000_000);

/// What `max_files` (and `--max-files`) may be: directory entries one pattern may visit.
pub const MAX_FILES: IntRange = IntRange::new(1, 100_000_000);

/// What `budget.seconds` may be: a time limit in seconds ([`cellseq::solve::MAX_SECONDS`]).
pub const SECONDS: FloatRange = FloatRange::above(0.0, cellseq::solve::MAX_SECONDS);

/// What `budget.calibration_units` may be; times the machine's calibration it must also be
/// a time limit in [`SECONDS`].
pub const CALIBRATION_UNITS: FloatRange = FloatRange::above(0.0, 1e9);

/// What `budget.evaluations` may be.
pub const EVALUATIONS: IntRange = IntRange::new(1, u64::MAX);

/// What `replicates` may be (the trial cap bounds it too).
pub const REPLICATES: IntRange = IntRange::new(1, u32::MAX as u64);

/// What a `[max_cells]` entry may be: cells of the largest instance the solver runs on.
pub const MAX_CELLS: IntRange = IntRange::new(1, u32::MAX as u64);

/// The numbers a plan holds with their ranges (for `cellseq limits` and docs/bad-input.md);
/// solver and generator parameters have their own declared ranges.
pub static NUMBERS: &[ParamSpec] = &[
    ParamSpec {
        name: "budget.seconds",
        default: "",
        kind: ParamKind::Float(SECONDS),
        help: "wall-clock seconds per trial; longer limits (over 11 days) are refused rather than overflowing a clock",
    },
    ParamSpec {
        name: "budget.evaluations",
        default: "",
        kind: ParamKind::Int(EVALUATIONS),
        help: "evaluations per trial (deterministic)",
    },
    ParamSpec {
        name: "budget.calibration_units",
        default: "",
        kind: ParamKind::Float(CALIBRATION_UNITS),
        help: "multiples of this machine's calibration kernel; the product must also lie in budget.seconds's range (checked by check and run on the machine)",
    },
    ParamSpec {
        name: "replicates",
        default: "1",
        kind: ParamKind::Int(REPLICATES),
        help: "runs per instance and solver configuration (the trial cap bounds it too)",
    },
    ParamSpec {
        name: "seed",
        default: "1",
        kind: ParamKind::Int(IntRange::new(0, u64::MAX)),
        help: "master seed of every trial seed",
    },
    ParamSpec {
        name: "max_trials",
        default: "100000",
        kind: ParamKind::Int(MAX_TRIALS),
        help: "trials the plan may have (also --max-trials); they are listed in memory, about 0.6 KB each",
    },
    ParamSpec {
        name: "max_files",
        default: "100000",
        kind: ParamKind::Int(MAX_FILES),
        help: "directory entries one file pattern may visit (also --max-files)",
    },
    ParamSpec {
        name: "max_cells.SOLVER",
        default: "",
        kind: ParamKind::Int(MAX_CELLS),
        help: "the solver runs only on instances of at most this many cells; its other trials are recorded as out of range",
    },
    ParamSpec {
        name: "instances.seeds",
        default: "1",
        kind: ParamKind::Int(IntRange::new(0, u64::MAX)),
        help: "generator seeds (a list; default [1])",
    },
    ParamSpec {
        name: "paper.figures.value",
        default: "",
        kind: ParamKind::Text,
        help: "a published figure printed beside ours: any finite number (NaN and inf are refused)",
    },
];

/// Caps a plan must stay within. Each is taken from the command line when given there, else
/// from the plan's own key, else the default.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Limits {
    /// Cap on instances × solver configurations × replicates (default [`DEFAULT_MAX_TRIALS`]).
    pub max_trials: Option<u64>,
    /// Cap on the directory entries one file pattern may visit (default
    /// [`files::DEFAULT_MAX_FILES`]).
    pub max_files: Option<u64>,
}

/// The plan file as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanFile {
    /// Campaign name.
    pub name: String,
    /// Master seed of every trial seed.
    #[serde(default = "one")]
    pub seed: u64,
    /// Independent runs per (instance, solver).
    #[serde(default = "one_u32")]
    pub replicates: u32,
    /// `time`, `air` or `matrix`; the instance's default when absent.
    #[serde(default)]
    pub objective: Option<String>,
    /// Solver id every other solver is tested against (default: the first solver).
    #[serde(default)]
    pub reference: Option<String>,
    /// Work limit of each trial.
    pub budget: BudgetSpec,
    /// Instance sources.
    pub instances: Vec<InstanceSpec>,
    /// Solvers.
    pub solvers: Vec<SolverSpec>,
    /// Published figures to print beside ours.
    #[serde(default)]
    pub paper: Option<Paper>,
    /// Raises (or lowers) the cap on the number of trials.
    #[serde(default)]
    pub max_trials: Option<u64>,
    /// Raises (or lowers) the cap on the directory entries one file pattern may visit.
    #[serde(default)]
    pub max_files: Option<u64>,
    /// Per solver name: the largest instance (cells) it runs on; its trials on larger
    /// instances are not run and are recorded as out of range (`[max_cells] exact = 16`).
    #[serde(default)]
    pub max_cells: BTreeMap<String, u64>,
}

fn one() -> u64 {
    1
}
fn one_u32() -> u32 {
    1
}

/// A trial budget: any combination of limits; at least one must be set.
#[derive(Debug, Clone, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BudgetSpec {
    /// Wall-clock seconds.
    #[serde(default)]
    pub seconds: Option<f64>,
    /// Counted evaluations (deterministic).
    #[serde(default)]
    pub evaluations: Option<u64>,
    /// Multiples of the machine calibration unit (seconds of the calibration kernel).
    #[serde(default)]
    pub calibration_units: Option<f64>,
}

impl BudgetSpec {
    /// The budget as written in the `budget` column (no machine-dependent numbers).
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        if let Some(e) = self.evaluations {
            parts.push(format!("evals={e}"));
        }
        if let Some(s) = self.seconds {
            parts.push(format!("seconds={s}"));
        }
        if let Some(c) = self.calibration_units {
            parts.push(format!("calib={c}"));
        }
        parts.join(";")
    }
}

/// One instance source: `files` (paths or globs, relative to the plan file) or a generator.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InstanceSpec {
    /// Files or glob patterns.
    #[serde(default)]
    pub files: Vec<String>,
    /// Generator kind.
    #[serde(default)]
    pub generator: Option<String>,
    /// Generator seeds (default `[1]`).
    #[serde(default)]
    pub seeds: Option<Vec<u64>>,
    /// Generator parameters; a list is a grid axis.
    #[serde(default)]
    pub grid: BTreeMap<String, toml::Value>,
}

/// One solver entry; `name = "*"` means every registered solver with default parameters.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Registry name, or `*`.
    pub name: String,
    /// Parameters; a list is a grid axis.
    #[serde(default)]
    pub params: BTreeMap<String, toml::Value>,
}

/// Published results to print beside ours.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Paper {
    /// Citation.
    pub source: String,
    /// The figures (may be empty: the source is then only cited).
    #[serde(default)]
    pub figures: Vec<Figure>,
    /// Add the per-layer table (path length, lifts, machining time per layer, from `layers.csv`).
    #[serde(default)]
    pub layers: bool,
    /// Add the tool table (tools chosen and cells per tool, from `instances.csv`).
    #[serde(default)]
    pub tools: bool,
}

/// One published figure and the metric of ours it corresponds to.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Figure {
    /// Human label.
    pub label: String,
    /// One of [`FIGURE_METRICS`].
    pub metric: String,
    /// The paper's value.
    pub value: f64,
    /// Solver id the metric is taken from (default: the best solver by mean reduction).
    #[serde(default)]
    pub solver: Option<String>,
}

/// Metrics a paper figure can be compared with (means over the solver's feasible trials).
pub const FIGURE_METRICS: &[&str] = &[
    "reduction_pct",
    "air_reduction_pct",
    "path_reduction_pct",
    "time_reduction_pct",
    "lifts",
    "tool_changes",
    "machining_time",
    "air_length",
];

/// Where an instance comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum Source {
    /// An instance file.
    File(PathBuf),
    /// A generator call.
    Generated {
        /// Generator kind.
        kind: String,
        /// Parameters.
        params: BTreeMap<String, String>,
        /// Seed.
        seed: u64,
    },
}

/// An instance of the campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct InstanceRef {
    /// Unique id (file stem, or generator, grid values and seed).
    pub id: String,
    /// Source.
    pub source: Source,
}

/// A solver configuration of the campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct SolverRef {
    /// Unique id: the name, with the given parameters in brackets.
    pub id: String,
    /// Registry name.
    pub name: String,
    /// Given parameters (defaults are filled in by the solver).
    pub params: BTreeMap<String, String>,
}

/// One run: an instance, a solver configuration and a replicate.
#[derive(Debug, Clone, PartialEq)]
pub struct Trial {
    /// Position in plan order.
    pub index: usize,
    /// Index into [`Plan::instances`].
    pub instance: usize,
    /// Index into [`Plan::solvers`].
    pub solver: usize,
    /// Replicate number (0-based).
    pub replicate: u32,
    /// Derived seed.
    pub seed: u64,
    /// Idempotency key.
    pub key: String,
}

/// A validated, expanded plan.
#[derive(Debug, Clone)]
pub struct Plan {
    /// The plan file as errors name it.
    pub path: String,
    /// The file contents, parsed.
    pub file: PlanFile,
    /// The plan text (stored in the manifest).
    pub text: String,
    /// Hash of the plan text.
    pub hash: String,
    /// Instances in plan order.
    pub instances: Vec<InstanceRef>,
    /// Solver configurations in plan order.
    pub solvers: Vec<SolverRef>,
    /// Objective, when the plan fixes one.
    pub objective: Option<Objective>,
    /// Reference solver id.
    pub reference: String,
}

/// Checks that a plan `name` is a plain name, usable as one directory name under `results/`:
/// not empty, at most 100 characters, no `/`, `\\`, `:` or control characters, not starting with
/// `.` (so neither `.`, `..` nor a hidden name).
pub fn check_name(name: &str) -> std::result::Result<(), String> {
    let why = if name.trim().is_empty() {
        "is empty"
    } else if name.chars().count() > 100 {
        "is longer than 100 characters"
    } else if name.contains(['/', '\\']) {
        "holds a path separator ('/' or '\\')"
    } else if name.contains(':') {
        "holds ':'"
    } else if name.chars().any(char::is_control) {
        "holds a control character"
    } else if name.starts_with('.') {
        "starts with '.'"
    } else if name != name.trim() {
        "starts or ends with white space"
    } else {
        return Ok(());
    };
    Err(format!(
        "plan name {name:?} {why}; the name becomes the directory results/<name>, so it must be \
         a plain name such as \"sop-quick\""
    ))
}

/// Expands `{k: v or [v...]}` into the cartesian product, in key order then value order.
fn expand_grid(
    file: &str,
    what: &str,
    grid: &BTreeMap<String, toml::Value>,
    cap: u64,
) -> Result<Vec<BTreeMap<String, String>>> {
    let points = grid.values().try_fold(1u64, |acc, v| match v {
        toml::Value::Array(a) => acc.checked_mul(a.len().max(1) as u64),
        _ => Some(acc),
    });
    if points.is_none_or(|p| p > cap) {
        return Err(Error::invalid(
            file,
            format!(
                "{what}: the grid has more than {cap} points (the trial cap); shrink it, or \
                 raise the cap with the plan key max_trials or the --max-trials flag"
            ),
        ));
    }
    let mut out = vec![BTreeMap::new()];
    for (k, v) in grid {
        let values: Vec<String> = match v {
            toml::Value::Array(a) => {
                if a.is_empty() {
                    return Err(Error::invalid(
                        file,
                        format!("{what}: parameter '{k}' has an empty grid"),
                    ));
                }
                a.iter()
                    .map(|x| {
                        cellseq::params::toml_text(x).ok_or_else(|| {
                            Error::invalid(
                                file,
                                format!("{what}: parameter '{k}' has a non-scalar value"),
                            )
                        })
                    })
                    .collect::<Result<_>>()?
            }
            other => vec![cellseq::params::toml_text(other).ok_or_else(|| {
                Error::invalid(
                    file,
                    format!("{what}: parameter '{k}' has a non-scalar value"),
                )
            })?],
        };
        let mut next = Vec::with_capacity(out.len() * values.len());
        for base in &out {
            for v in &values {
                let mut m = base.clone();
                m.insert(k.clone(), v.clone());
                next.push(m);
            }
        }
        out = next;
    }
    Ok(out)
}

fn params_suffix(p: &BTreeMap<String, String>) -> String {
    p.iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(",")
}

/// A budget sets at least one limit, and each lies in its range ([`SECONDS`],
/// [`CALIBRATION_UNITS`], [`EVALUATIONS`]).
fn check_budget(b: &BudgetSpec) -> std::result::Result<(), String> {
    if b.seconds.is_none() && b.evaluations.is_none() && b.calibration_units.is_none() {
        return Err("budget: set seconds, evaluations or calibration_units".into());
    }
    if let Some(x) = b.seconds {
        SECONDS.check("budget.seconds", x)?;
    }
    if let Some(x) = b.calibration_units {
        CALIBRATION_UNITS.check("budget.calibration_units", x)?;
    }
    if let Some(x) = b.evaluations {
        EVALUATIONS.check("budget.evaluations", x)?;
    }
    Ok(())
}

/// A trial's time limit in seconds under budget `b` on a machine whose calibration kernel
/// takes `calib_s` seconds: `seconds`, or `calibration_units` × `calib_s`, whichever is
/// shorter; an error when the product leaves (0, [`cellseq::solve::MAX_SECONDS`]].
pub fn trial_seconds(b: &BudgetSpec, calib_s: f64) -> std::result::Result<Option<f64>, String> {
    let mut limit = b.seconds;
    if let Some(c) = b.calibration_units {
        let s = SECONDS
            .check(
                &format!(
                    "budget.calibration_units x this machine's calibration ({c} x {calib_s:.4} s)"
                ),
                c * calib_s,
            )
            .map_err(|e| format!("{e}; lower calibration_units"))?;
        limit = Some(limit.map_or(s, |x: f64| x.min(s)));
    }
    Ok(limit)
}

/// The plan's instances in order (files matched by each pattern, or every generator parameter
/// combination × seed), every id once; `caps` = (trial cap, directory entries per pattern).
fn plan_instances(
    file: &str,
    specs: &[InstanceSpec],
    base: &Path,
    caps: (u64, u64),
) -> Result<Vec<InstanceRef>> {
    let bad = |m: String| Error::invalid(file, m);
    if specs.is_empty() {
        return Err(bad("no [[instances]]".into()));
    }
    let mut instances = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let what = format!("instances[{i}]");
        match (&spec.generator, spec.files.is_empty()) {
            (Some(_), false) => {
                return Err(bad(format!(
                    "{what}: give either files or generator, not both"
                )));
            }
            (None, true) => return Err(bad(format!("{what}: give files or a generator"))),
            (None, false) => {
                if spec.seeds.is_some() || !spec.grid.is_empty() {
                    return Err(bad(format!(
                        "{what}: seeds and grid apply to generators only"
                    )));
                }
                file_instances(file, &what, &spec.files, base, caps, &mut instances)?;
            }
            (Some(kind), true) => {
                generated_instances(file, &what, kind, spec, caps.0, &mut instances)?;
            }
        }
    }
    let mut seen = BTreeSet::new();
    for inst in &instances {
        if !seen.insert(inst.id.clone()) {
            return Err(bad(format!("instance id '{}' occurs twice", inst.id)));
        }
    }
    Ok(instances)
}

/// The files matched by each of `patterns` (relative to `base`), appended to `out`.
fn file_instances(
    file: &str,
    what: &str,
    patterns: &[String],
    base: &Path,
    (max_trials, max_files): (u64, u64),
    out: &mut Vec<InstanceRef>,
) -> Result<()> {
    let bad = |m: String| Error::invalid(file, m);
    for pat in patterns {
        let full_s = base.join(pat).display().to_string();
        let found = files::expand(base, pat, max_files).map_err(|e| bad(format!("{what}: {e}")))?;
        if found.is_empty() {
            return Err(bad(format!("{what}: '{pat}' matches no file ({full_s})")));
        }
        if (out.len() + found.len()) as u64 > max_trials {
            return Err(bad(format!(
                "{what}: more than {max_trials} instances (the trial cap); \
                 raise it with the plan key max_trials or --max-trials"
            )));
        }
        for p in found {
            out.push(InstanceRef {
                id: cellseq::formats::stem_name(&p),
                source: Source::File(p),
            });
        }
    }
    Ok(())
}

/// Generated instances of at most this many cells are generated and validated when the plan
/// is read (by `check` as by `run`); larger ones have their parameters checked only.
pub const BUILD_AT_CHECK: u64 = 1000;

/// A grid point as errors name it: `n=60,tools=3`, or `default parameters`.
pub fn grid_point(params: &BTreeMap<String, String>) -> String {
    if params.is_empty() {
        "default parameters".to_string()
    } else {
        params_suffix(params)
    }
}

/// Generator `kind` at every parameter combination of the spec's grid × its seeds, appended to
/// `out`.
fn generated_instances(
    file: &str,
    what: &str,
    kind: &String,
    spec: &InstanceSpec,
    max_trials: u64,
    out: &mut Vec<InstanceRef>,
) -> Result<()> {
    let bad = |m: String| Error::invalid(file, m);
    let info = KINDS.iter().find(|k| k.name == kind).ok_or_else(|| {
        bad(format!(
            "{what}: unknown generator '{kind}' (known: {})",
            KINDS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
        ))
    })?;
    let seeds = spec.seeds.clone().unwrap_or_else(|| vec![1]);
    if seeds.is_empty() {
        return Err(bad(format!("{what}: empty seeds list")));
    }
    for params in expand_grid(file, what, &spec.grid, max_trials)? {
        let point = format!("{what} (generator {kind}, {})", grid_point(&params));
        Params::new(kind, info.params, &params).map_err(|e| bad(format!("{point}: {e}")))?;
        // the parameters together, without generating; tiny instances are generated and
        // validated too, so `check` refuses what `run` would fail on
        let cells =
            cellseq::generate::check(kind, &params).map_err(|e| bad(format!("{point}: {e}")))?;
        if cells <= BUILD_AT_CHECK {
            for &seed in &seeds {
                cellseq::generate::generate(kind, &params, seed)
                    .map_err(|e| bad(format!("{point}, seed {seed}: {e}")))?;
            }
        }
        for &seed in &seeds {
            let mut id = kind.clone();
            for (k, v) in &params {
                id.push_str(&format!("-{k}{v}"));
            }
            id.push_str(&format!("-s{seed}"));
            out.push(InstanceRef {
                id,
                source: Source::Generated {
                    kind: kind.clone(),
                    params: params.clone(),
                    seed,
                },
            });
        }
    }
    Ok(())
}

/// The plan's solver configurations in order (`*` = every registered solver; a parameter grid
/// = one configuration per combination), every id once.
/// An `auto` portfolio file given by a relative path is read from the plan's directory
/// `base`, like the plan's instance patterns.
fn plan_solvers(
    file: &str,
    specs: &[SolverSpec],
    base: &Path,
    max_trials: u64,
) -> Result<Vec<SolverRef>> {
    let bad = |m: String| Error::invalid(file, m);
    if specs.is_empty() {
        return Err(bad("no [[solvers]]".into()));
    }
    let mut solvers_out = Vec::new();
    for (i, spec) in specs.iter().enumerate() {
        let what = format!("solvers[{i}]");
        if spec.name == "*" {
            if !spec.params.is_empty() {
                return Err(bad(format!("{what}: '*' takes no parameters")));
            }
            for info in solvers::all() {
                solvers_out.push(SolverRef {
                    id: info.name.to_string(),
                    name: info.name.to_string(),
                    params: BTreeMap::new(),
                });
            }
            continue;
        }
        let info = solvers::find(&spec.name).map_err(|e| bad(format!("{what}: {e}")))?;
        for mut params in expand_grid(file, &what, &spec.params, max_trials)? {
            // the id keeps the parameters as written, so seeds do not depend on where the
            // plan lies
            let id = if params.is_empty() {
                info.name.to_string()
            } else {
                format!("{}[{}]", info.name, params_suffix(&params))
            };
            if info.name == SolverKind::Auto.name()
                && let Some(p) = params.get_mut("portfolio")
                && p != solvers::BUILT_IN_PORTFOLIO
                && Path::new(p.as_str()).is_relative()
            {
                *p = base.join(p.as_str()).to_string_lossy().into_owned();
            }
            // building the solver validates what its parameters mean (an `auto` plan or
            // portfolio file)
            info.check_params(&params)
                .map_err(|e| bad(format!("{what}: {e}")))?;
            solvers_out.push(SolverRef {
                id,
                name: info.name.to_string(),
                params,
            });
        }
    }
    let mut seen = BTreeSet::new();
    solvers_out.retain(|s| seen.insert(s.id.clone()));
    Ok(solvers_out)
}

/// Every `[max_cells]` entry names a solver of the plan and lies in [`MAX_CELLS`].
fn check_max_cells(
    m: &BTreeMap<String, u64>,
    solvers: &[SolverRef],
) -> std::result::Result<(), String> {
    for (name, &v) in m {
        if !solvers.iter().any(|s| &s.name == name) {
            return Err(format!(
                "max_cells.{name}: '{name}' is not a solver of the plan ({})",
                solvers
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<BTreeSet<_>>()
                    .into_iter()
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        MAX_CELLS.check(&format!("max_cells.{name}"), v)?;
    }
    Ok(())
}

/// Every paper figure names a known metric and, if any, a solver of the plan.
fn check_paper(p: &Paper, solvers: &[SolverRef]) -> std::result::Result<(), String> {
    for f in &p.figures {
        if !f.value.is_finite() {
            return Err(format!(
                "paper figure '{}': value must be a finite number, got {}",
                f.label, f.value
            ));
        }
        if !FIGURE_METRICS.contains(&f.metric.as_str()) {
            return Err(format!(
                "paper figure '{}': unknown metric '{}' (known: {})",
                f.label,
                f.metric,
                FIGURE_METRICS.join(", ")
            ));
        }
        if let Some(s) = &f.solver
            && !solvers.iter().any(|x| &x.id == s)
        {
            return Err(format!(
                "paper figure '{}': solver '{s}' is not in the plan",
                f.label
            ));
        }
    }
    Ok(())
}

impl Plan {
    /// Reads and validates a plan file; relative paths are resolved against its directory.
    pub fn load(path: &Path) -> Result<Plan> {
        Plan::load_with(path, Limits::default())
    }

    /// [`Plan::load`] with caps given on the command line.
    pub fn load_with(path: &Path, limits: Limits) -> Result<Plan> {
        let text = cellseq::files::read_text(path)?;
        let base = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        Plan::parse_with(&path.display().to_string(), &text, &base, limits)
    }

    /// Parses and validates plan text. `file` names the plan in errors.
    pub fn parse(file: &str, text: &str, base: &Path) -> Result<Plan> {
        Plan::parse_with(file, text, base, Limits::default())
    }

    /// [`Plan::parse`] with caps given on the command line.
    pub fn parse_with(file: &str, text: &str, base: &Path, limits: Limits) -> Result<Plan> {
        let pf: PlanFile = toml::from_str(text).map_err(|e| Error::invalid(file, e.to_string()))?;
        let bad = |m: String| Error::invalid(file, m);
        check_name(&pf.name).map_err(bad)?;
        for (key, v) in [
            ("max_trials", pf.max_trials),
            ("--max-trials", limits.max_trials),
        ] {
            if let Some(v) = v {
                MAX_TRIALS.check(key, v).map_err(bad)?;
            }
        }
        for (key, v) in [
            ("max_files", pf.max_files),
            ("--max-files", limits.max_files),
        ] {
            if let Some(v) = v {
                MAX_FILES.check(key, v).map_err(bad)?;
            }
        }
        let max_trials = limits
            .max_trials
            .or(pf.max_trials)
            .unwrap_or(DEFAULT_MAX_TRIALS);
        let max_files = limits
            .max_files
            .or(pf.max_files)
            .unwrap_or(files::DEFAULT_MAX_FILES);
        if pf.replicates == 0 {
            return Err(bad("replicates must be at least 1".into()));
        }
        check_budget(&pf.budget).map_err(bad)?;
        let objective = match &pf.objective {
            None => None,
            Some(s) => Some(Objective::parse(s).ok_or_else(|| {
                bad(format!(
                    "unknown objective '{s}' (known: time, air, matrix)"
                ))
            })?),
        };
        let caps = (max_trials, max_files);
        let instances = plan_instances(file, &pf.instances, base, caps)?;
        let solvers_out = plan_solvers(file, &pf.solvers, base, max_trials)?;
        let reference = match &pf.reference {
            Some(r) => {
                if !solvers_out.iter().any(|s| &s.id == r) {
                    return Err(bad(format!(
                        "reference solver '{r}' is not among the plan's solvers ({})",
                        solvers_out
                            .iter()
                            .map(|s| s.id.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    )));
                }
                r.clone()
            }
            None => solvers_out[0].id.clone(),
        };
        if let Some(p) = &pf.paper {
            check_paper(p, &solvers_out).map_err(bad)?;
        }
        let trials = (instances.len() as u64)
            .checked_mul(solvers_out.len() as u64)
            .and_then(|x| x.checked_mul(u64::from(pf.replicates)));
        if trials.is_none_or(|t| t > max_trials) {
            return Err(bad(format!(
                "{} instances x {} solvers x {} replicates = {} trials, more than the cap of \
                 {max_trials}; shrink the plan, or raise the cap with the plan key max_trials \
                 or the --max-trials flag",
                instances.len(),
                solvers_out.len(),
                pf.replicates,
                trials.map_or_else(|| "too many".to_string(), |t| t.to_string()),
            )));
        }
        check_max_cells(&pf.max_cells, &solvers_out).map_err(bad)?;
        Ok(Plan {
            path: file.to_string(),
            hash: hex(stable_hash(&[text.as_bytes()])),
            text: text.to_string(),
            file: pf,
            instances,
            solvers: solvers_out,
            objective,
            reference,
        })
    }

    /// The largest instance (cells) solver `name` runs on, when the plan's `[max_cells]`
    /// says.
    pub fn max_cells(&self, name: &str) -> Option<u64> {
        self.file.max_cells.get(name).copied()
    }

    /// The number of trials, counted without listing them (at most the plan's trial cap).
    pub fn trial_count(&self) -> u64 {
        self.instances.len() as u64 * self.solvers.len() as u64 * u64::from(self.file.replicates)
    }

    /// Every trial in plan order: instance-major, then solver, then replicate.
    pub fn trials(&self) -> Vec<Trial> {
        let mut out = Vec::new();
        let budget = self.file.budget.label();
        let objective = self.objective.map(|o| o.name()).unwrap_or("default");
        for (ii, inst) in self.instances.iter().enumerate() {
            for (si, s) in self.solvers.iter().enumerate() {
                for r in 0..self.file.replicates {
                    let seed = trial_seed(self.file.seed, &inst.id, &s.id, r);
                    let key = hex(stable_hash(&[
                        inst.id.as_bytes(),
                        source_text(&inst.source).as_bytes(),
                        s.id.as_bytes(),
                        &r.to_le_bytes(),
                        &seed.to_le_bytes(),
                        budget.as_bytes(),
                        objective.as_bytes(),
                    ]));
                    out.push(Trial {
                        index: out.len(),
                        instance: ii,
                        solver: si,
                        replicate: r,
                        seed,
                        key,
                    });
                }
            }
        }
        out
    }
}

fn source_text(s: &Source) -> String {
    match s {
        Source::File(p) => format!("file:{}", p.display()),
        Source::Generated { kind, params, seed } => {
            format!("gen:{kind}:{}:{seed}", params_suffix(params))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(t: &str) -> Result<Plan> {
        Plan::parse("plan.toml", t, Path::new("."))
    }

    const OK: &str = r#"
name = "t"
replicates = 2
[budget]
evaluations = 1000
[[instances]]
generator = "uniform"
seeds = [1, 2]
grid = { n = [5, 8], tools = 2 }
[[solvers]]
name = "greedy"
[[solvers]]
name = "as-given"
"#;

    #[test]
    fn expands_grid_and_trials() {
        let p = parse(OK).unwrap();
        assert_eq!(p.instances.len(), 4);
        assert_eq!(p.instances[0].id, "uniform-n5-tools2-s1");
        assert_eq!(p.solvers.len(), 2);
        assert_eq!(p.reference, "greedy");
        let t = p.trials();
        assert_eq!(t.len(), 16);
        let keys: BTreeSet<_> = t.iter().map(|x| x.key.clone()).collect();
        assert_eq!(keys.len(), 16);
    }

    #[test]
    fn rejects_bad_plans() {
        let cases = [
            (OK.replace("\"greedy\"", "\"nope\""), "unknown solver"),
            (OK.replace("n = [5, 8]", "n = []"), "empty grid"),
            (OK.replace("tools = 2", "toolz = 2"), "no parameter 'toolz'"),
            (OK.replace("generator = \"uniform\"", "generator = \"x\""), "unknown generator"),
            (OK.replace("evaluations = 1000", ""), "budget"),
            (OK.replace("replicates = 2", "replicates = 2\nreference = \"sa\""), "reference solver"),
            (
                OK.replace("[[instances]]\ngenerator = \"uniform\"\nseeds = [1, 2]\ngrid = { n = [5, 8], tools = 2 }", "[[instances]]\nfiles = [\"nowhere/*.sop\"]"),
                "matches no file",
            ),
        ];
        for (text, want) in cases {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains(want), "{e} should mention {want}");
            assert!(e.starts_with("plan.toml"), "{e}");
        }
    }

    #[test]
    fn plan_names_are_names_not_paths() {
        for bad in [
            "../../x", "/tmp/x", "a/b", "a\\b", "", "  ", ".", "..", ".hidden", "a\nb", "c:x", " x",
        ] {
            let text = OK.replace("name = \"t\"", &format!("name = {bad:?}"));
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains("plan name"), "{bad:?}: {e}");
            assert!(e.starts_with("plan.toml"), "{e}");
        }
        for good in ["sop-quick", "paper casing", "run_2", "ünïcode"] {
            let text = OK.replace("name = \"t\"", &format!("name = {good:?}"));
            assert!(parse(&text).is_ok(), "{good:?} refused");
        }
    }

    #[test]
    fn a_million_replicates_are_refused_without_listing_trials() {
        let text = OK.replace("replicates = 2", "replicates = 1000000");
        let e = parse(&text).unwrap_err().to_string();
        assert!(
            e.contains("8000000 trials") && e.contains("max_trials"),
            "{e}"
        );
        let text = OK.replace("replicates = 2", "replicates = 4294967295");
        assert!(parse(&text).is_err());
        // the cap can be raised by the plan or by the caller, and the count is arithmetic
        let raised = OK.replace(
            "replicates = 2",
            "replicates = 1000000\nmax_trials = 8000000",
        );
        let p = parse(&raised).unwrap();
        assert_eq!(p.trial_count(), 8_000_000);
        let limits = Limits {
            max_trials: Some(8_000_000),
            max_files: None,
        };
        let text = OK.replace("replicates = 2", "replicates = 1000000");
        let p = Plan::parse_with("plan.toml", &text, Path::new("."), limits).unwrap();
        assert_eq!(p.trial_count(), 8_000_000);
        // a lowered cap refuses a small plan
        let low = OK.replace("replicates = 2", "replicates = 2\nmax_trials = 15");
        assert!(parse(&low).unwrap_err().to_string().contains("16 trials"));
    }

    #[test]
    fn huge_grids_are_refused_before_expansion() {
        let big: Vec<String> = (1..=1000).map(|i| i.to_string()).collect();
        let axis = format!("[{}]", big.join(","));
        let text = OK.replace(
            "grid = { n = [5, 8], tools = 2 }",
            &format!("grid = {{ n = {axis}, seed_offset = {axis}, x = {axis} }}"),
        );
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("grid has more than"), "{e}");
    }

    #[test]
    fn file_patterns_outside_the_plan_tree_are_refused() {
        let text = OK.replace(
            "[[instances]]\ngenerator = \"uniform\"\nseeds = [1, 2]\ngrid = { n = [5, 8], tools = 2 }",
            "[[instances]]\nfiles = [\"../../**/*.sop\"]",
        );
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("absolute pattern"), "{e}");
        let text = OK.replace(
            "[[instances]]\ngenerator = \"uniform\"\nseeds = [1, 2]\ngrid = { n = [5, 8], tools = 2 }",
            "[[instances]]\nfiles = [\"/**/*\"]",
        );
        let e = parse(&text).unwrap_err().to_string();
        assert!(e.contains("more than 100000"), "{e}");
    }

    #[test]
    fn star_means_all_registered() {
        let p = parse(&OK.replace("name = \"greedy\"", "name = \"*\"")).unwrap();
        assert_eq!(p.solvers.len(), solvers::all().len());
    }
}

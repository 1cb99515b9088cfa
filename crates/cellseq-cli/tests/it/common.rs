//! Helpers shared by the integration tests: where the repository's files are (every fixture
//! path is built here, from `CARGO_MANIFEST_DIR`, so no test depends on the working directory),
//! the `cellseq` binary, and small instances built in code.
#![allow(dead_code)]

use cellseq::formats::load_instance;
use cellseq::geom::Point3;
use cellseq::model::{Cell, Instance, Machine, Mode, Objective, Tool, Visit};
use cellseq::solvers::{self, Budget, NoObserver, RunResult};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The `cellseq` binary built for these tests.
pub const BIN: &str = env!("CARGO_BIN_EXE_cellseq");

/// A command running the `cellseq` binary (working directory: the caller's).
pub fn cellseq() -> Command {
    Command::new(BIN)
}

/// Runs the `cellseq` binary with `args` and waits for it.
pub fn run(args: &[&str]) -> Output {
    cellseq().args(args).output().unwrap()
}

/// A command's standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// True when `text` holds a non-finite number as a word: `NaN`, `inf`, `-inf`, `Infinity`.
pub fn has_non_finite(text: &str) -> bool {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .any(|w| {
            matches!(
                w,
                "NaN" | "nan" | "inf" | "Inf" | "INF" | "Infinity" | "infinity"
            )
        })
}

/// Writes `text` to `dir/name` and returns the path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// A one-solver plan (greedy on a 6-cell generated instance, 1000 evaluations) named `name`.
pub fn tiny_plan(name: &str) -> String {
    format!(
        r#"
name = "{name}"
[budget]
evaluations = 1000
[[instances]]
generator = "uniform"
grid = {{ n = 6 }}
[[solvers]]
name = "greedy"
"#
    )
}

/// Runs registry solver `name` through `solvers::run` with default parameters, seed 1, no
/// budget limit and no observer.
pub fn solve(name: &str, inst: &Instance, obj: Objective) -> cellseq::Result<RunResult> {
    solve_with(name, inst, obj, &BTreeMap::new(), Budget::default())
}

/// [`solve`] with parameters and a budget.
pub fn solve_with(
    name: &str,
    inst: &Instance,
    obj: Objective,
    params: &BTreeMap<String, String>,
    budget: Budget,
) -> cellseq::Result<RunResult> {
    solvers::run(name, inst, obj, params, 1, budget, &mut NoObserver)
}

/// The repository root.
pub fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// Path of a file shipped in `instances/`, e.g. `instance_path("tsplib-sop/ESC07.sop")`.
pub fn instance_path(rel: &str) -> PathBuf {
    root().join("instances").join(rel)
}

/// An instance shipped in `instances/`, loaded (panics with the path when it does not load).
pub fn load(rel: &str) -> Instance {
    let p = instance_path(rel);
    load_instance(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A TSPLIB SOP instance by name, e.g. `sop("ESC07")`.
pub fn sop(name: &str) -> Instance {
    load(&format!("tsplib-sop/{name}.sop"))
}

/// Path of a file under `tests/fixtures/`, e.g. `fixture_path("gcode/mill.ngc")`.
pub fn fixture_path(rel: &str) -> PathBuf {
    root().join("tests/fixtures").join(rel)
}

/// The text of a file under `tests/fixtures/`.
pub fn fixture_text(rel: &str) -> String {
    let p = fixture_path(rel);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// A small geometric instance: `n` cells on a line, two tools, optional precedence chain.
pub fn line_instance(n: usize, reversible: bool) -> Instance {
    let cells = (0..n)
        .map(|i| {
            let x = (i * 37 % 11) as f64 * 10.0;
            let y = (i * 17 % 7) as f64 * 10.0;
            let e = Point3::new(x, y, -1.0);
            let f = Point3::new(x + 5.0, y, -1.0);
            let mut modes = vec![Mode::new(e, f)];
            if reversible {
                modes.push(Mode::new(f, e));
            }
            let mut c = Cell::new(format!("c{i}"), if i % 3 == 0 { "T2" } else { "T1" }, modes);
            c.reversible = reversible;
            c.cut_length = 5.0;
            c.z = -1.0;
            c
        })
        .collect();
    Instance {
        name: format!("line{n}"),
        machine: Machine::default(),
        tools: vec![
            Tool {
                id: "T1".into(),
                diameter: 6.0,
                name: None,
                feed: None,
            },
            Tool {
                id: "T2".into(),
                diameter: 10.0,
                name: Some("rougher".into()),
                feed: Some(800.0),
            },
        ],
        cells,
        precedence: vec![],
        as_given: Some((0..n).map(|c| Visit::new(c, 0)).collect()),
        ..Instance::default()
    }
}

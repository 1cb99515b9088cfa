//! The golden guard: results a user sees, recorded once and compared on every run.
//!
//! Pinned here, in `tests/fixtures/golden/`:
//! - `solvers.tsv`: every registry solver on a dozen instances (TSPLIB SOP, PCGTSPLIB, one of
//!   each generator) at a fixed seed and evaluation budget: cost, evaluations, proof flag, lower
//!   bound and the sequence (or the error, for a refusal such as `exact` beyond its limit);
//! - `demo.tsv`: `cellseq demo`'s `results.csv` without its wall-clock column;
//! - `gcode.tsv`, `svg.tsv`: `cellseq optimize` on every real program and drawing in
//!   `tests/fixtures/{gcode,svg}/real/` (default options, `--seed 1 --max-evals 20000`): the
//!   exit status, the `--json` report without its timings, the output's length and FNV-1a hash
//!   (the error message for a refused file), and a few outputs in full under `full/`.
//!
//! A run fails on any difference and lists every entry that differs. The set was recorded at
//! 404a0b7; it is re-recorded only when a change of results is intended, with
//! `CELLSEQ_GOLDEN_RECORD=1 cargo test --release golden` (without the variable the test only
//! compares; a missing file is an error).

use cellseq::files::write_atomic;
use cellseq::formats::load_instance;
use cellseq::generate::generate;
use cellseq::model::{Instance, Sequence};
use cellseq::solvers::{Budget, NoObserver, registry, run};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The repository root.
fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// The golden files' folder.
fn golden_dir() -> PathBuf {
    root().join("tests/fixtures/golden")
}

/// True when the run records the golden set instead of comparing with it.
fn recording() -> bool {
    std::env::var("CELLSEQ_GOLDEN_RECORD").is_ok_and(|v| v == "1")
}

/// One golden table: a header and rows keyed by their first column.
struct Table {
    file: &'static str,
    header: Vec<String>,
    rows: BTreeMap<String, Vec<String>>,
}

/// A TSV field: tabs and line ends escaped so that a row stays one line.
fn field(s: &str) -> String {
    s.replace('\\', "\\\\")
        .replace('\t', "\\t")
        .replace('\n', "\\n")
        .replace('\r', "\\r")
}

impl Table {
    fn new(file: &'static str, header: &[&str]) -> Self {
        Table {
            file,
            header: header.iter().map(|h| h.to_string()).collect(),
            rows: BTreeMap::new(),
        }
    }

    /// Adds a row; `values` are the columns after the key.
    fn add(&mut self, key: &str, values: Vec<String>) {
        assert_eq!(values.len() + 1, self.header.len(), "row {key}");
        let prev = self
            .rows
            .insert(field(key), values.iter().map(|v| field(v)).collect());
        assert!(prev.is_none(), "duplicate golden key {key}");
    }

    fn text(&self) -> String {
        let mut s = self.header.join("\t");
        s.push('\n');
        for (k, v) in &self.rows {
            s.push_str(k);
            for x in v {
                s.push('\t');
                s.push_str(x);
            }
            s.push('\n');
        }
        s
    }

    /// Records the table, or compares it with the recorded one and panics listing every
    /// difference.
    fn settle(&self) {
        let path = golden_dir().join(self.file);
        if recording() {
            write_atomic(&path, self.text().as_bytes()).expect("write golden file");
            eprintln!(
                "golden: recorded {} ({} rows)",
                path.display(),
                self.rows.len()
            );
            return;
        }
        let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
            panic!(
                "{}: {e}; record the golden set with CELLSEQ_GOLDEN_RECORD=1",
                path.display()
            )
        });
        let diffs = self.differences(&text);
        if !diffs.is_empty() {
            panic!(
                "{} of {} golden entries in {} differ:\n{}",
                diffs.len(),
                self.rows.len(),
                path.display(),
                diffs.join("\n")
            );
        }
    }

    /// Every difference between `recorded` (the file's text) and this table.
    fn differences(&self, recorded: &str) -> Vec<String> {
        let mut lines = recorded.lines();
        let mut out = Vec::new();
        let header: Vec<&str> = lines.next().unwrap_or("").split('\t').collect();
        if header != self.header.iter().map(String::as_str).collect::<Vec<_>>() {
            out.push(format!(
                "header: recorded {header:?}, now {:?}",
                self.header
            ));
        }
        let mut old: BTreeMap<&str, Vec<&str>> = BTreeMap::new();
        for l in lines {
            let mut it = l.split('\t');
            let k = it.next().unwrap_or("");
            old.insert(k, it.collect());
        }
        for (k, v) in &old {
            match self.rows.get(*k) {
                None => out.push(format!("{k}: recorded but not produced now")),
                Some(now) => {
                    for (i, (a, b)) in v.iter().zip(now.iter()).enumerate() {
                        if a != b {
                            let col = self.header.get(i + 1).map_or("?", String::as_str);
                            out.push(format!("{k}: {col} was {} now {}", clip(a), clip(b)));
                        }
                    }
                    if v.len() != now.len() {
                        out.push(format!("{k}: {} columns, now {}", v.len(), now.len()));
                    }
                }
            }
        }
        for k in self.rows.keys() {
            if !old.contains_key(k.as_str()) {
                out.push(format!("{k}: produced now but not recorded"));
            }
        }
        out
    }
}

/// A long value shortened for a difference message.
fn clip(s: &str) -> String {
    if s.len() <= 160 {
        s.to_string()
    } else {
        let cut = (0..=160)
            .rev()
            .find(|&i| s.is_char_boundary(i))
            .unwrap_or(0);
        format!("{}… ({} bytes)", &s[..cut], s.len())
    }
}

/// 64-bit FNV-1a: a stable hash of an output file (the same on every platform and release).
fn fnv1a(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// A float exactly as it round-trips.
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// `cell` or `cell.mode` for every visit (mode 0 left out).
fn sequence_text(s: &Sequence) -> String {
    s.iter()
        .map(|v| {
            if v.mode == 0 {
                v.cell.to_string()
            } else {
                format!("{}.{}", v.cell, v.mode)
            }
        })
        .collect::<Vec<_>>()
        .join(" ")
}

// ---------------------------------------------------------------------------------------------
// solvers

/// Evaluation budget of every solver run: small enough for the whole table to take seconds.
const SOLVER_EVALS: u64 = 20_000;
const SOLVER_SEED: u64 = 3;

fn kv(s: &[(&str, &str)]) -> BTreeMap<String, String> {
    s.iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// The golden instances with their keys.
fn solver_instances() -> Vec<(String, Instance)> {
    let files = [
        "tsplib-sop/ESC07.sop",
        "tsplib-sop/br17.10.sop",
        "tsplib-sop/ESC25.sop",
        "tsplib-sop/rbg048a.sop",
        "tsplib-sop/prob.42.sop",
        "pcgtsplib/ESC12.pcglns",
        "pcgtsplib/p43.1.pcglns",
        "pcgtsplib/ry48p.1.pcglns",
        "generated/panel-20.json",
        "generated/casing-20.json",
        "generated/cabin-20.json",
    ];
    let mut v: Vec<(String, Instance)> = files
        .iter()
        .map(|f| {
            let p = root().join("instances").join(f);
            let inst = load_instance(&p).unwrap_or_else(|e| panic!("{f}: {e}"));
            (f.to_string(), inst)
        })
        .collect();
    let uniform = [
        ("n", "30"),
        ("modes", "3"),
        ("closed", "0.4"),
        ("tools", "3"),
        ("density", "0.05"),
    ];
    let key = "generate uniform n=30 modes=3 closed=0.4 tools=3 density=0.05 seed=7";
    v.push((key.into(), generate("uniform", &kv(&uniform), 7).unwrap()));
    v
}

/// Solvers that cannot be made deterministic under an evaluation budget, with the reason.
/// Empty at 404a0b7: every registry solver stops on its evaluation count alone.
const NONDETERMINISTIC: &[(&str, &str)] = &[];

#[test]
fn golden_solvers() {
    let mut t = Table::new(
        "solvers.tsv",
        &[
            "solver@instance",
            "seed",
            "max_evals",
            "cost",
            "evaluations",
            "proven_optimal",
            "lower_bound",
            "sequence_or_error",
        ],
    );
    let insts = solver_instances();
    let none = BTreeMap::new();
    for info in registry() {
        if let Some((_, why)) = NONDETERMINISTIC.iter().find(|(n, _)| *n == info.name) {
            eprintln!("golden: {} excluded: {why}", info.name);
            continue;
        }
        for (key, inst) in &insts {
            let budget = Budget {
                time_limit: None,
                max_evals: Some(SOLVER_EVALS),
            };
            let obj = inst.default_objective();
            let t0 = std::time::Instant::now();
            let r = run(
                info.name,
                inst,
                obj,
                &none,
                SOLVER_SEED,
                budget,
                &mut NoObserver,
            );
            if std::env::var_os("CELLSEQ_GOLDEN_TIMES").is_some() {
                eprintln!("{} {key}: {:.2} s", info.name, t0.elapsed().as_secs_f64());
            }
            let row = match r {
                Ok(r) => vec![
                    num(r.report.cost),
                    r.evaluations.to_string(),
                    r.outcome.proven_optimal.to_string(),
                    r.outcome.lower_bound.map(num).unwrap_or_default(),
                    sequence_text(&r.outcome.sequence),
                ],
                Err(e) => vec![
                    String::new(),
                    String::new(),
                    String::new(),
                    String::new(),
                    format!("error: {e}"),
                ],
            };
            let mut values = vec![SOLVER_SEED.to_string(), SOLVER_EVALS.to_string()];
            values.extend(row);
            t.add(&format!("{}@{key}", info.name), values);
        }
    }
    t.settle();
}

// ---------------------------------------------------------------------------------------------
// the CLI: demo and optimize

fn cellseq() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_cellseq"));
    c.current_dir(root());
    c
}

#[test]
fn golden_demo() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = cellseq()
        .args(["demo", "--threads", "2", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "demo failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let mut rd = csv::Reader::from_path(out.join("results.csv")).unwrap();
    let head: Vec<String> = rd.headers().unwrap().iter().map(String::from).collect();
    let wall: Vec<bool> = head.iter().map(|h| h.starts_with("wall_")).collect();
    let col = |name: &str| head.iter().position(|h| h == name).unwrap();
    let (ci, cs, cr) = (col("instance"), col("solver_id"), col("replicate"));
    let mut header = vec!["instance/solver/replicate"];
    header.extend(
        head.iter()
            .zip(&wall)
            .filter(|(_, w)| !**w)
            .map(|(h, _)| h.as_str()),
    );
    let mut t = Table::new("demo.tsv", &header);
    for rec in rd.records() {
        let rec = rec.unwrap();
        let key = format!("{}/{}/{}", &rec[ci], &rec[cs], &rec[cr]);
        let values = rec
            .iter()
            .zip(&wall)
            .filter(|(_, w)| !**w)
            .map(|(v, _)| v.to_string())
            .collect();
        t.add(&key, values);
    }
    t.settle();
}

/// Outputs kept in full under `golden/full/` (small programs of different kinds).
const FULL: &[&str] = &[
    "ugs_ruler.gcode",
    "cncjs_helical_thread_milling.gcode",
    "linuxcnc_plasmatest.ngc",
    "eggbot_single_star_outline_x3.svg",
    "vpype_cmyk_file1.svg",
];

/// The `--json` report's values except timings and paths, as `key=value` pairs.
fn report_fields(v: &Value, prefix: &str, out: &mut Vec<String>) {
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                if k.ends_with("_s") || k == "timings" || k == "input" || k == "output" {
                    continue;
                }
                let p = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                report_fields(x, &p, out);
            }
        }
        other => out.push(format!("{prefix}={other}")),
    }
}

/// `cellseq optimize` on every real file of `kind` (`gcode` or `svg`).
fn golden_optimize(kind: &'static str, file: &'static str) {
    let dir = tempfile::tempdir().unwrap();
    let real = root().join("tests/fixtures").join(kind).join("real");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&real)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().is_some_and(|n| n != "SOURCES.md"))
        .collect();
    files.sort();
    let mut t = Table::new(
        file,
        &["file", "exit", "report", "output_bytes", "output_fnv1a"],
    );
    let mut full_diffs = Vec::new();
    for f in &files {
        let name = f.file_name().unwrap().to_str().unwrap().to_string();
        let rel = f.strip_prefix(root()).unwrap();
        let out = dir.path().join(&name);
        let o = cellseq()
            .arg("optimize")
            .arg(rel)
            .arg("-o")
            .arg(&out)
            .args(["--seed", "1", "--max-evals", "20000", "--json"])
            .output()
            .unwrap();
        let exit = o
            .status
            .code()
            .map(|c| c.to_string())
            .unwrap_or("signal".into());
        let row = if o.status.success() {
            let v: Value = serde_json::from_slice(&o.stdout)
                .unwrap_or_else(|e| panic!("{name}: report is not JSON: {e}"));
            let mut fields = Vec::new();
            report_fields(&v, "", &mut fields);
            let bytes = std::fs::read(&out).unwrap();
            if FULL.contains(&name.as_str()) {
                let kept = golden_dir().join("full").join(&name);
                if recording() {
                    write_atomic(&kept, &bytes).unwrap();
                } else if std::fs::read(&kept).ok().as_deref() != Some(&bytes[..]) {
                    full_diffs.push(first_line_difference(&kept, &bytes));
                }
            }
            vec![
                exit,
                fields.join(" "),
                bytes.len().to_string(),
                fnv1a(&bytes),
            ]
        } else {
            let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
            vec![exit, format!("error: {err}"), String::new(), String::new()]
        };
        t.add(&name, row);
    }
    assert!(
        full_diffs.is_empty(),
        "outputs kept in full differ:\n{}",
        full_diffs.join("\n")
    );
    t.settle();
}

/// Where a kept output and a new one first differ, by line.
fn first_line_difference(kept: &Path, now: &[u8]) -> String {
    let old = std::fs::read_to_string(kept).unwrap_or_default();
    let now = String::from_utf8_lossy(now);
    for (i, (a, b)) in old.lines().zip(now.lines()).enumerate() {
        if a != b {
            return format!("{}:{}: was {a:?} now {b:?}", kept.display(), i + 1);
        }
    }
    format!(
        "{}: {} lines, now {}",
        kept.display(),
        old.lines().count(),
        now.lines().count()
    )
}

#[test]
fn golden_gcode() {
    golden_optimize("gcode", "gcode.tsv");
}

#[test]
fn golden_svg() {
    golden_optimize("svg", "svg.tsv");
}

#[test]
fn golden_diff_lists_every_difference() {
    let mut t = Table::new("x.tsv", &["k", "a", "b"]);
    t.add("one", vec!["1".into(), "2".into()]);
    t.add("two", vec!["3".into(), "4".into()]);
    t.add("new", vec!["5".into(), "6".into()]);
    let recorded = "k\ta\tb\none\t1\t9\ntwo\t0\t0\ngone\t1\t1\n";
    let d = t.differences(recorded);
    assert_eq!(
        d,
        vec![
            "gone: recorded but not produced now",
            "one: b was 9 now 2",
            "two: a was 0 now 3",
            "two: b was 0 now 4",
            "new: produced now but not recorded",
        ]
    );
    assert!(t.differences(&t.text()).is_empty());
}

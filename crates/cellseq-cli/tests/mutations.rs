//! Deterministic mutation testing of every reader, on stable Rust, in `cargo test`.
//!
//! Seeds are files of the repository (`instances/`, `tests/fixtures/`, `experiments/`,
//! `results/reference/`, `fuzz/seeds/`); each case applies one to three seeded mutations (byte
//! flips, truncation, duplicated, deleted or swapped lines, numbers replaced by huge, negative,
//! NaN or infinite ones, unicode, repeated chunks, the empty file) and runs the reader
//! in-process under `catch_unwind`. A case fails when it panics, takes longer than
//! [`CASE_SECONDS`] or allocates more than [`CASE_BYTES`] on its thread; a single allocation
//! above [`ALLOC_CAP`] is refused (and aborts the run, naming the case). Instances that parse
//! and validate are then solved by `greedy`, `insertion` and `process` (and `exact` when
//! small), which must succeed: `validate` and `solve` agree.
//!
//! [`CASES`] cases per reader by default; `CELLSEQ_MUTATION_CASES=N` runs more. A failing case
//! is written to `$CARGO_TARGET_TMPDIR/mutations/` so it can be replayed with the CLI.
//!
//! This file is a test binary of its own, not a module of `tests/it/`: its counting
//! `#[global_allocator]` would otherwise count (and cap) the allocations of every test there.

use cellseq::formats::{self, Format, json};
use cellseq::model::Instance;
use cellseq::solvers::{self, Budget, NoObserver};
use cellseq_lab::plan::Plan;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::{Cell, RefCell};
use std::collections::BTreeMap;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Cases per reader.
const CASES: usize = 300;
/// Longest a case may take (a hang guard, not a speed test).
const CASE_SECONDS: f64 = 10.0;
/// Most a case may allocate on its thread (peak above what it started with).
const CASE_BYTES: usize = 1 << 30;
/// Largest single allocation the test binary grants.
const ALLOC_CAP: usize = 4 << 30;
/// Seed files above this size are left out (mutations of small files reach the same code).
const MAX_SEED_BYTES: u64 = 200_000;
/// At most this many seed files per reader (the first ones in path order).
const MAX_SEEDS: usize = 40;

// ---------------------------------------------------------------------------------------------
// allocation accounting

struct Counting;

thread_local! {
    static CURRENT: Cell<usize> = const { Cell::new(0) };
    static PEAK: Cell<usize> = const { Cell::new(0) };
    static LABEL: RefCell<String> = const { RefCell::new(String::new()) };
}

fn grow(n: usize) {
    let _ = CURRENT.try_with(|c| {
        let v = c.get().saturating_add(n);
        c.set(v);
        let _ = PEAK.try_with(|p| p.set(p.get().max(v)));
    });
}

fn shrink(n: usize) {
    let _ = CURRENT.try_with(|c| c.set(c.get().saturating_sub(n)));
}

fn refuse(size: usize) {
    use std::io::Write;
    let mut e = std::io::stderr().lock();
    let _ = write!(
        e,
        "mutations: refused an allocation of {size} bytes (cap {ALLOC_CAP}) in case "
    );
    let _ = LABEL.try_with(|l| {
        if let Ok(l) = l.try_borrow() {
            let _ = e.write_all(l.as_bytes());
        }
    });
    let _ = e.write_all(b"\n");
}

// SAFETY: every call is forwarded to the system allocator unchanged (or refused with a null
// pointer, which the allocation API allows); the thread-local counters do not allocate.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        if l.size() > ALLOC_CAP {
            refuse(l.size());
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded with the caller's layout.
        let p = unsafe { System.alloc(l) };
        if !p.is_null() {
            grow(l.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        if l.size() > ALLOC_CAP {
            refuse(l.size());
            return std::ptr::null_mut();
        }
        // SAFETY: forwarded with the caller's layout.
        let p = unsafe { System.alloc_zeroed(l) };
        if !p.is_null() {
            grow(l.size());
        }
        p
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        // SAFETY: `p` was allocated by `System` with this layout.
        unsafe { System.dealloc(p, l) };
        shrink(l.size());
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new_size: usize) -> *mut u8 {
        if new_size > ALLOC_CAP {
            refuse(new_size);
            return std::ptr::null_mut();
        }
        // SAFETY: `p` was allocated by `System` with layout `l`.
        let q = unsafe { System.realloc(p, l, new_size) };
        if !q.is_null() {
            shrink(l.size());
            grow(new_size);
        }
        q
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

// ---------------------------------------------------------------------------------------------
// seeds and mutations

// the integration tests' shared paths (this file is a binary of its own: see below)
#[path = "it/common.rs"]
mod common;
use common::root;

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        let Ok(ft) = e.file_type() else { continue };
        if ft.is_dir() {
            walk(&p, out);
        } else if ft.is_file() {
            out.push(p);
        }
    }
}

/// Seed files under `dirs` (relative to the repository) whose names end in one of `exts`.
fn seeds(dirs: &[&str], exts: &[&str]) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    for d in dirs {
        walk(&root().join(d), &mut files);
    }
    files.sort();
    files.dedup();
    let out: Vec<(String, Vec<u8>)> = files
        .into_iter()
        .filter(|p| {
            let name = p.file_name().and_then(|n| n.to_str()).unwrap_or("");
            exts.iter().any(|e| name.ends_with(e))
        })
        .filter(|p| std::fs::metadata(p).is_ok_and(|m| m.len() <= MAX_SEED_BYTES))
        .take(MAX_SEEDS)
        .map(|p| {
            let rel = p.strip_prefix(root()).unwrap_or(&p).display().to_string();
            let bytes = std::fs::read(&p).expect("seed file reads");
            (rel, bytes)
        })
        .collect();
    assert!(
        !out.is_empty(),
        "no seed files with {exts:?} under {dirs:?}"
    );
    out
}

const NUMBERS: &[&str] = &[
    "1e308",
    "-1e308",
    "1e400",
    "NaN",
    "nan",
    "inf",
    "-inf",
    "Infinity",
    "-1",
    "-0",
    "0",
    "-5",
    "4000000000",
    "100000",
    "18446744073709551616",
    "-9223372036854775809",
    "1e-320",
    "0.5",
    "2147483648",
    "65536",
    "1e9",
    "999999999999",
];

const UNICODE: &[&str] = &[
    "é", "\u{202e}", "𝔘", "\u{0}", "\u{feff}", "\u{fffd}", "漢字", "\r", "\t", "\u{2028}",
];

/// Byte ranges of the lines of `d` (each without its newline).
fn lines(d: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start = 0;
    for (i, &b) in d.iter().enumerate() {
        if b == b'\n' {
            out.push((start, i));
            start = i + 1;
        }
    }
    if start < d.len() {
        out.push((start, d.len()));
    }
    out
}

/// Byte ranges of number-like tokens: a digit, or a minus sign before a digit, then digits,
/// dots, exponents and signs.
fn numbers(d: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < d.len() {
        let starts = d[i].is_ascii_digit()
            || (d[i] == b'-' && d.get(i + 1).is_some_and(|c| c.is_ascii_digit()));
        let after_word = i > 0 && (d[i - 1].is_ascii_alphanumeric() || d[i - 1] == b'_');
        if starts && !after_word {
            let mut j = i + 1;
            while j < d.len() && (d[j].is_ascii_digit() || b".eE+-".contains(&d[j])) {
                j += 1;
            }
            out.push((i, j));
            i = j;
        } else {
            i += 1;
        }
    }
    out
}

/// Applies one mutation to `d` and names it.
fn mutate_once(rng: &mut ChaCha8Rng, d: &mut Vec<u8>) -> String {
    let pos = |rng: &mut ChaCha8Rng, len: usize| rng.random_range(0..=len);
    match rng.random_range(0..10u32) {
        0 if !d.is_empty() => {
            let p = rng.random_range(0..d.len());
            let b: u8 = rng.random();
            d[p] = b;
            format!("byte {p} := {b:#04x}")
        }
        1 => {
            let p = pos(rng, d.len());
            d.truncate(p);
            format!("truncate at {p}")
        }
        2..=4 => {
            let ls = lines(d);
            if ls.is_empty() {
                return "no lines".into();
            }
            let (a, b) = ls[rng.random_range(0..ls.len())];
            match rng.random_range(0..3u32) {
                0 => {
                    let mut copy = d[a..b].to_vec();
                    copy.push(b'\n');
                    d.splice(a..a, copy);
                    format!("duplicate line at {a}")
                }
                1 => {
                    let end = (b + 1).min(d.len());
                    d.drain(a..end);
                    format!("delete line at {a}")
                }
                _ => {
                    let (c, e) = ls[rng.random_range(0..ls.len())];
                    if (c, e) == (a, b) {
                        return "swap a line with itself".into();
                    }
                    let (first, second) = if c < a {
                        ((c, e), (a, b))
                    } else {
                        ((a, b), (c, e))
                    };
                    let x = d[first.0..first.1].to_vec();
                    let y = d[second.0..second.1].to_vec();
                    d.splice(second.0..second.1, x);
                    d.splice(first.0..first.1, y);
                    format!("swap lines at {} and {}", first.0, second.0)
                }
            }
        }
        5..=6 => {
            let ns = numbers(d);
            if ns.is_empty() {
                return "no numbers".into();
            }
            let (a, b) = ns[rng.random_range(0..ns.len())];
            let v = NUMBERS[rng.random_range(0..NUMBERS.len())];
            d.splice(a..b, v.bytes());
            format!("number at {a} := {v}")
        }
        7 => {
            let p = pos(rng, d.len());
            let u = UNICODE[rng.random_range(0..UNICODE.len())];
            d.splice(p..p, u.bytes());
            format!("insert {u:?} at {p}")
        }
        8 if !d.is_empty() => {
            let a = rng.random_range(0..d.len());
            let len = rng.random_range(1..=64usize).min(d.len() - a);
            let k = rng.random_range(2..=50usize);
            let chunk = d[a..a + len].repeat(k);
            d.splice(a..a, chunk);
            format!("repeat {len} bytes at {a} x{k}")
        }
        9 if rng.random_range(0..4u32) == 0 => {
            d.clear();
            "empty".into()
        }
        _ => {
            let p = pos(rng, d.len());
            let v = NUMBERS[rng.random_range(0..NUMBERS.len())];
            d.splice(p..p, format!(" {v} ").into_bytes());
            format!("insert number {v} at {p}")
        }
    }
}

// ---------------------------------------------------------------------------------------------
// the driver

fn panic_message(e: &(dyn std::any::Any + Send)) -> String {
    e.downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| e.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "non-string panic".into())
}

fn cases() -> usize {
    std::env::var("CELLSEQ_MUTATION_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(CASES)
}

/// Runs `cases()` mutated copies of `seeds` through `read` (given a file name with the seed's
/// extension and the bytes); fails with every bad case listed.
fn run(reader: &str, seeds: &[(String, Vec<u8>)], read: &dyn Fn(&str, &[u8])) {
    let salt = reader
        .bytes()
        .fold(0u64, |h, b| h.wrapping_mul(31).wrapping_add(b as u64));
    let mut rng = ChaCha8Rng::seed_from_u64(0x0C31_15E9 ^ salt);
    let mut failures = Vec::new();
    let dump = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("mutations");
    for case in 0..cases() {
        let (name, orig) = &seeds[case % seeds.len()];
        let mut d = orig.clone();
        let k = rng.random_range(1..=3usize);
        let what: Vec<String> = (0..k).map(|_| mutate_once(&mut rng, &mut d)).collect();
        let label = format!("{reader} #{case} ({name}: {})", what.join("; "));
        let ext = Path::new(name)
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("txt");
        let file = format!("case{case}.{ext}");
        LABEL.with(|l| *l.borrow_mut() = label.clone());
        let base = CURRENT.with(|c| c.get());
        PEAK.with(|p| p.set(base));
        let t = Instant::now();
        let r = catch_unwind(AssertUnwindSafe(|| read(&file, &d)));
        let secs = t.elapsed().as_secs_f64();
        let grew = PEAK.with(|p| p.get()).saturating_sub(base);
        let bad = match r {
            Err(e) => Some(format!("panicked: {}", panic_message(e.as_ref()))),
            Ok(()) if secs > CASE_SECONDS => Some(format!("took {secs:.1} s")),
            Ok(()) if grew > CASE_BYTES => Some(format!("allocated {grew} bytes")),
            Ok(()) => None,
        };
        if let Some(why) = bad {
            let _ = std::fs::create_dir_all(&dump);
            let out = dump.join(format!("{reader}-{case}.{ext}"));
            let _ = std::fs::write(&out, &d);
            failures.push(format!("{label}: {why} [input: {}]", out.display()));
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {} {reader} cases failed:\n{}",
        failures.len(),
        cases(),
        failures.join("\n")
    );
}

fn text(d: &[u8]) -> std::borrow::Cow<'_, str> {
    String::from_utf8_lossy(d)
}

/// Parses, validates and, when valid, solves: a refusal names the file, and validation must
/// leave nothing a solver fails on.
fn instance_case(file: &str, d: &[u8], format: Format) {
    let refused = |e: cellseq::Error| {
        let m = e.to_string();
        assert!(m.contains(file), "the error does not name the file: {m}");
    };
    let inst = match formats::parse_instance(file, &text(d), format) {
        Ok(inst) => inst,
        Err(e) => return refused(e),
    };
    if let Err(e) = cellseq::validate::validate(&inst, file) {
        return refused(e);
    }
    solve_all(&inst);
}

fn solve_all(inst: &Instance) {
    let mut names = vec!["greedy", "insertion", "process"];
    if inst.n() <= 12 {
        names.push("exact");
    }
    for s in names {
        let budget = Budget {
            time_limit: None,
            max_evals: Some(200_000),
        };
        let obj = inst.default_objective();
        if let Err(e) = solvers::run(s, inst, obj, &BTreeMap::new(), 1, budget, &mut NoObserver) {
            panic!("validated instance, but solver {s} fails: {e}");
        }
    }
}

fn load(rel: &str) -> Instance {
    formats::load_instance(&root().join(rel)).expect("reference instance loads")
}

#[test]
fn sop_reader_survives_mutations() {
    let s = seeds(&["instances/tsplib-sop", "fuzz/seeds"], &[".sop"]);
    let s: Vec<_> = s.into_iter().filter(|(_, b)| b.len() <= 20_000).collect();
    run("sop", &s, &|f, d| instance_case(f, d, Format::Sop));
}

#[test]
fn pcglns_reader_survives_mutations() {
    let s = seeds(&["instances/pcgtsplib", "fuzz/seeds"], &[".pcglns"]);
    let s: Vec<_> = s.into_iter().filter(|(_, b)| b.len() <= 20_000).collect();
    run("pcglns", &s, &|f, d| instance_case(f, d, Format::Pcglns));
}

#[test]
fn pcgtsp_reader_survives_mutations() {
    // both real files (the larger is 51 kB): the only PCGTSP seeds there are
    let s = seeds(&["tests/fixtures/pcgtsp", "fuzz/seeds"], &[".pcgtsp"]);
    run("pcgtsp", &s, &|f, d| instance_case(f, d, Format::Pcgtsp));
}

#[test]
fn json_instance_reader_survives_mutations() {
    let s = seeds(
        &["instances/generated", "fuzz/seeds/json"],
        &["-20.json", ".json"],
    );
    let s: Vec<_> = s.into_iter().filter(|(_, b)| b.len() <= 60_000).collect();
    run("json-instance", &s, &|f, d| {
        instance_case(f, d, Format::Json)
    });
}

#[test]
fn json_solution_reader_survives_mutations() {
    let s = seeds(&["results/reference", "fuzz/seeds/solution"], &[".json"]);
    let insts = [
        load("instances/tsplib-sop/prob.100.sop"),
        load("fuzz/seeds/json/matrix-first-last.json"),
    ];
    run("json-solution", &s, &|f, d| {
        let Ok(sol) = json::parse_solution(f, &text(d)) else {
            return;
        };
        for inst in &insts {
            if let Ok(seq) = json::from_refs(inst, &sol.sequence, f) {
                let _ = cellseq::check(inst, &seq, inst.default_objective());
            }
        }
    });
}

#[test]
fn gcode_reader_survives_mutations() {
    let s = seeds(
        &["tests/fixtures", "fuzz/seeds"],
        &[".ngc", ".nc", ".gcode", ".gco", ".tap"],
    );
    run("gcode", &s, &|f, d| {
        let _ = cellseq_programs::gcode::parse(f, &text(d));
    });
}

#[test]
fn svg_reader_survives_mutations() {
    let s = seeds(&["tests/fixtures", "fuzz/seeds"], &[".svg"]);
    run("svg", &s, &|f, d| {
        let _ = cellseq_programs::svg::read(f, &text(d), Default::default());
    });
}

#[test]
fn dxf_reader_survives_mutations() {
    let s = seeds(&["tests/fixtures", "fuzz/seeds"], &[".dxf"]);
    run("dxf", &s, &|f, d| {
        let _ = cellseq_programs::dxf::read(f, d, Default::default());
    });
}

#[test]
fn plan_reader_survives_mutations() {
    let s = seeds(&["experiments", "fuzz/seeds"], &[".toml"]);
    let base = root().join("experiments");
    run("plan", &s, &|f, d| {
        let _ = Plan::parse(f, &text(d), &base);
    });
}

/// The mutations are a pure function of the seed: the same case list every run.
#[test]
fn mutations_are_deterministic() {
    let seed = b"NAME: x\nDIMENSION: 3\n1 2 3\n-1 0 4\n".to_vec();
    let draw = || {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        (0..50)
            .map(|_| {
                let mut d = seed.clone();
                let w = mutate_once(&mut rng, &mut d);
                (w, d)
            })
            .collect::<Vec<_>>()
    };
    let (a, b) = (draw(), draw());
    assert_eq!(a, b);
    // and they do change the input (all but the rare no-op ones)
    let changed = a.iter().filter(|(_, d)| *d != seed).count();
    assert!(
        changed >= 40,
        "only {changed} of 50 mutations changed the input"
    );
}

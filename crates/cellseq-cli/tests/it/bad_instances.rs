//! Instances a solver cannot handle are refused by validation, so `validate` and `solve` agree:
//! fixed first/last cells against the precedence, numbers whose costs could overflow,
//! negative matrix entries, declared sizes the file cannot hold. Each case is run through the
//! command line (`validate` and `solve` both refuse it with one line naming the file, exit 2,
//! no panic) and, where it matters, through the library.

use cellseq::formats::{self, Format};
use cellseq::model::{CostMatrix, Instance, Mode};
use cellseq::solvers::{self, Budget};
use cellseq::{Cell, Objective, Visit};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;

use crate::common::{run as cellseq, solve, solve_with, write};

/// `validate`, `info`, `bound` and `solve` (with each solver given) all refuse `text` with one line holding
/// the file name and every needle, exit code 2 and no panic.
fn refused(name: &str, text: &str, needles: &[&str], solvers: &[&str]) {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), name, text);
    let p = p.to_str().unwrap();
    let mut runs = vec![
        ("validate".to_string(), cellseq(&["validate", p])),
        ("info".to_string(), cellseq(&["info", p])),
    ];
    if !solvers.is_empty() {
        runs.push(("bound".to_string(), cellseq(&["bound", p])));
    }
    for s in solvers {
        runs.push((
            format!("solve --solver {s}"),
            cellseq(&["solve", p, "--solver", s, "--max-evals", "10000"]),
        ));
    }
    for (what, out) in runs {
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{what} {name}: {err}");
        assert!(!err.contains("panicked"), "{what} {name} panics: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{what} {name}: {err}");
        assert!(err.contains(name), "{what}: no file name in {err}");
        for n in needles {
            assert!(err.contains(n), "{what} {name}: '{n}' not in {err}");
        }
    }
}

/// Every registry solver (the issue found 11 of them panicking on contradictory first/last
/// cells).
fn all_solvers() -> Vec<&'static str> {
    solvers::registry().iter().map(|i| i.name).collect()
}

fn geo(extra: &str, machine: &str) -> String {
    format!(
        r#"{{"format":"cellseq-instance/1","name":"t","machine":{{{machine}}},
"tools":[{{"id":"T1","diameter":6}}],
"cells":[
 {{"id":"a","tool":"T1","modes":[{{"entry":[0,0,-1],"exit":[5,0,-1]}}]}},
 {{"id":"b","tool":"T1","modes":[{{"entry":[10,0,-1],"exit":[15,0,-1]}}]}},
 {{"id":"c","tool":"T1","modes":[{{"entry":[20,0,-1],"exit":[25,0,-1]}}]}}],
"precedence":[["a","b"]]{extra}}}"#
    )
}

#[test]
fn first_cell_with_a_predecessor_is_refused() {
    refused(
        "first.json",
        &geo(r#","first":"b""#, ""),
        &["'b' is fixed first", "'a' before it"],
        &all_solvers(),
    );
}

#[test]
fn last_cell_with_a_successor_is_refused() {
    refused(
        "last.json",
        &geo(r#","last":"a""#, ""),
        &["'a' is fixed last", "'b' after it"],
        &all_solvers(),
    );
}

#[test]
fn same_cell_first_and_last_is_refused() {
    refused(
        "same.json",
        &geo(r#","first":"c","last":"c""#, ""),
        &["fixed both first and last"],
        &all_solvers(),
    );
}

#[test]
fn unknown_first_or_last_cell_is_refused() {
    refused(
        "unk.json",
        &geo(r#","first":"zz""#, ""),
        &["first refers to unknown cell 'zz'"],
        &["greedy"],
    );
    refused(
        "unkl.json",
        &geo(r#","last":"zz""#, ""),
        &["last refers to unknown cell 'zz'"],
        &["greedy"],
    );
}

#[test]
fn consistent_first_and_last_cells_solve() {
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "ok.json", &geo(r#","first":"a","last":"c""#, ""));
    for s in all_solvers() {
        let out = cellseq(&[
            "solve",
            p.to_str().unwrap(),
            "--solver",
            s,
            "--max-evals",
            "10000",
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{s}: {err}");
    }
    // one cell may be both first and last
    let one = r#"{"format":"cellseq-instance/1","name":"one","tools":[{"id":"T1","diameter":6}],
"cells":[{"id":"a","tool":"T1","modes":[{"entry":[0,0,-1],"exit":[5,0,-1]}]}],"first":"a","last":"a"}"#;
    let p = write(d.path(), "one.json", one);
    assert!(cellseq(&["solve", p.to_str().unwrap()]).status.success());
}

#[test]
fn huge_or_non_finite_numbers_are_refused() {
    // a field set on cell "c", on machine, or on tool "T1"
    let cell = |kv: &str| geo("", "").replace(r#""id":"c","#, &format!(r#""id":"c",{kv},"#));
    let machine = |kv: &str| geo("", kv);
    let tool = |kv: &str| geo("", "").replace(r#""diameter":6"#, kv);
    let cases = [
        (
            "coord.json",
            geo("", "").replace("[20,0,-1]", "[1e308,0,-1]"),
            "beyond",
        ),
        (
            "big.json",
            geo("", "").replace("[20,0,-1]", "[2e9,0,-1]"),
            "beyond",
        ),
        ("lift.json", machine(r#""lift_time":1e308"#), "lift_time"),
        (
            "change.json",
            machine(r#""tool_change_time":1e300"#),
            "tool_change_time",
        ),
        ("home.json", machine(r#""home":[1e308,0,50]"#), "home"),
        (
            "tc.json",
            machine(r#""tool_change":[0,-1e200,50]"#),
            "tool_change",
        ),
        ("clear.json", machine(r#""clearance":1e300"#), "clearance"),
        (
            "rapid.json",
            machine(r#""rapid_feed":1e-300"#),
            "rapid_feed",
        ),
        ("feed.json", machine(r#""cut_feed":0.0000001"#), "cut_feed"),
        (
            "link.json",
            machine(r#""link_distance":1e300"#),
            "link_distance",
        ),
        ("cut.json", cell(r#""cut_length":1e300"#), "cut_length"),
        ("cellfeed.json", cell(r#""feed":1e-9"#), "feed"),
        ("z.json", cell(r#""z":-1e300"#), "has a z"),
        ("diam.json", tool(r#""diameter":1e300"#), "diameter"),
        (
            "toolfeed.json",
            tool(r#""diameter":6,"feed":1e-30"#),
            "feed",
        ),
    ];
    for (name, text, needle) in cases {
        refused(name, &text, &[needle], &["greedy", "exact"]);
    }
}

#[test]
fn duplicate_tool_ids_are_refused() {
    let text = geo("", "").replace(
        r#"[{"id":"T1","diameter":6}]"#,
        r#"[{"id":"T1","diameter":6},{"id":"T1","diameter":2,"feed":100}]"#,
    );
    refused(
        "tools.json",
        &text,
        &["tool id 'T1' is listed twice"],
        &["greedy"],
    );
}

#[test]
fn closed_geometric_tour_is_refused() {
    refused(
        "closed.json",
        &geo(r#","first":"a","closed":true"#, ""),
        &["closed tours apply to matrix instances only"],
        &["greedy"],
    );
}

const MATRIX: &str = r#"{"format":"cellseq-instance/1","name":"m",
"cells":[{"id":"a","modes":[{"entry":[0,0,0],"exit":[0,0,0]}]},
 {"id":"b","modes":[{"entry":[0,0,0],"exit":[0,0,0]}]}],
"matrix":[[0, 1],
 [ENTRY, 0]]}"#;

#[test]
fn json_matrix_entries_must_be_non_negative_and_bounded() {
    for (v, needle) in [
        ("-1", "matrix entry (2, 1) is -1"),
        ("-0.5", "matrix entry (2, 1) is -0.5"),
        ("1e308", "matrix entry (2, 1) is 1e308"),
        ("2e12", "matrix entry (2, 1) is 2000000000000"),
    ] {
        // the line of the entry: the fifth
        refused(
            "neg.json",
            &MATRIX.replace("ENTRY", v),
            &[needle, "neg.json:5:"],
            &["exact"],
        );
    }
    let ok = MATRIX.replace("ENTRY", "1e9");
    let inst = formats::parse_instance("m", &ok, Format::Json).unwrap();
    cellseq::validate::validate(&inst, "m").unwrap();
}

fn sop(dim: &str, body: &str) -> String {
    format!(
        "NAME: t\nTYPE: SOP\nDIMENSION: {dim}\nEDGE_WEIGHT_TYPE: EXPLICIT\n\
         EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n{body}EOF\n"
    )
}

#[test]
fn sop_negative_or_huge_entries_are_refused_with_line_and_entry() {
    let body = "3\n0 1 1000000\n-1 0 2\n-1 -5 0\n";
    refused(
        "neg.sop",
        &sop("3", body),
        &["neg.sop:10:", "entry (3, 2) is negative (-5)"],
        &["greedy"],
    );
    let body = "3\n0 1 1000000\n-1 0 1e308\n-1 -1 0\n";
    refused(
        "huge.sop",
        &sop("3", body),
        &["huge.sop:9:", "entry (2, 3) is 1e308"],
        &["exact"],
    );
}

#[test]
fn sop_declared_dimension_is_checked_before_allocating() {
    // 4·10⁹ nodes: 1.3·10²⁰ bytes (a capacity overflow before); refused by the cap
    let t = sop("4000000000", "4000000000\n0 1\n1 0\n");
    refused(
        "cap.sop",
        &t,
        &[
            "DIMENSION 4000000000 is above the limit",
            "CELLSEQ_MAX_MATRIX_NODES",
        ],
        &[],
    );
    // 10⁵ nodes: refused by the cap; with the cap raised, by the body's size (80 GB before)
    let t = sop("100000", "100000\n0 1\n1 0\n");
    refused("dim.sop", &t, &["DIMENSION 100000 is above the limit"], &[]);
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "dim.sop", &t);
    let out = crate::common::cellseq()
        .args(["validate", p.to_str().unwrap()])
        .env("CELLSEQ_MAX_MATRIX_NODES", "100000")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("holds 4 numbers, but a 100000x100000 matrix needs 10000000000"),
        "{err}"
    );
}

fn pcglns(dim: &str, sets: &str) -> String {
    pcglns_body(dim, sets, "0 1\n1 0\n")
}

fn pcglns_body(dim: &str, sets: &str, body: &str) -> String {
    format!(
        "NAME: t\nTYPE: PCGLNS\nDIMENSION: {dim}\nGTSP_SETS: {sets}\nEDGE_WEIGHT_TYPE: EXPLICIT\n\
         EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n{body}\
         GTSP_SET_SECTION\n1 1 -1\n2 2 -1\nSTART_GROUP_SECTION\n1\nEOF\n"
    )
}

#[test]
fn pcglns_declared_sizes_are_checked_before_allocating() {
    refused(
        "dim.pcglns",
        &pcglns("100000", "2"),
        &["DIMENSION 100000 is above the limit"],
        &[],
    );
    refused(
        "cap.pcglns",
        &pcglns("4000000000", "2"),
        &["above the limit"],
        &[],
    );
    refused(
        "sets.pcglns",
        &pcglns("2", "4000000000"),
        &["GTSP_SETS 4000000000 is more than the 2 nodes"],
        &[],
    );
    refused(
        "body.pcglns",
        &pcglns_body("2", "2", "0 1\n"),
        &["holds 2 numbers, but a 2x2 matrix needs 4"],
        &[],
    );
    // the same file with consistent sizes solves
    let d = tempfile::tempdir().unwrap();
    let p = write(d.path(), "ok.pcglns", &pcglns("2", "2"));
    let out = cellseq(&["solve", p.to_str().unwrap(), "--solver", "exact"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Every committed instance passes validation, and its cost bound is finite and far from
/// overflow.
#[test]
fn committed_instances_validate_with_finite_cost_bounds() {
    let root = crate::common::instance_path("");
    let mut n = 0;
    for dir in ["tsplib-sop", "pcgtsplib", "generated"] {
        let mut files: Vec<_> = std::fs::read_dir(root.join(dir))
            .unwrap()
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                let e = p.extension().and_then(|e| e.to_str()).unwrap_or("");
                ["sop", "pcglns", "json"].contains(&e)
            })
            .collect();
        files.sort();
        for p in files {
            let inst = formats::load_instance(&p).unwrap_or_else(|e| panic!("{e}"));
            let b = cellseq::validate::cost_bound(&inst);
            assert!(b.is_finite() && b < 1e30, "{}: bound {b}", p.display());
            n += 1;
        }
    }
    assert!(n > 60, "only {n} instances");
}

/// A random matrix instance with 1–3 modes per cell, sparse precedence, fractional costs
/// (ties within any tolerance are likely at this scale) and optional fixed ends.
fn random_instance(rng: &mut ChaCha8Rng, n: usize) -> Instance {
    let cells: Vec<Cell> = (0..n)
        .map(|i| {
            let k = rng.random_range(1..=3usize);
            Cell::new(format!("c{i}"), "", vec![Mode::default(); k])
        })
        .collect();
    let nodes: usize = cells.iter().map(|c| c.modes.len()).sum();
    // costs on a coarse grid of fractions, so many paths tie
    let costs = (0..nodes * nodes)
        .map(|_| rng.random_range(0..8u32) as f64 * 0.1 + 1e6)
        .collect();
    let mut precedence = Vec::new();
    for b in 2..n {
        if rng.random_range(0..2u32) == 0 {
            precedence.push((rng.random_range(1..b), b));
        }
    }
    Instance {
        name: "r".into(),
        cells,
        precedence,
        matrix: Some(CostMatrix { size: nodes, costs }),
        first: Some(0),
        ..Instance::default()
    }
}

/// The cheapest feasible sequence by enumeration (permutations × modes).
fn brute_force(inst: &Instance) -> f64 {
    fn rec(inst: &Instance, seq: &mut Vec<Visit>, used: &mut Vec<bool>, best: &mut f64) {
        let n = inst.n();
        if seq.len() == n {
            if let Ok(r) = cellseq::check(inst, seq, Objective::Matrix) {
                *best = best.min(r.cost);
            }
            return;
        }
        for c in 0..n {
            if used[c] {
                continue;
            }
            for m in 0..inst.cells[c].modes.len() {
                used[c] = true;
                seq.push(Visit::new(c, m));
                rec(inst, seq, used, best);
                seq.pop();
                used[c] = false;
            }
        }
    }
    let mut best = f64::INFINITY;
    rec(inst, &mut Vec::new(), &mut vec![false; inst.n()], &mut best);
    best
}

/// `exact` reads its path back from stored predecessors: on instances full of near-ties it
/// returns a sequence whose checked cost is the enumerated optimum, never "broken DP
/// back-pointer".
#[test]
fn exact_path_read_back_matches_enumeration() {
    let mut rng = ChaCha8Rng::seed_from_u64(26);
    for case in 0..30 {
        let n = rng.random_range(2..=5usize);
        let inst = random_instance(&mut rng, n);
        cellseq::validate::validate(&inst, "r").unwrap();
        let r =
            solve("exact", &inst, Objective::Matrix).unwrap_or_else(|e| panic!("case {case}: {e}"));
        let want = brute_force(&inst);
        assert!(
            (r.report.cost - want).abs() <= 1e-6,
            "case {case}: exact {} vs enumeration {want}",
            r.report.cost
        );
        assert!(r.outcome.proven_optimal);
    }
}

/// Defence in depth: the library's `solvers::run` refuses an instance whose first cell has a
/// predecessor even when nobody validated it, instead of panicking inside a solver.
#[test]
fn unvalidated_contradictory_instance_is_an_error_not_a_panic() {
    let text = geo(r#","first":"b""#, "");
    let inst = formats::parse_instance("first.json", &text, Format::Json).unwrap();
    for s in all_solvers() {
        let r = std::panic::catch_unwind(|| {
            let budget = Budget {
                time_limit: None,
                max_evals: Some(10_000),
            };
            solve_with(s, &inst, Objective::Time, &BTreeMap::new(), budget).map(|_| ())
        });
        match r {
            Ok(Err(e)) => assert!(e.to_string().contains("fixed first and last"), "{s}: {e}"),
            Ok(Ok(())) => panic!("{s} solved a contradictory instance"),
            Err(_) => panic!("{s} panicked"),
        }
    }
}

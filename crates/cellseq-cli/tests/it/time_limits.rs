//! The time limit is a promise for every solver: every registry solver (the list is read from
//! the registry, so a new solver is covered without touching this file) runs on a set of
//! degenerate instances generated here with a 1 s limit, one solver at a time, and must end
//! within the limit plus the margin with a feasible sequence that the independent checker
//! accepts.
//!
//! The instances: one cell, two cells, all-zero costs, all costs equal, costs at the
//! validator's limits (0 and 10¹²), a full chain, no precedence, coincident points, one cell
//! with thousands of modes (far corners at the coordinate limit), and a 400-cell asymmetric
//! instance with costs 0–100 and no inner precedence (many zero arcs: the regime where `beam`
//! once ran 25 s and 635 MB under `--time-limit 1`). `CELLSEQ_TIME_TRACE=1` prints every run's
//! wall time.

use cellseq::checker::check;
use cellseq::generate::generate;
use cellseq::geom::Point3;
use cellseq::model::{Cell, CostMatrix, Instance, Machine, Mode, Tool};
use cellseq::solvers::{Budget, Needs, NoObserver, registry, run};
use cellseq::validate::validate;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

/// The limit every run gets.
const LIMIT: Duration = Duration::from_secs(1);

/// What a run may take beyond [`LIMIT`] here. The promise in docs/bad-input.md is
/// max(0.1 s, 2 % of the limit) for the solver on an idle machine; this test allows more
/// because CI runs it on a loaded 2-core machine beside other test threads (a run is
/// descheduled for tens of milliseconds at a time there), while an overrun of the kind this
/// test guards against (a loop with no clock check) costs seconds.
const TEST_MARGIN: Duration = Duration::from_millis(400);

/// A small linear congruential stream, so the instances need no random crate.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
}

/// A matrix instance of `n` single-mode cells with `cost(i, j)` off the diagonal.
fn matrix(
    name: &str,
    n: usize,
    mut cost: impl FnMut(usize, usize) -> f64,
    precedence: Vec<(usize, usize)>,
) -> Instance {
    let costs = (0..n * n)
        .map(|k| {
            if k / n == k % n {
                0.0
            } else {
                cost(k / n, k % n)
            }
        })
        .collect();
    Instance {
        name: name.into(),
        cells: (0..n)
            .map(|i| Cell::new(i.to_string(), "", vec![Mode::default()]))
            .collect(),
        precedence,
        matrix: Some(CostMatrix { size: n, costs }),
        ..Instance::default()
    }
}

/// A geometric instance with one tool: closed contours with the given start points.
fn geometric(name: &str, cells: Vec<Vec<Point3>>) -> Instance {
    Instance {
        name: name.into(),
        machine: Machine::default(),
        tools: vec![Tool {
            id: "T1".into(),
            diameter: 6.0,
            name: None,
            feed: None,
        }],
        cells: cells
            .into_iter()
            .enumerate()
            .map(|(i, pts)| {
                let mut c = Cell::new(
                    format!("c{i}"),
                    "T1",
                    pts.into_iter().map(Mode::closed).collect(),
                );
                c.cut_length = 10.0;
                c
            })
            .collect(),
        ..Instance::default()
    }
}

/// The degenerate instances, each valid.
fn instances() -> Vec<Instance> {
    let mut r = Lcg(7);
    let limit = cellseq::validate::MAX_MATRIX_COST;
    let at = |x: f64, y: f64| Point3::new(x, y, -1.0);
    let big = cellseq::validate::MAX_COORD * 0.99;
    let mut many = vec![vec![at(0.0, 0.0)]; 20];
    many[7] = (0..3000)
        .map(|k| {
            let a = k as f64 * std::f64::consts::TAU / 3000.0;
            at(big * a.cos(), big * a.sin())
        })
        .collect();
    let kv = |s: &[(&str, &str)]| -> BTreeMap<String, String> {
        s.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let free = [("n", "398"), ("c", "100"), ("p", "0")];
    let v = vec![
        matrix("one cell", 1, |_, _| 0.0, vec![]),
        matrix("two cells", 2, |i, _| i as f64, vec![]),
        matrix("all zero", 60, |_, _| 0.0, vec![]),
        matrix("all equal", 60, |_, _| 7.0, vec![(3, 9), (9, 20)]),
        matrix(
            "costs at the limits",
            60,
            |_, _| {
                if r.next().is_multiple_of(2) {
                    0.0
                } else {
                    limit
                }
            },
            vec![(1, 2)],
        ),
        matrix(
            "full chain",
            60,
            |i, j| ((i * 31 + j * 17) % 11) as f64,
            (0..59).map(|i| (i, i + 1)).collect(),
        ),
        geometric("coincident points", vec![vec![at(5.0, 5.0)]; 60]),
        geometric("one cell with 3000 modes", many),
        generate("random-sop", &kv(&free), 1).expect("random-sop generates"),
    ];
    for inst in &v {
        validate(inst, &inst.name).unwrap_or_else(|e| panic!("{}: {e}", inst.name));
    }
    v
}

/// True when solver `needs` applies to `inst`.
fn applies(needs: Needs, inst: &Instance) -> bool {
    match needs {
        Needs::Any => true,
        Needs::Geometric => !inst.is_matrix(),
        Needs::Matrix => inst.is_matrix(),
    }
}

#[test]
fn every_solver_keeps_a_one_second_limit_on_degenerate_instances() {
    let insts = instances();
    let trace = std::env::var_os("CELLSEQ_TIME_TRACE").is_some();
    let budget = Budget {
        time_limit: Some(LIMIT),
        max_evals: None,
    };
    let none = BTreeMap::new();
    let mut failures = Vec::new();
    for info in registry() {
        for inst in insts.iter().filter(|i| applies(info.caps.needs, i)) {
            let obj = inst.default_objective();
            let t0 = Instant::now();
            let r = run(info.name, inst, obj, &none, 1, budget, &mut NoObserver);
            let wall = t0.elapsed();
            if trace {
                eprintln!(
                    "{:>12} {:>28}: {:.3} s",
                    info.name,
                    inst.name,
                    wall.as_secs_f64()
                );
            }
            let what = format!("{} on {}", info.name, inst.name);
            if wall > LIMIT + TEST_MARGIN {
                failures.push(format!("{what}: {:.3} s", wall.as_secs_f64()));
            }
            match r {
                Ok(r) => {
                    if let Err(v) = check(inst, &r.outcome.sequence, obj) {
                        failures.push(format!("{what}: infeasible: {v}"));
                    }
                }
                // an exact solver without a warm start has no answer before its proof: it
                // refuses, in time, an instance beyond its range or its budget
                Err(e) if info.caps.exact && !info.warm_start() => {
                    let e = e.to_string();
                    if !(e.contains("budget") || e.contains("accepts at most")) {
                        failures.push(format!("{what}: {e}"));
                    }
                }
                Err(e) => failures.push(format!("{what}: {e}")),
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The command as a user runs it on the defect's regime (400 cells, costs 0–100, no inner
/// precedence): `solve --time-limit 1` with the default `auto`, with `beam` (which ran
/// 25.6 s and 635 MB there) and with `atsp` (whose branch and bound checks the clock before
/// each augmenting path) ends within the limit and the margin, reading the file and the
/// lower bound after the solve included, and reports a checked result.
#[test]
fn solve_keeps_its_limit_on_a_free_small_cost_instance() {
    use crate::common::{cellseq, run, s, stderr};
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("free400.sop");
    let g = run(&[
        "generate",
        "random-sop",
        "--param",
        "n=398",
        "--param",
        "c=100",
        "--param",
        "p=0",
        "--seed",
        "2",
        "-o",
        s(&file),
    ]);
    assert!(g.status.success(), "{}", stderr(&g));
    for solver in ["auto", "beam", "atsp"] {
        let t0 = Instant::now();
        let o = cellseq()
            .args([
                "solve",
                s(&file),
                "--solver",
                solver,
                "--time-limit",
                "1",
                "--json",
            ])
            .output()
            .unwrap();
        let wall = t0.elapsed();
        assert!(o.status.success(), "{solver}: {}", stderr(&o));
        assert!(
            wall <= LIMIT + TEST_MARGIN,
            "{solver}: solve --time-limit 1 took {:.3} s",
            wall.as_secs_f64()
        );
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["feasible"], true, "{solver}");
    }
}

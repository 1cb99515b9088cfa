//! Conformance suite run over every registered solver: feasibility on small fixtures,
//! determinism under an evaluation budget, budget respected, improvement solvers never worse
//! than their greedy start, reported cost equal to the checker's (enforced by `run`).

use cellseq::formats::load_instance;
use cellseq::generate::generate;
use cellseq::model::Instance;
use cellseq::solvers::{Budget, NoObserver, registry, run};
use std::collections::BTreeMap;
use std::path::Path;

fn fixtures() -> Vec<Instance> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("instances");
    let mut v: Vec<Instance> = [
        "tsplib-sop/ESC07.sop",
        "tsplib-sop/br17.10.sop",
        "tsplib-sop/ESC25.sop",
        "pcgtsplib/ESC12.pcglns",
    ]
    .iter()
    .map(|f| load_instance(&root.join(f)).expect("fixture loads"))
    .collect();
    let kv = |s: &[(&str, &str)]| -> BTreeMap<String, String> {
        s.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    v.push(
        generate(
            "uniform",
            &kv(&[
                ("n", "30"),
                ("modes", "3"),
                ("closed", "0.4"),
                ("tools", "3"),
                ("density", "0.05"),
            ]),
            7,
        )
        .unwrap(),
    );
    v.push(
        generate(
            "uniform",
            &kv(&[("n", "25"), ("tools", "2"), ("layers", "2"), ("preds", "2")]),
            3,
        )
        .unwrap(),
    );
    v
}

const IMPROVERS: &[&str] = &[
    "two-opt",
    "local-search",
    "sa",
    "tabu",
    "aco",
    "eacs",
    "ils",
    "reopt",
];

fn budget(evals: u64) -> Budget {
    Budget {
        time_limit: None,
        max_evals: Some(evals),
    }
}

#[test]
fn every_solver_is_feasible_deterministic_and_within_budget() {
    let insts = fixtures();
    let none = BTreeMap::new();
    for info in registry() {
        for inst in &insts {
            if info.name == "exact" && inst.n() > 10 {
                continue;
            }
            let obj = inst.default_objective();
            let max = 200_000u64;
            // run() checks feasibility and that the reported cost equals the checker's
            let a = run(info.name, inst, obj, &none, 5, budget(max), &mut NoObserver)
                .unwrap_or_else(|e| panic!("{} on {}: {e}", info.name, inst.name));
            let b = run(info.name, inst, obj, &none, 5, budget(max), &mut NoObserver).unwrap();
            assert_eq!(
                a.outcome.sequence, b.outcome.sequence,
                "{} not deterministic on {}",
                info.name, inst.name
            );
            assert_eq!(a.report.cost, b.report.cost);
            if IMPROVERS.contains(&info.name) {
                // one pass or construction may overshoot the budget, but not wildly
                assert!(
                    a.evaluations <= 2 * max + 100_000,
                    "{} used {} evaluations on {}",
                    info.name,
                    a.evaluations,
                    inst.name
                );
                let g = run("greedy", inst, obj, &none, 5, budget(max), &mut NoObserver).unwrap();
                assert!(
                    a.report.cost <= g.report.cost + 1e-6 * g.report.cost.abs().max(1.0),
                    "{} ended worse than greedy on {}: {} > {}",
                    info.name,
                    inst.name,
                    a.report.cost,
                    g.report.cost
                );
            }
        }
    }
}

#[test]
fn tiny_budget_still_returns_a_feasible_sequence() {
    let insts = fixtures();
    let none = BTreeMap::new();
    for name in IMPROVERS.iter().chain(["process", "rules"].iter()) {
        if registry().iter().all(|i| i.name != *name) {
            continue;
        }
        for inst in &insts {
            run(
                name,
                inst,
                inst.default_objective(),
                &none,
                1,
                budget(10),
                &mut NoObserver,
            )
            .unwrap_or_else(|e| panic!("{name} on {}: {e}", inst.name));
        }
    }
}

#[test]
fn improvers_reach_small_gaps_on_esc25() {
    // ESC25: best known 1681 (instances/tsplib-sop/bks.csv)
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("instances/tsplib-sop/ESC25.sop");
    let inst = load_instance(&root).unwrap();
    let none = BTreeMap::new();
    for name in ["sa", "tabu", "aco"] {
        let r = run(
            name,
            &inst,
            inst.default_objective(),
            &none,
            1,
            budget(5_000_000),
            &mut NoObserver,
        )
        .unwrap();
        assert!(r.report.cost <= 1681.0 * 1.05, "{name}: {}", r.report.cost);
    }
}

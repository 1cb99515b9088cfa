//! Conformance of every registered solver (the registry's `SolverKind::ALL`, so a new solver is
//! covered automatically): feasibility on small fixtures, determinism under an
//! evaluation budget, the budget respected, improvement solvers never worse than their greedy
//! start, a feasible sequence even from a tiny budget, reported cost equal to the checker's
//! (enforced by `run`). A solver's test checks every fixture and reports all its failures
//! together.

use crate::common::instance_path;
use cellseq::SolverKind;
use cellseq::formats::load_instance;
use cellseq::generate::generate;
use cellseq::model::Instance;
use cellseq::solvers::{Budget, NoObserver, run};
use std::collections::BTreeMap;

/// What a solver can do, as far as these tests need to know.
struct Caps {
    /// Starts from a construction (greedy or better) and only improves on it.
    improves_start: bool,
    /// Proves optimality or refuses: no answer from a budget too small for a proof.
    exact: bool,
}

/// The capabilities of solver `name`: the one place the tests read them.
fn caps(name: &str) -> Caps {
    let info = cellseq::solvers::find(name).expect("a registry solver");
    Caps {
        improves_start: info.caps.improves,
        // an exact solver with its own warm start (beam) answers from any budget; one without
        // (exact) has no answer before its proof
        exact: info.caps.exact && !info.warm_start(),
    }
}

fn fixtures() -> Vec<Instance> {
    let mut v: Vec<Instance> = [
        "tsplib-sop/ESC07.sop",
        "tsplib-sop/br17.10.sop",
        "tsplib-sop/ESC25.sop",
        "pcgtsplib/ESC12.pcglns",
    ]
    .iter()
    .map(|f| load_instance(&instance_path(f)).expect("fixture loads"))
    .collect();
    let kv = |s: &[(&str, &str)]| -> BTreeMap<String, String> {
        s.iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect()
    };
    let uniform = [
        ("n", "30"),
        ("modes", "3"),
        ("closed", "0.4"),
        ("tools", "3"),
        ("density", "0.05"),
    ];
    v.push(generate("uniform", &kv(&uniform), 7).unwrap());
    let layered = [("n", "25"), ("tools", "2"), ("layers", "2"), ("preds", "2")];
    v.push(generate("uniform", &kv(&layered), 3).unwrap());
    v
}

fn budget(evals: u64) -> Budget {
    Budget {
        time_limit: None,
        max_evals: Some(evals),
    }
}

/// Every failure of solver `name` with parameters `params` on the fixtures, as messages.
fn failures(name: &str, params: &BTreeMap<String, String>) -> Vec<String> {
    let caps = caps(name);
    let none = BTreeMap::new();
    let max = 200_000u64;
    let mut out = Vec::new();
    for inst in &fixtures() {
        if caps.exact && inst.n() > 10 {
            continue;
        }
        let obj = inst.default_objective();
        let go = |solver: &str, evals: u64, seed: u64| {
            run(
                solver,
                inst,
                obj,
                if solver == name { params } else { &none },
                seed,
                budget(evals),
                &mut NoObserver,
            )
        };
        // run() checks feasibility and that the reported cost equals the checker's
        let (a, b) = match (go(name, max, 5), go(name, max, 5)) {
            (Ok(a), Ok(b)) => (a, b),
            (Err(e), _) | (_, Err(e)) => {
                out.push(format!("{name} on {}: {e}", inst.name));
                continue;
            }
        };
        if a.outcome.sequence != b.outcome.sequence || a.report.cost != b.report.cost {
            out.push(format!("{name} not deterministic on {}", inst.name));
        }
        if caps.improves_start {
            // one pass or construction may overshoot the budget, but not wildly
            if a.evaluations > 2 * max + 100_000 {
                out.push(format!(
                    "{name} used {} evaluations of {max} on {}",
                    a.evaluations, inst.name
                ));
            }
            let g = go("greedy", max, 5).expect("greedy runs");
            if a.report.cost > g.report.cost + 1e-6 * g.report.cost.abs().max(1.0) {
                out.push(format!(
                    "{name} ended worse than greedy on {}: {} > {}",
                    inst.name, a.report.cost, g.report.cost
                ));
            }
        }
        if !caps.exact
            && let Err(e) = go(name, 10, 1)
        {
            out.push(format!("{name} with 10 evaluations on {}: {e}", inst.name));
        }
    }
    out
}

/// Runs the conformance checks of one solver with `params` and fails with all of its failures.
fn conforms_with(name: &str, params: &[(&str, &str)]) {
    let params = params
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let f = failures(name, &params);
    assert!(f.is_empty(), "{} failures:\n{}", f.len(), f.join("\n"));
}

/// `ils` with several walks (their scattered starts, the turns, the per-walk records and the
/// walks dropped by halves) and
/// with a set SOP-3-exchange block length:
/// the same checks as every solver's defaults.
#[test]
fn ils_with_walks_conforms() {
    conforms_with("ils", &[("walks", "3")]);
    conforms_with(
        "ils",
        &[("walks", "4"), ("perturb", "swap"), ("accept", "0.01")],
    );
    // walks dropped by halves as the budget goes (the `symmetric` rule's setting)
    conforms_with(
        "ils",
        &[("walks", "8"), ("halve", "0.15"), ("accept", "0.01")],
    );
    // a short SOP-3-exchange block, and a huge one (capped to the path)
    conforms_with("ils", &[("max-block", "3")]);
    conforms_with("ils", &[("max-block", "10000000")]);
}

/// Every registry solver with its default parameters: the list is `SolverKind::ALL`, derived
/// from the registry, so a new solver is covered without a line here. The solvers run in
/// parallel and every failure of every solver is reported together.
#[test]
fn every_registry_solver_conforms() {
    use rayon::prelude::*;
    let none = BTreeMap::new();
    let f: Vec<String> = SolverKind::ALL
        .par_iter()
        .flat_map(|k| failures(k.name(), &none))
        .collect();
    assert!(f.is_empty(), "{} failures:\n{}", f.len(), f.join("\n"));
}

#[test]
fn improvers_reach_small_gaps_on_esc25() {
    // ESC25: best known 1681 (instances/tsplib-sop/bks.csv)
    let inst = load_instance(&instance_path("tsplib-sop/ESC25.sop")).unwrap();
    let none = BTreeMap::new();
    let mut f = Vec::new();
    for name in ["sa", "tabu", "aco", "gls"] {
        let obj = inst.default_objective();
        let r = run(
            name,
            &inst,
            obj,
            &none,
            1,
            budget(5_000_000),
            &mut NoObserver,
        )
        .unwrap();
        if r.report.cost > 1681.0 * 1.05 {
            f.push(format!("{name}: {}", r.report.cost));
        }
    }
    assert!(f.is_empty(), "more than 5 % above 1681: {}", f.join(", "));
}

//! `greedy-edge` (greedy matching construction): feasible and complete on every kind of
//! geometric cell, cheaper than the nearest-neighbour greedy where it applies, and the
//! greedy sequence itself where it does not.

use cellseq::generate::generate;
use cellseq::solvers::{Budget, NoObserver, run};
use proptest::prelude::*;
use std::collections::BTreeMap;

fn kv(pairs: &[(&str, String)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(30))]
    /// Whatever the cells (open, reversible or not, closed with several start points), the
    /// result passes the independent checker (`run` checks it) and is deterministic.
    #[test]
    fn feasible_and_deterministic(seed in 0u64..1000, n in 1usize..300, modes in 1usize..4,
                                  closed in 0.0f64..1.0, reversible in any::<bool>(), lift in 0.0f64..10.0) {
        let p = kv(&[
            ("n", n.to_string()),
            ("modes", modes.to_string()),
            ("closed", closed.to_string()),
            ("reversible", reversible.to_string()),
            ("lift", lift.to_string()),
        ]);
        let inst = generate("uniform", &p, seed).unwrap();
        let obj = inst.default_objective();
        let none = BTreeMap::new();
        let a = run("greedy-edge", &inst, obj, &none, 1, Budget::default(), &mut NoObserver).unwrap();
        let b = run("greedy-edge", &inst, obj, &none, 1, Budget::default(), &mut NoObserver).unwrap();
        prop_assert_eq!(a.outcome.sequence.len(), n);
        prop_assert_eq!(a.outcome.sequence, b.outcome.sequence);
    }
}

/// The checked result of `solver` on `inst` (no budget, seed 1).
fn solve(
    solver: &str,
    inst: &cellseq::model::Instance,
    obj: cellseq::model::Objective,
) -> cellseq::solvers::RunResult {
    run(
        solver,
        inst,
        obj,
        &BTreeMap::new(),
        1,
        Budget::default(),
        &mut NoObserver,
    )
    .unwrap()
}

#[test]
fn beats_nearest_neighbour_on_uniform_strokes() {
    for seed in 1..4 {
        // the density of 10^5 cells on a 1 m square (strokes much longer than the spacing)
        let p = kv(&[
            ("n", "3000".into()),
            ("size", "175".into()),
            ("lift", "0".into()),
        ]);
        let inst = generate("uniform", &p, seed).unwrap();
        let obj = cellseq::model::Objective::Air;
        let (e, g) = (
            solve("greedy-edge", &inst, obj),
            solve("greedy", &inst, obj),
        );
        assert!(
            e.report.cost < 0.95 * g.report.cost,
            "seed {seed}: greedy-edge {} vs greedy {}",
            e.report.cost,
            g.report.cost
        );
    }
}

#[test]
fn falls_back_to_greedy_under_precedence_or_several_tools() {
    for p in [
        kv(&[("n", "200".into()), ("preds", "1".into())]),
        kv(&[("n", "200".into()), ("tools", "3".into())]),
    ] {
        let inst = generate("uniform", &p, 7).unwrap();
        let obj = inst.default_objective();
        let (e, g) = (
            solve("greedy-edge", &inst, obj),
            solve("greedy", &inst, obj),
        );
        assert_eq!(e.outcome.sequence, g.outcome.sequence);
    }
}

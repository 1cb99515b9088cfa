//! `local-search` on the two-level list (`two-level=on`): checked results (`run` checks every
//! one), deterministic for a seed and an evaluation budget, better than the greedy start,
//! with and without precedence.

use cellseq::generate::generate;
use cellseq::model::Objective;
use cellseq::solvers::{Budget, NoObserver, run};
use std::collections::BTreeMap;

fn kv(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

#[test]
fn two_level_local_search_is_checked_deterministic_and_improves() {
    for preds in ["0", "1"] {
        let inst = generate(
            "uniform",
            &kv(&[("n", "3000"), ("lift", "0"), ("preds", preds)]),
            3,
        )
        .unwrap();
        let budget = Budget {
            max_evals: Some(3_000_000),
            ..Budget::default()
        };
        let p = kv(&[("two-level", "on")]);
        let solve = |p: &BTreeMap<String, String>| {
            run(
                "local-search",
                &inst,
                Objective::Air,
                p,
                7,
                budget,
                &mut NoObserver,
            )
            .unwrap()
        };
        let a = solve(&p);
        let b = solve(&p);
        assert_eq!(a.outcome.sequence, b.outcome.sequence);
        let greedy = run(
            "greedy",
            &inst,
            Objective::Air,
            &BTreeMap::new(),
            1,
            Budget::default(),
            &mut NoObserver,
        )
        .unwrap();
        assert!(
            a.report.air_length < 0.95 * greedy.report.air_length,
            "preds={preds}: {} against greedy {}",
            a.report.air_length,
            greedy.report.air_length
        );
        // the array path gives a different (also checked) result: the switch is live
        let off = solve(&kv(&[("two-level", "off")]));
        assert_ne!(off.outcome.sequence, a.outcome.sequence);
    }
}

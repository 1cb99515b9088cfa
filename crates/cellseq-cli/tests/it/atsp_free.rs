//! The free asymmetric case: `auto` routes matrix instances without precedence (apart from a
//! fixed start and end) to the `atsp` solver and keeps its other cases, and `atsp` results
//! pass the independent checker and stay above the assignment bound.

use cellseq::cost::CostModel;
use cellseq::engine::atsp::free_density;
use cellseq::model::{Cell, CostMatrix, Instance, Mode, Objective};
use cellseq::solvers::auto::Auto;
use cellseq::solvers::{Budget, NoObserver, Params, find, run};
use std::collections::BTreeMap;

/// A random SOP-like instance: cell 0 first, cell n−1 last, integer costs in 0..=c from a
/// small linear congruential generator, and `pairs` extra precedence pairs.
fn instance(n: usize, c: u64, seed: u64, pairs: &[(usize, usize)]) -> Instance {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let costs = (0..n * n)
        .map(|k| {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            if k / n == k % n {
                0.0
            } else {
                ((x >> 33) % (c + 1)) as f64
            }
        })
        .collect();
    Instance {
        name: format!("free{n}"),
        cells: (0..n)
            .map(|i| Cell::new(i.to_string(), "", vec![Mode::default()]))
            .collect(),
        precedence: pairs.to_vec(),
        matrix: Some(CostMatrix { size: n, costs }),
        first: Some(0),
        last: Some(n - 1),
        ..Instance::default()
    }
}

fn auto_default() -> Auto {
    let info = find("auto").unwrap();
    Auto::from_params(&Params::new("auto", info.params, &BTreeMap::new()).unwrap()).unwrap()
}

#[test]
fn auto_routes_free_instances_to_atsp_and_keeps_the_rest() {
    let free = CostModel::new(&instance(80, 100, 1, &[]), Objective::Matrix);
    assert_eq!(free_density(&free), 0.0);
    assert_eq!(auto_default().choose(&free).rule, "free");
    // a chain through a tenth of the cells: far above the free threshold
    let chain: Vec<(usize, usize)> = (1..40).map(|i| (i, i + 1)).collect();
    let tied = CostModel::new(&instance(80, 100, 1, &chain), Objective::Matrix);
    assert!(free_density(&tied) > 0.01);
    // random costs (cost_spread 0.5 and above): the sparse rule for such costs
    assert_eq!(auto_default().choose(&tied).rule, "sparse-random");
}

#[test]
fn atsp_results_are_checked_deterministic_and_above_the_assignment_bound() {
    let inst = instance(120, 100, 3, &[(5, 9), (9, 30)]);
    let budget = Budget {
        time_limit: None,
        max_evals: Some(300_000),
    };
    let go = |name: &str| {
        run(
            name,
            &inst,
            Objective::Matrix,
            &BTreeMap::new(),
            11,
            budget,
            &mut NoObserver,
        )
        .unwrap()
    };
    let a = go("atsp");
    let b = go("atsp");
    assert_eq!(a.outcome.sequence, b.outcome.sequence);
    let model = CostModel::new(&inst, Objective::Matrix);
    let lb = cellseq::bound::assignment::hungarian(model.n(), |i, j| {
        if i == j {
            f64::INFINITY
        } else {
            model.arc(i, 0, j, 0)
        }
    })
    .unwrap()
    .0;
    // the path plus a free return is a cycle cover: the assignment bounds it from below
    assert!(a.report.cost + model.arc(model.n() - 1, 0, 0, 0) >= lb - 1e-9);
    // greedy is the start it is never worse than
    let g = go("greedy");
    assert!(a.report.cost <= g.report.cost);
}

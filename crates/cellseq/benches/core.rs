//! Core benches: full evaluation of a 100k-cell sequence, greedy on 10k / 100k cells, and
//! greedy against insertion on 100k cells with one random predecessor each.
//!
//! `cargo bench --bench core`; compare commits with `-- --save-baseline NAME` / `--baseline NAME`.

use cellseq::cost::CostModel;
use cellseq::model::{Instance, Objective, Visit};
use cellseq::solvers::{self, Budget, NoObserver};
use criterion::{Criterion, criterion_group, criterion_main};
use std::collections::BTreeMap;
use std::hint::black_box;

fn uniform(n: usize, tools: usize) -> Instance {
    let p: BTreeMap<String, String> = [("n", n.to_string()), ("tools", tools.to_string())]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
    cellseq::generate::generate("uniform", &p, 1).expect("uniform instance")
}

fn evaluation(c: &mut Criterion) {
    let inst = uniform(100_000, 3);
    let model = CostModel::new(&inst, Objective::Time);
    let seq: Vec<Visit> = (0..inst.n()).map(|i| Visit::new(i, 0)).collect();
    let mut g = c.benchmark_group("evaluate");
    g.bench_function("cost_model_100k", |b| {
        b.iter(|| black_box(model.evaluate(black_box(&seq))))
    });
    g.bench_function("checker_100k", |b| {
        b.iter(|| black_box(cellseq::check(&inst, black_box(&seq), Objective::Time).unwrap()))
    });
    g.finish();
}

fn greedy(c: &mut Criterion) {
    let mut g = c.benchmark_group("greedy");
    g.sample_size(10);
    for n in [10_000usize, 100_000] {
        let inst = uniform(n, 3);
        g.bench_function(format!("uniform_{n}"), |b| {
            b.iter(|| {
                solvers::run(
                    "greedy",
                    &inst,
                    Objective::Time,
                    &BTreeMap::new(),
                    1,
                    Budget::default(),
                    &mut NoObserver,
                )
                .unwrap()
            })
        });
    }
    g.finish();
}

/// The two constructions `local-search` starts from on sparse precedence (`uniform`, 10^5
/// cells, `preds=1`, lift 0, air length).
fn sparse_precedence(c: &mut Criterion) {
    let p: BTreeMap<String, String> = [("n", "100000"), ("preds", "1"), ("lift", "0")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let inst = cellseq::generate::generate("uniform", &p, 1).expect("uniform instance");
    let mut g = c.benchmark_group("sparse_precedence_100k");
    g.sample_size(10);
    for solver in ["greedy", "insertion"] {
        g.bench_function(solver, |b| {
            b.iter(|| {
                solvers::run(
                    solver,
                    &inst,
                    Objective::Air,
                    &BTreeMap::new(),
                    1,
                    Budget::default(),
                    &mut NoObserver,
                )
                .unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, evaluation, greedy, sparse_precedence);
criterion_main!(benches);

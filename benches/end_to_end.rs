//! A small end-to-end solve: generate a uniform instance, run every registered solver through
//! `solvers::run` (solve + independent check) with an evaluation budget; plus one harness trial.
//!
//! `cargo bench --bench end_to_end -- --save-baseline main` on one commit, then
//! `cargo bench --bench end_to_end -- --baseline main` on another to compare.

use cellseq::solvers::{self, Budget, NoObserver};
use criterion::{Criterion, criterion_group, criterion_main};
use std::collections::BTreeMap;
use std::hint::black_box;

fn end_to_end(c: &mut Criterion) {
    // criterion's plots go through plotters, which (ab_glyph feature) needs a registered font
    cellseq::harness::plots::register();
    let params: BTreeMap<String, String> = [("n", "60"), ("tools", "3"), ("density", "0.02")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let inst = cellseq::generate::generate("uniform", &params, 1).expect("generator");
    let objective = inst.default_objective();
    let budget = Budget {
        time_limit: None,
        max_evals: Some(200_000),
    };
    let mut g = c.benchmark_group("end_to_end_n60");
    g.sample_size(10);
    for s in solvers::registry() {
        // solvers that refuse this instance (e.g. exact beyond its limit) are skipped
        if solvers::run(
            s.name,
            &inst,
            objective,
            &BTreeMap::new(),
            1,
            budget,
            &mut NoObserver,
        )
        .is_err()
        {
            continue;
        }
        g.bench_function(s.name, |b| {
            b.iter(|| {
                solvers::run(
                    s.name,
                    black_box(&inst),
                    objective,
                    &BTreeMap::new(),
                    1,
                    budget,
                    &mut NoObserver,
                )
                .expect("solve")
            })
        });
    }
    g.finish();
    let plan = cellseq::harness::plan::Plan::parse(
        "bench",
        "name = \"bench\"\n[budget]\nevaluations = 200000\n[[instances]]\ngenerator = \"uniform\"\ngrid = { n = 60, tools = 3 }\n[[solvers]]\nname = \"greedy\"\n",
        std::path::Path::new("."),
    )
    .expect("plan");
    let prep = cellseq::harness::run::prepare(&plan, 0).expect("prepare");
    let trial = plan.trials().remove(0);
    c.bench_function("harness_trial_greedy_n60", |b| {
        b.iter(|| cellseq::harness::run::run_trial(&plan, &prep, black_box(&trial), 0.01))
    });
}

criterion_group!(benches, end_to_end);
criterion_main!(benches);

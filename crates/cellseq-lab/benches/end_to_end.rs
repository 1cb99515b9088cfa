//! A small end-to-end solve: generate a uniform instance, run every registered solver through
//! `solvers::run` (solve + independent check) with an evaluation budget; plus one harness trial,
//! and the input steps that once grew with a product of sizes (issue 26): reading a DXF of two
//! long entities, and the containment test between them.
//!
//! `cargo bench --bench end_to_end -- --save-baseline main` on one commit, then
//! `cargo bench --bench end_to_end -- --baseline main` on another to compare.

use cellseq::solvers::{self, Budget, NoObserver};
use criterion::{Criterion, criterion_group, criterion_main};
use std::collections::BTreeMap;
use std::hint::black_box;

fn end_to_end(c: &mut Criterion) {
    // criterion's plots go through plotters, which (ab_glyph feature) needs a registered font
    cellseq_lab::plot::register_font();
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
    let plan = cellseq_lab::plan::Plan::parse(
        "bench",
        "name = \"bench\"\n[budget]\nevaluations = 200000\n[[instances]]\ngenerator = \"uniform\"\ngrid = { n = 60, tools = 3 }\n[[solvers]]\nname = \"greedy\"\n",
        std::path::Path::new("."),
    )
    .expect("plan");
    let prep = cellseq_lab::run::prepare(&plan, 0).expect("prepare");
    let trial = plan.trials().remove(0);
    c.bench_function("harness_trial_greedy_n60", |b| {
        b.iter(|| cellseq_lab::run::run_trial(&plan, &prep, black_box(&trial), 0.01))
    });
}

/// A DXF of two entities: a closed LWPOLYLINE of `n` vertices (bulged every 7th) and a cubic
/// SPLINE of `m` control points inside it.
fn two_entity_dxf(n: usize, m: usize) -> String {
    use std::fmt::Write;
    let mut s = String::from(
        "0\nSECTION\n2\nHEADER\n9\n$INSUNITS\n70\n4\n0\nENDSEC\n0\nSECTION\n2\nENTITIES\n",
    );
    let _ = write!(s, "0\nLWPOLYLINE\n8\nA\n90\n{n}\n70\n1\n");
    for k in 0..n {
        let a = std::f64::consts::TAU * k as f64 / n as f64;
        let r = 100.0 + 8.0 * (37.0 * a).sin() + 3.0 * (401.0 * a).sin();
        let _ = write!(s, "10\n{:.4}\n20\n{:.4}\n", r * a.cos(), r * a.sin());
        if k % 7 == 0 {
            s.push_str("42\n0.2\n");
        }
    }
    let deg = 3;
    let _ = write!(
        s,
        "0\nSPLINE\n8\nA\n70\n8\n71\n{deg}\n72\n{}\n73\n{m}\n",
        m + deg + 1
    );
    for k in 0..m + deg + 1 {
        let _ = write!(s, "40\n{}\n", k.saturating_sub(deg).min(m - deg));
    }
    for k in 0..m {
        let a = std::f64::consts::TAU * k as f64 / m as f64;
        let (x, y) = (
            60.0 * (3.0 * a).cos() + k as f64 * 1e-3,
            60.0 * (5.0 * a).sin(),
        );
        let _ = write!(s, "10\n{x:.4}\n20\n{y:.4}\n30\n0\n");
    }
    s.push_str("0\nENDSEC\n0\nEOF\n");
    s
}

fn inputs(c: &mut Criterion) {
    use cellseq_programs::dxf;
    let text = two_entity_dxf(100_000, 20_000);
    let mut g = c.benchmark_group("inputs");
    g.sample_size(10);
    g.bench_function(
        "dxf read: 2 entities (100k-vertex polyline, 20k-point spline)",
        |b| {
            b.iter(|| {
                dxf::read(
                    "two.dxf",
                    black_box(text.as_bytes()),
                    dxf::ReadOptions::default(),
                )
            })
        },
    );
    let d = dxf::read("two.dxf", text.as_bytes(), dxf::ReadOptions::default()).expect("reads");
    let scope: Vec<usize> = (0..d.strokes.len()).collect();
    g.bench_function("containment: the 2 strokes (100k + 160k points)", |b| {
        b.iter(|| cellseq_programs::optimize::strokes::containment(black_box(&d), &scope, 1e-3))
    });
    g.finish();
}

criterion_group!(benches, end_to_end, inputs);
criterion_main!(benches);

//! Engine benchmarks: delta evaluations per second, one local-search pass on 10k cells, the
//! two-level descent on 10k points (with and without 3-opt), the Lin–Kernighan descent on a
//! symmetric matrix with precedence, the two-way SOP-3-exchange descent on a symmetric matrix
//! with sparse precedence and its pass at a local optimum (without, sparse and time-window
//! precedence), one SA chain, one tabu iteration, one ant construction; `atsp` to its
//! branch-and-bound proof on a 300-cell random matrix with costs 0–100; 50 subgradient steps
//! of the position-indexed path bound on a 100-cell symmetric matrix, and the beam to widths
//! 256 and 4096 there; `ils` for 10^7 evaluations on a dense 340-cell `time-window` instance.

use cellseq::bound::cells::CellGraph;
use cellseq::bound::qpath::QPath;
use cellseq::bound::sec::sec_bound;
use cellseq::cost::CostModel;
use cellseq::engine::large::Large;
use cellseq::engine::lk::Lk;
use cellseq::engine::moves::sop3_delta;
use cellseq::engine::sop3x::{TwoWay, sop3_two_way};
use cellseq::engine::vnd::Search;
use cellseq::engine::{Costs, Neighbours, Solution};
use cellseq::generate::generate;
use cellseq::model::Instance;
use cellseq::precedence::closure::Closure;
use cellseq::solvers::aco::{Aco, Pheromone};
use cellseq::solvers::sa::Anneal;
use cellseq::solvers::tabu::{TabuList, tabu_step};
use cellseq::solvers::{Budget, Context, NoObserver, RunResult, greedy, run};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::BTreeMap;
use std::hint::black_box;

/// Generator parameters as key–value pairs.
type Params<'a> = &'a [(&'a str, &'a str)];

/// Key–value pairs as the owned map that generators and solvers take.
fn strings(kv: &[(&str, &str)]) -> BTreeMap<String, String> {
    kv.iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

/// A generated instance of `kind` with these parameters, seed 1.
fn generated(kind: &str, params: &[(&str, &str)]) -> Instance {
    generate(kind, &strings(params), 1).unwrap()
}

/// `solver` with `params` on `inst`, seed 1, under an evaluation budget of `evals` (large
/// enough that the solver ends on its own).
fn run_to_end(
    solver: &str,
    inst: &Instance,
    params: &BTreeMap<String, String>,
    evals: u64,
) -> RunResult {
    let budget = Budget {
        time_limit: None,
        max_evals: Some(evals),
    };
    run(
        solver,
        inst,
        inst.default_objective(),
        params,
        1,
        budget,
        &mut NoObserver,
    )
    .unwrap()
}

fn uniform(n: usize, extra: &[(&str, &str)]) -> Instance {
    let n = n.to_string();
    let mut params = vec![("n", n.as_str())];
    params.extend_from_slice(extra);
    generated("uniform", &params)
}

fn benches(cr: &mut Criterion) {
    let inst = uniform(
        1000,
        &[
            ("tools", "3"),
            ("modes", "2"),
            ("closed", "0.3"),
            ("preds", "1"),
        ],
    );
    let m = CostModel::new(&inst, inst.default_objective());
    let c = Costs::open(&m);
    let seq = greedy::geometric(&m, &mut |_| {});
    let s0 = Solution::new(&c, &seq);

    let mut g = cr.benchmark_group("engine");
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let triples: Vec<(isize, isize, isize)> = (0..1024)
        .map(|_| {
            let h = rng.random_range(-1..997i64) as isize;
            let i = h + 1 + rng.random_range(0..(997 - h) as i64) as isize;
            let j = i + 1 + rng.random_range(0..(998 - i) as i64) as isize;
            (h, i, j)
        })
        .collect();
    g.throughput(Throughput::Elements(triples.len() as u64));
    g.bench_function("sop3 delta evaluations (1k cells)", |b| {
        b.iter(|| {
            triples
                .iter()
                .map(|&(h, i, j)| sop3_delta(&c, &s0, h, i, j))
                .sum::<f64>()
        })
    });
    g.throughput(Throughput::Elements(1));

    let big = uniform(10_000, &[("tools", "2"), ("preds", "1")]);
    let bm = CostModel::new(&big, big.default_objective());
    let bc = Costs::open(&bm);
    let bseq = greedy::geometric(&bm, &mut |_| {});
    let bs = Solution::new(&bc, &bseq);
    let mut bsearch = Search::new(bc, 8);
    g.sample_size(10);
    g.bench_function("local-search Or-opt pass (10k cells)", |b| {
        b.iter(|| {
            let mut s = bs.clone();
            let mut obs = NoObserver;
            let mut ctx = Context::new(&big, &bm, 1, Budget::default(), &mut obs);
            bsearch.or_opt(&mut s, &mut ctx);
            black_box(s.cost)
        })
    });
    g.bench_function("local-search 2-opt pass (10k cells)", |b| {
        b.iter(|| {
            let mut s = bs.clone();
            let mut obs = NoObserver;
            let mut ctx = Context::new(&big, &bm, 1, Budget::default(), &mut obs);
            bsearch.two_opt(&mut s, &mut ctx);
            black_box(s.cost)
        })
    });

    // the two-level list's descent from the greedy start on 10k points (air): 2-opt and
    // Or-opt, and with the sequential 3-opt moves in place of Or-opt
    let pts = uniform(10_000, &[("closed", "1"), ("length", "0"), ("lift", "0")]);
    let pm = CostModel::new(&pts, cellseq::model::Objective::Air);
    let pc = Costs::open(&pm);
    let ps = Solution::new(&pc, &greedy::geometric(&pm, &mut |_| {}));
    let pnb = Neighbours::new(&pm, 8);
    for (name, three) in [
        ("two-level descent, 2-opt + Or-opt (10k points)", false),
        ("two-level descent, 2-opt + 3-opt (10k points)", true),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut obs = NoObserver;
                let mut ctx = Context::new(&pts, &pm, 1, Budget::default(), &mut obs);
                let mut l = Large::new(pc, &pnb, &ps);
                l.three = three;
                l.optimize(&mut ctx);
                black_box(l.t.cost)
            })
        });
    }

    // Lin–Kernighan chains that may pass through broken precedence pairs (the `ils` repair
    // and polish on symmetric matrices), from the greedy order to an LK optimum: a generated
    // `symmetric` instance, 200 cells, precedence closure density 5 %
    let sym = generated("symmetric", &[("n", "200"), ("c", "1000"), ("p", "5")]);
    let sm = CostModel::new(&sym, sym.default_objective());
    let sc = Costs::open(&sm);
    let ss = Solution::new(&sc, &greedy::matrix(&sm, &mut |_| {}));
    let ssearch = Search::new(sc, 12);
    g.bench_function(
        "Lin-Kernighan descent, penalty chains (symmetric, 200 cells, p = 5 %)",
        |b| {
            b.iter(|| {
                let mut obs = NoObserver;
                let mut ctx = Context::new(&sym, &sm, 1, Budget::default(), &mut obs);
                let mut s = ss.clone();
                let mut lk = Lk::new(&sc, 12, 3);
                lk.penalty = 2.0 * s.cost / 201.0;
                while lk.improve_all(&sc, &ssearch.nb, &mut s, &mut ctx) {}
                black_box(s.cost)
            })
        },
    );

    // SOP-3-exchange, both directions, from every cell of the Or-opt optimum of the greedy
    // order to a local optimum: a generated `symmetric` instance, 100 cells, 1 % precedence
    // (blocks up to the whole path; near the optimum most blocks are skipped by the bound)
    let sop = generated("symmetric", &[("n", "100"), ("c", "500"), ("p", "1")]);
    let om = CostModel::new(&sop, sop.default_objective());
    let oc = Costs::open(&om);
    let mut osearch = Search::new(oc, 12);
    let mut os = Solution::new(&oc, &greedy::matrix(&om, &mut |_| {}));
    {
        let mut obs = NoObserver;
        let mut ctx = Context::new(&sop, &om, 1, Budget::default(), &mut obs);
        osearch.or_opt(&mut os, &mut ctx);
    }
    let every: Vec<u32> = (0..os.n() as u32).collect();
    let mut two_way = TwoWay::default();
    g.bench_function(
        "SOP-3-exchange descent, two-way (symmetric, 100 cells, p = 1 %)",
        |b| {
            b.iter(|| {
                let mut obs = NoObserver;
                let mut ctx = Context::new(&sop, &om, 1, Budget::default(), &mut obs);
                let mut s = os.clone();
                while sop3_two_way(&osearch, &mut two_way, &mut s, &mut ctx, &every) {}
                black_box(s.cost)
            })
        },
    );

    // the same pass at a local optimum (the work after a kick, when no move is left) of a
    // `random-sop` instance without precedence, 300 cells, costs 0-100 (blocks of 64; every
    // scan runs to its block's end), and of the precedence regimes the walks meet:
    // `near-symmetric` with 10 % precedence in the plane (100 cells, blocks up to the path)
    // and `time-window` (350 cells, dense)
    let passes: [(&str, &str, Params); 3] = [
        (
            "random-sop, 300 cells, p = 0",
            "random-sop",
            &[("n", "300"), ("p", "0"), ("c", "100")],
        ),
        (
            "near-symmetric, 100 cells, p = 10 %",
            "near-symmetric",
            &[("n", "100"), ("c", "1000"), ("p", "10"), ("plane", "true")],
        ),
        (
            "time-window, 350 cells, w = 20",
            "time-window",
            &[("n", "350"), ("w", "20")],
        ),
    ];
    for (name, kind, params) in passes {
        let inst = generated(kind, params);
        let fm = CostModel::new(&inst, inst.default_objective());
        let fc = Costs::open(&fm);
        let fsearch = Search::new(fc, 12);
        let mut fs = Solution::new(&fc, &greedy::matrix(&fm, &mut |_| {}));
        let all: Vec<u32> = (0..fs.n() as u32).collect();
        {
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &fm, 1, Budget::default(), &mut obs);
            while sop3_two_way(&fsearch, &mut two_way, &mut fs, &mut ctx, &all) {}
        }
        let id = format!("SOP-3-exchange pass at a local optimum, two-way ({name})");
        g.bench_function(id, |b| {
            b.iter(|| {
                let mut obs = NoObserver;
                let mut ctx = Context::new(&inst, &fm, 1, Budget::default(), &mut obs);
                let mut s = fs.clone();
                let moved = sop3_two_way(&fsearch, &mut two_way, &mut s, &mut ctx, &all);
                assert!(!moved);
                black_box(s.cost)
            })
        });
    }

    let anneal = Anneal {
        chain: 1.0,
        alpha: 0.95,
        accept0: 0.3,
        stall: 1,
        max_chains: 1,
        reheats: 0,
        closed: false,
    };
    g.bench_function("SA chain (L = n = 1000)", |b| {
        b.iter(|| {
            let mut s = s0.clone();
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
            let mut rng = ChaCha8Rng::seed_from_u64(3);
            anneal.run(&mut ctx, &c, &mut s, None, &mut rng);
            black_box(s.cost)
        })
    });

    let search = Search::new(c, 10);
    g.bench_function("tabu iteration (1000 cells, K = 10)", |b| {
        let mut s = s0.clone();
        let mut tabu = TabuList {
            until: vec![0; 1000],
            iter: 0,
            tenure: 55,
        };
        b.iter(|| {
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
            tabu.iter += 1;
            tabu_step(&c, &search, &mut s, &mut tabu, f64::NEG_INFINITY, &mut ctx);
            black_box(s.cost)
        })
    });

    let aco = Aco {
        ants: 1,
        beta: 2.0,
        s: 10.0,
        rho: 0.1,
        phi: 0.01,
        iters: 1,
        stall: 1,
        ls: "none".into(),
        k: 10,
    };
    let mut tau = Pheromone::new(1000, 1.0 / (1000.0 * s0.cost));
    g.bench_function("ant construction (1000 cells)", |b| {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        b.iter(|| {
            let mut obs = NoObserver;
            let mut ctx = Context::new(&inst, &m, 1, Budget::default(), &mut obs);
            black_box(aco.construct(&mut ctx, &mut tau, 1e-6, &mut rng).len())
        })
    });
    g.finish();

    // the atsp solver to its proof on a tie-rich asymmetric matrix: assignment, patching, the
    // Or-3opt walk until it stalls, then the branch and bound until its tree is exhausted
    let free = generated("random-sop", &[("n", "300"), ("c", "100"), ("p", "0")]);
    let mut g = cr.benchmark_group("atsp");
    g.sample_size(10);
    g.bench_function("atsp to a proof (random-sop n = 300, costs 0-100)", |b| {
        b.iter(|| {
            let r = run_to_end("atsp", &free, &BTreeMap::new(), 1_000_000_000);
            assert!(r.outcome.proven_optimal);
            black_box(r.report.cost)
        })
    });
    g.finish();

    // the position-indexed path relaxation's subgradient steps (one O(n · arcs) DP each),
    // the set-up of every beam run, on a symmetric matrix with sparse precedence
    let sym = generated("symmetric", &[("n", "98"), ("c", "500"), ("p", "1")]);
    let ms = CostModel::new(&sym, sym.default_objective());
    let mut g = cr.benchmark_group("bound");
    g.sample_size(10);
    g.bench_function("qpath 50 subgradient steps (symmetric n = 98)", |b| {
        b.iter(|| {
            let q = QPath::new(&ms, None, 50).expect("acyclic");
            black_box(q.root)
        })
    });
    // the subtour-elimination bound's subgradient steps (one dense assignment each): the
    // first half of the beam's set-up on the same instance
    let cl = Closure::new(&ms.dag).expect("acyclic");
    let cg = CellGraph::new(&ms, &cl);
    g.bench_function("sec 50 subgradient steps (symmetric n = 98)", |b| {
        b.iter(|| {
            let s = sec_bound(&cg, Some(&cl), None, 50, 4 * cg.n + 16).expect("finite");
            black_box(s.value)
        })
    });
    g.finish();

    // the beam on the same instance up to width 256: its warm start, the sec and qpath
    // tables, then passes of width 1, 2, …, 256 (truncated levels sort only their head)
    let narrow = strings(&[("max_width", "256"), ("warm_evals", "100000")]);
    let mut g = cr.benchmark_group("beam");
    g.sample_size(10);
    g.bench_function("beam to width 256 (symmetric n = 98)", |b| {
        b.iter(|| {
            let r = run_to_end("beam", &sym, &narrow, 1_000_000_000_000);
            black_box(r.report.cost)
        })
    });
    // the same up to width 4096: wide levels, where each cell's list of parents, the
    // children's bounds and the dominance map take most of the time (the `symmetric` rule's
    // stretched widest pass at 10 s is 16384 wide)
    let wide = strings(&[("max_width", "4096"), ("warm_evals", "100000")]);
    g.bench_function("beam to width 4096 (symmetric n = 98)", |b| {
        b.iter(|| {
            let r = run_to_end("beam", &sym, &wide, 1_000_000_000_000);
            black_box(r.report.cost)
        })
    });
    g.finish();

    // the dense rule's walk: `ils` with kicks of up to 45 cells, from the greedy start, for
    // 10^7 evaluations (Or-opt and two-way SOP-3-exchange repairs of every kick) on a
    // generated `time-window` instance (340 cells, precedence closure density about 0.9)
    let tw = generated("time-window", &[("n", "340"), ("w", "10"), ("c", "100")]);
    let walk = strings(&[("max-seg", "45")]);
    let mut g = cr.benchmark_group("ils");
    g.sample_size(10);
    g.bench_function("ils 10^7 evaluations (time-window n = 340, w = 10)", |b| {
        b.iter(|| {
            let r = run_to_end("ils", &tw, &walk, 10_000_000);
            black_box(r.report.cost)
        })
    });
    g.finish();
}

criterion_group! {
    name = engine;
    // no plots: the plotters backend needs system fonts
    config = Criterion::default().without_plots();
    targets = benches
}
criterion_main!(engine);

//! Families: determinism per seed, densities on target, acyclic and unclosed DAGs, the
//! SOP text read back as the same instance, fixed first and last cells, and solvability.

use super::sop::to_sop_text;
use crate::formats::json::instance_to_json;
use crate::generate::generate;
use crate::model::{CostMatrix, Instance, Objective};
use crate::precedence::{Dag, closure_density, closure_size, topological_order};
use std::collections::BTreeMap;

const MATRIX_KINDS: &[&str] = &[
    "random-sop",
    "atsp",
    "symmetric",
    "near-symmetric",
    "compiler-dag",
    "time-window",
    "generalized",
];

fn kv(pairs: &[(&str, &str)]) -> BTreeMap<String, String> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn gen_(kind: &str, pairs: &[(&str, &str)], seed: u64) -> Instance {
    generate(kind, &kv(pairs), seed).unwrap_or_else(|e| panic!("{kind}: {e}"))
}

/// Precedence edges between free cells (dummies dropped), renumbered from 0.
fn free_edges(inst: &Instance) -> (usize, Vec<(usize, usize)>) {
    let n = inst.n() - 2;
    let last = inst.n() - 1;
    let e = inst
        .precedence
        .iter()
        .filter(|&&(a, b)| a != 0 && b != last)
        .map(|&(a, b)| (a - 1, b - 1))
        .collect();
    (n, e)
}

#[test]
fn same_seed_same_bytes_other_seed_other_instance() {
    for kind in MATRIX_KINDS.iter().chain(&["geometric-sparse"]) {
        let p = [("n", "40")];
        let a = instance_to_json(&gen_(kind, &p, 5));
        let b = instance_to_json(&gen_(kind, &p, 5));
        assert_eq!(a, b, "{kind}: not deterministic");
        let (x, y) = (gen_(kind, &p, 5), gen_(kind, &p, 6));
        assert!(
            x.matrix != y.matrix || x.cells != y.cells,
            "{kind}: the seed changes nothing"
        );
    }
}

#[test]
fn closure_density_of_free_cells_is_on_target() {
    for kind in ["random-sop", "symmetric", "near-symmetric", "generalized"] {
        for p in [0.0, 1.0, 5.0, 15.0, 30.0, 60.0] {
            let inst = gen_(kind, &[("n", "200"), ("p", &p.to_string())], 3);
            let (n, e) = free_edges(&inst);
            let d = closure_density(&Dag::new(n, &e));
            // target plus at most max(n, 0.5 % of pairs) pairs: 1 percentage point at n = 200
            assert!(
                d * 100.0 >= p - 1e-9 && d * 100.0 <= p + 1.0 + 1e-9,
                "{kind} p={p}: closure density {:.3} %",
                d * 100.0
            );
        }
    }
}

#[test]
fn atsp_has_only_the_dummy_precedence_and_tmat_satisfies_the_triangle_inequality() {
    let inst = gen_("atsp", &[("n", "60"), ("class", "tmat")], 2);
    let (n, e) = free_edges(&inst);
    assert!(e.is_empty());
    let m = inst.matrix.as_ref().unwrap();
    for i in 1..=n {
        for j in 1..=n {
            for k in 1..=n {
                if i != j && j != k && i != k {
                    assert!(m.get(i, k) <= m.get(i, j) + m.get(j, k) + 1e-9);
                }
            }
        }
    }
}

#[test]
fn near_symmetric_in_the_plane_is_metric_up_to_rounding_and_its_asymmetric_part() {
    // asym = 0: symmetric rounded distances, so the triangle inequality holds within 1
    let inst = gen_(
        "near-symmetric",
        &[("n", "40"), ("asym", "0"), ("plane", "true")],
        4,
    );
    let m = inst.matrix.as_ref().unwrap();
    let n = m.size - 2;
    for i in 1..=n {
        for j in 1..=n {
            assert_eq!(m.get(i, j), m.get(j, i));
            for k in 1..=n {
                if i != j && j != k && i != k {
                    assert!(m.get(i, k) <= m.get(i, j) + m.get(j, k) + 1.0 + 1e-9);
                }
            }
        }
    }
    // a random matrix breaks the inequality somewhere; with asym = 5 each arc adds at most 50
    let random = gen_("near-symmetric", &[("n", "40"), ("asym", "0")], 4);
    let r = random.matrix.as_ref().unwrap();
    let broken = (1..=n)
        .any(|i| (1..=n).any(|j| (1..=n).any(|k| r.get(i, k) > r.get(i, j) + r.get(j, k) + 1.0)));
    assert!(
        broken,
        "the random matrix is metric too: the test tells nothing"
    );
    let noisy = gen_("near-symmetric", &[("n", "40"), ("plane", "true")], 4);
    let q = noisy.matrix.as_ref().unwrap();
    for i in 1..=n {
        for j in 1..=n {
            let d = q.get(i, j) - m.get(i, j);
            assert!((0.0..=50.0).contains(&d), "{i} {j}: {d}");
        }
    }
}

#[test]
fn compiler_dag_is_acyclic_sparse_and_not_transitively_closed() {
    for seed in 1..=5 {
        let inst = gen_("compiler-dag", &[("n", "300")], seed);
        let (n, e) = free_edges(&inst);
        let dag = Dag::new(n, &e);
        assert!(topological_order(&dag).is_ok());
        // program order is a schedule
        assert!(e.iter().all(|&(a, b)| a < b));
        let closed = closure_size(n, &e);
        assert!(
            closed > e.len(),
            "seed {seed}: {} edges, closure {closed}",
            e.len()
        );
        assert!((e.len() as f64) < 0.1 * (n * (n - 1) / 2) as f64, "sparse");
        let m = inst.matrix.as_ref().unwrap();
        for i in 1..=n {
            for j in 1..=n {
                let c = m.get(i, j);
                assert!(c >= crate::model::CostMatrix::FORBIDDEN || (0.0..=32.0).contains(&c));
            }
        }
    }
}

#[test]
fn time_window_precedence_is_a_closed_interval_order_denser_for_shorter_windows() {
    let mut last = 1.0;
    for w in ["2", "10", "40"] {
        let inst = gen_("time-window", &[("n", "200"), ("w", w)], 7);
        let (n, e) = free_edges(&inst);
        // the numbering follows the releases, so it is a schedule
        assert!(e.iter().all(|&(a, b)| a < b), "w={w}");
        // an interval order is its own transitive closure
        assert_eq!(closure_size(n, &e), e.len(), "w={w}");
        // an interval order has no 2 + 2: of two ordered pairs a < b, c < d, a < d or c < b
        let set: std::collections::HashSet<_> = e.iter().copied().collect();
        for &(a, b) in e.iter().step_by(97) {
            for &(c, d) in e.iter().step_by(89) {
                if [a, b].iter().all(|x| ![c, d].contains(x)) {
                    assert!(
                        set.contains(&(a, d)) || set.contains(&(c, b)),
                        "w={w}: 2 + 2 at {a}<{b}, {c}<{d}"
                    );
                }
            }
        }
        let d = closure_density(&Dag::new(n, &e));
        // about 1 - 2w/n of the pairs are ordered
        let want = 1.0 - 2.0 * w.parse::<f64>().unwrap() / 200.0;
        assert!((d - want).abs() < 0.08, "w={w}: density {d}, about {want}");
        assert!(d < last, "w={w}: density {d} not below {last}");
        last = d;
    }
}

#[test]
fn time_window_station_jobs_give_free_empty_moves_and_loaded_moves_shift_every_order_alike() {
    let p = |io: &str, loaded: &str, setup: &str| {
        gen_(
            "time-window",
            &[
                ("n", "150"),
                ("c", "20"),
                ("w", "10"),
                ("io", io),
                ("loaded", loaded),
                ("setup", setup),
            ],
            4,
        )
    };
    let zero_arcs = |inst: &Instance| {
        let m = inst.matrix.as_ref().unwrap();
        let n = inst.n();
        (1..n - 1)
            .flat_map(|i| (1..n - 1).map(move |j| (i, j)))
            .filter(|&(i, j)| i != j && m.get(i, j) == 0.0)
            .count()
    };
    // io = 0 draws what the generator drew before the parameter (same matrix and order)
    let before = gen_("time-window", &[("n", "150"), ("c", "20"), ("w", "10")], 4);
    let plain = p("0", "true", "0");
    assert_eq!(before.matrix, plain.matrix);
    assert_eq!(before.precedence, plain.precedence);
    // a retrieval (set down at the station) then a storage (picked up there): a free empty
    // move, so with the station the instance has many more zero-cost links
    let (empty0, empty_io) = (p("0", "false", "0"), p("0.5", "false", "0"));
    assert!(
        zero_arcs(&empty_io) > 3 * zero_arcs(&empty0).max(1),
        "{} zero arcs with the station, {} without",
        zero_arcs(&empty_io),
        zero_arcs(&empty0)
    );
    // with the loaded moves, every order costs the sum of the loaded moves of all jobs but
    // the first more (the dummy start links to the first job for nothing): two orders with
    // the same first job
    let (with, without) = (p("0.5", "true", "0"), p("0.5", "false", "0"));
    let cost = |inst: &Instance, order: &[usize]| {
        let m = inst.matrix.as_ref().unwrap();
        order.windows(2).map(|w| m.get(w[0], w[1])).sum::<f64>()
    };
    // the numbering is a schedule; a second one swaps the first two neighbours left unordered
    // after the first job
    let a: Vec<usize> = (0..with.n()).collect();
    let k = (2..with.n() - 2)
        .find(|&k| !with.precedence.contains(&(k, k + 1)))
        .expect("two unordered neighbours");
    let mut b = a.clone();
    b.swap(k, k + 1);
    let shift_a = cost(&with, &a) - cost(&without, &a);
    let shift_b = cost(&with, &b) - cost(&without, &b);
    assert!(shift_a > 0.0);
    assert_eq!(shift_a, shift_b);
    // with a start-and-stop time, an empty move costs nothing or at least that time, and
    // the links that stay put are the same as without it
    let setup = p("0.5", "false", "10");
    let (ms, m0) = (
        setup.matrix.as_ref().unwrap(),
        without.matrix.as_ref().unwrap(),
    );
    for i in 1..setup.n() - 1 {
        for j in (1..setup.n() - 1).filter(|&j| j != i) {
            let (x, y) = (ms.get(i, j), m0.get(i, j));
            if y >= CostMatrix::FORBIDDEN {
                // against the precedence: forbidden in both
                assert_eq!(x, y, "{i}->{j}");
                continue;
            }
            assert_eq!(x == 0.0, y == 0.0, "{i}->{j}: {x} against {y}");
            assert!(x == 0.0 || x == y + 10.0, "{i}->{j}: {x} against {y}");
        }
    }
    assert!(zero_arcs(&setup) > 0);
}

/// The free precedence edges of a `time-window` instance of 300 cells (seed 7) with `pairs`,
/// checked to be transitively closed (an interval order is its own closure).
fn closed_time_window(pairs: &[(&str, &str)]) -> (usize, Vec<(usize, usize)>) {
    let mut all = vec![("n", "300")];
    all.extend_from_slice(pairs);
    let (n, e) = free_edges(&gen_("time-window", &all, 7));
    assert_eq!(closure_size(n, &e), e.len(), "{pairs:?}: not closed");
    (n, e)
}

#[test]
fn exponential_windows_keep_an_interval_order_and_let_a_few_jobs_go_further() {
    // the most positions a job may take: the cells neither before nor after it
    let widest_freedom = |windows: &str| {
        let (n, e) = closed_time_window(&[("w", "10"), ("windows", windows)]);
        let mut related = vec![0usize; n];
        for &(a, b) in &e {
            related[a] += 1;
            related[b] += 1;
        }
        let d = closure_density(&Dag::new(n, &e));
        (related.iter().map(|r| n - 1 - r).max().unwrap(), d)
    };
    let (uniform, du) = widest_freedom("uniform");
    let (exponential, de) = widest_freedom("exponential");
    // the same mean window: about as dense, with a longer tail
    assert!((du - de).abs() < 0.03, "densities {du} and {de}");
    assert!(
        exponential > uniform + 10,
        "widest freedom {exponential} against {uniform}"
    );
}

#[test]
fn bursts_keep_an_interval_order_with_wider_levels() {
    // the most cells at one depth of the precedence (longest chain of predecessors)
    let widest_level = |bursts: &str| {
        let (n, e) = closed_time_window(&[("w", "8"), ("bursts", bursts)]);
        crate::precedence::widest_level(&Dag::new(n, &e))
    };
    let (uniform, bursty) = (widest_level("0"), widest_level("35"));
    assert!(
        bursty >= 2 * uniform,
        "widest level {bursty} against {uniform}"
    );
}

#[test]
fn generalized_open_features_cut_either_way_with_asymmetric_costs() {
    let inst = gen_("generalized", &[("n", "30"), ("open", "1"), ("p", "0")], 3);
    let m = inst.matrix.as_ref().unwrap();
    // node index of every cell's first mode (the dummies have one node each)
    let mut first = vec![0usize];
    for c in &inst.cells {
        first.push(first.last().unwrap() + c.modes.len());
    }
    let free = 1..inst.n() - 1;
    assert!(free.clone().all(|i| inst.cells[i].modes.len() == 2));
    let mut asymmetric = 0;
    for x in free.clone() {
        for y in free.clone().filter(|&y| y != x) {
            let (fx, rx, fy, ry) = (first[x], first[x] + 1, first[y], first[y] + 1);
            // u then v costs u's exit to v's entry: a stroke cut backwards swaps its ends
            assert_eq!(m.get(fx, fy), m.get(ry, rx), "cells {x}, {y}");
            assert_eq!(m.get(rx, fy), m.get(ry, fx), "cells {x}, {y}");
            asymmetric += usize::from(m.get(fx, fy) != m.get(fy, fx));
        }
    }
    assert!(asymmetric > 0, "open features give asymmetric costs");
    let some = gen_("generalized", &[("n", "200"), ("open", "0.5")], 3);
    let two = some.cells.iter().filter(|c| c.modes.len() == 2).count();
    assert!(
        (80..=160).contains(&two),
        "about half open: {two} of 200 have two modes"
    );
}

#[test]
fn sop_text_reads_back_as_the_same_instance() {
    for kind in MATRIX_KINDS.iter().filter(|k| **k != "generalized") {
        let inst = gen_(kind, &[("n", "25")], 9);
        let text = to_sop_text(&inst).unwrap();
        let back = crate::formats::tsplib::parse_sop("x.sop", &text).unwrap();
        crate::validate::validate(&back, "x.sop").unwrap();
        assert_eq!(back.matrix, inst.matrix, "{kind}: matrix");
        let mut a = inst.precedence.clone();
        let mut b = back.precedence.clone();
        a.sort_unstable();
        b.sort_unstable();
        assert_eq!(a, b, "{kind}: precedence");
        assert_eq!((back.first, back.last), (inst.first, inst.last));
        assert_eq!(back.cells, inst.cells, "{kind}: cells");
    }
    let g = gen_("generalized", &[("n", "10")], 1);
    assert!(to_sop_text(&g).is_err(), "several modes are not SOP");
    let geo = gen_("geometric-sparse", &[("n", "10")], 1);
    assert!(to_sop_text(&geo).is_err());
}

#[test]
fn first_and_last_cells_are_the_dummies() {
    for kind in MATRIX_KINDS {
        let inst = gen_(kind, &[("n", "30")], 4);
        let last = inst.n() - 1;
        assert_eq!(inst.first, Some(0), "{kind}");
        assert_eq!(inst.last, Some(last), "{kind}");
        assert!(!inst.closed);
        assert_eq!(inst.cells[0].modes.len(), 1);
        assert_eq!(inst.cells[last].modes.len(), 1);
        let seq = inst.as_given.as_ref().unwrap();
        assert_eq!(seq.first().unwrap().cell, 0);
        assert_eq!(seq.last().unwrap().cell, last);
        crate::checker::check(&inst, seq, Objective::Matrix)
            .unwrap_or_else(|v| panic!("{kind}: as-given infeasible: {v}"));
    }
    let geo = gen_("geometric-sparse", &[("n", "500")], 2);
    crate::checker::check(&geo, geo.as_given.as_ref().unwrap(), Objective::Time).unwrap();
    let d = closure_density(&Dag::new(geo.n(), &geo.precedence));
    assert!(d > 0.0 && d < 0.01, "sparse: {d}");
}

#[test]
fn every_family_is_solved_by_the_registry() {
    for kind in MATRIX_KINDS.iter().chain(&["geometric-sparse"]) {
        let inst = gen_(kind, &[("n", "40")], 1);
        let obj = inst.default_objective();
        for solver in ["greedy", "local-search", "auto"] {
            let r = crate::solvers::run(
                solver,
                &inst,
                obj,
                &BTreeMap::new(),
                1,
                crate::solvers::Budget {
                    time_limit: None,
                    max_evals: Some(20_000),
                },
                &mut crate::solvers::NoObserver,
            )
            .unwrap_or_else(|e| panic!("{kind} / {solver}: {e}"));
            let seq = &r.outcome.sequence;
            crate::checker::check(&inst, seq, obj)
                .unwrap_or_else(|v| panic!("{kind} / {solver}: infeasible: {v}"));
        }
    }
}

#[test]
fn bad_parameters_are_refused() {
    for (kind, pairs) in [
        ("random-sop", vec![("p", "101")]),
        ("random-sop", vec![("n", "0")]),
        ("random-sop", vec![("n", "6000")]),
        ("atsp", vec![("c", "0")]),
        ("atsp", vec![("class", "tmat"), ("n", "2500")]),
        ("compiler-dag", vec![("regs", "1")]),
        ("generalized", vec![("modes", "0")]),
        ("generalized", vec![("n", "2000"), ("modes", "4")]),
        ("generalized", vec![("open", "1.5")]),
        ("generalized", vec![("open", "nan")]),
        ("geometric-sparse", vec![("size", "1")]),
        ("time-window", vec![("w", "0")]),
        ("time-window", vec![("n", "20"), ("w", "21")]),
        ("time-window", vec![("c", "0")]),
        ("time-window", vec![("io", "1.5")]),
        ("time-window", vec![("io", "-0.1")]),
        ("time-window", vec![("loaded", "maybe")]),
        ("time-window", vec![("setup", "-1")]),
        ("time-window", vec![("windows", "normal")]),
        ("time-window", vec![("bursts", "-1")]),
    ] {
        assert!(
            generate(kind, &kv(&pairs), 1).is_err(),
            "{kind} {pairs:?} accepted"
        );
    }
}

#[test]
fn symmetric_pairs_are_disjoint_and_the_only_precedence() {
    let inst = gen_(
        "symmetric",
        &[("n", "98"), ("c", "500"), ("pairs", "41")],
        7,
    );
    let (n, e) = free_edges(&inst);
    assert_eq!((n, e.len()), (98, 41));
    let mut seen = vec![false; n];
    for &(a, b) in &e {
        assert!(!seen[a] && !seen[b], "cell in two pairs");
        seen[a] = true;
        seen[b] = true;
    }
    // the closure adds nothing: 41 pairs of 98 · 97 / 2
    let d = closure_density(&Dag::new(n, &e));
    assert!((d - 41.0 / 4753.0).abs() < 1e-12, "closure density {d}");
    assert!(inst.name.contains("pairs41"));
    // without pairs the instance is the one generated before the parameter existed
    let plain = gen_("symmetric", &[("n", "40"), ("p", "5")], 3);
    assert_eq!(plain.name, "symmetric-n40-c100-p5-s3");
    for bad in [
        &[("n", "10"), ("pairs", "6")][..],
        &[("n", "10"), ("pairs", "2"), ("p", "5")],
    ] {
        let err = generate("symmetric", &kv(bad), 1).expect_err("refused");
        assert!(err.to_string().contains("symmetric: "), "{err}");
    }
}

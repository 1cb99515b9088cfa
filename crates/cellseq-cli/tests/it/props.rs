//! Property tests on random small instances: greedy is feasible, exact <= greedy, and exact
//! equals brute-force enumeration (scored by the independent checker) for n <= 7.

use cellseq::checker::check;
use cellseq::geom::Point3;
use cellseq::model::{Cell, CostMatrix, Instance, Machine, Mode, Objective, Tool, Visit};
use cellseq::solvers::{self, Budget, NoObserver};
use proptest::prelude::*;
use std::collections::BTreeMap;

#[derive(Debug, Clone)]
struct Spec {
    pts: Vec<(f64, f64, f64, f64, u8, bool, u8)>,
    edges: Vec<(usize, usize)>,
    matrix: Option<Vec<u16>>,
    closed: bool,
}

fn spec(max_n: usize) -> impl Strategy<Value = Spec> {
    (2..=max_n).prop_flat_map(|n| {
        (
            prop::collection::vec(
                (
                    0.0..100.0,
                    0.0..100.0,
                    0.0..100.0,
                    0.0..100.0,
                    0u8..2,
                    any::<bool>(),
                    0u8..3,
                ),
                n,
            ),
            prop::collection::vec((0..n, 0..n), 0..n),
            prop::option::of(prop::collection::vec(0u16..500, (2 * n) * (2 * n))),
            any::<bool>(),
        )
            .prop_map(|(pts, raw, matrix, closed)| {
                // orient edges by index so the graph is acyclic
                let edges = raw
                    .into_iter()
                    .filter(|(a, b)| a != b)
                    .map(|(a, b)| (a.min(b), a.max(b)))
                    .collect();
                Spec {
                    pts,
                    edges,
                    matrix,
                    closed,
                }
            })
    })
}

fn build(s: &Spec) -> Instance {
    let n = s.pts.len();
    let mut cells = Vec::new();
    for (i, &(x, y, u, v, tool, rev, depth)) in s.pts.iter().enumerate() {
        let z = -(depth as f64);
        let m = Mode::new(Point3::new(x, y, z), Point3::new(u, v, z));
        let modes = if rev { vec![m, m.reversed()] } else { vec![m] };
        let mut c = Cell::new(format!("c{i}"), format!("T{tool}"), modes);
        c.reversible = rev;
        c.cut_length = (x - u).hypot(y - v);
        cells.push(c);
    }
    let mut inst = Instance {
        name: "prop".into(),
        machine: Machine {
            link_distance: 15.0,
            initial_tool: Some("T0".into()),
            ..Machine::default()
        },
        tools: vec![
            Tool {
                id: "T0".into(),
                diameter: 6.0,
                name: None,
                feed: None,
            },
            Tool {
                id: "T1".into(),
                diameter: 3.0,
                name: None,
                feed: Some(300.0),
            },
        ],
        cells,
        precedence: s.edges.clone(),
        as_given: None,
        ..Instance::default()
    };
    if let Some(mx) = &s.matrix {
        let size = inst.total_modes();
        let costs = (0..size * size).map(|k| mx[k % mx.len()] as f64).collect();
        inst.matrix = Some(CostMatrix { size, costs });
        if s.closed {
            // closed tours need a fixed single-mode first cell
            inst.cells[0].modes.truncate(1);
            inst.cells[0].reversible = false;
            let size = inst.total_modes();
            inst.matrix = Some(CostMatrix {
                size,
                costs: (0..size * size).map(|k| mx[k % mx.len()] as f64).collect(),
            });
            inst.first = Some(0);
            inst.closed = true;
        }
    }
    let _ = n;
    inst
}

/// Enumerates every feasible (order, modes) and returns the checker's minimum cost.
fn brute_force(inst: &Instance, obj: Objective) -> f64 {
    fn rec(
        inst: &Instance,
        obj: Objective,
        seq: &mut Vec<Visit>,
        used: &mut Vec<bool>,
        best: &mut f64,
    ) {
        let n = inst.n();
        if seq.len() == n {
            if let Ok(r) = check(inst, seq, obj) {
                *best = best.min(r.cost);
            }
            return;
        }
        for c in 0..n {
            if used[c] || inst.precedence.iter().any(|&(a, b)| b == c && !used[a]) {
                continue;
            }
            if inst.first.is_some_and(|f| f != c) && seq.is_empty() {
                continue;
            }
            used[c] = true;
            for m in 0..inst.cells[c].modes.len() {
                seq.push(Visit::new(c, m));
                rec(inst, obj, seq, used, best);
                seq.pop();
            }
            used[c] = false;
        }
    }
    let mut best = f64::INFINITY;
    rec(
        inst,
        obj,
        &mut Vec::new(),
        &mut vec![false; inst.n()],
        &mut best,
    );
    best
}

fn run(name: &str, inst: &Instance, obj: Objective) -> f64 {
    solvers::run(
        name,
        inst,
        obj,
        &BTreeMap::new(),
        3,
        Budget::default(),
        &mut NoObserver,
    )
    .unwrap_or_else(|e| panic!("{name}: {e}"))
    .report
    .cost
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(120))]

    #[test]
    fn greedy_and_insertion_feasible_and_exact_not_worse(s in spec(10), air in any::<bool>()) {
        let inst = build(&s);
        cellseq::validate::validate(&inst, "prop").unwrap();
        let obj = if inst.is_matrix() { Objective::Matrix } else if air { Objective::Air } else { Objective::Time };
        let g = run("greedy", &inst, obj);
        let a = run("as-given", &inst, obj);
        let i = run("insertion", &inst, obj);
        let e = run("exact", &inst, obj);
        prop_assert!(e <= g + 1e-6, "exact {e} > greedy {g}");
        prop_assert!(e <= i + 1e-6, "exact {e} > insertion {i}");
        prop_assert!(e <= a + 1e-6, "exact {e} > as-given {a}");
    }

    #[test]
    fn exact_equals_brute_force(mut s in spec(8), air in any::<bool>()) {
        if s.pts.len() > 6 {
            // keep enumeration affordable: one mode per cell above six cells
            for p in s.pts.iter_mut() {
                p.5 = false;
            }
        }
        let inst = build(&s);
        let obj = if inst.is_matrix() { Objective::Matrix } else if air { Objective::Air } else { Objective::Time };
        let e = run("exact", &inst, obj);
        let b = brute_force(&inst, obj);
        prop_assert!((e - b).abs() <= 1e-6 * b.abs().max(1.0), "exact {e} vs brute force {b}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(80))]

    /// The backwards twin of a matrix instance (`Instance::reversed_matrix`) has the same
    /// optimum, and `reverse_sequence` carries the exact solution over at the same cost,
    /// feasible by the checker, and back again unchanged.
    #[test]
    fn reversed_twin_keeps_costs_and_optimum(mut s in spec(6)) {
        if s.matrix.is_none() {
            return Ok(());
        }
        let few = s.pts.len() <= 4;
        for p in s.pts.iter_mut() {
            p.5 = p.5 && few;
        }
        let inst = build(&s);
        let twin = inst.reversed_matrix().expect("matrix instances have a twin");
        cellseq::validate::validate(&twin, "twin").unwrap();
        let obj = Objective::Matrix;
        let seq = solvers::run("exact", &inst, obj, &BTreeMap::new(), 3, Budget::default(), &mut NoObserver)
            .unwrap()
            .outcome
            .sequence;
        let back = inst.reverse_sequence(&seq);
        let there = check(&twin, &back, obj).expect("reversed sequence feasible on the twin");
        let here = check(&inst, &seq, obj).unwrap();
        prop_assert!((there.cost - here.cost).abs() <= 1e-9, "{} vs {}", there.cost, here.cost);
        prop_assert_eq!(twin.reverse_sequence(&back), seq);
        let b = brute_force(&twin, obj);
        prop_assert!((b - here.cost).abs() <= 1e-6, "twin optimum {b} vs {}", here.cost);
    }
}

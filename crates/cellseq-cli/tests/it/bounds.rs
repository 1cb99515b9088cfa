//! Lower bounds never exceed the optimum; the beam search agrees with the exact DP and proves
//! known optima.

use cellseq::bound::{self, BoundOptions};
use cellseq::clock::Deadline;
use cellseq::cost::CostModel;
use cellseq::formats::{self, Format};
use cellseq::model::{Instance, Objective, Sequence};
use cellseq::solvers::{self, Budget};
use proptest::prelude::*;
use std::collections::BTreeMap;

use crate::common::{solve, solve_with};

fn load(rel: &str) -> Instance {
    formats::load_instance(&crate::common::root().join(rel)).expect("instance loads")
}

/// The exact solver's result, proven optimal.
fn exact_run(inst: &Instance, obj: Objective) -> solvers::RunResult {
    let r = solve("exact", inst, obj).expect("exact solves");
    assert!(r.outcome.proven_optimal);
    r
}

fn exact(inst: &Instance, obj: Objective) -> f64 {
    exact_run(inst, obj).report.cost
}

/// The beam with these parameters (the rest at their defaults).
fn beam_with(inst: &Instance, obj: Objective, params: &[(&str, &str)]) -> solvers::RunResult {
    let p: BTreeMap<String, String> = params
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    solve_with("beam", inst, obj, &p, Budget::default()).expect("beam solves")
}

fn beam(inst: &Instance, obj: Objective) -> solvers::RunResult {
    beam_with(inst, obj, &[("warm_evals", "20000")])
}

/// The beam with no warm start and no root bound: the tree search alone must find and prove
/// the optimum, so an invalid node bound (over-pruning) shows up as a wrong cost.
fn beam_alone(inst: &Instance, obj: Objective) -> solvers::RunResult {
    beam_with(inst, obj, &[("warm_evals", "0"), ("root_bound", "false")])
}

/// The beam alone (as [`beam_alone`]) going to its unbounded pass right after width 1:
/// the exhaustive pass (adaptive refinement, compact levels) must find and prove the optimum.
/// With `memory_mb` = 0 that pass stops at its memory cap at once.
fn beam_exhaustive(inst: &Instance, obj: Objective, memory_mb: &str) -> solvers::RunResult {
    let params = [
        ("warm_evals", "0"),
        ("root_bound", "false"),
        ("exhaustive_from", "1"),
        ("memory_mb", memory_mb),
    ];
    beam_with(inst, obj, &params)
}

fn all_bounds(inst: &Instance, obj: Objective) -> bound::Bounds {
    let m = CostModel::new(inst, obj);
    bound::compute(&m, &BoundOptions::default())
}

fn check_instance(inst: &Instance, obj: Objective) {
    let opt = exact(inst, obj);
    let b = all_bounds(inst, obj);
    for p in &b.parts {
        assert!(
            p.value <= opt + 1e-6 * opt.abs().max(1.0),
            "{}: bound {} = {} exceeds the optimum {opt}",
            inst.name,
            p.name,
            p.value
        );
    }
    // a one-prefix beam rarely proves anything: its reported lower bound (the first-level
    // node bound) must still be below the optimum
    let narrow = beam_with(inst, obj, &[("warm_evals", "0"), ("max_width", "1")]);
    let lb = narrow.outcome.lower_bound.expect("beam reports a bound");
    assert!(
        lb <= opt + 1e-6 * opt.abs().max(1.0),
        "{}: beam lower bound {lb} exceeds the optimum {opt}",
        inst.name
    );
    // an unbounded pass cut at once by its memory cap proves nothing it should not
    let capped = beam_exhaustive(inst, obj, "0");
    assert!(capped.report.cost >= opt - 1e-6 * opt.abs().max(1.0));
    assert!(
        !capped.outcome.proven_optimal
            || (capped.report.cost - opt).abs() <= 1e-6 * opt.abs().max(1.0)
    );
    for r in [
        beam(inst, obj),
        beam_alone(inst, obj),
        beam_exhaustive(inst, obj, "2048"),
    ] {
        assert!(
            r.outcome.proven_optimal,
            "{}: beam did not prove optimality",
            inst.name
        );
        assert!(
            (r.report.cost - opt).abs() <= 1e-6 * opt.abs().max(1.0),
            "{}: beam {} vs exact {opt}",
            inst.name,
            r.report.cost
        );
    }
}

/// A TSPLIB SOP text whose cells fall into groups: cheap arcs inside a group, expensive ones
/// between groups (like p43), so the beam's cluster surcharges are exercised.
fn clustered_sop_text(group: &[usize], small: &[u32], big: &[u32], prec: &[bool]) -> String {
    let k = group.len();
    let n = k + 2;
    let mut s = format!(
        "NAME: rnd\nTYPE: SOP\nDIMENSION: {n}\nEDGE_WEIGHT_TYPE: EXPLICIT\n\
         EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n{n}\n"
    );
    let mut idx = 0;
    for i in 0..n {
        let mut row = Vec::new();
        for j in 0..n {
            let v: i64 = if i == j {
                0
            } else if j == 0 || i == n - 1 {
                -1
            } else if i == 0 || j == n - 1 {
                (small[(i + j) % small.len()] % 10) as i64
            } else {
                idx += 1;
                // j precedes i (only for j < i, so the order stays acyclic)
                if j < i && prec[idx % prec.len()] {
                    -1
                } else {
                    let (gi, gj) = (group[i - 1], group[j - 1]);
                    let c = small[idx % small.len()] as i64;
                    if gi == gj {
                        c
                    } else {
                        c + big[idx % big.len()] as i64
                    }
                }
            };
            row.push(v.to_string());
        }
        s += &row.join(" ");
        s += "\n";
    }
    s += "EOF\n";
    s
}

#[test]
fn bounds_and_beam_on_small_tsplib_sop() {
    for name in ["ESC07", "ESC11", "ESC12", "br17.10", "br17.12"] {
        let inst = load(&format!("instances/tsplib-sop/{name}.sop"));
        check_instance(&inst, Objective::Matrix);
    }
}

#[test]
fn bounds_and_beam_on_small_pcgtsp() {
    for name in ["ESC07", "ESC12"] {
        let inst = load(&format!("instances/pcgtsplib/{name}.pcglns"));
        check_instance(&inst, Objective::Matrix);
    }
}

#[test]
fn beam_proves_known_optima() {
    // values from instances/tsplib-sop/bks.csv (proven optimal there)
    for (name, opt) in [("ESC25", 1681.0), ("ESC47", 1288.0), ("ESC63", 62.0)] {
        let inst = load(&format!("instances/tsplib-sop/{name}.sop"));
        let r = beam(&inst, Objective::Matrix);
        assert!(r.outcome.proven_optimal, "{name} not proven");
        assert_eq!(r.report.cost, opt, "{name}");
        let b = all_bounds(&inst, Objective::Matrix);
        assert!(b.best <= opt, "{name}: bound {} above the optimum", b.best);
    }
}

#[test]
fn qpath_bound_is_strong_under_dense_precedence() {
    // rbg048a: optimum 351 (bks.csv); the assignment bound is 337
    let inst = load("instances/tsplib-sop/rbg048a.sop");
    let m = CostModel::new(&inst, Objective::Matrix);
    let q = bound::qpath::QPath::new(&m, Some(351.0), 1000).expect("qpath bound");
    assert!(q.root <= 351.0 + 1e-6, "qpath {} above the optimum", q.root);
    assert!(q.root > 345.0, "qpath {} is weak", q.root);
    let opts = BoundOptions {
        upper: Some(351.0),
        ..BoundOptions::default()
    };
    let b = bound::compute(&m, &opts);
    assert_eq!(b.best_name, "qpath");
    assert!(b.best <= 351.0);
}

/// The cost model, an optimal sequence (by the exact solver) and its cost.
fn optimum(inst: &Instance, obj: Objective) -> (CostModel, Sequence, f64) {
    let r = exact_run(inst, obj);
    let m = CostModel::new(inst, obj);
    let opt = m.evaluate(&r.outcome.sequence);
    (m, r.outcome.sequence, opt)
}

/// The qpath completion bound of every prefix along an optimal sequence never exceeds the
/// cost of the rest of that sequence.
fn check_qpath_along_optimum(inst: &Instance, obj: Objective) {
    let (m, seq, opt) = optimum(inst, obj);
    let seq = &seq;
    for upper in [None, Some(opt)] {
        let Some(q) = bound::qpath::QPath::new(&m, upper, 200) else {
            continue;
        };
        assert!(q.root <= opt + 1e-6 * opt.abs().max(1.0));
        let mut g = m.constant() + m.start(seq[0].cell, seq[0].mode);
        let mut open = q.lambda_total();
        for p in 1..=seq.len() {
            let (c, md) = (seq[p - 1].cell, seq[p - 1].mode);
            open -= q.lambda(c);
            let node = m.node(c, md);
            let lb = g + q.completion(p, node, open);
            assert!(
                lb <= opt + 1e-6 * opt.abs().max(1.0),
                "qpath prefix bound {lb} above the optimum {opt} at position {p}"
            );
            if p < seq.len() {
                let (d, mdd) = (seq[p].cell, seq[p].mode);
                g += m.arc(c, md, d, mdd);
            }
        }
    }
}

/// The beam's node bound (assignment potentials, subtour-elimination multipliers, degree
/// sums, cluster surcharges) of every prefix of an optimal sequence never exceeds the
/// optimum, with and without a known upper value for the subgradient steps; neither does the
/// `sec` root bound.
fn check_node_bounds_along_optimum(inst: &Instance, obj: Objective) {
    let (m, seq, opt) = optimum(inst, obj);
    let seq = &seq;
    let tol = 1e-6 * opt.abs().max(1.0);
    for upper in [None, Some(opt)] {
        let lbs = solvers::beam::prefix_bounds(&m, seq, upper).expect("node bounds");
        assert_eq!(lbs.len(), seq.len());
        for (p, lb) in lbs.iter().enumerate() {
            assert!(
                *lb <= opt + tol,
                "node bound {lb} above the optimum {opt} after {} cells (upper {upper:?})",
                p + 1
            );
        }
        let cl = cellseq::precedence::Closure::new(&m.dag).expect("acyclic");
        let g = bound::cells::CellGraph::new(&m, &cl);
        if let Some(s) =
            bound::sec::sec_bound(&g, Some(&cl), upper.map(|u| u - m.constant()), 200, 64)
        {
            assert!(
                s.value + m.constant() <= opt + tol,
                "sec bound {} above the optimum {opt}",
                s.value + m.constant()
            );
        }
    }
}

#[test]
fn sec_bound_is_strong_on_p43() {
    // p43.1: optimum 28140 (bks.csv); the plain assignment bound is 900, the cluster
    // surcharges of the beam gave 27810
    let inst = load("instances/tsplib-sop/p43.1.sop");
    let m = CostModel::new(&inst, Objective::Matrix);
    let b = bound::compute(&m, &BoundOptions::default());
    let sec = b.parts.iter().find(|p| p.name == "sec").expect("sec bound");
    assert!(sec.value <= 28140.0, "sec {} above the optimum", sec.value);
    assert!(sec.value > 28000.0, "sec {} is weak", sec.value);
    let seq = &load_solution_p43_1(&inst);
    let lbs = solvers::beam::prefix_bounds(&m, seq, Some(28140.0)).expect("node bounds");
    assert!(lbs.iter().all(|&lb| lb <= 28140.0 + 1e-6));
}

/// A sequence of p43.1 of cost 28140 (optimal), found by `beam` and checked here.
fn load_solution_p43_1(inst: &Instance) -> Vec<cellseq::model::Visit> {
    let labels = [
        1, 5, 38, 8, 31, 30, 35, 34, 14, 13, 15, 42, 41, 43, 39, 40, 26, 22, 24, 23, 25, 27, 18,
        16, 17, 20, 21, 19, 10, 11, 12, 9, 32, 33, 7, 6, 3, 28, 29, 2, 4, 37, 36, 44,
    ];
    let seq: Vec<cellseq::model::Visit> = labels
        .iter()
        .map(|l| {
            let c = inst
                .cells
                .iter()
                .position(|c| c.id == l.to_string())
                .expect("cell label");
            cellseq::model::Visit::new(c, 0)
        })
        .collect();
    let m = CostModel::new(inst, Objective::Matrix);
    assert_eq!(m.evaluate(&seq), 28140.0);
    seq
}

#[test]
fn lagrangian_beats_assignment_on_ry48p() {
    let inst = load("instances/tsplib-sop/ry48p.1.sop");
    let b = all_bounds(&inst, Objective::Matrix);
    let get = |n: &str| {
        b.parts
            .iter()
            .find(|p| p.name == n)
            .map(|p| p.value)
            .unwrap()
    };
    assert!(get("lagrangian") > get("assignment"));
    assert!(get("assignment") > get("degree"));
    assert!(b.best <= 15805.0);
}

#[test]
fn knn_bounds_are_below_a_solution_on_a_large_geometric_instance() {
    let mut p = BTreeMap::new();
    p.insert("n".to_string(), "4000".to_string());
    p.insert("tools".to_string(), "2".to_string());
    let inst = cellseq::generate::generate("uniform", &p, 3).unwrap();
    let m = CostModel::new(&inst, Objective::Time);
    let opts = BoundOptions {
        dense_max_cells: 1000,
        ..BoundOptions::default()
    };
    let b = bound::compute(&m, &opts);
    assert_eq!(b.best_name, "assignment_knn");
    let g = solve("greedy", &inst, Objective::Time).unwrap();
    for name in ["degree_knn", "assignment_knn"] {
        let p = b.parts.iter().find(|p| p.name == name).expect(name);
        assert!(p.value > m.constant() && p.value <= g.report.cost, "{name}");
    }
}

/// A `uniform` instance with the machine varied: cells linked at feed up to `link` mm, a
/// return home, an initial tool (the precedence, modes, tools and lifts come from `uniform`).
#[allow(clippy::too_many_arguments)]
fn geometric_variant(
    n: usize,
    tools: usize,
    density: f64,
    layers: usize,
    lift: f64,
    link: f64,
    home: bool,
    seed: u64,
) -> Instance {
    let mut p = BTreeMap::new();
    for (k, v) in [
        ("n", n.to_string()),
        ("tools", tools.to_string()),
        ("density", density.to_string()),
        ("layers", layers.to_string()),
        ("lift", lift.to_string()),
        ("size", "60".to_string()),
        ("closed", "0.4".to_string()),
        ("modes", "3".to_string()),
        ("reversible", (seed & 1 == 1).to_string()),
    ] {
        p.insert(k.to_string(), v);
    }
    let mut inst = cellseq::generate::generate("uniform", &p, seed).unwrap();
    inst.machine.link_distance = link;
    inst.machine.return_home = home;
    if seed.is_multiple_of(3) {
        inst.machine.initial_tool = inst.tools.first().map(|t| t.id.clone());
    }
    inst
}

/// The sparse assignment bound at several candidate counts: below `upper` and below the
/// dense assignment bound (its duals are feasible for a graph with more arcs).
fn check_assignment_knn(inst: &Instance, obj: Objective, upper: f64) {
    let m = CostModel::new(inst, obj);
    let tol = 1e-6 * upper.abs().max(1.0);
    let dense = bound::compute(
        &m,
        &BoundOptions {
            lagrangian_max_cells: 0,
            qpath_work: 0.0,
            sec_work: 0.0,
            ..BoundOptions::default()
        },
    );
    let ap = dense
        .parts
        .iter()
        .find(|p| p.name == "assignment")
        .map(|p| p.value);
    for k in [1, 2, 5, 16] {
        let v = bound::assignment_knn::assignment_knn_until(&m, k, Deadline::NONE)
            .expect("a bound without a deadline");
        let b = m.constant() + v;
        assert!(
            b <= upper + tol,
            "{} {obj:?} k={k}: assignment_knn {b} exceeds {upper}",
            inst.name
        );
        if let Some(a) = ap {
            assert!(
                b <= a + tol,
                "{} k={k}: {b} above the assignment {a}",
                inst.name
            );
        }
    }
}

#[test]
fn assignment_knn_is_below_solutions_on_larger_geometric_instances() {
    for (seed, n) in [(1u64, 150usize), (2, 400), (3, 900)] {
        for (link, home) in [(0.0, false), (8.0, true)] {
            let inst = geometric_variant(n, 3, 0.002, 2, 7.0, link, home, seed);
            for obj in [Objective::Time, Objective::Air] {
                let budget = Budget {
                    time_limit: None,
                    max_evals: Some(300_000),
                };
                let r = solve_with("ils", &inst, obj, &BTreeMap::new(), budget).unwrap();
                check_assignment_knn(&inst, obj, r.report.cost);
            }
        }
    }
    // the family of issue 51, beyond the dense bounds: close to a solution
    let mut p = BTreeMap::new();
    p.insert("n".to_string(), "5000".to_string());
    let inst = cellseq::generate::generate("geometric-sparse", &p, 4).unwrap();
    let m = CostModel::new(&inst, Objective::Time);
    let b = bound::compute(&m, &BoundOptions::default());
    assert_eq!(b.best_name, "assignment_knn");
    let g = solve("greedy", &inst, Objective::Time).unwrap();
    assert!(b.best <= g.report.cost && b.best >= 0.8 * g.report.cost);
}

/// A random PCGTSP (PCGLNS) text: `groups` clusters of 1–3 nodes, integer costs, random
/// precedence between clusters; cluster 1 is the start.
fn pcglns_text(groups: usize, sizes: &[usize], costs: &[u32], prec: &[bool]) -> String {
    // the start group holds one node, as in PCGTSPLIB (closed tours return to it)
    let sizes: Vec<usize> = std::iter::once(1)
        .chain(sizes[1..].iter().copied())
        .collect();
    let sizes = &sizes[..];
    let dim: usize = sizes.iter().sum();
    let mut s = format!(
        "NAME : rnd\nTYPE : PCGLNS\nDIMENSION : {dim}\nGTSP_SETS : {groups}\nEDGE_WEIGHT_TYPE : EXPLICIT\nEDGE_WEIGHT_FORMAT : FULL_MATRIX\nEDGE_WEIGHT_SECTION\n"
    );
    for i in 0..dim {
        let row: Vec<String> = (0..dim)
            .map(|j| {
                if i == j {
                    "0".into()
                } else {
                    costs[(i * dim + j) % costs.len()].to_string()
                }
            })
            .collect();
        s += &row.join(" ");
        s += "\n";
    }
    s += "GTSP_SET_SECTION\n";
    let mut node = 1;
    for (g, &k) in sizes.iter().enumerate() {
        let ids: Vec<String> = (node..node + k).map(|x| x.to_string()).collect();
        s += &format!("{} {} -1\n", g + 1, ids.join(" "));
        node += k;
    }
    s += "GTSP_SET_ORDERING\n";
    let mut idx = 0;
    for a in 2..=groups {
        let mut after = Vec::new();
        for b in a + 1..=groups {
            if prec[idx % prec.len()] {
                after.push(b.to_string());
            }
            idx += 1;
        }
        if !after.is_empty() {
            s += &format!("{a} {} -1\n", after.join(" "));
        }
    }
    s += "START_GROUP_SECTION\n1\nEOF\n";
    s
}

/// A random TSPLIB SOP matrix on `n` nodes (first and last fixed): arc costs cycled from
/// `costs`, and j before i (entry −1) for j < i wherever `prec` says so, so the order stays
/// acyclic.
fn random_sop_matrix(n: usize, costs: &[u32], prec: &[bool]) -> Vec<Vec<i64>> {
    let mut idx = 0;
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    idx += 1;
                    let forced = j == 0 || i == n - 1 || (j < i && prec[idx % prec.len()]);
                    if i == j {
                        0
                    } else if forced {
                        -1
                    } else {
                        costs[idx % costs.len()] as i64
                    }
                })
                .collect()
        })
        .collect()
}

/// The TSPLIB SOP text of a full matrix.
fn sop_matrix_text(name: &str, m: &[Vec<i64>]) -> String {
    let n = m.len();
    let mut s = format!(
        "NAME: {name}\nTYPE: SOP\nDIMENSION: {n}\nEDGE_WEIGHT_TYPE: EXPLICIT\n\
         EDGE_WEIGHT_FORMAT: FULL_MATRIX\nEDGE_WEIGHT_SECTION\n{n}\n"
    );
    for row in m {
        let r: Vec<String> = row.iter().map(|v| v.to_string()).collect();
        s += &r.join(" ");
        s += "\n";
    }
    s += "EOF\n";
    s
}

/// A random TSPLIB SOP text on `k` cells where cell 2 is a copy of cell 1 (and cell 3 too
/// when `triple`), so the beam's symmetry breaking applies; `skew` makes the arcs between
/// the copies asymmetric (then they are not interchangeable).
fn twin_sop_text(k: usize, costs: &[u32], prec: &[bool], triple: bool, skew: bool) -> String {
    let n = k + 2;
    let mut m = random_sop_matrix(n, costs, prec);
    let copies: &[usize] = if triple { &[2, 3] } else { &[2] };
    for &c in copies {
        m[c] = m[1].clone();
        for row in m.iter_mut() {
            row[c] = row[1];
        }
        m[c][c] = 0;
    }
    for &a in &[1usize, 2, 3][..copies.len() + 1] {
        for &b in &[1usize, 2, 3][..copies.len() + 1] {
            if a != b {
                m[a][b] = 7;
            }
        }
    }
    if skew {
        m[1][2] = 9;
    }
    sop_matrix_text("twins", &m)
}

/// A random TSPLIB SOP text on `k` cells (precedence only from lower to higher indices, by
/// `prec`) where each cell of `copies` gets the arc costs of cell 1 wherever both arcs are
/// allowed, but keeps its own precedence: copies apart from the precedence, which the beam
/// may order when one of them is less constrained at the front and more at the back.
/// `extra`: further (i, j) entries set to −1 (j precedes i).
fn near_twin_sop_text(
    k: usize,
    costs: &[u32],
    prec: &[bool],
    copies: &[usize],
    extra: &[(usize, usize)],
) -> String {
    let n = k + 2;
    let mut m = random_sop_matrix(n, costs, prec);
    for &(i, j) in extra {
        m[i][j] = -1;
    }
    for &c in copies {
        #[allow(clippy::needless_range_loop)]
        for j in 0..n {
            if j != c && j != 1 {
                if m[c][j] != -1 && m[1][j] != -1 {
                    m[c][j] = m[1][j];
                }
                if m[j][c] != -1 && m[j][1] != -1 {
                    m[j][c] = m[j][1];
                }
            }
        }
    }
    for &a in copies.iter().chain(&[1]) {
        for &b in copies.iter().chain(&[1]) {
            if a != b && m[a][b] != -1 && m[b][a] != -1 {
                m[a][b] = 7;
                m[b][a] = 7;
            }
        }
    }
    sop_matrix_text("near-twins", &m)
}

#[test]
fn near_twins_are_ordered_by_constraint() {
    let costs: Vec<u32> = (0..50).map(|i| (i * 37 % 41) as u32).collect();
    // cell 6 copies cell 1 and also needs cell 3 first: 1 may lead it
    let text = near_twin_sop_text(6, &costs, &[false], &[6], &[(6, 3)]);
    let inst = formats::parse_instance("near.sop", &text, Format::Sop).unwrap();
    let m = CostModel::new(&inst, Objective::Matrix);
    let cl = cellseq::precedence::Closure::new(&m.dag).unwrap();
    assert!(
        cl.ancestors(6) > cl.ancestors(1),
        "the copy is more constrained"
    );
    let pairs = solvers::beam::interchangeable_order(&m);
    assert!(pairs.contains(&(1, 6)), "{pairs:?}");
    assert!(!pairs.contains(&(6, 1)), "{pairs:?}");
    // cell 1 also needs cell 2 first: neither may lead the other
    let text = near_twin_sop_text(6, &costs, &[false], &[6], &[(6, 3), (1, 2)]);
    let inst = formats::parse_instance("near.sop", &text, Format::Sop).unwrap();
    let m = CostModel::new(&inst, Objective::Matrix);
    let pairs = solvers::beam::interchangeable_order(&m);
    assert!(
        !pairs.iter().any(|&p| p == (1, 6) || p == (6, 1)),
        "{pairs:?}"
    );
    // the same costs and no copy: no pair
    let text = near_twin_sop_text(6, &costs, &[false], &[], &[(6, 3)]);
    let inst = formats::parse_instance("near.sop", &text, Format::Sop).unwrap();
    let m = CostModel::new(&inst, Objective::Matrix);
    assert!(!solvers::beam::interchangeable_order(&m).contains(&(1, 6)));
}

#[test]
fn interchangeable_cells_are_found() {
    let costs: Vec<u32> = (0..50).map(|i| (i * 37 % 41) as u32).collect();
    let text = twin_sop_text(6, &costs, &[false], true, false);
    let inst = formats::parse_instance("twins.sop", &text, Format::Sop).unwrap();
    let m = CostModel::new(&inst, Objective::Matrix);
    let pairs = solvers::beam::interchangeable_order(&m);
    // every pair of the three copies, the smaller index first
    assert_eq!(pairs, vec![(1, 2), (1, 3), (2, 3)]);
    let text = twin_sop_text(6, &costs, &[false], false, true);
    let inst = formats::parse_instance("twins.sop", &text, Format::Sop).unwrap();
    let m = CostModel::new(&inst, Objective::Matrix);
    assert!(solvers::beam::interchangeable_order(&m).is_empty());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]

    #[test]
    fn bounds_below_optimum_and_beam_exact_on_random_matrix(
        sizes in prop::collection::vec(1usize..=3, 3..=7),
        costs in prop::collection::vec(0u32..100, 64),
        prec in prop::collection::vec(prop::bool::weighted(0.25), 32),
    ) {
        let text = pcglns_text(sizes.len(), &sizes, &costs, &prec);
        let inst = formats::parse_instance("rnd.pcglns", &text, Format::Pcglns).unwrap();
        check_instance(&inst, Objective::Matrix);
    }

    #[test]
    fn beam_exact_on_random_clustered_sop(
        group in prop::collection::vec(0usize..3, 4..=9),
        small in prop::collection::vec(0u32..20, 40),
        big in prop::collection::vec(50u32..500, 40),
        prec in prop::collection::vec(prop::bool::weighted(0.15), 40),
    ) {
        let text = clustered_sop_text(&group, &small, &big, &prec);
        let inst = formats::parse_instance("rnd.sop", &text, Format::Sop).unwrap();
        check_instance(&inst, Objective::Matrix);
        check_node_bounds_along_optimum(&inst, Objective::Matrix);
    }

    #[test]
    fn beam_exact_on_random_dense_precedence_sop(
        small in prop::collection::vec(0u32..20, 40),
        big in prop::collection::vec(0u32..60, 40),
        prec in prop::collection::vec(prop::bool::weighted(0.5), 40),
        k in 5usize..=10,
    ) {
        // one group: plain random costs, dense precedence (narrow qpath windows)
        let text = clustered_sop_text(&vec![0; k], &small, &big, &prec);
        let inst = formats::parse_instance("rnd.sop", &text, Format::Sop).unwrap();
        check_instance(&inst, Objective::Matrix);
        check_qpath_along_optimum(&inst, Objective::Matrix);
        check_node_bounds_along_optimum(&inst, Objective::Matrix);
    }

    #[test]
    fn beam_exact_with_interchangeable_cells(
        k in 4usize..=9,
        costs in prop::collection::vec(0u32..50, 50),
        prec in prop::collection::vec(prop::bool::weighted(0.3), 40),
        triple in any::<bool>(),
        skew in any::<bool>(),
    ) {
        let text = twin_sop_text(k, &costs, &prec, triple, skew);
        let inst = formats::parse_instance("twins.sop", &text, Format::Sop).unwrap();
        check_instance(&inst, Objective::Matrix);
    }

    #[test]
    fn beam_exact_with_near_twin_cells(
        k in 4usize..=9,
        costs in prop::collection::vec(0u32..50, 50),
        prec in prop::collection::vec(prop::bool::weighted(0.3), 40),
        two in any::<bool>(),
    ) {
        // copies at the high indices: more predecessors than cell 1, so the precedence
        // differs while one copy may still lead the other
        let copies: Vec<usize> = if two { vec![k - 1, k] } else { vec![k] };
        let text = near_twin_sop_text(k, &costs, &prec, &copies, &[]);
        let inst = formats::parse_instance("near.sop", &text, Format::Sop).unwrap();
        check_instance(&inst, Objective::Matrix);
    }

    #[test]
    fn qpath_prefix_bounds_valid_on_random_matrix(
        sizes in prop::collection::vec(1usize..=3, 3..=7),
        costs in prop::collection::vec(0u32..100, 64),
        prec in prop::collection::vec(prop::bool::weighted(0.4), 32),
    ) {
        let text = pcglns_text(sizes.len(), &sizes, &costs, &prec);
        let inst = formats::parse_instance("rnd.pcglns", &text, Format::Pcglns).unwrap();
        check_qpath_along_optimum(&inst, Objective::Matrix);
        check_node_bounds_along_optimum(&inst, Objective::Matrix);
    }

    #[test]
    fn bounds_below_optimum_and_beam_exact_on_random_geometric(
        n in 3usize..=8,
        tools in 1usize..=2,
        density in 0.0f64..0.4,
        seed in 0u64..1000,
    ) {
        let mut p = BTreeMap::new();
        p.insert("n".to_string(), n.to_string());
        p.insert("tools".to_string(), tools.to_string());
        p.insert("density".to_string(), density.to_string());
        p.insert("closed".to_string(), "0.3".to_string());
        p.insert("modes".to_string(), "2".to_string());
        let inst = cellseq::generate::generate("uniform", &p, seed).unwrap();
        check_instance(&inst, Objective::Time);
        check_instance(&inst, Objective::Air);
    }

    #[test]
    fn assignment_knn_below_optimum_on_random_geometric(
        n in 2usize..=8,
        tools in 1usize..=3,
        density in 0.0f64..0.5,
        layers in 1usize..=3,
        lift in prop::sample::select(vec![0.0, 7.0]),
        link in prop::sample::select(vec![0.0, 4.0, 20.0]),
        home in any::<bool>(),
        seed in 0u64..1000,
    ) {
        let inst = geometric_variant(n, tools, density, layers, lift, link, home, seed);
        for obj in [Objective::Time, Objective::Air] {
            check_assignment_knn(&inst, obj, exact(&inst, obj));
        }
    }
}

/// A zero optimum gives bounds of 0, never -0 (the integral rounding used to print "-0"), and
/// the assignment bound of a matrix of many equal costs is exact.
#[test]
fn zero_bounds_are_positive_zero() {
    let n = 60;
    let costs: Vec<f64> = (0..n * n)
        .map(|k| {
            let (i, j) = (k / n, k % n);
            // a zero path 0 -> 1 -> ... and many other zero arcs: the optimum is 0
            if j == i + 1 || (i * 7 + j) % 5 == 0 {
                0.0
            } else {
                3.0
            }
        })
        .collect();
    let inst = Instance::from_matrix("ties", n, costs, &[]).unwrap();
    let b = all_bounds(&inst, Objective::Matrix);
    for p in &b.parts {
        assert!(
            p.value <= 0.0,
            "{}: {} above the optimum 0",
            p.name,
            p.value
        );
        assert!(
            p.value != 0.0 || p.value.is_sign_positive(),
            "{}: -0",
            p.name
        );
    }
    assert_eq!(b.best.to_string(), "0");
    assert!(b.parts.iter().any(|p| p.name == "assignment"));
}

/// `soft`: every pass of the beam runs within that share of its budget, but the widest
/// bounded pass (the last before the unbounded one: width `exhaustive_from` when the widths
/// reach it), which may use the whole budget when the pass before it predicts that it fits.
/// Evaluation budgets make both runs deterministic, so the soft run is compared with the same
/// beam given only the soft share.
#[test]
fn beam_soft_share_holds_every_pass_but_the_widest() {
    let inst = crate::common::sop("prob.100");
    let run = |exhaustive_from: &str, soft: &str, evals: u64| {
        let p: BTreeMap<String, String> = [
            ("warm_evals", "20000"),
            ("exhaustive_from", exhaustive_from),
            ("soft", soft),
        ]
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        let budget = Budget {
            max_evals: Some(evals),
            ..Budget::default()
        };
        solve_with("beam", &inst, Objective::Matrix, &p, budget).expect("beam solves")
    };
    // the pass of width 512 is predicted to fit in 32e6 evaluations: it runs past the soft
    // half, and the beam ends within the whole budget; with 300, not a width of the ladder,
    // the widest bounded pass is the one of width 256, and it fits in 16e6
    for (exhaustive_from, evals) in [("512", 32_000_000), ("300", 16_000_000)] {
        let (soft, half) = (
            run(exhaustive_from, "0.5", evals),
            run(exhaustive_from, "1", evals / 2),
        );
        assert!(
            soft.evaluations > evals / 2 && soft.evaluations <= evals,
            "exhaustive_from {exhaustive_from}: the widest pass runs past the soft share: {} \
             evaluations",
            soft.evaluations
        );
        assert!(soft.report.cost <= half.report.cost);
    }
    // with 512 in 16e6 it is not: every pass stays within the soft half, as with that half
    let (soft, half) = (run("512", "0.5", 16_000_000), run("512", "1", 8_000_000));
    assert_eq!(soft.evaluations, half.evaluations);
    assert_eq!(soft.report.cost, half.report.cost);
}

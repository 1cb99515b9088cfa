//! Property tests: every move's O(1) delta equals a full re-evaluation, and the O(1)
//! precedence tests accept only feasible results.

use cellseq::cost::CostModel;
use cellseq::engine::moves::{
    Reversal, apply_segment, mode_delta, reverse_delta_direct, reversible_segment, segment_delta,
    sop3_delta, window,
};
use cellseq::engine::{Costs, Solution, modes::mode_dp};
use cellseq::generate::generate;
use cellseq::solvers::greedy;
use proptest::prelude::*;
use std::collections::BTreeMap;

/// A `uniform` instance: 30 % closed cells, two layers.
fn instance(
    seed: u64,
    n: usize,
    modes: usize,
    tools: usize,
    density: f64,
    reversible: bool,
    return_home: bool,
) -> cellseq::model::Instance {
    let kv: BTreeMap<String, String> = [
        ("n", n.to_string()),
        ("modes", modes.to_string()),
        ("closed", "0.3".to_string()),
        ("tools", tools.to_string()),
        ("layers", "2".to_string()),
        ("density", density.to_string()),
        ("reversible", reversible.to_string()),
    ]
    .into_iter()
    .map(|(k, v)| (k.to_string(), v))
    .collect();
    let mut inst = generate("uniform", &kv, seed).unwrap();
    inst.machine.return_home = return_home;
    inst
}

fn model(
    seed: u64,
    n: usize,
    modes: usize,
    tools: usize,
    density: f64,
    return_home: bool,
) -> CostModel {
    let inst = instance(seed, n, modes, tools, density, true, return_home);
    CostModel::new(&inst, inst.default_objective())
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-7 * a.abs().max(b.abs()).max(1.0)
}

/// `s` is a permutation of the model's cells, `pos` inverts `order`, and every mode exists.
/// What a search context borrows, for tests: no observer.
struct Ctx {
    obs: cellseq::solvers::NoObserver,
}

impl Ctx {
    fn new() -> Self {
        Ctx {
            obs: cellseq::solvers::NoObserver,
        }
    }
    /// A context of seed 1 whose budget is `max_evals` evaluations.
    fn ctx<'a>(
        &'a mut self,
        inst: &'a cellseq::model::Instance,
        m: &'a CostModel,
        max_evals: u64,
    ) -> cellseq::solvers::Context<'a> {
        let budget = cellseq::solvers::Budget {
            max_evals: Some(max_evals),
            ..Default::default()
        };
        cellseq::solvers::Context::new(inst, m, 1, budget, &mut self.obs)
    }
}

/// A window `[lo, lo + len)` of `len.min(n)` places in a sequence of `n`, placed by `a`.
fn window_at(n: usize, len: usize, a: u64) -> (usize, usize, usize) {
    let len = len.min(n);
    let lo = (a % (n - len + 1) as u64) as usize;
    (len, lo, lo + len)
}

fn well_formed(m: &CostModel, s: &Solution) -> Result<(), TestCaseError> {
    prop_assert_eq!(s.n(), m.n());
    let mut seen = vec![false; s.n()];
    for (p, &cell) in s.order.iter().enumerate() {
        prop_assert!(!seen[cell as usize]);
        seen[cell as usize] = true;
        prop_assert_eq!(s.pos[cell as usize] as usize, p);
        prop_assert!((s.mode[cell as usize] as usize) < m.modes(cell as usize));
    }
    Ok(())
}

/// A feasible sequence in a random topological order (the ready cell `shuffle` names at each
/// step), every cell in its first mode: a start with much to improve, with precedence.
fn shuffled_feasible(m: &CostModel, shuffle: &[u64]) -> cellseq::model::Sequence {
    let n = m.n();
    let mut missing: Vec<usize> = (0..n).map(|c| m.dag.preds[c].len()).collect();
    let mut ready: Vec<usize> = (0..n).filter(|&c| missing[c] == 0).collect();
    let mut seq = Vec::with_capacity(n);
    while !ready.is_empty() {
        let r = shuffle[seq.len() % shuffle.len()] as usize % ready.len();
        let c = ready.swap_remove(r);
        seq.push(cellseq::model::Visit::new(c, 0));
        for &q in &m.dag.succs[c] {
            missing[q as usize] -= 1;
            if missing[q as usize] == 0 {
                ready.push(q as usize);
            }
        }
    }
    seq
}

/// Greedy's sequence scrambled by the swaps `shuffle` names (a start with much to improve;
/// feasible only without precedence).
fn scrambled(m: &CostModel, shuffle: &[u64]) -> cellseq::model::Sequence {
    let n = m.n();
    let mut seq = greedy::geometric(m, &mut |_| {});
    for (i, r) in shuffle.iter().enumerate().take(n) {
        seq.swap(i, (*r % n as u64) as usize);
    }
    seq
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]
    #[test]
    fn deltas_match_full_evaluation(seed in 0u64..1000, n in 4usize..40, modes in 1usize..4, tools in 1usize..3,
                                    density in 0.0f64..0.2, closed in any::<bool>(), rh in any::<bool>(), picks in prop::collection::vec(any::<u64>(), 60)) {
        let m = model(seed, n, modes, tools, density, rh);
        let c = Costs { m: &m, closed };
        let seq = greedy::geometric(&m, &mut |_| {});
        let mut s = Solution::new(&c, &seq);
        prop_assert!(s.feasible(&m));
        let mut it = picks.into_iter();
        let mut next = |k: usize| (it.next().unwrap_or(7) % k as u64) as usize;
        for round in 0..10 {
            let kind = round % 5;
            match kind {
                0 => {
                    // SOP-3-exchange
                    let h = next(n - 2) as isize - 1;
                    let i = h + 1 + next((n as isize - 2 - h) as usize) as isize;
                    let j = i + 1 + next((n as isize - 1 - i) as usize) as isize;
                    let d = sop3_delta(&c, &s, h, i, j);
                    let mut t = s.clone();
                    t.swap_blocks(h, i as usize, j as usize, d);
                    prop_assert!(close(t.cost, t.evaluate(&c)));
                    if t.feasible(&m) { s = t; }
                }
                1 => {
                    let len = 1 + next(3.min(n - 1));
                    let i = next(n - len + 1);
                    let (lo, hi) = window(&m, &s, i, len);
                    let p = lo + next((hi - lo) as usize) as isize;
                    if p >= i as isize - 1 && p < (i + len) as isize { continue; }
                    let rev = len > 1 && reversible_segment(&m, &s, i, len);
                    for r in [false, rev] {
                        let d = segment_delta(&c, &s, i, len, p, r);
                        let mut t = s.clone();
                        apply_segment(&m, &mut t, i, len, p, r, d);
                        prop_assert!(t.feasible(&m), "window admitted an infeasible move");
                        prop_assert!(close(t.cost, t.evaluate(&c)));
                    }
                    let d = segment_delta(&c, &s, i, len, p, rev);
                    apply_segment(&m, &mut s, i, len, p, rev, d);
                }
                2 => {
                    let mut rv = Reversal::default();
                    rv.refresh(&c, &s);
                    let i = next(n);
                    let reach = rv.reach(i);
                    if reach < i as isize { continue; }
                    let j = i + next((reach - i as isize + 1) as usize);
                    prop_assert!(reversible_segment(&m, &s, i, j - i + 1));
                    let d = rv.delta(&c, &s, i, j);
                    prop_assert!(close(d, reverse_delta_direct(&c, &s, i, j)));
                    s.reverse(&m, i, j, d);
                    prop_assert!(s.feasible(&m));
                    prop_assert!(close(s.cost, s.evaluate(&c)));
                }
                3 => {
                    let p = next(n);
                    let cell = s.order[p] as usize;
                    let md = next(m.modes(cell));
                    let d = mode_delta(&c, &s, p, md);
                    s.set_mode(cell, md, d);
                    prop_assert!(close(s.cost, s.evaluate(&c)));
                }
                _ => {
                    let before = s.cost;
                    mode_dp(&c, &mut s);
                    prop_assert!(s.cost <= before + 1e-9 * before.abs().max(1.0));
                    prop_assert!(close(s.cost, s.evaluate(&c)));
                }
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]
    /// The incremental 2-opt state (`Reversal::reversed`, no O(n) refresh) gives the same
    /// deltas as a direct computation after a run of applied reversals, in all three ways of
    /// deciding feasibility: no precedence (any segment), exact reach array, per-candidate check.
    #[test]
    fn incremental_reversal_state_matches_direct(seed in 0u64..1000, n in 4usize..40, modes in 1usize..3,
                                                 density in 0.0f64..0.2, lazy in any::<bool>(), time in any::<bool>(),
                                                 matrix in 0usize..4, picks in prop::collection::vec(any::<u64>(), 80)) {
        let kv: BTreeMap<String, String> = [
            ("n", n.to_string()),
            ("modes", modes.to_string()),
            ("closed", "0.2".to_string()),
            ("density", density.to_string()),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect();
        // asymmetric matrices (every reversal changes the inside links' cost) one time in four
        let inst = if matrix == 0 {
            let f = ["ESC12", "br17.10", "p43.1", "ft53.1"][(seed % 4) as usize];
            crate::common::sop(f)
        } else {
            generate("uniform", &kv, seed).unwrap()
        };
        let n = inst.n();
        let obj = if inst.is_matrix() {
            cellseq::model::Objective::Matrix
        } else if time { cellseq::model::Objective::Time } else { cellseq::model::Objective::Air };
        let m = CostModel::new(&inst, obj);
        let c = Costs::open(&m);
        let seq = if m.is_geometric() {
            greedy::geometric(&m, &mut |_| {})
        } else {
            greedy::matrix(&m, &mut |_| {})
        };
        let mut s = Solution::new(&c, &seq);
        let mut rv = Reversal::default();
        if lazy {
            rv.lazy_above = 0;
        }
        rv.refresh(&c, &s);
        let mut it = picks.into_iter();
        let mut next = |k: usize| (it.next().unwrap_or(3) % k as u64) as usize;
        let mut applied = 0;
        for _ in 0..40 {
            let i = next(n - 1);
            let j = i + 1 + next(n - 1 - i);
            let reach = rv.reach(i);
            let ok = j as isize <= reach && rv.allowed(&m, &s, i, j);
            // the test agrees with the direct definition
            prop_assert_eq!(ok, reversible_segment(&m, &s, i, j - i + 1));
            if !ok {
                continue;
            }
            let d = rv.delta(&c, &s, i, j);
            prop_assert!(close(d, reverse_delta_direct(&c, &s, i, j)));
            s.reverse(&m, i, j, d);
            rv.reversed(&c, &s, i, j);
            applied += 1;
            prop_assert!(s.feasible(&m));
            prop_assert!(close(s.cost, s.evaluate(&c)));
        }
        // some reversals must have been tried for the property to say anything
        prop_assume!(applied > 0);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(60))]
    /// The linked-list Or-opt pass: its incrementally updated cost equals a full
    /// re-evaluation, the result is a permutation with valid modes, never worse than the start,
    /// and the checker agrees (so precedence holds) — over open and closed cells, several
    /// modes, several tools, reversible or not, with or without precedence, paths with or
    /// without the return home.
    #[test]
    fn linked_or_opt_is_exact(seed in 0u64..1000, n in 2usize..50, modes in 1usize..4, tools in 1usize..3,
                              reversible in any::<bool>(), rh in any::<bool>(), k in 1usize..8,
                              density in prop_oneof![Just(0.0), 0.01f64..0.3],
                              shuffle in prop::collection::vec(any::<u64>(), 50)) {
        use cellseq::engine::{Neighbours, linked};
        let inst = instance(seed, n, modes, tools, density, reversible, rh);
        let m = CostModel::new(&inst, inst.default_objective());
        let c = Costs::open(&m);
        let start_seq = if m.dag.is_empty() { scrambled(&m, &shuffle) } else { shuffled_feasible(&m, &shuffle) };
        let mut s = Solution::new(&c, &start_seq);
        let start = s.cost;
        let nb = Neighbours::new(&m, k);
        let mut fx = Ctx::new();
        // an evaluation budget, so that a wrong delta that cycles still ends (and fails below)
        let mut ctx = fx.ctx(&inst, &m, 2_000_000);
        linked::or_opt(&c, &nb, &mut s, &mut ctx);
        prop_assert!(close(s.cost, s.evaluate(&c)), "tracked {} vs evaluated {}", s.cost, s.evaluate(&c));
        prop_assert!(s.cost <= start + 1e-9 * start.abs().max(1.0));
        well_formed(&m, &s)?;
        // passes from a local optimum of the don't-look-bit search stay exact
        linked::or_opt(&c, &nb, &mut s, &mut ctx);
        prop_assert!(close(s.cost, s.evaluate(&c)));
        let r = cellseq::check(&inst, &s.sequence(), inst.default_objective()).unwrap();
        prop_assert!(close(r.cost, s.cost + m.constant()));
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]
    /// The two-level list applies reversals and block swaps exactly as the array form does.
    #[test]
    fn two_level_matches_array(seed in 0u64..1000, n in 2usize..80, reversible in any::<bool>(),
                               ops in prop::collection::vec((0u8..2, any::<u64>(), any::<u64>(), any::<u64>()), 1..120)) {
        use cellseq::engine::twolevel::TwoLevel;
        let inst = instance(seed, n, 2, 1, 0.0, reversible, false);
        let m = CostModel::new(&inst, inst.default_objective());
        let c = Costs::open(&m);
        let seq = greedy::geometric(&m, &mut |_| {});
        let mut s = Solution::new(&c, &seq);
        let mut t = TwoLevel::new(&s);
        for (kind, a, b, d) in ops {
            if kind == 0 {
                let i = (a % n as u64) as usize;
                let j = i + (b % (n - i) as u64) as usize;
                s.reverse(&m, i, j, 0.0);
                t.reverse(&m, i, j, 0.0);
            } else if n >= 2 {
                let h = (a % (n as u64 - 1)) as isize - 1;
                let i = h + 1 + (b % (n as isize - 1 - h) as u64) as isize;
                if i as usize + 1 >= n {
                    continue;
                }
                let j = i + 1 + (d % (n as isize - 1 - i) as u64) as isize;
                s.swap_blocks(h, i as usize, j as usize, 0.0);
                t.swap_blocks(&m, h, i as usize, j as usize, 0.0);
            }
            for p in 0..n {
                let x = s.order[p];
                prop_assert_eq!(t.cell_at(p), x);
                prop_assert_eq!(t.pos(x), p);
                prop_assert_eq!(t.mode(&m, x), s.mode[x as usize]);
                prop_assert_eq!(t.next(x), s.order.get(p + 1).copied());
                prop_assert_eq!(t.prev(x), p.checked_sub(1).map(|q| s.order[q]));
            }
        }
        let mut u = s.clone();
        t.write(&m, &mut u);
        prop_assert_eq!(&u.order, &s.order);
        prop_assert_eq!(&u.pos, &s.pos);
        prop_assert_eq!(&u.mode, &s.mode);
    }

    /// The two-level search keeps an exact cost and a feasible permutation, with and without
    /// precedence, through the descent (with and without 3-opt moves) and the kicks (local and
    /// random-walk ones, two or three blocks) with their undo.
    #[test]
    fn two_level_search_is_exact(seed in 0u64..1000, n in 2usize..60, modes in 1usize..4, tools in 1usize..3,
                                 density in prop_oneof![Just(0.0), 0.0f64..0.1], reversible in any::<bool>(),
                                 rh in any::<bool>(), k in 1usize..8, rev_max in 1usize..20,
                                 walk in prop_oneof![Just(0.0), Just(0.5), Just(1.0)], three in any::<bool>(),
                                 shuffle in prop::collection::vec(any::<u64>(), 60)) {
        use cellseq::engine::{Neighbours, large::{self, Large}};
        let inst = instance(seed, n, modes, tools, density, reversible, rh);
        let m = CostModel::new(&inst, inst.default_objective());
        let c = Costs::open(&m);
        prop_assert!(large::applies(&c));
        let seq = if density == 0.0 {
            scrambled(&m, &shuffle)
        } else {
            greedy::geometric(&m, &mut |_| {})
        };
        let mut s = Solution::new(&c, &seq);
        let start = s.cost;
        let nb = Neighbours::new(&m, k);
        let mut fx = Ctx::new();
        // an evaluation budget, so that a wrong delta that cycles still ends (and fails below)
        let mut ctx = fx.ctx(&inst, &m, 400_000);
        let mut l = Large::new(c, &nb, &s);
        l.rev_max = rev_max;
        l.walk = walk;
        l.three = three;
        l.three_k = k;
        l.optimize(&mut ctx);
        l.write(&mut s);
        prop_assert!(close(s.cost, s.evaluate(&c)), "descent: tracked {} vs evaluated {}", s.cost, s.evaluate(&c));
        prop_assert!(s.cost <= start + 1e-9 * start.abs().max(1.0));
        let after = s.cost;
        l.kicks(&mut ctx, seed, 4, 200);
        l.write(&mut s);
        prop_assert!(close(s.cost, s.evaluate(&c)), "kicks: tracked {} vs evaluated {}", s.cost, s.evaluate(&c));
        prop_assert!(s.cost <= after + 1e-9 * after.abs().max(1.0));
        well_formed(&m, &s)?;
        prop_assert!(s.feasible(&m));
        let r = cellseq::check(&inst, &s.sequence(), inst.default_objective()).unwrap();
        prop_assert!(close(r.cost, s.cost + m.constant()));
    }
}

/// From a local optimum of 2-opt, Or-opt and mode moves, the two-level descent with 3-opt
/// moves still finds improvements (uniform points, air, greedy start): they reach what the
/// other moves cannot, and the tracked cost stays exact.
#[test]
fn three_opt_improves_a_two_opt_or_opt_optimum() {
    use cellseq::engine::{Neighbours, large::Large};
    for seed in 1..=4u64 {
        let kv: BTreeMap<String, String> = [
            ("n", "2000"),
            ("closed", "1"),
            ("length", "0"),
            ("lift", "0"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        let inst = generate("uniform", &kv, seed).unwrap();
        let m = CostModel::new(&inst, cellseq::model::Objective::Air);
        let c = Costs::open(&m);
        let mut s = Solution::new(&c, &greedy::geometric(&m, &mut |_| {}));
        let nb = Neighbours::new(&m, 8);
        let mut fx = Ctx::new();
        let mut ctx = fx.ctx(&inst, &m, 1_000_000_000);
        let mut l = Large::new(c, &nb, &s);
        l.optimize(&mut ctx);
        let without = l.t.cost;
        l.three = true;
        l.optimize(&mut ctx);
        let with = l.t.cost;
        l.write(&mut s);
        assert!(close(s.cost, s.evaluate(&c)));
        assert!(
            with < without * 0.995,
            "seed {seed}: with 3-opt {with}, without {without}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]
    /// Ruin and recreate keeps every precedence pair (also through removed chains of
    /// predecessors and successors), keeps a permutation, and leaves the cached cost exact.
    #[test]
    fn ruin_and_recreate_stays_feasible(seed in 0u64..1000, n in 4usize..60, modes in 1usize..3, tools in 1usize..3,
                                        density in 0.0f64..0.6, size in 1usize..30, string in 1usize..12) {
        use cellseq::engine::ruin::Ruin;
        use cellseq::engine::Neighbours;
        use rand::SeedableRng;
        let m = model(seed, n, modes, tools, density, false);
        let c = Costs::open(&m);
        let seq = greedy::geometric(&m, &mut |_| {});
        let mut s = Solution::new(&c, &seq);
        let nb = Neighbours::new(&m, 6);
        let mut ruin = Ruin::new(size, string, 0.05);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        for _ in 0..20 {
            let mut seeds = Vec::new();
            prop_assert!(ruin.kick(&c, &nb, &mut s, &mut rng, &mut seeds).is_some());
            prop_assert!(s.feasible(&m), "recreate broke precedence");
            prop_assert!(!seeds.is_empty());
            well_formed(&m, &s)?;
            prop_assert!(close(s.cost, s.evaluate(&c)));
        }
    }
}

/// `seq` with `windows` of its positions (taken from `picks`) each put in another random
/// order that keeps the precedence among the window's cells, and some modes changed: a
/// second feasible parent that shares some of `seq`'s structure and differs elsewhere.
fn reshuffled(
    m: &CostModel,
    seq: &cellseq::model::Sequence,
    picks: &[u64],
) -> cellseq::model::Sequence {
    let n = seq.len();
    let mut out = seq.clone();
    let mut it = picks.iter().copied().cycle();
    for _ in 0..3 {
        let w = 2 + (it.next().unwrap() % 8) as usize;
        if w > n {
            break;
        }
        let a = (it.next().unwrap() % (n - w + 1) as u64) as usize;
        let cells: Vec<usize> = out[a..a + w].iter().map(|v| v.cell).collect();
        let inside = |x: usize| cells.contains(&x);
        let mut missing: Vec<usize> = cells
            .iter()
            .map(|&x| {
                m.dag.preds[x]
                    .iter()
                    .filter(|&&p| inside(p as usize))
                    .count()
            })
            .collect();
        let mut ready: Vec<usize> = (0..w).filter(|&k| missing[k] == 0).collect();
        let mut order = Vec::with_capacity(w);
        while !ready.is_empty() {
            let k = ready.swap_remove((it.next().unwrap() % ready.len() as u64) as usize);
            order.push(k);
            for &q in &m.dag.succs[cells[k]] {
                if let Some(kq) = cells.iter().position(|&x| x == q as usize) {
                    missing[kq] -= 1;
                    if missing[kq] == 0 {
                        ready.push(kq);
                    }
                }
            }
        }
        let old: Vec<cellseq::model::Visit> = out[a..a + w].to_vec();
        for (slot, &k) in order.iter().enumerate() {
            let mut v = old[k];
            if it.next().unwrap() % 3 == 0 {
                v.mode = (it.next().unwrap() % m.modes(v.cell) as u64) as usize;
            }
            out[a + slot] = v;
        }
    }
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(60))]
    /// The partition crossover's child is a feasible permutation with an exact cached cost,
    /// strictly cheaper than both parents, and as cheap as the best of all combinations of
    /// the parents' segments (enumerated here from the prefix sets); when it returns nothing,
    /// no combination beats the better parent.
    #[test]
    fn partition_crossover_is_the_best_feasible_combination(seed in 0u64..1000, n in 2usize..40, modes in 1usize..3,
            tools in 1usize..3, density in 0.0f64..0.5, closed in any::<bool>(),
            shuffle in prop::collection::vec(any::<u64>(), 1..40), picks in prop::collection::vec(any::<u64>(), 1..40)) {
        use cellseq::engine::crossover::Crossover;
        use std::collections::BTreeSet;
        let m = model(seed, n, modes, tools, density, false);
        let c = Costs { m: &m, closed };
        let sa = shuffled_feasible(&m, &shuffle);
        let sb = reshuffled(&m, &sa, &picks);
        let (a, b) = (Solution::new(&c, &sa), Solution::new(&c, &sb));
        prop_assert!(a.feasible(&m) && b.feasible(&m));
        // segments: maximal runs between positions where both prefixes hold the same cells
        let mut cuts = Vec::new();
        let (mut pa, mut pb) = (BTreeSet::new(), BTreeSet::new());
        for k in 0..n {
            pa.insert(sa[k].cell);
            pb.insert(sb[k].cell);
            if pa == pb {
                cuts.push(k);
            }
        }
        let mut best = f64::INFINITY;
        if cuts.len() <= 12 {
            for mask in 0u32..(1 << cuts.len()) {
                let mut seq = Vec::with_capacity(n);
                let mut from = 0;
                for (si, &k) in cuts.iter().enumerate() {
                    let src = if mask >> si & 1 == 1 { &sb } else { &sa };
                    seq.extend_from_slice(&src[from..=k]);
                    from = k + 1;
                }
                let s = Solution::new(&c, &seq);
                prop_assert!(s.feasible(&m));
                best = best.min(s.cost);
            }
        }
        let better = a.cost.min(b.cost);
        match Crossover::default().cross(&c, &a, &b) {
            Some(child) => {
                well_formed(&m, &child)?;
                prop_assert!(child.feasible(&m));
                prop_assert!(close(child.cost, child.evaluate(&c)));
                prop_assert!(child.cost < better);
                if best.is_finite() {
                    prop_assert!(close(child.cost, best), "child {} but best combination {}", child.cost, best);
                }
            }
            None => {
                if best.is_finite() {
                    prop_assert!(best >= better - 1e-7 * better.abs().max(1.0), "missed {} < {}", best, better);
                }
            }
        }
    }
}

/// Brute force: the cheapest cost of `s` with the cells at positions `lo..=hi` put in the
/// order `cells` and their modes chosen freely (every combination), everything else kept.
fn best_over_modes(c: &Costs, s: &Solution, lo: usize, cells: &[u32]) -> f64 {
    let m = c.m;
    let mut t = s.clone();
    t.order[lo..lo + cells.len()].copy_from_slice(cells);
    for (p, &x) in t.order.iter().enumerate() {
        t.pos[x as usize] = p as u32;
    }
    let mut best = f64::INFINITY;
    let mut digits = vec![0usize; cells.len()];
    loop {
        for (k, &x) in cells.iter().enumerate() {
            t.mode[x as usize] = digits[k] as u32;
        }
        best = best.min(t.evaluate(c));
        // next combination of modes
        let mut k = 0;
        loop {
            if k == cells.len() {
                return best;
            }
            digits[k] += 1;
            if digits[k] < m.modes(cells[k] as usize) {
                break;
            }
            digits[k] = 0;
            k += 1;
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Window moves with modes keep the cached cost exact, never make a sequence worse,
    /// keep precedence (the checker agrees), and stop where no single-cell move inside a
    /// window, with every mode of the window and its two neighbours chosen by brute force,
    /// is cheaper.
    #[test]
    fn window_moves_with_modes_reach_their_local_optimum(seed in 0u64..1000, n in 2usize..14, modes in 1usize..4,
                              tools in 1usize..3, density in prop_oneof![Just(0.0), 0.05f64..0.5],
                              shuffle in prop::collection::vec(any::<u64>(), 30)) {
        use cellseq::engine::window::ModeWindow;
        let inst = instance(seed, n, modes, tools, density, true, false);
        let m = CostModel::new(&inst, inst.default_objective());
        let c = Costs::open(&m);
        let mut s = Solution::new(&c, &shuffled_feasible(&m, &shuffle));
        let start = s.cost;
        let mut fx = Ctx::new();
        let mut ctx = fx.ctx(&inst, &m, 50_000_000);
        let w = 4;
        let mut mw = ModeWindow::new(w);
        mw.improve(&c, &mut s, &mut ctx, None);
        prop_assert!(!ctx.exhausted());
        prop_assert!(close(s.cost, s.evaluate(&c)), "tracked {} vs evaluated {}", s.cost, s.evaluate(&c));
        prop_assert!(s.cost <= start + 1e-9 * start.abs().max(1.0));
        well_formed(&m, &s)?;
        let r = cellseq::check(&inst, &s.sequence(), inst.default_objective()).unwrap();
        prop_assert!(close(r.cost, s.cost + m.constant()));
        // local optimum against brute force over every window's feasible single-cell moves
        let w = w.min(n);
        for i in 0..=n - w {
            let lo = i.saturating_sub(1);
            let hi = (i + w).min(n - 1);
            for a in i..i + w {
                for b in i..i + w {
                    let mut cells = s.order[lo..=hi].to_vec();
                    let x = cells.remove(a - lo);
                    cells.insert(b - lo, x);
                    let mut t = s.clone();
                    t.order[lo..=hi].copy_from_slice(&cells);
                    for (p, &y) in t.order.iter().enumerate() {
                        t.pos[y as usize] = p as u32;
                    }
                    if !t.feasible(&m) {
                        continue;
                    }
                    let v = best_over_modes(&c, &s, lo, &cells);
                    prop_assert!(v >= s.cost - 1e-7 * s.cost.abs().max(1.0),
                                 "window {} move {}->{}: {} < {}", i, a, b, v, s.cost);
                }
            }
        }
    }
}

/// Every permutation of `cells` (Heap's algorithm), passed to `f`.
fn permutations(cells: &[u32], f: &mut impl FnMut(&[u32])) {
    fn go(k: usize, a: &mut Vec<u32>, f: &mut impl FnMut(&[u32])) {
        if k <= 1 {
            f(a);
            return;
        }
        for i in 0..k {
            go(k - 1, a, f);
            let j = if k.is_multiple_of(2) { i } else { 0 };
            a.swap(j, k - 1);
        }
    }
    let mut a = cells.to_vec();
    go(a.len(), &mut a, f);
}

/// After a window search from cost `start`: `s` is well formed, feasible, its cached cost
/// exact (the checker agrees), it costs the better of `start` and the brute-force optimum
/// `brute`, and `improved` says whether it fell.
fn window_result(
    inst: &cellseq::model::Instance,
    c: &Costs,
    s: &Solution,
    start: f64,
    brute: f64,
    improved: bool,
) -> Result<(), TestCaseError> {
    let m = c.m;
    prop_assert!(
        close(s.cost, s.evaluate(c)),
        "tracked {} vs evaluated {}",
        s.cost,
        s.evaluate(c)
    );
    well_formed(m, s)?;
    prop_assert!(s.feasible(m));
    let r = cellseq::check(inst, &s.sequence(), inst.default_objective()).unwrap();
    prop_assert!(close(r.cost, s.cost + m.constant()));
    prop_assert!(
        close(s.cost, brute.min(start)),
        "search {} brute {} start {}",
        s.cost,
        brute,
        start
    );
    prop_assert_eq!(improved, s.cost < start - 1e-9 * start.abs().max(1.0));
    Ok(())
}

/// The cheapest cost of `s` over every order of its cells at positions `lo..hi` that keeps
/// precedence and passes `allow`, with every mode combination of those cells.
fn brute_window(
    c: &Costs,
    s: &Solution,
    lo: usize,
    hi: usize,
    allow: impl Fn(&Solution) -> bool,
) -> f64 {
    let mut brute = f64::INFINITY;
    permutations(&s.order[lo..hi], &mut |perm| {
        let mut t = s.clone();
        t.order[lo..hi].copy_from_slice(perm);
        for (p, &y) in t.order.iter().enumerate() {
            t.pos[y as usize] = p as u32;
        }
        if t.feasible(c.m) && allow(&t) {
            brute = brute.min(best_over_modes(c, s, lo, perm));
        }
    });
    brute
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(40))]
    /// The bounded-shift DP keeps the cached cost exact and precedence intact, and finds the
    /// cheapest reorder of its window (with the best modes) among those in which no cell
    /// passes a cell that lay `k` or more places after it: brute force over every such
    /// permutation and every mode combination agrees.
    #[test]
    fn shift_dp_is_exact_over_its_neighbourhood(seed in 0u64..1000, n in 2usize..10, modes in 1usize..4,
                              tools in 1usize..3, density in prop_oneof![Just(0.0), 0.05f64..0.5],
                              k in 2usize..6, a in any::<u64>(), len in 2usize..7,
                              shuffle in prop::collection::vec(any::<u64>(), 30)) {
        use cellseq::engine::shift::ShiftDp;
        let inst = instance(seed, n, modes, tools, density, true, false);
        let m = CostModel::new(&inst, inst.default_objective());
        let c = Costs::open(&m);
        let mut s = Solution::new(&c, &shuffled_feasible(&m, &shuffle));
        let (len, lo, hi) = window_at(n, len, a);
        // brute force first, on the sequence as it is
        let cells = s.order[lo..hi].to_vec();
        let brute = brute_window(&c, &s, lo, hi, |t| {
            (0..len).all(|i| (i + k..len).all(|j| t.pos[cells[i] as usize] < t.pos[cells[j] as usize]))
        });
        let start = s.cost;
        let mut fx = Ctx::new();
        let mut ctx = fx.ctx(&inst, &m, 50_000_000);
        let mut dp = ShiftDp::new(k, 1_000_000);
        let improved = dp.improve_range(&c, &mut s, &mut ctx, lo, hi);
        window_result(&inst, &c, &s, start, brute, improved)?;
        prop_assert_eq!(&s.order[..lo], &shuffled_order(&m, &shuffle)[..lo]);
    }
}

fn shuffled_order(m: &CostModel, shuffle: &[u64]) -> Vec<u32> {
    shuffled_feasible(m, shuffle)
        .iter()
        .map(|v| v.cell as u32)
        .collect()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    /// Window re-optimization solves its window as an instance of its own: the result is
    /// feasible, its cost exact, and the window's links cost what brute force over every
    /// feasible order and every mode combination of the window's cells finds (the beam
    /// proves windows this small), on open paths and on paths that return home.
    #[test]
    fn reopt_window_is_the_brute_force_optimum(seed in 0u64..1000, n in 2usize..10, modes in 1usize..4,
                              tools in 1usize..3, density in prop_oneof![Just(0.0), 0.05f64..0.5],
                              rh in any::<bool>(), a in any::<u64>(), len in 1usize..6,
                              shuffle in prop::collection::vec(any::<u64>(), 30)) {
        use cellseq::solvers::reopt::Reopt;
        let inst = instance(seed, n, modes, tools, density, true, rh);
        let m = CostModel::new(&inst, inst.default_objective());
        let c = Costs::open(&m);
        let mut s = Solution::new(&c, &shuffled_feasible(&m, &shuffle));
        let (len, lo, hi) = window_at(n, len, a);
        let brute = brute_window(&c, &s, lo, hi, |_| true);
        let start = s.cost;
        let mut fx = Ctx::new();
        let mut ctx = fx.ctx(&inst, &m, 500_000_000);
        let r = Reopt { window: len, step: 0, window_share: 1.0, max_window: 200, k: 8 };
        let (gain, proven) = r.window(&c, &mut s, &mut ctx, lo, hi).unwrap();
        prop_assert!(proven);
        window_result(&inst, &c, &s, start, brute, gain)?;
    }
}

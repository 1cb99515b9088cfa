//! The default portfolio (`auto`) and the enhanced ant colony (`eacs`): plans, determinism
//! under an evaluation budget, and solution quality on a small TSPLIB SOP instance.

use cellseq::solvers::auto::{Start, parse_plan, plan_text};
use cellseq::solvers::{Budget, NoObserver, run};
use std::collections::BTreeMap;

use crate::common::sop;

fn evals(n: u64) -> Budget {
    Budget {
        time_limit: None,
        max_evals: Some(n),
    }
}

fn secs(s: f64) -> Budget {
    Budget {
        time_limit: Some(std::time::Duration::from_secs_f64(s)),
        max_evals: None,
    }
}

#[test]
fn plans_parse_and_bad_plans_are_rejected() {
    let p = parse_plan("local-search:0.3, eacs*:0.5,ils*:1").unwrap();
    assert_eq!(p.len(), 3);
    assert_eq!(p[1].solver, "eacs");
    assert_eq!((p[0].start, p[1].start), (Start::Fresh, Start::Best));
    assert!((p[0].share - 0.3).abs() < 1e-12);
    assert!(p[0].params.is_empty());
    let p = parse_plan("local-search[kicks=0; k=8]:0.3,ils[accept=0.01]*:1").unwrap();
    assert_eq!(p[0].solver, "local-search");
    assert_eq!(p[0].params.get("kicks").map(String::as_str), Some("0"));
    assert_eq!(p[0].params.get("k").map(String::as_str), Some("8"));
    assert!(p[1].start == Start::Best && p[1].solver == "ils");
    assert_eq!(p[1].params.get("accept").map(String::as_str), Some("0.01"));
    let p = parse_plan("local-search:0.2,~eacs:0.5,ils[accept=0.01]+:1").unwrap();
    assert!(p[1].reversed && !p[0].reversed && !p[2].reversed);
    assert_eq!((p[1].start, p[2].start), (Start::Fresh, Start::Previous));
    assert_eq!(p[2].params.get("accept").map(String::as_str), Some("0.01"));
    for bad in [
        "local-search[kicks=0:0.3",
        "local-search[kicks]:0.3",
        "local-search[nosuch=1]:0.3",
        "local-search[kicks=x]:0.3",
        "",
        "ils",
        "ils:0",
        "ils:1.5",
        "nosuch:1",
        "auto:1",
        "local-search*:1",
        "ils+:1",
        "local-search:0.5,local-search+:1",
        "~:1",
    ] {
        assert!(parse_plan(bad).is_err(), "plan '{bad}' accepted");
    }
}

/// `@until` after a phase's share: parsed, printed back, checked, and the phase is skipped
/// once more than that share of the budget is used (an evaluation budget: deterministic).
#[test]
fn a_phase_with_until_runs_only_while_the_budget_lasts() {
    let p = parse_plan("ils:0.9,ils[accept=0.01]*:1@0.5").unwrap();
    assert_eq!((p[0].until, p[1].until), (None, Some(0.5)));
    assert_eq!(parse_plan(&plan_text(&p)).unwrap(), p);
    for bad in ["ils:1@0", "ils:1@1.5", "ils:1@x", "ils:1@", "ils:@0.5"] {
        assert!(parse_plan(bad).is_err(), "plan '{bad}' accepted");
    }
    let inst = sop("ry48p.1");
    let budget = 1_000_000u64;
    let used = |plan: &str| {
        let given = BTreeMap::from([("plan".to_string(), plan.to_string())]);
        run(
            "auto",
            &inst,
            inst.default_objective(),
            &given,
            1,
            evals(budget),
            &mut NoObserver,
        )
        .unwrap()
        .evaluations
    };
    // the first phase uses 90 % of the budget: a second phase with until = 0.5 is skipped,
    // one with until = 0.95 or none runs and spends the rest
    let skipped = used("ils:0.9,ils*:1@0.5");
    assert!(skipped < budget * 92 / 100, "{skipped}");
    assert!(skipped > budget * 85 / 100, "{skipped}");
    for plan in ["ils:0.9,ils*:1@0.95", "ils:0.9,ils*:1"] {
        let all = used(plan);
        assert!(all >= budget * 99 / 100, "{plan}: {all}");
    }
}

#[test]
fn auto_rejects_a_bad_plan_parameter() {
    // every bad value is refused when the solver is built, before anything runs
    let inst = sop("ESC12");
    for (key, value) in [
        ("plan", "ils:2"),
        ("beam-share", "1.5"),
        ("beam-share", "x"),
        ("portfolio", "/nonexistent/portfolio.toml"),
    ] {
        let mut given = BTreeMap::new();
        given.insert(key.to_string(), value.to_string());
        let e = run(
            "auto",
            &inst,
            inst.default_objective(),
            &given,
            1,
            evals(10_000),
            &mut NoObserver,
        );
        assert!(e.is_err(), "{key}={value} was accepted");
    }
}

#[test]
fn chained_portfolio_is_deterministic_under_an_evaluation_budget() {
    let inst = sop("ry48p.1");
    let none = BTreeMap::new();
    for name in ["auto", "eacs"] {
        let solve = || {
            run(
                name,
                &inst,
                inst.default_objective(),
                &none,
                3,
                evals(400_000),
                &mut NoObserver,
            )
            .unwrap()
        };
        let (a, b) = (solve(), solve());
        assert_eq!(a.outcome.sequence, b.outcome.sequence, "{name}");
        assert!(
            a.evaluations <= 400_000 + 50_000,
            "{name}: {}",
            a.evaluations
        );
    }
}

#[test]
fn eacs_reaches_the_best_known_value_of_esc25() {
    // ESC25: best known 1681, proven optimal (instances/tsplib-sop/bks.csv)
    let inst = sop("ESC25");
    let r = run(
        "eacs",
        &inst,
        inst.default_objective(),
        &BTreeMap::new(),
        1,
        evals(3_000_000),
        &mut NoObserver,
    )
    .unwrap();
    assert!(r.report.cost <= 1681.0 + 1e-9, "{}", r.report.cost);
}

#[test]
fn ils_lin_kernighan_chains_help_on_a_symmetric_instance_and_stay_deterministic() {
    // prob.42: symmetric costs, so lk=auto turns the LK chains on
    let inst = sop("prob.42");
    let solve = |lk: &str| {
        let mut given = BTreeMap::new();
        given.insert("lk".to_string(), lk.to_string());
        run(
            "ils",
            &inst,
            inst.default_objective(),
            &given,
            3,
            evals(300_000),
            &mut NoObserver,
        )
        .unwrap()
    };
    let on = solve("auto");
    let again = solve("auto");
    let off = solve("false");
    assert_eq!(on.outcome.sequence, again.outcome.sequence);
    // same seed and budget: the LK repair ends lower (256 vs 277 when written)
    assert!(
        on.report.cost < off.report.cost,
        "{} vs {}",
        on.report.cost,
        off.report.cost
    );
}

#[test]
fn auto_picks_its_rule_by_symmetry_and_precedence_density() {
    use cellseq::cost::CostModel;
    use cellseq::solvers::auto::{Auto, PLAN_RULE, plan_text};
    use cellseq::solvers::{Params, find};
    let auto = |kv: &[(&str, &str)]| {
        let given: BTreeMap<String, String> = kv
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let info = find("auto").unwrap();
        Auto::from_params(&Params::new("auto", info.params, &given).unwrap()).unwrap()
    };
    let model = |name: &str| {
        let inst = sop(name);
        CostModel::new(&inst, inst.default_objective())
    };
    // prob.42's matrix reads the same backwards; ESC25's does not, and its precedence
    // closure is sparse (0.18); rbg109a's is dense (0.91), rbg323a is dense and large
    let (p42, esc, rbg, big) = (
        model("prob.42"),
        model("ESC25"),
        model("rbg109a"),
        model("rbg323a"),
    );
    let generated = |kind: &str, pairs: &[(&str, &str)], seed: u64| {
        let kv: BTreeMap<String, String> = pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let inst = cellseq::generate::generate(kind, &kv, seed).unwrap();
        CostModel::new(&inst, inst.default_objective())
    };
    let a = auto(&[]);
    let c = a.choose(&p42);
    assert_eq!(c.rule, "symmetric");
    assert!(c.features.symmetric && !c.features.geometric);
    assert_eq!(
        plan_text(c.plan(false, secs(1.0))),
        "local-search:0.1,gls[alpha=3;top=2]*:1"
    );
    assert_eq!(plan_text(c.plan(true, secs(1.0))), "gls[alpha=3;top=2]*:1");
    assert_eq!(c.beam.share, 0.3);
    // sparse precedence: kro124p.3's costs are travel-like (cost_spread 0.48), ESC25's
    // spread as random ones (0.61), which under long budgets adds guided local search
    // between the two walks, also after the beam phase
    let sparse = "local-search:0.1,~eacs:0.2,\
                  ils[accept=0.01;kicks=2;perturb=swap;shift-repair=2]*:0.25,\
                  ils[accept=0.03;kicks=2;perturb=swap;shift-repair=2]*:0.85,reopt[window=16]*:1";
    let with_gls = "local-search:0.1,~eacs:0.2,\
                    ils[accept=0.01;kicks=2;perturb=swap;shift-repair=2]*:0.25,gls*:0.6,\
                    ils[accept=0.03;kicks=2;perturb=swap;shift-repair=2]*:0.85,reopt[window=16]*:1";
    // kro124p.3 (101 cells) takes the sparse plan with carry moves, and three colony rounds
    // under budgets from 7.5 s
    let carry = "local-search:0.1,~eacs:0.2,\
                 ils[accept=0.01;carry=true;kicks=2;perturb=swap;shift-repair=2]*:0.25,\
                 ils[accept=0.03;carry=true;kicks=2;perturb=swap;shift-repair=2]*:0.85,\
                 reopt[window=16]*:1";
    // (three rounds whose walks end when they stall, then up to five more while less than
    // 70 % of the budget is used)
    let walk = "ils[accept=0.01;carry=true;end-stall=2000;kicks=2;perturb=swap;shift-repair=2]+";
    let extra: Vec<String> = (3..8)
        .map(|i| {
            let back = if i % 2 == 0 { "~" } else { "" };
            format!("{back}eacs:0.08@0.7,{walk}:0.25@0.7")
        })
        .collect();
    let rounds = format!(
        "local-search:0.04,~eacs:0.07,{walk}:0.2,eacs:0.09,{walk}:0.25,~eacs:0.12,{walk}:0.33,\
         {},ils[accept=0.03;carry=true;kicks=2;perturb=swap;shift-repair=2]*:0.8,\
         reopt[window=16]*:1",
        extra.join(",")
    );
    let kro = model("kro124p.3");
    let cases = [
        (
            &kro,
            "sparse-small",
            carry,
            rounds.as_str(),
            [secs(1.0), secs(7.49), evals(249_999_999)],
            [secs(7.5), secs(60.0), evals(250_000_000)],
        ),
        (
            &esc,
            "sparse-random",
            sparse,
            with_gls,
            [secs(1.0), secs(4.99), evals(149_999_999)],
            [secs(5.0), secs(10.0), evals(150_000_000)],
        ),
    ];
    for (m, rule, short_plan, long_plan, shorts, longs) in cases {
        let c = a.choose(m);
        assert_eq!(c.rule, rule);
        assert!(c.features.closure_density < 0.2);
        assert_eq!(c.beam.share, 0.1);
        for after_beam in [false, true] {
            for short in shorts {
                assert_eq!(plan_text(c.plan(after_beam, short)), short_plan);
            }
            for long in longs {
                assert_eq!(plan_text(c.plan(after_beam, long)), long_plan);
            }
        }
    }
    // above 500 cells the same costs and precedence keep the `sparse` plan at every budget
    let large = generated(
        "near-symmetric",
        &[("n", "600"), ("c", "1000"), ("p", "10"), ("plane", "true")],
        1,
    );
    let c = a.choose(&large);
    assert_eq!(c.rule, "sparse");
    assert!(c.features.cells > 500 && c.features.cost_spread < 0.5);
    assert_eq!(plan_text(c.plan(true, secs(60.0))), sparse);
    assert!(
        a.choose(&kro).features.cost_spread < 0.5 && a.choose(&esc).features.cost_spread >= 0.5
    );
    // dense instances with many zero-cost links (crane jobs at stations), up to 400 cells:
    // ils with longer kicks; after a beam phase (up to 300 cells) a colony; under a long
    // budget without a beam phase, guided local search, then the walk
    for m in [&rbg, &big] {
        let c = a.choose(m);
        assert_eq!(
            (c.rule, c.beam.share, c.beam.max_cells),
            ("dense-ties", 0.5, 300)
        );
        assert!(c.features.zero_arcs >= 0.01);
        let walk = "local-search:0.1,ils[max-seg=45]*:1";
        for short in [secs(1.0), secs(4.99), evals(299_999_999)] {
            assert_eq!(plan_text(c.plan(false, short)), walk);
        }
        for long in [secs(5.0), secs(60.0), evals(300_000_000)] {
            assert_eq!(plan_text(c.plan(false, long)), "gls:0.7,ils[max-seg=45]*:1");
            assert_eq!(
                plan_text(c.plan(true, long)),
                "local-search:0.3,eacs:0.5,ils*:1"
            );
        }
        // a time limit decides over an evaluation budget given with it
        let both = Budget {
            time_limit: Some(std::time::Duration::from_secs(1)),
            max_evals: Some(1_000_000_000),
        };
        assert_eq!(plan_text(c.plan(false, both)), walk);
    }
    // without those zero-cost links (the generated `time-window` family), the `dense` rule
    let kv: BTreeMap<String, String> = [("n", "120"), ("w", "10"), ("c", "100")]
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let tw = cellseq::generate::generate("time-window", &kv, 1).unwrap();
    let tw = CostModel::new(&tw, tw.default_objective());
    let c = a.choose(&tw);
    assert!(c.features.closure_density >= 0.8 && c.features.zero_arcs < 0.01);
    assert_eq!(c.rule, "dense");
    assert_eq!(
        plan_text(c.plan(false, secs(10.0))),
        "local-search:0.1,ils[max-seg=45]*:1"
    );
    // the larger one is above the beam's bound: it gets no beam phase
    assert!(rbg.n() <= 300 && big.n() > 300);
    // a plan the user chose replaces the rules, with the catch-all rule's beam share
    let own = "local-search:0.5,ils*:1";
    let mine = auto(&[("plan", own)]);
    for m in [&p42, &rbg, &big] {
        let c = mine.choose(m);
        assert_eq!((c.rule, c.beam.share), (PLAN_RULE, 0.1));
        for after_beam in [false, true] {
            assert_eq!(plan_text(c.plan(after_beam, secs(1.0))), own);
        }
    }
    // beam-share replaces the rule's share, and no pass stretches it
    assert_eq!(auto(&[("beam-share", "0")]).choose(&p42).beam.share, 0.0);
    assert_eq!(auto(&[]).choose(&p42).beam.stretch, 2.0);
    assert_eq!(
        auto(&[("beam-share", "0.3")]).choose(&p42).beam.stretch,
        1.0
    );
    // geometric instances: without precedence and with links that cost the same both ways,
    // the two-level local search; with precedence, the catch-all rule
    let geo = |pairs: &[(&str, &str)]| generated("uniform", pairs, 3);
    let free = geo(&[("n", "30"), ("modes", "2"), ("reversible", "true")]);
    let c = a.choose(&free);
    assert_eq!(c.rule, "geometric-free");
    assert!(c.features.geometric && c.features.symmetric);
    assert_eq!(
        plan_text(c.plan(true, secs(1.0))),
        "local-search[three-opt=true;two-level=on;walk-kicks=0.3]:1"
    );
    let ordered = geo(&[("n", "30"), ("preds", "1")]);
    let c = a.choose(&ordered);
    assert_eq!(c.rule, "default");
    assert!(c.features.geometric && c.features.free_density > 0.001);
    assert_eq!(
        plan_text(c.plan(true, secs(1.0))),
        "local-search:0.3,eacs:0.5,ils*:1"
    );
    // a symmetric matrix of one mode per cell above the beam's 400 cells: no beam phase;
    // up to 1000 cells guided local search alone, at 400 cells the `symmetric` rule
    for (n, rule) in [("398", "symmetric"), ("399", "symmetric-medium")] {
        let c = a.choose(&generated("symmetric", &[("n", n), ("p", "1")], 1));
        assert_eq!(c.rule, rule, "{n} cells and the two ends");
    }
    for (n, p) in [("450", "1"), ("450", "30")] {
        let c = a.choose(&generated("symmetric", &[("n", n), ("p", p)], 1));
        assert_eq!((c.rule, c.beam.share), ("symmetric-medium", 0.0));
        assert_eq!(plan_text(c.plan(false, secs(1.0))), "gls[alpha=3;top=2]:1");
    }
    for (n, rule) in [("998", "symmetric-medium"), ("999", "symmetric-large")] {
        let c = a.choose(&generated("symmetric", &[("n", n), ("p", "1")], 1));
        assert_eq!(c.rule, rule, "{n} cells and the two ends");
    }
    // above 1000 cells `ils` alone, with the halved walks
    let c = a.choose(&generated("symmetric", &[("n", "1050"), ("p", "1")], 1));
    assert_eq!((c.rule, c.beam.share), ("symmetric-large", 0.0));
    assert!(c.features.symmetric && c.features.modes == 1.0);
    assert_eq!(
        plan_text(c.plan(false, secs(1.0))),
        "ils[accept=0.01;halve=0.15;max-seg=10;walks=8]:1"
    );
    // `compiler-dag` (closure density 0.8 and above) keeps `ils` at every size above 400
    let c = a.choose(&generated("compiler-dag", &[("n", "450")], 1));
    assert!(c.features.closure_density >= 0.8);
    assert_eq!(c.rule, "symmetric-large-dense");
    // with dense precedence (closure density 0.2 and above) the kicks keep their longer
    // windows
    let c = a.choose(&generated("compiler-dag", &[("n", "1050")], 1));
    assert!(c.features.closure_density >= 0.2);
    assert_eq!((c.rule, c.beam.share), ("symmetric-large-dense", 0.0));
    assert_eq!(
        plan_text(c.plan(false, secs(1.0))),
        "ils[accept=0.01;halve=0.15;walks=8]:1"
    );
    let c = a.choose(&generated("symmetric", &[("n", "1050"), ("p", "30")], 1));
    assert_eq!(c.rule, "symmetric-large-dense");
    // a symmetric matrix with several modes per cell keeps the colony in its plan
    let c = a.choose(&generated("generalized", &[("n", "30"), ("modes", "3")], 1));
    assert_eq!((c.rule, c.beam.share), ("symmetric-modes", 0.3));
    assert!(c.features.symmetric && c.features.modes > 1.0);
    assert_eq!(
        plan_text(c.plan(false, secs(1.0))),
        "local-search:0.2,eacs*:0.3,ils*:1"
    );
    assert_eq!(plan_text(c.plan(true, secs(1.0))), "ils[accept=0.01]*:1");
    // an asymmetric matrix with sparse precedence and several modes per cell (open features
    // cut either way) gets three colony rounds, each polished by `ils`
    let c = a.choose(&generated(
        "generalized",
        &[("n", "40"), ("modes", "3"), ("open", "0.5"), ("p", "5")],
        1,
    ));
    assert_eq!((c.rule, c.beam.share), ("sparse-modes", 0.1));
    assert!(!c.features.symmetric && c.features.modes > 1.0);
    assert!(c.features.closure_density < 0.8);
    assert_eq!(
        plan_text(c.plan(false, secs(1.0))),
        "local-search:0.04,~eacs:0.07,ils[accept=0.01;shift-repair=2]+:0.2,eacs:0.09,\
         ils[accept=0.01;shift-repair=2]+:0.25,~eacs:0.12,ils[accept=0.01;shift-repair=2]+:0.33,\
         ils[accept=0.03;shift-repair=2]*:0.8,reopt[window=16]*:1"
    );
    // the rounds need time to settle: larger instances of the same family stay with `sparse`
    let c = a.choose(&generated(
        "generalized",
        &[("n", "320"), ("modes", "3"), ("open", "0.5"), ("p", "5")],
        1,
    ));
    assert_eq!(c.rule, "sparse");
    assert!(c.features.modes > 1.0 && c.features.cells > 300);
}

#[test]
fn a_colony_run_backwards_solves_the_forward_instance() {
    // ~eacs runs on the transposed twin; the result comes back as a forward sequence that
    // the checker scores (run() checks it), at ESC25's proven optimum 1681, and a plan
    // with two colonies (repeat seeds) and a following ils stays deterministic
    let inst = sop("ESC25");
    let mut given = BTreeMap::new();
    given.insert("beam-share".to_string(), "0".to_string());
    given.insert("plan".to_string(), "~eacs:1".to_string());
    let r = run(
        "auto",
        &inst,
        inst.default_objective(),
        &given,
        1,
        evals(3_000_000),
        &mut NoObserver,
    )
    .unwrap();
    assert!(r.report.cost <= 1681.0 + 1e-9, "{}", r.report.cost);
    let inst = sop("ry48p.1");
    given.insert(
        "plan".to_string(),
        "local-search:0.2,eacs:0.3,~eacs:0.5,ils+:1".to_string(),
    );
    let solve = || {
        run(
            "auto",
            &inst,
            inst.default_objective(),
            &given,
            5,
            evals(600_000),
            &mut NoObserver,
        )
        .unwrap()
    };
    let (a, b) = (solve(), solve());
    assert_eq!(a.outcome.sequence, b.outcome.sequence);
    assert_eq!(a.report.cost, b.report.cost);
}

// ---- the portfolio file ----

/// A portfolio whose every instance goes to one rule running `greedy` alone, no beam phase.
const GREEDY_ONLY: &str = r#"
[beam]
max_cells = 400
min_seconds = 2.0

[[rule]]
name = "greedy-everywhere"
beam = { share = 0.0 }
phases = [ { solver = "greedy", share = 1.0 } ]
"#;

#[test]
fn the_built_in_portfolio_parses_validates_and_ends_with_a_catch_all() {
    use cellseq::solvers::auto::portfolio::{BUILT_IN, Portfolio};
    let p = Portfolio::built_in().unwrap();
    let names: Vec<&str> = p.rules.iter().map(|r| r.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "symmetric-medium",
            "symmetric-large",
            "symmetric-large-dense",
            "symmetric",
            "symmetric-modes",
            "free",
            "sparse-modes",
            "sparse-random",
            "sparse-small",
            "sparse",
            "dense-random",
            "dense-ties",
            "dense",
            "geometric-free",
            "default"
        ]
    );
    assert!(p.catch_all().when.is_empty());
    // three rules have a plan for long budgets: sparse-random, sparse-small and dense-ties
    let long: Vec<&str> = p
        .rules
        .iter()
        .filter(|r| r.long.is_some())
        .map(|r| r.name.as_str())
        .collect();
    assert_eq!(long, ["sparse-random", "sparse-small", "dense-ties"]);
    assert!(
        p.rules[..p.rules.len() - 1]
            .iter()
            .all(|r| !r.when.is_empty())
    );
    // the file says what each rule is for in terms of features, never by benchmark instance
    for word in ["ESC", "rbg", "kro", "prob.", "ft70", "ry48", "p43", "br17"] {
        assert!(
            !BUILT_IN.contains(word),
            "the built-in portfolio names '{word}'"
        );
    }
}

#[test]
fn bad_portfolios_are_refused_naming_the_file_and_the_entry() {
    use cellseq::solvers::auto::portfolio::Portfolio;
    let head = "[beam]\nmax_cells = 400\nmin_seconds = 2.0\n";
    let rule = |name: &str, when: &str, phases: &str| {
        format!(
            "[[rule]]\nname = \"{name}\"\n{when}beam = {{ share = 0.1 }}\nphases = [ {phases} ]\n"
        )
    };
    let ok_phase = "{ solver = \"greedy\", share = 1.0 }";
    let last = rule("rest", "", ok_phase);
    // a rule with a `[rule.long]` table
    let long = |table: &str| {
        format!(
            "{head}{}[rule.long]\n{table}{last}",
            rule("a", "when = { cells = { max = 9 } }\n", ok_phase)
        )
    };
    let cases: Vec<(String, &str)> = vec![
        (
            format!(
                "{head}{}{last}",
                rule(
                    "a",
                    "when = { clossure_density = { max = 0.5 } }\n",
                    ok_phase
                )
            ),
            "unknown field `clossure_density`",
        ),
        (
            long(&format!(
                "min_seconds = -1.0\nmin_evals = 0\nphases = [ {ok_phase} ]\n"
            )),
            "rule 1 'a': long.min_seconds must be a number >= 0, got -1",
        ),
        (
            long(&format!(
                "min_seconds = 5.0\nmin_evals = 1e16\nphases = [ {ok_phase} ]\n"
            )),
            "rule 1 'a': long.min_evals must be a number in [0, 1e15], got 10000000000000000",
        ),
        (
            long("min_seconds = 5.0\nmin_evals = 0\nphases = []\n"),
            "rule 1 'a': long.phases: no phases",
        ),
        (
            long(&format!("min_evals = 0\nphases = [ {ok_phase} ]\n")),
            "missing field `min_seconds`",
        ),
        (
            long(&format!(
                "min_seconds = 1.0\nmin_evals = 0\nmin_cells = 3\nphases = [ {ok_phase} ]\n"
            )),
            "unknown field `min_cells`",
        ),
        (
            format!(
                "{head}{}{last}",
                rule("a", "", "{ solver = \"nosuch\", share = 1.0 }")
            ),
            "rule 1 'a': phases: phase 1 (nosuch): unknown solver 'nosuch'",
        ),
        (
            format!(
                "{head}{}{last}",
                rule(
                    "a",
                    "when = { cells = { max = 9 } }\n",
                    "{ solver = \"greedy\", share = 0.0 }"
                )
            ),
            "share must be in (0, 1]",
        ),
        (
            format!(
                "{head}{}{last}",
                rule(
                    "a",
                    "when = { cells = { max = 9 } }\n",
                    "{ solver = \"greedy\", share = 1.5 }"
                )
            ),
            "share must be in (0, 1]",
        ),
        (
            format!(
                "{head}{}",
                rule("a", "when = { geometric = true }\n", ok_phase)
            ),
            "the last rule must have none",
        ),
        (
            format!(
                "{head}{}{}{last}",
                rule("wide", "when = { cells = { max = 500 } }\n", ok_phase),
                rule(
                    "narrow",
                    "when = { cells = { min = 10, max = 100 } }\n",
                    ok_phase
                )
            ),
            "rule 2 'narrow' is never reached: every instance it matches is taken by the earlier rule 'wide'",
        ),
        (
            format!("{head}{last}{}", rule("after", "", ok_phase)),
            "rule 2 'after' is never reached",
        ),
        (
            format!(
                "{head}{}{last}",
                rule(
                    "a",
                    "when = { zero_arcs = { min = 0.5, below = 0.5 } }\n",
                    ok_phase
                )
            ),
            "when.zero_arcs is empty",
        ),
        (
            format!(
                "{head}{}{last}",
                rule(
                    "a",
                    "",
                    "{ solver = \"greedy\", share = 1.0, start = \"best\" }"
                )
            ),
            "only gls, ils, eacs, reopt and corridor can start from an earlier sequence",
        ),
        (
            format!(
                "{head}{}{last}",
                rule(
                    "a",
                    "",
                    "{ solver = \"ils\", share = 1.0, params = { nosuch = 1 } }"
                )
            ),
            "'ils' has no parameter 'nosuch'",
        ),
        (
            format!(
                "{head}{}{last}",
                rule("a", "", "{ solver = \"auto\", share = 1.0 }")
            ),
            "a plan cannot contain auto itself",
        ),
        (
            format!(
                "{head}{}{last}",
                rule("a", "", "{ solver = \"ils\", share = 1.0, until = 1.5 }")
            ),
            "until must be in (0, 1], got 1.5",
        ),
        (
            format!(
                "{head}{}",
                last.replace("share = 0.1 }", "share = 0.1, stretch = 0.5 }")
            ),
            "beam.stretch must be in [1, 10], got 0.5",
        ),
        (
            format!(
                "{head}{}",
                last.replace("share = 0.1 }", "share = 0.1, stretch = 11 }")
            ),
            "beam.stretch must be in [1, 10], got 11",
        ),
        (head.to_string(), "no [[rule]]"),
        (last.clone(), "missing field `beam`"),
        ("[[rule]\n".to_string(), "p.toml:1:"),
    ];
    for (text, want) in cases {
        let e = Portfolio::parse("p.toml", &text)
            .err()
            .unwrap_or_else(|| panic!("accepted:\n{text}"))
            .to_string();
        assert!(e.starts_with("p.toml"), "{e}");
        assert!(e.contains(want), "want '{want}', got '{e}'\n{text}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

#[test]
fn a_custom_portfolio_changes_the_plan_that_runs() {
    let d = tempfile::tempdir().unwrap();
    let file = d.path().join("greedy.toml");
    std::fs::write(&file, GREEDY_ONLY).unwrap();
    let inst = sop("ESC25");
    let given = BTreeMap::from([("portfolio".to_string(), file.to_string_lossy().into_owned())]);
    let go = |solver: &str, given: &BTreeMap<String, String>| {
        run(
            solver,
            &inst,
            inst.default_objective(),
            given,
            1,
            evals(200_000),
            &mut NoObserver,
        )
        .unwrap()
    };
    // auto under the one-rule portfolio is greedy, exactly
    let mine = go("auto", &given);
    let greedy = go("greedy", &BTreeMap::new());
    assert_eq!(mine.outcome.sequence, greedy.outcome.sequence);
    assert_eq!(mine.report.cost, greedy.report.cost);
    // and the built-in one does better on this instance
    let built_in = go("auto", &BTreeMap::new());
    assert!(built_in.report.cost < mine.report.cost);
    // the rule is reported
    let out = crate::common::cellseq()
        .arg("solve")
        .arg(crate::common::instance_path("tsplib-sop/ESC25.sop"))
        .args(["--max-evals", "20000", "--explain", "--portfolio"])
        .arg(&file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(text.contains("rule       greedy-everywhere"), "{text}");
    assert!(text.contains("phases     greedy:1"), "{text}");
    assert!(text.contains("free_density="), "{text}");
    let out = crate::common::cellseq()
        .arg("solve")
        .arg(crate::common::instance_path("tsplib-sop/ESC25.sop"))
        .args(["--max-evals", "20000", "--explain", "--json"])
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["explain"]["rule"], "sparse-random", "{v}");
    assert_eq!(v["explain"]["portfolio"], "built-in");
    assert!(
        v["explain"]["features"]["closure_density"]
            .as_f64()
            .unwrap()
            > 0.1
    );
}

#[test]
fn check_and_solve_refuse_a_bad_portfolio_with_exit_2() {
    let d = tempfile::tempdir().unwrap();
    let bad = d.path().join("bad.toml");
    std::fs::write(
        &bad,
        GREEDY_ONLY.replace("[[rule]]\nname", "[[rule]]\nwhen = { colour = true }\nname"),
    )
    .unwrap();
    let good = d.path().join("good.toml");
    std::fs::write(&good, GREEDY_ONLY).unwrap();
    let esc = crate::common::instance_path("tsplib-sop/ESC07.sop");
    let runs: Vec<Vec<std::ffi::OsString>> = vec![
        vec!["check".into(), bad.clone().into()],
        vec![
            "solve".into(),
            esc.clone().into(),
            "--portfolio".into(),
            bad.clone().into(),
        ],
        vec![
            "solve".into(),
            esc.clone().into(),
            "--param".into(),
            format!("portfolio={}", bad.display()).into(),
        ],
    ];
    for args in runs {
        let out = crate::common::cellseq().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains("bad.toml"), "{args:?}: {err}");
        assert!(err.contains("unknown field `colour`"), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // a missing file, and --portfolio with another solver
    let out = crate::common::cellseq()
        .arg("solve")
        .arg(&esc)
        .args(["--portfolio", "/nonexistent/p.toml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/p.toml"));
    let out = crate::common::cellseq()
        .arg("solve")
        .arg(&esc)
        .args(["--solver", "greedy", "--portfolio"])
        .arg(&good)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    // check accepts the good one and names its rules
    let out = crate::common::cellseq()
        .arg("check")
        .arg(&good)
        .output()
        .unwrap();
    assert!(out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stdout)
            .contains("ok: portfolio with 1 rules (greedy-everywhere)")
    );
}

#[test]
fn a_plan_reads_its_portfolio_from_the_plan_directory() {
    let d = tempfile::tempdir().unwrap();
    std::fs::create_dir(d.path().join("plans")).unwrap();
    std::fs::write(d.path().join("plans/mine.toml"), GREEDY_ONLY).unwrap();
    let plan = |portfolio: &str| {
        format!(
            "name = \"p\"\n[budget]\nevaluations = 1000\n[[instances]]\nfiles = [\"{}\"]\n\
             [[solvers]]\nname = \"auto\"\nparams = {{ portfolio = \"{portfolio}\" }}\n",
            crate::common::instance_path("tsplib-sop/ESC07.sop").display()
        )
    };
    let path = d.path().join("plans/plan.toml");
    std::fs::write(&path, plan("mine.toml")).unwrap();
    // run from elsewhere: the relative name is the plan directory's file
    let check = || {
        crate::common::cellseq()
            .current_dir(d.path())
            .arg("check")
            .arg(&path)
            .output()
            .unwrap()
    };
    let out = check();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::write(&path, plan("missing.toml")).unwrap();
    let out = check();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("plan.toml") && err.contains("missing.toml"),
        "{err}"
    );
}

/// The beam runs from `[beam] min_seconds` (3 s) of the limit given: `--time-limit 3` gets it
/// although reading the file and the bound's share leave the solver less than 3 s, and a limit
/// just under the bound does not (seen in the phase trace on stderr).
#[test]
fn time_bounds_are_read_against_the_whole_limit_given() {
    let file = crate::common::instance_path("tsplib-sop/ESC07.sop");
    let trace = |limit: &str| {
        let out = crate::common::cellseq()
            .arg("solve")
            .arg(&file)
            .args(["--time-limit", limit])
            .env("CELLSEQ_TRACE", "1")
            .output()
            .unwrap();
        let err = crate::common::stderr(&out);
        assert!(out.status.success(), "{err}");
        err
    };
    let at = trace("3");
    assert!(at.contains("budgets of at least 3 s"), "{at}");
    assert!(at.contains("auto: beam cost"), "{at}");
    let under = trace("2.9");
    assert!(!under.contains("auto: beam cost"), "{under}");
}

/// A solve whose limit is counted from a start long past has nothing left: it ends at once
/// with its first sequence, feasible and checked, and its plan is still the one for the whole
/// limit.
#[test]
fn a_limit_counted_from_an_earlier_start_ends_the_run_there() {
    use cellseq::solve::Solve;
    use cellseq::solvers::SolverKind;
    use std::time::{Duration, Instant};
    let inst = sop("ESC25");
    let long_ago = Instant::now()
        .checked_sub(Duration::from_secs(30))
        .unwrap_or_else(Instant::now);
    let r = Solve::new(SolverKind::Auto)
        .time_limit(Duration::from_secs(20))
        .started(long_ago)
        .lower_bound(true)
        .run(&inst)
        .unwrap();
    assert_eq!(r.sequence.len(), inst.n());
    assert!(r.cost().is_finite());
}

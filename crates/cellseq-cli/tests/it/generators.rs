//! Generators: determinism, validity, feasibility of the as-programmed order, precedence rules.

use cellseq::formats::json::instance_to_json;
use cellseq::generate::{KINDS, generate};
use cellseq::model::{Instance, Objective, StepKind};
use proptest::prelude::*;
use std::collections::BTreeMap;

fn params(kv: &[(&str, &str)]) -> BTreeMap<String, String> {
    kv.iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn small(kind: &str) -> BTreeMap<String, String> {
    match kind {
        "panel" => params(&[("rows", "2"), ("cols", "2")]),
        "casing" => params(&[("regions", "2"), ("features", "4")]),
        "cabin" => params(&[]),
        "uniform" => params(&[("n", "50"), ("density", "0.05")]),
        _ => params(&[("n", "30")]),
    }
}

/// Cells reachable from `a` through precedence edges.
fn reaches(inst: &Instance, a: usize, b: usize) -> bool {
    let mut succ = vec![Vec::new(); inst.n()];
    for &(x, y) in &inst.precedence {
        succ[x].push(y);
    }
    let mut seen = vec![false; inst.n()];
    let mut stack = vec![a];
    while let Some(x) = stack.pop() {
        if x == b {
            return true;
        }
        for &y in &succ[x] {
            if !seen[y] {
                seen[y] = true;
                stack.push(y);
            }
        }
    }
    false
}

fn as_given_feasible(inst: &Instance) {
    let seq = inst.as_given.as_ref().expect("as-programmed order");
    cellseq::check(inst, seq, Objective::Time)
        .unwrap_or_else(|v| panic!("{}: as-given infeasible: {v}", inst.name));
}

#[test]
fn every_kind_is_registered() {
    let names: Vec<&str> = KINDS.iter().map(|k| k.name).collect();
    for k in ["panel", "casing", "cabin", "uniform"] {
        assert!(names.contains(&k), "{k} missing from KINDS");
    }
}

#[test]
fn same_seed_same_bytes_different_seed_different_instance() {
    for k in KINDS {
        let p = small(k.name);
        let a = instance_to_json(&generate(k.name, &p, 7).unwrap());
        let b = instance_to_json(&generate(k.name, &p, 7).unwrap());
        assert_eq!(a, b, "{}: not deterministic", k.name);
        let c = generate(k.name, &p, 8).unwrap();
        let a = generate(k.name, &p, 7).unwrap();
        assert!(
            a.cells != c.cells || a.matrix != c.matrix || a.precedence != c.precedence,
            "{}: seed has no effect",
            k.name
        );
        assert_eq!(a.meta.generator.as_deref(), Some(k.name));
        assert_eq!(a.meta.seed, Some(7));
        assert!(a.meta.params.len() >= k.params.len());
    }
}

#[test]
fn generated_instances_validate_and_as_given_is_feasible() {
    let cases: Vec<(&str, Vec<(&str, &str)>)> = vec![
        ("panel", vec![]),
        (
            "panel",
            vec![
                ("rows", "3"),
                ("cols", "2"),
                ("skew", "-0.3"),
                ("jitter", "0.15"),
                ("islands", "1"),
                ("open", "0.5"),
                ("grooves", "1"),
            ],
        ),
        (
            "panel",
            vec![
                ("rule4", "rib,flange,pocket,wall-groove"),
                ("grooves", "1"),
                ("outer_first", "false"),
            ],
        ),
        (
            "panel",
            vec![
                ("rule4", "pocket,wall-groove,rib,flange"),
                ("holes", "0"),
                ("pitch_var", "0"),
            ],
        ),
        ("panel", vec![("eta_min", "0.999"), ("mu", "0.95")]),
        ("casing", vec![]),
        (
            "casing",
            vec![("region_first", "false"), ("reversible", "false")],
        ),
        ("casing", vec![("features", "0")]),
        ("cabin", vec![("open_fraction", "0")]),
        ("cabin", vec![("open_fraction", "1"), ("hole_groups", "0")]),
        (
            "cabin",
            vec![("features", "40"), ("faces", "5"), ("levels", "1")],
        ),
    ];
    for (kind, kv) in cases {
        for seed in 1..4 {
            let inst =
                generate(kind, &params(&kv), seed).unwrap_or_else(|e| panic!("{kind} {kv:?}: {e}"));
            cellseq::validate::validate(&inst, "<test>").unwrap();
            as_given_feasible(&inst);
            // round trip through the file format
            let text = instance_to_json(&inst);
            let back =
                cellseq::formats::parse_instance("<mem>", &text, cellseq::formats::Format::Json)
                    .unwrap();
            assert_eq!(instance_to_json(&back), text);
        }
    }
}

#[test]
fn panel_follows_the_paper_rules() {
    let inst = generate(
        "panel",
        &params(&[
            ("rows", "2"),
            ("cols", "3"),
            ("grooves", "1"),
            ("islands", "0.5"),
        ]),
        3,
    )
    .unwrap();
    let by_feat = |f: &str, s: StepKind| -> Vec<usize> {
        (0..inst.n())
            .filter(|&i| inst.cells[i].feature.as_deref() == Some(f) && inst.cells[i].step == s)
            .collect()
    };
    for p in 1..=6 {
        let fid = format!("P{p:03}");
        let rough = by_feat(&fid, StepKind::PocketRough);
        let fin = by_feat(&fid, StepKind::PocketFinish);
        let groove = by_feat(&fid, StepKind::WallGroove);
        assert!(!rough.is_empty() && !fin.is_empty() && groove.len() == 1);
        // layers top-down, rough before finish, groove (rule 4 first) before the pocket finish
        for w in rough.windows(2) {
            assert!(reaches(&inst, w[0], w[1]));
            assert!(inst.cells[w[0]].z > inst.cells[w[1]].z);
        }
        for &f in fin.iter().chain(&groove) {
            assert!(reaches(&inst, *rough.last().unwrap(), f));
        }
        for &f in &fin {
            assert!(
                reaches(&inst, groove[0], f),
                "rule 4: wall groove before pocket finishing"
            );
        }
        // rule 2: outer contour roughing first
        let oc = (0..inst.n())
            .find(|&i| inst.cells[i].id == "OC-R1")
            .unwrap();
        assert!(reaches(&inst, oc, rough[0]));
        // same tool for all roughing layers of a pocket; finishing tool fits the corners
        assert!(
            rough
                .iter()
                .all(|&r| inst.cells[r].tool == inst.cells[rough[0]].tool)
        );
    }
    // rule 4 default: pocket finishing before ribs next to it
    let rib = (0..inst.n())
        .find(|&i| inst.cells[i].step == StepKind::Rib)
        .unwrap();
    let any_fin = (0..inst.n()).filter(|&i| inst.cells[i].step == StepKind::PocketFinish);
    assert!(any_fin.into_iter().any(|f| reaches(&inst, f, rib)));
    // face before hole
    for h in (0..inst.n()).filter(|&i| inst.cells[i].step == StepKind::Hole) {
        assert!(
            inst.precedence
                .iter()
                .any(|&(a, b)| b == h && inst.cells[a].step == StepKind::Flange)
        );
    }
    // the layer formula: depth H, a_p = 6, delta = 1
    for p in 1..=6 {
        let fid = format!("P{p:03}");
        let rough = by_feat(&fid, StepKind::PocketRough);
        let deepest = inst
            .cells
            .iter()
            .filter(|c| c.feature.as_deref() == Some(&fid))
            .map(|c| -c.z)
            .fold(0.0, f64::max);
        assert_eq!(
            rough.len() as u32,
            cellseq::generate::toolsel::layer_count(deepest, 6.0, 1.0).max(1)
        );
    }
}

#[test]
fn panel_reversed_rule4_reverses_edges() {
    let p = params(&[
        ("rows", "2"),
        ("cols", "2"),
        ("grooves", "1"),
        ("rule4", "rib,flange,pocket,wall-groove"),
    ]);
    let inst = generate("panel", &p, 1).unwrap();
    let groove = (0..inst.n())
        .find(|&i| inst.cells[i].step == StepKind::WallGroove)
        .unwrap();
    let fid = inst.cells[groove].feature.clone();
    let fin: Vec<usize> = (0..inst.n())
        .filter(|&i| inst.cells[i].feature == fid && inst.cells[i].step == StepKind::PocketFinish)
        .collect();
    for f in fin {
        assert!(reaches(&inst, f, groove));
        assert!(!reaches(&inst, groove, f));
    }
}

#[test]
fn casing_layers_and_regions() {
    let inst = generate(
        "casing",
        &params(&[
            ("regions", "3"),
            ("features", "6"),
            ("region_first", "true"),
        ]),
        5,
    )
    .unwrap();
    // first layer (w = 0.15): no features yet, one sub-region per region
    assert_eq!(inst.cells.iter().filter(|c| c.layer == 0).count(), 3);
    assert_eq!(inst.tools.len(), 1);
    assert_eq!(inst.machine.cut_feed, 500.0);
    assert_eq!(inst.machine.rapid_feed, 2000.0);
    assert!(inst.machine.link_distance > 0.0);
    for (a, b) in &inst.precedence {
        let (ca, cb) = (&inst.cells[*a], &inst.cells[*b]);
        // either the next layer (overlap) or the same layer (region order)
        assert!(cb.layer == ca.layer + 1 || (cb.layer == ca.layer && ca.feature < cb.feature));
        assert!(cb.z < ca.z || cb.layer == ca.layer);
    }
    // depth grows with w
    let zs: Vec<f64> = (0..5)
        .map(|l| inst.cells.iter().find(|c| c.layer == l).unwrap().z)
        .collect();
    assert!(zs.windows(2).all(|w| w[1] < w[0]));
    // as programmed: layer by layer in numbering order
    let order = inst.as_given.as_ref().unwrap();
    assert!(
        order
            .windows(2)
            .all(|w| inst.cells[w[0].cell].layer <= inst.cells[w[1].cell].layer)
    );
    let free = generate(
        "casing",
        &params(&[
            ("regions", "3"),
            ("features", "6"),
            ("region_first", "false"),
        ]),
        5,
    )
    .unwrap();
    assert!(free.precedence.len() < inst.precedence.len());
    assert!(
        free.precedence
            .iter()
            .all(|&(a, b)| free.cells[b].layer == free.cells[a].layer + 1)
    );
}

#[test]
fn cabin_rules() {
    let inst = generate("cabin", &params(&[("features", "10")]), 2).unwrap();
    assert!(inst.tools.len() >= 3);
    for (i, c) in inst.cells.iter().enumerate() {
        match c.step {
            StepKind::PocketFinish => {
                let rough = inst
                    .cells
                    .iter()
                    .position(|r| r.id == c.id.replace("-F", "-R"))
                    .unwrap();
                assert!(reaches(&inst, rough, i));
            }
            StepKind::Hole => {
                assert!(
                    inst.precedence
                        .iter()
                        .any(|&(a, b)| b == i && inst.cells[a].step == StepKind::Face)
                );
            }
            _ => {}
        }
        // open features: two contact points, both directions; closed: one point at the centre
        if c.feature.as_deref().is_some_and(|f| f.ends_with("-open")) {
            assert_eq!(c.modes.len(), 2);
            assert_eq!(c.modes[0], c.modes[1].reversed());
        }
        if c.feature.as_deref().is_some_and(|f| f.ends_with("-closed")) {
            assert_eq!(c.modes.len(), 1);
            assert_eq!(c.modes[0].entry, c.modes[0].exit);
        }
    }
}

#[test]
fn bad_parameters_are_errors() {
    let e = generate("panel", &params(&[("rule4", "rib,pocket")]), 1).unwrap_err();
    assert!(e.to_string().contains("rule4"), "{e}");
    let e = generate("panel", &params(&[("tools", "/nonexistent/lib.toml")]), 1).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/lib.toml"), "{e}");
    let e = generate("panel", &params(&[("depth_max", "100")]), 1).unwrap_err();
    assert!(e.to_string().contains("thickness"), "{e}");
    let e = generate("casing", &params(&[("features", "200")]), 1).unwrap_err();
    assert!(e.to_string().contains("diameter"), "{e}");
    let e = generate("cabin", &params(&[("open_fraction", "2")]), 1).unwrap_err();
    assert!(e.to_string().contains("open_fraction"), "{e}");
    assert!(generate("nosuch", &params(&[]), 1).is_err());
}

#[test]
fn custom_tool_library() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("lib.toml");
    std::fs::write(
        &path,
        "[[tool]]\nid=\"BIG\"\ndiameter=30.0\ncutting_width=20.0\nfeed=0.3\nspindle=8000\n\
         [[tool]]\nid=\"SMALL\"\ndiameter=8.0\ncutting_width=5.0\nfeed=0.1\nspindle=15000\n\
         [[tool]]\nid=\"D6\"\nkind=\"drill\"\ndiameter=6.0\ncutting_width=6.0\nfeed=0.1\nspindle=3000\n",
    )
    .unwrap();
    let p = params(&[
        ("tools", path.to_str().unwrap()),
        ("rows", "2"),
        ("cols", "2"),
    ]);
    let inst = generate("panel", &p, 1).unwrap();
    for c in &inst.cells {
        assert!(
            ["BIG", "SMALL", "D6"].contains(&c.tool.as_str()),
            "{}",
            c.tool
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, .. ProptestConfig::default() })]
    #[test]
    fn random_small_instances_are_valid(seed in 0u64..10_000, rows in 1u64..4, cols in 1u64..4,
                                       regions in 1u64..4, feats in 0u64..8, nf in 0u64..12) {
        let p = params(&[("rows", &rows.to_string()), ("cols", &cols.to_string()), ("jitter", "0.1"), ("skew", "0.2")]);
        let inst = generate("panel", &p, seed).unwrap();
        as_given_feasible(&inst);
        let c = generate("casing", &params(&[("regions", &regions.to_string()), ("features", &feats.to_string())]), seed).unwrap();
        as_given_feasible(&c);
        let k = generate("cabin", &params(&[("features", &nf.to_string())]), seed).unwrap();
        as_given_feasible(&k);
    }
}

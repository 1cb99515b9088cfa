//! At-depth moves past keep-out areas (blocks, islands): the solvers' cost model and the
//! independent checker must agree on which moves stay at depth and how long they are, also when
//! a move touches or follows an area's boundary (integer coordinates make that common).

use cellseq::checker::{at_depth_length, check};
use cellseq::cost::CostModel;
use cellseq::geom::Point3;
use cellseq::model::{Cell, Instance, KeepOut, Machine, Mode, Objective, Tool, Visit};
use proptest::prelude::*;

fn instance(pts: &[(i32, i32)], boxes: &[(i32, i32, i32, i32, bool)]) -> Instance {
    let z = -5.0;
    let cells = pts
        .chunks(2)
        .enumerate()
        .map(|(i, w)| {
            let p = |(x, y): (i32, i32)| Point3::new(x as f64, y as f64, z);
            let m = Mode::new(p(w[0]), p(w[1]));
            let mut c = Cell::new(format!("c{i}"), "T", vec![m, m.reversed()]);
            c.reversible = true;
            c.cut_length = 1.0;
            c.z = z;
            c
        })
        .collect();
    let keep_out = boxes
        .iter()
        .map(|&(x, y, w, h, high)| KeepOut {
            x0: x as f64,
            y0: y as f64,
            x1: (x + w) as f64,
            y1: (y + h) as f64,
            // a block below the cutting depth stops nothing
            top: if high { 0.0 } else { -8.0 },
        })
        .collect();
    Instance {
        name: "keep-out".into(),
        machine: Machine {
            link_distance: 12.0,
            initial_tool: Some("T".into()),
            keep_out,
            ..Machine::default()
        },
        tools: vec![Tool {
            id: "T".into(),
            diameter: 2.0,
            name: None,
            feed: None,
        }],
        cells,
        ..Instance::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, .. ProptestConfig::default() })]
    #[test]
    fn cost_model_and_checker_agree_past_blocks(
        pts in prop::collection::vec((0i32..10, 0i32..10), 8),
        boxes in prop::collection::vec((0i32..9, 0i32..9, 0i32..5, 0i32..5, any::<bool>()), 0..4),
        modes in prop::collection::vec(0usize..2, 4),
    ) {
        let inst = instance(&pts, &boxes);
        cellseq::validate::validate(&inst, "prop").unwrap();
        let seq: Vec<Visit> = (0..4).map(|c| Visit { cell: c, mode: modes[c] }).collect();
        for obj in [Objective::Air, Objective::Time] {
            let r = check(&inst, &seq, obj).unwrap();
            let m = CostModel::new(&inst, obj);
            let c = m.evaluate(&seq);
            prop_assert!((c - r.cost).abs() < 1e-9 * (1.0 + c.abs()), "{c} vs {}", r.cost);
        }
        // every move between consecutive cells: a link is never shorter than the straight line
        // and never longer than the dog-leg
        for w in seq.windows(2) {
            let a = inst.cells[w[0].cell].modes[w[0].mode].exit;
            let b = inst.cells[w[1].cell].modes[w[1].mode].entry;
            if let Some(d) = at_depth_length(&inst.machine, a.into(), b.into()) {
                prop_assert!(d + 1e-9 >= a.dist_xy(&b));
                prop_assert!(d <= (a.x - b.x).abs() + (a.y - b.y).abs() + 1e-9);
            }
        }
    }
}

/// A block between two points stops the straight move and both dog-legs; one that leaves a
/// corridor lets the dog-leg through; one whose top lies below the depth stops nothing.
#[test]
fn blocks_and_corridors() {
    let m = |boxes: Vec<KeepOut>| Machine {
        keep_out: boxes,
        link_distance: 100.0,
        ..Machine::default()
    };
    let wall = |y1: f64, top: f64| KeepOut {
        x0: 4.0,
        y0: -10.0,
        x1: 6.0,
        y1,
        top,
    };
    let (a, b) = ([0.0, 0.0, -5.0], [10.0, 3.0, -5.0]);
    // a wall across both legs' paths
    assert_eq!(at_depth_length(&m(vec![wall(10.0, 0.0)]), a, b), None);
    // a wall that ends at y = 2: the straight line crosses it, the y-first dog-leg passes above
    let d = at_depth_length(&m(vec![wall(2.0, 0.0)]), a, b).unwrap();
    assert!((d - 13.0).abs() < 1e-12);
    // the same wall, its top below the cutting depth: straight
    let d = at_depth_length(&m(vec![wall(10.0, -8.0)]), a, b).unwrap();
    assert!((d - 109.0f64.sqrt()).abs() < 1e-12);
    // a move along the wall's side is free
    let along = at_depth_length(
        &m(vec![wall(10.0, 0.0)]),
        [4.0, 0.0, -5.0],
        [4.0, 8.0, -5.0],
    );
    assert_eq!(along, Some(8.0));
}

/// A keep-out area with its corners swapped or a value that is not finite is refused with the
/// file and the area's index.
#[test]
fn bad_keep_out_areas_are_refused() {
    for bad in [
        KeepOut {
            x0: 5.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            top: 0.0,
        },
        KeepOut {
            x0: 0.0,
            y0: 0.0,
            x1: 1.0,
            y1: 1.0,
            top: f64::NAN,
        },
    ] {
        let mut inst = instance(&[(0, 0), (1, 1), (2, 2), (3, 3)], &[]);
        inst.machine.keep_out.push(bad);
        let e = cellseq::validate::validate(&inst, "part.json")
            .unwrap_err()
            .to_string();
        assert!(e.contains("part.json") && e.contains("keep_out 0"), "{e}");
    }
}

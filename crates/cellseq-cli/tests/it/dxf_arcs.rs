//! DXF arcs written as G2/G3: ARC, CIRCLE (two or more arcs), bulged LWPOLYLINE segments and an
//! arc inside a rotated, uniformly scaled INSERT come out as arc moves whose centre, radius and
//! sweep are those of the DXF entity; the post's own check accepts them and refuses a moved
//! centre; LinuxCNC's interpreter (`rs274`) runs the program and finds the same arcs.

use ::dxf::entities::{Arc, Circle, Entity, EntityType, Insert};
use ::dxf::{Block, Point};
use cellseq_programs::dxf::{self, Post, ReadOptions};
use cellseq_programs::gcode::interp::{self, CutKind};
use cellseq_programs::optimize::strokes::{self as pipe, Options};
use std::f64::consts::PI;

fn ent(t: EntityType) -> Entity {
    let mut e = Entity::new(t);
    e.common.layer = "cut".into();
    e
}

/// (centre, radius, sweep in radians, counter-clockwise as drawn in the file) of every arc.
type Expected = Vec<([f64; 2], f64, f64)>;

fn drawing() -> (Vec<u8>, Expected) {
    let mut d = ::dxf::Drawing::new();
    d.header.version = ::dxf::enums::AcadVersion::R2000;
    d.header.default_drawing_units = ::dxf::enums::Units::Millimeters;
    d.add_entity(ent(EntityType::Circle(Circle::new(
        Point::new(20.0, 20.0, 0.0),
        5.0,
    ))));
    d.add_entity(ent(EntityType::Arc(Arc::new(
        Point::new(80.0, 45.0, 0.0),
        4.0,
        0.0,
        180.0,
    ))));
    // a slot: two straight sides and two half circles (bulge 1) of radius 5
    d.add_entity(ent(EntityType::LwPolyline(crate::dxf::slot())));
    // a quarter arc of radius 3 about the block's origin, inserted at (50, 70), scaled 2,
    // rotated 90°: centre (50, 70), radius 6, from 90° to 180°
    let mut b = Block {
        name: "Q".into(),
        ..Default::default()
    };
    b.entities.push(ent(EntityType::Arc(Arc::new(
        Point::new(0.0, 0.0, 0.0),
        3.0,
        0.0,
        90.0,
    ))));
    d.add_block(b);
    d.add_entity(ent(EntityType::Insert(Insert {
        name: "Q".into(),
        location: Point::new(50.0, 70.0, 0.0),
        rotation: 90.0,
        x_scale_factor: 2.0,
        y_scale_factor: 2.0,
        ..Default::default()
    })));
    let buf = crate::dxf::bytes_of(&d);
    let expected = vec![
        ([20.0, 20.0], 5.0, 2.0 * PI),
        ([80.0, 45.0], 4.0, PI),
        ([60.0, 25.0], 5.0, PI),
        ([40.0, 25.0], 5.0, PI),
        ([50.0, 70.0], 6.0, PI / 2.0),
    ];
    (buf, expected)
}

fn gcode() -> (String, Expected) {
    let (bytes, expected) = drawing();
    let d = dxf::read("arcs.dxf", &bytes, ReadOptions::default()).unwrap();
    let opts = Options {
        cut: true,
        ..Options::default()
    };
    let out = pipe::optimize(&d, &opts).unwrap();
    let post = Post::default();
    let g = dxf::write_gcode(&d, &out.strokes, &post);
    assert!(dxf::verify_gcode(&d, "arcs.ngc", &g, &post).unwrap() > 20);
    (g, expected)
}

/// The signed sweep of an arc move about `c` from `a` to `b` (0 < |sweep| <= 2π).
fn sweep(c: [f64; 2], a: [f64; 2], b: [f64; 2], ccw: bool) -> f64 {
    let t0 = (a[1] - c[1]).atan2(a[0] - c[0]);
    let t1 = (b[1] - c[1]).atan2(b[0] - c[0]);
    let d = (t1 - t0).rem_euclid(2.0 * PI);
    let d = if d < 1e-12 { 2.0 * PI } else { d };
    if ccw { d } else { -(2.0 * PI - d) }
}

#[test]
fn arcs_come_out_as_g2_g3_on_the_entities_circles() {
    let (g, expected) = gcode();
    let prog = interp::interpret(&g).unwrap();
    // per expected arc: the total sweep of the arc moves about its centre
    let mut swept = vec![0.0f64; expected.len()];
    let mut arcs = 0;
    for c in prog.lines.iter().flat_map(|l| &l.cuts) {
        let CutKind::Arc { center, cw, .. } = c.kind else {
            continue;
        };
        arcs += 1;
        let (a, b, m) = (
            [c.from[0], c.from[1]],
            [c.to[0], c.to[1]],
            [center[0], center[1]],
        );
        let k = expected
            .iter()
            .position(|(e, _, _)| (e[0] - m[0]).abs() < 1e-5 && (e[1] - m[1]).abs() < 1e-5)
            .unwrap_or_else(|| panic!("arc centre {m:?} is no entity's"));
        let r = expected[k].1;
        for p in [a, b] {
            let d = ((p[0] - m[0]).powi(2) + (p[1] - m[1]).powi(2)).sqrt();
            assert!(
                (d - r).abs() < 1e-5,
                "end {p:?} at {d} from {m:?}, radius {r}"
            );
        }
        let s = sweep(m, a, b, !cw);
        assert!(
            s.abs() <= PI + 1e-6,
            "an arc move covers at most a half turn"
        );
        swept[k] += s.abs();
    }
    for (k, (c, _, want)) in expected.iter().enumerate() {
        assert!(
            (swept[k] - want).abs() < 1e-6,
            "arc about {c:?}: {} of {want} radians written as arcs",
            swept[k]
        );
    }
    assert!(
        arcs >= 6,
        "the circle is at least two arcs: {arcs} arc moves"
    );
    assert!(g.lines().any(|l| l.starts_with("G2 ")) || g.lines().any(|l| l.starts_with("G3 ")));
}

#[test]
fn a_moved_arc_centre_is_refused() {
    let (bytes, _) = drawing();
    let d = dxf::read("arcs.dxf", &bytes, ReadOptions::default()).unwrap();
    let post = Post::default();
    let g = dxf::write_gcode(&d, &d.strokes, &post);
    dxf::verify_gcode(&d, "arcs.ngc", &g, &post).unwrap();
    // the same end point on a different circle: the centre moved along the chord's normal
    let line = g.lines().find(|l| l.starts_with("G3 ")).unwrap();
    let j = line.split(' ').find(|w| w.starts_with('J')).unwrap();
    let v: f64 = j[1..].parse().unwrap();
    let bad = g.replacen(line, &line.replacen(j, &format!("J{}", v + 0.5), 1), 1);
    assert!(dxf::verify_gcode(&d, "arcs.ngc", &bad, &post).is_err());
    // an arc turned the other way round is refused too
    let turned = g.replacen(line, &line.replacen("G3 ", "G2 ", 1), 1);
    assert!(dxf::verify_gcode(&d, "arcs.ngc", &turned, &post).is_err());
}

#[test]
fn rs274_runs_the_arcs_about_the_entities_centres() {
    let available = std::process::Command::new("sh")
        .args(["-c", "command -v rs274"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !available {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "rs274 (Debian linuxcnc-uspace) is not installed, and CI=true"
        );
        eprintln!("NOTICE: rs274 not on PATH (apt-get install linuxcnc-uspace): skipped");
        return;
    }
    let (g, expected) = gcode();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("prog.ngc"), &g).unwrap();
    std::fs::write(dir.path().join("tools.tbl"), "T1 P1 Z0 D1\n").unwrap();
    let out = std::process::Command::new("rs274")
        .args(["-n", "0", "-t", "tools.tbl", "-g", "prog.ngc"])
        .current_dir(dir.path())
        .stdin(std::process::Stdio::null())
        .output()
        .unwrap();
    assert!(out.status.success(), "rs274 failed: {out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.lines().all(|l| l.trim() == "executing"),
        "rs274 reports: {stderr}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let arcs: Vec<Vec<f64>> = stdout
        .lines()
        .filter_map(|l| {
            let i = l.find("ARC_FEED(")?;
            let args = &l[i + 9..l.rfind(')')?];
            Some(args.split(',').map(|s| s.trim().parse().unwrap()).collect())
        })
        .collect();
    let written = g
        .lines()
        .filter(|l| l.starts_with("G2 ") || l.starts_with("G3 "))
        .count();
    assert_eq!(arcs.len(), written, "one ARC_FEED per G2/G3");
    for a in &arcs {
        // ARC_FEED(end x, end y, centre x, centre y, rotation, end z, ...)
        let (e, c) = ([a[0], a[1]], [a[2], a[3]]);
        let (_, r, _) = expected
            .iter()
            .find(|(m, _, _)| (m[0] - c[0]).abs() < 1e-3 && (m[1] - c[1]).abs() < 1e-3)
            .unwrap_or_else(|| panic!("rs274 arc about {c:?} is no entity's"));
        let d = ((e[0] - c[0]).powi(2) + (e[1] - c[1]).powi(2)).sqrt();
        assert!(
            (d - r).abs() < 1e-3,
            "rs274 arc end {e:?} at {d} from {c:?}"
        );
        assert!(
            (a[5] + Post::default().depth).abs() < 1e-3,
            "at the cutting depth"
        );
    }
}

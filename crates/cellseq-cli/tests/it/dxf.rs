//! DXF reader (through the `dxf` crate), chaining, inner-first, G-code post and SVG preview.

use ::dxf::entities::{Arc, Circle, Entity, EntityType, Insert, Line, LwPolyline};
use ::dxf::{Block, LwPolylineVertex, Point};
use cellseq_programs::dxf::{self, Post, ReadOptions};
use cellseq_programs::optimize::strokes::{self as pipe, Options};
use cellseq_programs::svg;
use proptest::prelude::*;

fn ent(layer: &str, t: EntityType) -> Entity {
    let mut e = Entity::new(t);
    e.common.layer = layer.into();
    e
}

/// A slot, closed: two straight sides from (40, 20) to (60, 20) and from (60, 30) to
/// (40, 30), and two half circles (bulge 1) of radius 5 (in both test drawings).
pub(crate) fn slot() -> LwPolyline {
    let mut pl = LwPolyline::default();
    for (x, y, b) in [
        (40.0, 20.0, 0.0),
        (60.0, 20.0, 1.0),
        (60.0, 30.0, 0.0),
        (40.0, 30.0, 1.0),
    ] {
        pl.vertices.push(LwPolylineVertex {
            x,
            y,
            bulge: b,
            ..Default::default()
        });
    }
    pl.set_is_closed(true);
    pl
}

/// An outer 100x60 frame made of 3 loose LINEs and an ARC-free closing line in shuffled
/// directions, a hole (CIRCLE), a slot (LWPOLYLINE with two bulges), and a block of a small
/// square inserted twice (once rotated) on layer "inner".
fn drawing() -> Vec<u8> {
    let mut d = ::dxf::Drawing::new();
    d.header.version = ::dxf::enums::AcadVersion::R2000;
    let l = |a: (f64, f64), b: (f64, f64)| {
        EntityType::Line(Line::new(
            Point::new(a.0, a.1, 0.0),
            Point::new(b.0, b.1, 0.0),
        ))
    };
    d.add_entity(ent("outer", l((0.0, 0.0), (100.0, 0.0))));
    d.add_entity(ent("outer", l((100.0, 60.0), (100.0, 0.0)))); // reversed piece
    d.add_entity(ent("outer", l((0.0, 60.0), (0.0, 0.0))));
    d.add_entity(ent("outer", l((100.0, 60.0), (0.0, 60.0 + 1e-5)))); // gap within tolerance
    d.add_entity(ent(
        "inner",
        EntityType::Circle(Circle::new(Point::new(20.0, 20.0, 0.0), 5.0)),
    ));
    d.add_entity(ent("inner", EntityType::LwPolyline(slot())));
    let mut a = Arc::new(Point::new(80.0, 45.0, 0.0), 4.0, 0.0, 180.0);
    a.thickness = 0.0;
    d.add_entity(ent("inner", EntityType::Arc(a)));
    let mut b = Block {
        name: "SQ".into(),
        ..Default::default()
    };
    for (p, q) in [
        ((0.0, 0.0), (4.0, 0.0)),
        ((4.0, 0.0), (4.0, 4.0)),
        ((4.0, 4.0), (0.0, 4.0)),
        ((0.0, 4.0), (0.0, 0.0)),
    ] {
        b.entities.push(ent("0", l(p, q)));
    }
    d.add_block(b);
    for (x, rot) in [(10.0, 0.0), (30.0, 90.0)] {
        let ins = Insert {
            name: "SQ".into(),
            location: Point::new(x, 45.0, 0.0),
            rotation: rot,
            ..Default::default()
        };
        d.add_entity(ent("inner", EntityType::Insert(ins)));
    }
    bytes_of(&d)
}

#[test]
fn reads_chains_and_transforms() {
    let d = dxf::read(
        "t.dxf",
        &drawing(),
        ReadOptions {
            join: 1e-3,
            ..ReadOptions::default()
        },
    )
    .unwrap();
    let labels: Vec<&str> = d.layers.iter().map(|l| l.label.as_str()).collect();
    assert_eq!(labels, vec!["", "outer", "inner"]);
    let outer: Vec<_> = d.strokes.iter().filter(|s| s.layer == 1).collect();
    assert_eq!(outer.len(), 1, "four loose lines chain into one contour");
    assert!(outer[0].closed && outer[0].points.len() == 4);
    let inner: Vec<_> = d.strokes.iter().filter(|s| s.layer == 2).collect();
    // circle, slot, arc, 2 inserted squares
    assert_eq!(inner.len(), 5);
    assert_eq!(inner.iter().filter(|s| s.closed).count(), 4);
    // the rotated insert: square (0,0)-(4,4) rotated 90° about its base, placed at (30,45)
    let sq = inner.iter().filter(|s| s.points.len() == 4).nth(1).unwrap();
    let (mut minx, mut maxx) = (f64::MAX, f64::MIN);
    for p in &sq.points {
        minx = minx.min(p[0]);
        maxx = maxx.max(p[0]);
    }
    assert!(
        (minx - 26.0).abs() < 1e-9 && (maxx - 30.0).abs() < 1e-9,
        "{minx} {maxx}"
    );
    // the slot's bulges are half circles of radius 5: its x range grows to 35..65
    let slot = inner
        .iter()
        .find(|s| s.points.iter().any(|p| p[0] > 64.9 && p[0] < 65.1))
        .unwrap();
    assert!(slot.points.iter().all(|p| p[0] >= 34.99 && p[0] <= 65.01));
}

#[test]
fn gcode_post_is_verified_and_inner_first() {
    let d = dxf::read("t.dxf", &drawing(), ReadOptions::default()).unwrap();
    let opts = Options {
        cut: true,
        ..Options::default()
    };
    let out = pipe::optimize(&d, &opts).unwrap();
    // the outer frame's layer comes after the inner layer
    assert_eq!(out.strokes.last().unwrap().layer, 1);
    assert_eq!(out.strokes.first().unwrap().layer, 2);
    let post = Post::default();
    let g = dxf::write_gcode(&d, &out.strokes, &post);
    assert!(dxf::verify_gcode(&d, "o.ngc", &g, &post).unwrap() > 20);
    // a lost move is caught
    let mut s = out.strokes.clone();
    s.remove(1);
    let g2 = dxf::write_gcode(&d, &s, &post);
    assert!(dxf::verify_gcode(&d, "o.ngc", &g2, &post).is_err());
    // the SVG preview (y mirrored) verifies too
    let p = svg::write(&d, &out.strokes);
    svg::verify(&d, "o.svg", &p).unwrap();
}

#[test]
fn garbage_is_refused() {
    assert!(
        dxf::read(
            "g.dxf",
            b"0\nSECTION\n2\nENTITIES\n0\nLINE\n10\nabc\n",
            ReadOptions::default()
        )
        .is_err()
    );
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]
    #[test]
    fn reader_never_panics_on_random_bytes(b in proptest::collection::vec(any::<u8>(), 0..300)) {
        let _ = dxf::read("f.dxf", &b, ReadOptions::default());
    }
    #[test]
    fn reader_never_panics_on_mutated_files(k in 0usize..4000, c in any::<u8>()) {
        let mut b = drawing();
        let i = k % b.len();
        b[i] = c;
        let _ = dxf::read("f.dxf", &b, ReadOptions::default());
    }
}

pub(crate) fn bytes_of(d: &::dxf::Drawing) -> Vec<u8> {
    let mut buf = Vec::new();
    d.save(&mut buf).unwrap();
    buf
}

#[test]
fn closed_polylines_without_vertices_draw_nothing_instead_of_panicking() {
    let mut d = ::dxf::Drawing::new();
    d.header.version = ::dxf::enums::AcadVersion::R2000;
    let mut pl = LwPolyline::default();
    pl.set_is_closed(true);
    d.add_entity(ent("a", EntityType::LwPolyline(pl)));
    let mut p = ::dxf::entities::Polyline::default();
    p.set_is_closed(true);
    d.add_entity(ent("a", EntityType::Polyline(p)));
    let r = dxf::read("z.dxf", &bytes_of(&d), ReadOptions::default()).unwrap();
    assert!(r.strokes.is_empty());
    let out = pipe::optimize(&r, &Options::default()).unwrap();
    assert!(out.strokes.is_empty());
}

#[test]
fn units_come_from_insunits_else_from_the_option_with_a_warning() {
    let mut d = ::dxf::Drawing::new();
    d.header.version = ::dxf::enums::AcadVersion::R2000;
    d.add_entity(ent(
        "a",
        EntityType::Line(Line::new(
            Point::new(0.0, 0.0, 0.0),
            Point::new(1.0, 0.0, 0.0),
        )),
    ));
    d.header.default_drawing_units = ::dxf::enums::Units::Unitless;
    let r = dxf::read("u.dxf", &bytes_of(&d), ReadOptions::default()).unwrap();
    assert_eq!(r.mm_per_unit, 1.0);
    assert!(r.warnings[0].contains("$INSUNITS"), "{:?}", r.warnings);
    let inch = ReadOptions {
        units: dxf::unit_mm("in"),
        ..ReadOptions::default()
    };
    let r = dxf::read("u.dxf", &bytes_of(&d), inch).unwrap();
    assert_eq!(r.mm_per_unit, 25.4);
    assert!(r.warnings[0].contains("--units"), "{:?}", r.warnings);
    d.header.default_drawing_units = ::dxf::enums::Units::Centimeters;
    let r = dxf::read("u.dxf", &bytes_of(&d), inch).unwrap();
    assert_eq!(r.mm_per_unit, 10.0);
    // the G-code is in mm: the 1 cm line is 10 mm long
    let g = dxf::write_gcode(&r, &r.strokes, &Post::default());
    assert!(g.contains("X10 Y0"), "{g}");
}

#[test]
fn spindle_and_laser_words_only_when_asked() {
    let d = dxf::read("t.dxf", &drawing(), ReadOptions::default()).unwrap();
    let plain = dxf::write_gcode(&d, &d.strokes, &Post::default());
    assert!(!plain.contains("M3") && !plain.contains("M4") && !plain.contains("M5"));
    let spindle = Post {
        spindle: 12000.0,
        ..Post::default()
    };
    let g = dxf::write_gcode(&d, &d.strokes, &spindle);
    assert!(g.contains("M3 S12000") && g.contains("M5"));
    dxf::verify_gcode(&d, "s.ngc", &g, &spindle).unwrap();
    let laser = Post {
        laser_power: 800.0,
        ..Post::default()
    };
    let g = dxf::write_gcode(&d, &d.strokes, &laser);
    assert!(
        g.contains("M4 S800") && g.contains("M5") && !g.contains('Z'),
        "{g}"
    );
    assert!(dxf::verify_gcode(&d, "l.ngc", &g, &laser).unwrap() > 20);
}

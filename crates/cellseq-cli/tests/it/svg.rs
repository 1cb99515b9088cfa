//! SVG reader, sequencer, writer and verifier.

use cellseq::SolverKind;
use cellseq_programs::optimize::strokes::{self as pipe, Options};
use cellseq_programs::svg::{self, ReadOptions};
use proptest::prelude::*;

fn fixture(name: &str) -> String {
    crate::common::fixture_text(&format!("svg/{name}"))
}

#[test]
fn reads_all_shapes_layers_and_dots() {
    let d = svg::read("shapes.svg", &fixture("shapes.svg"), ReadOptions::default()).unwrap();
    // rect, circle, ellipse, polygon; line, polyline, 2 subpaths of the path + 1 more, dot
    let labels: Vec<&str> = d.layers.iter().map(|l| l.label.as_str()).collect();
    assert_eq!(labels, vec!["", "cut", "draw"]);
    assert_eq!(d.strokes.iter().filter(|s| s.layer == 1).count(), 4);
    assert!(d.strokes.iter().filter(|s| s.layer == 1).all(|s| s.closed));
    let dots: Vec<_> = d.strokes.iter().filter(|s| s.is_dot()).collect();
    assert_eq!(dots.len(), 1);
    // transform of the layer and nested group applied to the dot (coordinates are kept at
    // the 6 decimals the writer prints): translate(1,2) scale(.5)
    // then matrix(1 0 0 1 5 5) skewX(10) skewY(5) on (150,150)
    let t = (10f64).to_radians().tan();
    let u = (5f64).to_radians().tan();
    let (x, y) = (150.0 + t * (150.0 + u * 150.0), 150.0 + u * 150.0);
    let (x, y) = (1.0 + 0.5 * (x + 5.0), 2.0 + 0.5 * (y + 5.0));
    assert!((dots[0].points[0][0] - x).abs() < 1e-6 && (dots[0].points[0][1] - y).abs() < 1e-6);
    // the first line scaled: (1,2)-(6,2), red, width 0.15
    let l = d
        .strokes
        .iter()
        .find(|s| s.layer == 2 && !s.closed)
        .unwrap();
    assert_eq!(l.points, vec![[1.0, 2.0], [6.0, 2.0]]);
    assert_eq!(d.styles[l.style].stroke, "#ff0000");
    assert!((d.styles[l.style].width - 0.15).abs() < 1e-12);
    // circle flattened within tolerance: all vertices on the circle of radius 5
    let c = d.strokes.iter().filter(|s| s.layer == 1).nth(1).unwrap();
    assert!(c.points.len() > 8);
    for p in &c.points {
        let r = ((p[0] - 30.0).powi(2) + (p[1] - 30.0).powi(2)).sqrt();
        assert!((r - 5.0).abs() < 0.011, "r = {r}");
    }
    assert!((d.mm_per_unit - 1.0).abs() < 1e-12);
}

#[test]
fn optimize_writes_the_same_drawing_with_less_pen_up() {
    let text = fixture("vpype_multilayer_3layers.svg");
    let d = svg::read("m.svg", &text, ReadOptions::default()).unwrap();
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    assert_eq!(out.strokes.len(), d.strokes.len());
    assert!(out.after.pen_up_mm < 0.2 * out.before.pen_up_mm);
    let w = svg::write(&d, &out.strokes);
    assert_eq!(svg::verify(&d, "w.svg", &w).unwrap(), 600);
    // scopes: layers stay contiguous and in order
    let layers: Vec<usize> = out.strokes.iter().map(|s| s.layer).collect();
    assert!(layers.windows(2).all(|w| w[0] <= w[1]));
    // the written file reads back to the same pen-up figure
    let back = svg::read("w.svg", &w, ReadOptions::default()).unwrap();
    let p = svg::pen_up(&back.strokes, back.mm_per_unit, |s| {
        back.layers[s.layer].label.clone()
    });
    assert!((p.pen_up_mm - out.after.pen_up_mm).abs() < 1e-3);
}

#[test]
fn registry_solver_and_no_reversal_also_verify() {
    let d = svg::read("s.svg", &fixture("shapes.svg"), ReadOptions::default()).unwrap();
    for (solver, rev) in [(SolverKind::AsGiven, true), (SolverKind::Drawing, false)] {
        let o = Options {
            solver,
            reversible: rev,
            ..Options::default()
        };
        let out = pipe::optimize(&d, &o).unwrap();
        let w = svg::write(&d, &out.strokes);
        svg::verify(&d, "w.svg", &w).unwrap();
        if !rev {
            for s in &out.strokes {
                assert!(d.strokes.contains(s), "stroke changed without reversal");
            }
        }
    }
}

#[test]
fn tampered_output_is_rejected() {
    let d = svg::read("s.svg", &fixture("shapes.svg"), ReadOptions::default()).unwrap();
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    let mut s = out.strokes.clone();
    s.pop();
    assert!(svg::verify(&d, "w.svg", &svg::write(&d, &s)).is_err());
    let mut s = out.strokes.clone();
    s[0].points[0][0] += 0.01;
    assert!(svg::verify(&d, "w.svg", &svg::write(&d, &s)).is_err());
}

#[test]
fn cut_mode_puts_inner_contours_first() {
    let d = svg::read("s.svg", &fixture("shapes.svg"), ReadOptions::default()).unwrap();
    let o = Options {
        cut: true,
        ..Options::default()
    };
    let out = pipe::optimize(&d, &o).unwrap();
    assert!(out.edges >= 3);
    let cut: Vec<_> = out.strokes.iter().filter(|s| s.layer == 1).collect();
    // the 80x80 square is last in its layer
    assert_eq!(cut.last().unwrap().points.len(), 4);
}

#[test]
fn elements_not_sequenced_are_kept_in_place_and_malformed_input_is_refused_with_a_line() {
    let t = "<svg xmlns=\"http://www.w3.org/2000/svg\">\n<g transform=\"scale(2)\"><text>hi &amp; ho</text></g>\n<line x2=\"1\" stroke=\"red\"/></svg>";
    let d = svg::read("t.svg", t, ReadOptions::default()).unwrap();
    assert_eq!(d.kept.len(), 1);
    assert_eq!(d.kept[0].line, 2);
    assert_eq!(
        d.kept[0].wrapped(),
        "<g transform=\"scale(2)\"><text>hi &amp; ho</text></g>"
    );
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    let w = svg::write(&d, &out.strokes);
    assert!(w.contains("<g transform=\"scale(2)\"><text>hi &amp; ho</text></g>"));
    svg::verify(&d, "w.svg", &w).unwrap();
    // a kept element lost on the way is caught
    let mut lost = d.clone();
    lost.kept.clear();
    let e = svg::verify(&d, "w.svg", &svg::write(&lost, &out.strokes)).unwrap_err();
    assert!(e.to_string().contains("kept"), "{e}");
    let skip = ReadOptions {
        skip_unsupported: true,
        ..ReadOptions::default()
    };
    let d = svg::read("t.svg", t, skip).unwrap();
    assert_eq!((d.skipped.len(), d.kept.len()), (1, 0));
    let t = "<svg xmlns=\"http://www.w3.org/2000/svg\">\n\n<path d=\"M 0 0 L 1 x\"/>\n</svg>";
    let e = svg::read("p.svg", t, ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("p.svg:3:"), "{e}");
    assert!(svg::read("x.svg", "<svg", ReadOptions::default()).is_err());
}

#[test]
fn doctype_is_accepted_and_entity_declarations_are_refused() {
    let t = "<?xml version=\"1.0\"?>\n<!DOCTYPE svg PUBLIC \"-//W3C//DTD SVG 1.1//EN\" \"http://www.w3.org/Graphics/SVG/1.1/DTD/svg11.dtd\">\n<svg xmlns=\"http://www.w3.org/2000/svg\"><line x2=\"5\" stroke=\"black\"/></svg>";
    assert_eq!(
        svg::read("d.svg", t, ReadOptions::default())
            .unwrap()
            .strokes
            .len(),
        1
    );
    let t = "<?xml version=\"1.0\"?>\n<!DOCTYPE svg [\n<!ENTITY a \"x\">]>\n<svg xmlns=\"http://www.w3.org/2000/svg\"><text>&a;</text></svg>";
    let e = svg::read("e.svg", t, ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("e.svg:3:") && e.contains("entity"), "{e}");
}

#[test]
fn invisible_zero_length_paths_are_kept_not_sequenced_and_round_caps_draw_dots() {
    let t = "<svg xmlns=\"http://www.w3.org/2000/svg\"><path d=\"M 3,4 Z\" stroke=\"black\"/><path d=\"M 5,5 Z\" stroke=\"black\" stroke-linecap=\"round\"/><line x2=\"1\" stroke=\"black\"/></svg>";
    let d = svg::read("z.svg", t, ReadOptions::default()).unwrap();
    assert_eq!(d.kept.len(), 1);
    assert_eq!(d.strokes.iter().filter(|s| s.is_dot()).count(), 1);
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    let w = svg::write(&d, &out.strokes);
    assert_eq!(svg::verify(&d, "w.svg", &w).unwrap(), 2);
}

fn svg_with(body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"100mm\" height=\"100mm\" viewBox=\"0 0 100 100\">\n{body}\n</svg>"
    )
}

#[test]
fn deep_nesting_huge_shapes_and_point_caps_are_bounded() {
    // 50 000 nested groups: walked without recursion
    let t = svg_with(&format!(
        "{}<line x2=\"1\" stroke=\"black\"/>{}",
        "<g>".repeat(50_000),
        "</g>".repeat(50_000)
    ));
    assert_eq!(
        svg::read("n.svg", &t, ReadOptions::default())
            .unwrap()
            .strokes
            .len(),
        1
    );
    // a circle of radius 1e308 is refused before kurbo builds it
    let t = svg_with("<circle r=\"1e308\" stroke=\"black\"/>");
    let e = svg::read("c.svg", &t, ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("c.svg:2:") && e.contains("size"), "{e}");
    // a circle of radius 1e9 reaches past the coordinate limit of validation: a clean refusal
    let t = svg_with("<circle r=\"1e9\" stroke=\"black\"/>");
    let d = svg::read("c.svg", &t, ReadOptions::default()).unwrap();
    let e = pipe::optimize(&d, &Options::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("beyond"), "{e}");
    // a circle of radius 1e8 is flattened with a tolerance relative to its size, and verifies
    let t = svg_with("<circle r=\"1e8\" stroke=\"black\"/>");
    let d = svg::read("c.svg", &t, ReadOptions::default()).unwrap();
    let n = d.strokes[0].points.len();
    assert!((100..20_000).contains(&n), "{n} points");
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    assert_eq!(
        svg::verify(&d, "w.svg", &svg::write(&d, &out.strokes)).unwrap(),
        n
    );
    // the point cap
    let capped = ReadOptions {
        max_points: 50,
        ..ReadOptions::default()
    };
    let t = svg_with("<circle r=\"40\" stroke=\"black\"/>");
    let e = svg::read("c.svg", &t, capped).unwrap_err().to_string();
    assert!(e.contains("--max-points"), "{e}");
}

#[test]
fn coincident_strokes_and_a_far_point_stay_linear() {
    // 4000 identical strokes and one dot at 1e7: the default budget is linear in the strokes
    let mut body = String::new();
    for _ in 0..4000 {
        body.push_str("<line x1=\"10\" y1=\"10\" x2=\"20\" y2=\"20\" stroke=\"black\"/>\n");
    }
    body.push_str("<path d=\"M 1e7,1e7 Z\" stroke=\"black\" stroke-linecap=\"round\"/>");
    let d = svg::read("c.svg", &svg_with(&body), ReadOptions::default()).unwrap();
    assert_eq!(d.strokes.len(), 4001);
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    // every stroke joins the previous one end to start (back and forth), then the far dot
    assert_eq!(out.after.lifts, 2);
    svg::verify(&d, "w.svg", &svg::write(&d, &out.strokes)).unwrap();
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]
    #[test]
    fn reader_never_panics_on_random_bytes(b in proptest::collection::vec(any::<u8>(), 0..400)) {
        let s = String::from_utf8_lossy(&b);
        let _ = svg::read("f.svg", &s, ReadOptions::default());
    }
    #[test]
    fn reader_never_panics_on_random_path_data(d in "[MmLlHhVvCcSsQqTtAaZz0-9 ,.eE+-]{0,80}") {
        let s = format!("<svg xmlns=\"http://www.w3.org/2000/svg\"><path d=\"{d}\"/></svg>");
        if let Ok(dr) = svg::read("f.svg", &s, ReadOptions::default()) {
            let out = pipe::optimize(&dr, &Options::default()).unwrap();
            let w = svg::write(&dr, &out.strokes);
            prop_assert!(svg::verify(&dr, "w.svg", &w).is_ok());
        }
    }
}

/// Percentage lengths (osm2svg4art's background `<rect width="100%" height="100%">`) are of
/// the viewport: its viewBox, else the root's size in px; without either they are refused.
#[test]
fn percentage_lengths_are_of_the_viewport() {
    let doc = |root: &str, body: &str| {
        format!("<svg xmlns=\"http://www.w3.org/2000/svg\" {root}>{body}</svg>")
    };
    let rect = "<rect x=\"10%\" width=\"50%\" height=\"100%\" stroke=\"black\" fill=\"none\"/>";
    let d = svg::read(
        "p.svg",
        &doc(
            "width=\"160mm\" height=\"100mm\" viewBox=\"0 0 160 100\"",
            rect,
        ),
        ReadOptions::default(),
    )
    .unwrap();
    let s = &d.strokes[0];
    assert!(s.closed);
    let xs: Vec<f64> = s.points.iter().map(|p| p[0]).collect();
    let ys: Vec<f64> = s.points.iter().map(|p| p[1]).collect();
    let min = |v: &[f64]| v.iter().cloned().fold(f64::MAX, f64::min);
    let max = |v: &[f64]| v.iter().cloned().fold(f64::MIN, f64::max);
    assert_eq!(min(&xs), 16.0);
    assert_eq!(max(&xs), 96.0);
    assert_eq!((min(&ys), max(&ys)), (0.0, 100.0));
    // without a viewBox: the root's size in px
    let d = svg::read(
        "p.svg",
        &doc("width=\"200\" height=\"50\"", rect),
        ReadOptions::default(),
    )
    .unwrap();
    let xs: Vec<f64> = d.strokes[0].points.iter().map(|p| p[0]).collect();
    assert_eq!(xs.iter().cloned().fold(f64::MIN, f64::max), 120.0);
    // no viewport: refused with the line
    let e = svg::read("p.svg", &doc("", rect), ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("p.svg:1") && e.contains("bad x='10%'"), "{e}");
}

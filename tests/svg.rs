//! SVG reader, sequencer, writer and verifier.

use cellseq::io::svg::{self, Options, ReadOptions};
use proptest::prelude::*;

fn fixture(name: &str) -> String {
    std::fs::read_to_string(format!("tests/fixtures/svg/{name}")).unwrap()
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
    // transform of the layer and nested group applied to the dot: translate(1,2) scale(.5)
    // then matrix(1 0 0 1 5 5) skewX(10) skewY(5) on (150,150)
    let t = (10f64).to_radians().tan();
    let u = (5f64).to_radians().tan();
    let (x, y) = (150.0 + t * (150.0 + u * 150.0), 150.0 + u * 150.0);
    let (x, y) = (1.0 + 0.5 * (x + 5.0), 2.0 + 0.5 * (y + 5.0));
    assert!((dots[0].points[0][0] - x).abs() < 1e-9 && (dots[0].points[0][1] - y).abs() < 1e-9);
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
    let out = svg::optimize(&d, &Options::default()).unwrap();
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
    for (solver, rev) in [("as-given", true), ("drawing", false)] {
        let o = Options {
            solver: solver.into(),
            reversible: rev,
            ..Options::default()
        };
        let out = svg::optimize(&d, &o).unwrap();
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
    let out = svg::optimize(&d, &Options::default()).unwrap();
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
    let out = svg::optimize(&d, &o).unwrap();
    assert!(out.edges >= 3);
    let cut: Vec<_> = out.strokes.iter().filter(|s| s.layer == 1).collect();
    // the 80x80 square is last in its layer
    assert_eq!(cut.last().unwrap().points.len(), 4);
}

#[test]
fn unsupported_and_malformed_input_is_refused_with_a_line() {
    let t = "<svg xmlns=\"http://www.w3.org/2000/svg\">\n<text>hi</text>\n</svg>";
    let e = svg::read("t.svg", t, ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("t.svg:2:") && e.contains("text"), "{e}");
    let skip = ReadOptions {
        skip_unsupported: true,
        ..ReadOptions::default()
    };
    assert_eq!(svg::read("t.svg", t, skip).unwrap().skipped.len(), 1);
    let t = "<svg xmlns=\"http://www.w3.org/2000/svg\">\n\n<path d=\"M 0 0 L 1 x\"/>\n</svg>";
    let e = svg::read("p.svg", t, ReadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("p.svg:3:"), "{e}");
    assert!(svg::read("x.svg", "<svg", ReadOptions::default()).is_err());
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
            let out = svg::optimize(&dr, &Options::default()).unwrap();
            let w = svg::write(&dr, &out.strokes);
            prop_assert!(svg::verify(&dr, "w.svg", &w).is_ok());
        }
    }
}

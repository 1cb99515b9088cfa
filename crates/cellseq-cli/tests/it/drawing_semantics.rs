//! Pen and block semantics of drawings (issue 47, "Drawings whose top-level groups are not
//! parts"): a layer is a pen in Inkscape files, a colour is a pen elsewhere, boxes.py groups
//! are parts and other plain groups are only grouping; `auto` keeps the shorter of the
//! convention it reads and the strictest reading, and says which it used.

use crate::common::{cellseq, fixture_text, s, stderr, write};
use cellseq_programs::optimize::strokes::{self as pipe, Blocks, Options, Pens, Reading};
use cellseq_programs::svg::{self, ReadOptions};
use std::fmt::Write as _;

const INKSCAPE: &str = "http://www.inkscape.org/namespaces/inkscape";

fn doc(body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:inkscape=\"{INKSCAPE}\" \
         width=\"100mm\" height=\"100mm\" viewBox=\"0 0 100 100\">\n{body}\n</svg>\n"
    )
}

fn line(x: f64, y: f64, dx: f64, colour: &str) -> String {
    format!("<path d=\"M{x},{y} l{dx},0\" stroke=\"{colour}\"/>")
}

/// Two Inkscape layers, each of 40 short lines in 4 colours interleaved along a row: by
/// colour each layer is four sweeps, by layer one.
fn two_layers_four_colours() -> String {
    let colours = ["red", "green", "blue", "black"];
    let mut body = String::new();
    for (l, y) in [(1, 10.0), (2, 60.0)] {
        let _ = write!(body, "<g inkscape:groupmode=\"layer\" id=\"L{l}\">");
        for i in 0..40 {
            body.push_str(&line(2.0 * i as f64, y, 1.0, colours[i % 4]));
        }
        body.push_str("</g>\n");
    }
    doc(&body)
}

/// 21 plain top-level groups, each a strip of lines of 4 colours across the page: as parts
/// each group is drawn colour by colour; merged, each colour is one sweep per row.
fn map_of_groups() -> String {
    let colours = ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"];
    let mut body = String::new();
    for g in 0..21 {
        let _ = write!(body, "<g id=\"tile{g}\">");
        for (c, colour) in colours.iter().enumerate() {
            for k in 0..3 {
                let x = (g % 7) as f64 * 14.0 + k as f64 * 4.0;
                let y = (g / 7) as f64 * 30.0 + c as f64 * 6.0;
                body.push_str(&line(x, y, 3.0, colour));
            }
        }
        body.push_str("</g>\n");
    }
    doc(&body)
}

fn read(name: &str, text: &str) -> svg::Drawing {
    svg::read(name, text, ReadOptions::default()).unwrap()
}

/// Options with these semantics and the default budget (evaluations per scope, the same
/// whichever readings are solved: a reading solved inside `auto` is the one solved alone).
fn with(pens: Pens, blocks: Blocks) -> Options {
    Options {
        pens,
        blocks,
        ..Options::default()
    }
}

/// The layer of each stroke, in drawing order, with repeats merged.
fn runs(
    d: &svg::Drawing,
    strokes: &[svg::Stroke],
    key: impl Fn(&svg::Stroke) -> String,
) -> Vec<String> {
    let mut v: Vec<String> = strokes.iter().map(key).collect();
    v.dedup();
    let _ = d;
    v
}

#[test]
fn an_inkscape_file_draws_each_layer_as_one_pen() {
    let d = read("l.svg", &two_layers_four_colours());
    let auto = pipe::optimize(&d, &with(Pens::Auto, Blocks::Auto)).unwrap();
    let strict = pipe::optimize(&d, &with(Pens::Colour, Blocks::Group)).unwrap();
    assert_eq!(auto.reading, Reading::new(Pens::Layer, Blocks::Group));
    assert!(
        auto.semantics.contains("Inkscape layers"),
        "{}",
        auto.semantics
    );
    // each layer is one pen: contiguous and in the file's order
    let layers = runs(&d, &auto.strokes, |s| d.layers[s.layer].label.clone());
    assert_eq!(layers, ["L1", "L2"]);
    // one sweep per layer instead of four: far less travel, and never more than the strict
    // reading it also solved
    assert!(
        auto.after.pen_up_total_mm < 0.5 * strict.after.pen_up_total_mm,
        "{} vs {}",
        auto.after.pen_up_total_mm,
        strict.after.pen_up_total_mm
    );
    assert_eq!(auto.tried.len(), 2);
    let least = auto.tried.iter().map(|t| t.1).fold(f64::INFINITY, f64::min);
    assert_eq!(auto.after.pen_up_total_mm, least);
    svg::verify(&d, "w.svg", &svg::write(&d, &auto.strokes)).unwrap();
}

#[test]
fn plain_groups_that_are_not_parts_are_merged_by_colour() {
    let d = read("m.svg", &map_of_groups());
    let auto = pipe::optimize(&d, &with(Pens::Auto, Blocks::Auto)).unwrap();
    let parts = pipe::optimize(&d, &with(Pens::Colour, Blocks::Group)).unwrap();
    assert_eq!(auto.reading, Reading::new(Pens::Colour, Blocks::None));
    // each colour is one pen across the groups, in the order the colours first appear
    let colours = runs(&d, &auto.strokes, |s| d.styles[s.style].stroke.clone());
    assert_eq!(colours, ["#1f77b4", "#ff7f0e", "#2ca02c", "#d62728"]);
    assert!(auto.after.pen_up_total_mm < parts.after.pen_up_total_mm);
    // the groups come back as groups (split where the colours interleave them), verified
    let w = svg::write(&d, &auto.strokes);
    svg::verify(&d, "w.svg", &w).unwrap();
    assert_eq!(w.matches("id=\"tile0\"").count(), 1);
}

#[test]
fn boxes_py_groups_are_parts_and_groups_with_conflicting_colour_orders_too() {
    // boxes.py's own files: parts in a free order, each drawn colour by colour or as one pen
    // inner strokes first, whichever is shorter
    for name in ["boxespy_ABox.svg", "boxespy_Spool.svg"] {
        let d = read(name, &fixture_text(&format!("svg/real/{name}")));
        assert_eq!(d.generator.as_deref(), Some("boxes.py"));
        let out = pipe::optimize(&d, &with(Pens::Auto, Blocks::Auto)).unwrap();
        assert!(out.semantics.contains("boxes.py"), "{}", out.semantics);
        let inner = Reading {
            inner_first: true,
            ..Reading::new(Pens::Layer, Blocks::Group)
        };
        let tried: Vec<Reading> = out.tried.iter().map(|t| t.0).collect();
        assert_eq!(tried, [Reading::STRICT, inner], "{name}");
        let least = out.tried.iter().map(|t| t.1).fold(f64::INFINITY, f64::min);
        assert_eq!(out.after.pen_up_total_mm, least, "{name}");
        if !out.reading.inner_first {
            continue;
        }
        // inner first: every stroke inside a closed stroke of its part comes before it
        // a stroke is named by its layer and the sum of its points, rounded: the same set of
        // points whichever vertex a closed stroke starts from (the first is not repeated),
        // though the order of the sum differs
        let key = |s: &svg::Stroke| {
            let sum = s
                .points
                .iter()
                .fold([0.0f64; 2], |a, p| [a[0] + p[0], a[1] + p[1]]);
            (s.layer, format!("{:?}", sum.map(|v| (v * 1e3).round())))
        };
        let pos: std::collections::HashMap<(usize, String), usize> = out
            .strokes
            .iter()
            .enumerate()
            .map(|(k, s)| (key(s), k))
            .collect();
        let all: Vec<usize> = (0..d.strokes.len()).collect();
        for (a, b) in pipe::containment(&d, &all, 0.01) {
            let (sa, sb) = (&d.strokes[a], &d.strokes[b]);
            if sa.layer == sb.layer {
                let at = |s: &svg::Stroke| {
                    *pos.get(&key(s))
                        .unwrap_or_else(|| panic!("{name}: stroke {:?} not in the output", key(s)))
                };
                assert!(at(sa) < at(sb), "{name}: stroke {a} after {b}");
            }
        }
    }
    // two groups ordering their colours the other way round: merging them by colour would
    // draw one of them in another colour order, so they stay parts
    let body = format!(
        "<g id=\"a\">{}{}</g><g id=\"b\">{}{}</g>",
        line(0.0, 0.0, 5.0, "blue"),
        line(0.0, 10.0, 5.0, "black"),
        line(50.0, 0.0, 5.0, "black"),
        line(50.0, 10.0, 5.0, "blue")
    );
    let d = read("c.svg", &doc(&body));
    assert!(!pipe::semantics::colour_orders_agree(&d));
    let out = pipe::optimize(&d, &with(Pens::Auto, Blocks::Auto)).unwrap();
    assert_eq!(out.reading, Reading::STRICT);
    assert!(out.semantics.contains("differently"), "{}", out.semantics);
}

#[test]
fn explicit_readings_are_kept_as_given() {
    let d = read("l.svg", &two_layers_four_colours());
    for (pens, blocks) in [
        (Pens::Colour, Blocks::Group),
        (Pens::Layer, Blocks::None),
        (Pens::None, Blocks::None),
    ] {
        let out = pipe::optimize(&d, &with(pens, blocks)).unwrap();
        assert_eq!(out.reading, Reading::new(pens, blocks));
        assert_eq!(out.tried.len(), 1);
        svg::verify(&d, "w.svg", &svg::write(&d, &out.strokes)).unwrap();
    }
    // colour pens: each layer draws its colours one after the other, in the file's order
    let out = pipe::optimize(&d, &with(Pens::Colour, Blocks::Group)).unwrap();
    let runs = runs(&d, &out.strokes, |s| {
        format!("{} {}", d.layers[s.layer].label, d.styles[s.style].stroke)
    });
    assert_eq!(runs.len(), 8, "{runs:?}");
}

#[test]
fn the_command_line_names_the_semantics_and_refuses_contradictions() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "l.svg", &two_layers_four_colours());
    let o = cellseq()
        .args(["optimize", s(&p), "--json", "--max-evals", "100000"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["semantics"]["pens"], "layer");
    assert_eq!(v["semantics"]["blocks"], "group");
    assert_eq!(v["semantics"]["tried"].as_array().unwrap().len(), 2);
    let o = cellseq()
        .args(["optimize", s(&p), "--pens", "colour", "--blocks", "group"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("semantics: pens colour, blocks group (as given)"),
        "{text}"
    );
    for bad in [
        vec!["--no-scopes", "--pens", "layer"],
        vec!["--keep-group-order", "--blocks", "none"],
        vec!["--pens", "pencil"],
    ] {
        let o = cellseq()
            .args(["optimize", s(&p)])
            .args(&bad)
            .output()
            .unwrap();
        assert!(!o.status.success(), "{bad:?}");
        assert!(!stderr(&o).is_empty());
    }
}

#[test]
fn real_inkscape_files_with_colours_in_their_layers_are_never_longer_than_the_strict_reading() {
    for name in ["axidraw_wedding-invite.svg", "eggbot_durer_layer.svg"] {
        let d = read(name, &fixture_text(&format!("svg/real/{name}")));
        let auto = pipe::optimize(&d, &with(Pens::Auto, Blocks::Auto)).unwrap();
        let strict = pipe::optimize(&d, &with(Pens::Colour, Blocks::Group)).unwrap();
        assert_eq!(auto.reading.pens, Pens::Layer, "{name}");
        assert!(
            auto.after.pen_up_total_mm <= strict.after.pen_up_total_mm + 1e-9,
            "{name}: {} vs {}",
            auto.after.pen_up_total_mm,
            strict.after.pen_up_total_mm
        );
        // the strict reading solved inside `auto` is the one solved alone
        let inside = auto
            .tried
            .iter()
            .find(|t| t.0 == Reading::STRICT)
            .unwrap()
            .1;
        assert!(
            (inside - strict.after.pen_up_total_mm).abs() < 1e-6,
            "{name}"
        );
    }
}

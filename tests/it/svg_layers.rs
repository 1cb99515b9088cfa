//! The SVG writer keeps the file's layers as the file has them: every group that is a child
//! of the root (boxes.py's parts, the layers plotter tools such as vpype read) and every
//! Inkscape layer comes back as one group with its id, in the file's order, holding exactly
//! its own strokes.

use cellseq::io::svg::{self, ReadOptions};
use cellseq::pipeline::drawing::{self as pipe, Options};

fn real(name: &str) -> String {
    crate::common::fixture_text(&format!("svg/real/{name}"))
}

/// (id, label, Inkscape layer) of every named layer (the writer puts the root's own elements
/// in an unnamed group, which reads back as an unnamed layer with the root's empty label).
fn layers(d: &cellseq::io::drawing::Drawing) -> Vec<(Option<String>, String, bool)> {
    d.layers[1..]
        .iter()
        .filter(|l| l.id.is_some() || !l.label.is_empty())
        .map(|l| (l.id.clone(), l.label.clone(), l.inkscape))
        .collect()
}

#[test]
fn top_level_groups_are_layers_and_are_written_back_as_groups() {
    let text = real("boxespy_ABox.svg");
    let d = svg::read("ABox.svg", &text, ReadOptions::default()).unwrap();
    let ids: Vec<String> = (0..6).map(|i| format!("p-{i}")).collect();
    let want: Vec<(Option<String>, String, bool)> = ids
        .iter()
        .map(|i| (Some(i.clone()), i.clone(), false))
        .collect();
    assert_eq!(layers(&d), want, "each part of boxes.py is a layer");
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    // layers are scopes: each stays contiguous, in the file's order
    let order: Vec<usize> = out.strokes.iter().map(|s| s.layer).collect();
    assert!(order.windows(2).all(|w| w[0] <= w[1]), "{order:?}");
    let w = svg::write(&d, &out.strokes);
    for id in &ids {
        assert_eq!(
            w.matches(&format!("<g id=\"{id}\">")).count(),
            1,
            "one group {id} in the output"
        );
    }
    let back = svg::read("w.svg", &w, ReadOptions::default()).unwrap();
    assert_eq!(layers(&back), want);
    // every stroke is back in its own group (verify compares segments per layer label)
    svg::verify(&d, "w.svg", &w).unwrap();
    let count = |d: &cellseq::io::drawing::Drawing, id: &str| {
        let l = d.layers.iter().position(|l| l.id.as_deref() == Some(id));
        d.strokes.iter().filter(|s| Some(s.layer) == l).count()
    };
    for id in &ids {
        assert_eq!(count(&d, id), count(&back, id), "strokes of layer {id}");
    }
}

#[test]
fn inkscape_layers_keep_their_ids_and_labels() {
    let text = real("vpype_cmyk_file1.svg");
    let d = svg::read("cmyk.svg", &text, ReadOptions::default()).unwrap();
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    let w = svg::write(&d, &out.strokes);
    let back = svg::read("w.svg", &w, ReadOptions::default()).unwrap();
    assert_eq!(layers(&back), layers(&d));
    assert!(layers(&d).iter().all(|l| l.2 && l.0.is_some()));
    svg::verify(&d, "w.svg", &w).unwrap();
}

#[test]
fn split_layers_keep_unique_ids_and_their_labels() {
    // without scopes the strokes of a layer may be split among several groups: the id is
    // written once, later groups carry the layer's name as their label
    let text = real("boxespy_ABox.svg");
    let d = svg::read("ABox.svg", &text, ReadOptions::default()).unwrap();
    let out = pipe::optimize(
        &d,
        &Options {
            scopes: false,
            ..Options::default()
        },
    )
    .unwrap();
    let w = svg::write(&d, &out.strokes);
    for i in 0..6 {
        assert!(w.matches(&format!("id=\"p-{i}\"")).count() <= 1);
    }
    svg::verify(&d, "w.svg", &w).unwrap();
}

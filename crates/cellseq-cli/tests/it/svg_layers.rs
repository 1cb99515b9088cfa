//! The SVG writer keeps the file's layers as the file has them: every group that is a child
//! of the root (boxes.py's parts, the layers plotter tools such as vpype read) and every
//! Inkscape layer comes back as one group with its id, holding exactly its own strokes.
//! Inkscape layers keep the file's order; plain top-level groups are blocks put in the order
//! of least pen-up travel (the file's with `--keep-group-order`).

use cellseq_programs::optimize::strokes::{self as pipe, Options};
use cellseq_programs::svg::{self, ReadOptions};

fn real(name: &str) -> String {
    crate::common::fixture_text(&format!("svg/real/{name}"))
}

/// (id, label, Inkscape layer) of every named layer (the writer puts the root's own elements
/// in an unnamed group, which reads back as an unnamed layer with the root's empty label).
fn layers(d: &cellseq_programs::drawing::Drawing) -> Vec<(Option<String>, String, bool)> {
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
    let keep = Options {
        free_groups: false,
        ..Options::default()
    };
    let out = pipe::optimize(&d, &keep).unwrap();
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
    let count = |d: &cellseq_programs::drawing::Drawing, id: &str| {
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

#[test]
fn plain_groups_are_blocks_in_a_shorter_order_and_never_longer() {
    let text = real("boxespy_ABox.svg");
    let d = svg::read("ABox.svg", &text, ReadOptions::default()).unwrap();
    let keep = pipe::optimize(
        &d,
        &Options {
            free_groups: false,
            ..Options::default()
        },
    )
    .unwrap();
    let free = pipe::optimize(&d, &Options::default()).unwrap();
    assert!(free.groups_reordered);
    assert!(
        free.after.pen_up_total_mm < keep.after.pen_up_total_mm,
        "{} vs {}",
        free.after.pen_up_total_mm,
        keep.after.pen_up_total_mm
    );
    assert!((free.after.draw_mm - keep.after.draw_mm).abs() < 1e-9);
    // each part is one contiguous block, written back as one group; not the file's order
    let mut order: Vec<usize> = free.strokes.iter().map(|s| s.layer).collect();
    order.dedup();
    let mut sorted = order.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(order.len(), sorted.len(), "a part split: {order:?}");
    assert_ne!(order, sorted, "the file's order");
    let w = svg::write(&d, &free.strokes);
    for i in 0..6 {
        assert_eq!(w.matches(&format!("<g id=\"p-{i}\">")).count(), 1);
    }
    svg::verify(&d, "w.svg", &w).unwrap();
    // within each part, the colour order of the file is kept
    let colours = |strokes: &[cellseq_programs::drawing::Stroke], layer: usize| {
        let mut c: Vec<&str> = strokes
            .iter()
            .filter(|s| s.layer == layer)
            .map(|s| d.styles[s.style].stroke.as_str())
            .collect();
        c.dedup();
        c
    };
    for l in 1..d.layers.len() {
        assert_eq!(colours(&free.strokes, l), colours(&keep.strokes, l));
    }
}

#[test]
fn inkscape_layers_keep_their_place_and_plain_groups_between_them_take_the_shortest_order() {
    // one stroke per group; file order a, b, c of plain groups is far from the shortest
    let line = |x: f64| format!("<path d=\"M{x},0 L{x},1\" stroke=\"black\" fill=\"none\"/>");
    let text = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" \
         xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\">\
         <g inkscape:groupmode=\"layer\" id=\"first\">{}</g>\
         <g id=\"a\">{}</g><g id=\"b\">{}</g><g id=\"c\">{}</g><g id=\"d\">{}</g>\
         <g inkscape:groupmode=\"layer\" id=\"last\">{}</g></svg>",
        line(0.0),
        line(40.0),
        line(10.0),
        line(30.0),
        line(20.0),
        line(50.0)
    );
    let d = svg::read("g.svg", &text, ReadOptions::default()).unwrap();
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    let ids: Vec<&str> = out
        .strokes
        .iter()
        .map(|s| d.layers[s.layer].id.as_deref().unwrap_or(""))
        .collect();
    assert_eq!(ids, ["first", "b", "d", "c", "a", "last"]);
    let keep = pipe::optimize(
        &d,
        &Options {
            free_groups: false,
            ..Options::default()
        },
    )
    .unwrap();
    let ids: Vec<&str> = keep
        .strokes
        .iter()
        .map(|s| d.layers[s.layer].id.as_deref().unwrap_or(""))
        .collect();
    assert_eq!(ids, ["first", "a", "b", "c", "d", "last"]);
}

//! `plot`: SVG and PNG pictures render without system fonts.

use cellseq::generate::generate;
use std::collections::BTreeMap;

#[test]
fn svg_and_png_render_with_embedded_font() {
    let dir = tempfile::tempdir().unwrap();
    let inst = generate("cabin", &BTreeMap::new(), 1).unwrap();
    let seq = inst.as_given.clone().unwrap();
    let svg = dir.path().join("a.svg");
    cellseq::plot::plot(&inst, Some(&seq), "cabin caption", &svg).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg"));
    assert!(text.contains("cabin caption"));
    // one air move per visit
    assert!(text.matches("<polyline").count() >= seq.len());
    let png = dir.path().join("a.png");
    cellseq::plot::plot(&inst, None, "no solution", &png).unwrap();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn bad_output_names_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let inst = generate("casing", &BTreeMap::new(), 1).unwrap();
    let e = cellseq::plot::plot(&inst, None, "x", &dir.path().join("a.pdf")).unwrap_err();
    assert!(
        e.to_string().contains("a.pdf") && e.to_string().contains(".svg"),
        "{e}"
    );
}

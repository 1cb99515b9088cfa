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

#[test]
fn cli_generate_solve_plot() {
    let exe = env!("CARGO_BIN_EXE_cellseq");
    let dir = tempfile::tempdir().unwrap();
    let inst = dir.path().join("p.json");
    let sol = dir.path().join("s.json");
    let pic = dir.path().join("p.svg");
    let run = |args: &[&str]| std::process::Command::new(exe).args(args).output().unwrap();
    let i = inst.to_str().unwrap();
    let o = run(&[
        "generate", "panel", "--param", "rows=1", "--param", "cols=2", "--seed", "3", "-o", i,
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "solve",
        i,
        "--solver",
        "greedy",
        "--out",
        sol.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "plot",
        i,
        "--solution",
        sol.to_str().unwrap(),
        "-o",
        pic.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let svg = std::fs::read_to_string(&pic).unwrap();
    assert!(svg.contains("greedy") && svg.contains("lifts"));
    let o = run(&["plot", i, "-o", dir.path().join("p.gif").to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("p.gif"));
    let o = run(&[
        "generate",
        "panel",
        "--param",
        "rows=99999999999",
        "--param",
        "cols=99999999999",
        "-o",
        i,
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("rows"));
}

//! `plot`: SVG and PNG pictures render without system fonts.

use cellseq::generate::generate;
use std::collections::BTreeMap;

#[test]
fn svg_and_png_render_with_embedded_font() {
    let dir = tempfile::tempdir().unwrap();
    let inst = generate("cabin", &BTreeMap::new(), 1).unwrap();
    let seq = inst.as_given.clone().unwrap();
    let svg = dir.path().join("a.svg");
    cellseq_lab::plot::plot(&inst, Some(&seq), "cabin caption", &svg).unwrap();
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.contains("<svg"));
    assert!(text.contains("cabin caption"));
    // one air move per visit
    assert!(text.matches("<polyline").count() >= seq.len());
    let png = dir.path().join("a.png");
    cellseq_lab::plot::plot(&inst, None, "no solution", &png).unwrap();
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
}

#[test]
fn bad_output_names_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let inst = generate("casing", &BTreeMap::new(), 1).unwrap();
    let e = cellseq_lab::plot::plot(&inst, None, "x", &dir.path().join("a.pdf")).unwrap_err();
    assert!(
        e.to_string().contains("a.pdf") && e.to_string().contains(".svg"),
        "{e}"
    );
}

#[test]
fn cli_generate_solve_plot() {
    let exe = crate::common::BIN;
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
    // the first parameter out of range is named (the parameters are checked by name)
    assert!(String::from_utf8_lossy(&o.stderr).contains("must be a whole number in [1, 1e5]"));
}

#[test]
fn programs_and_drawings_plot_directly_right_way_up() {
    use cellseq_lab::plot::{drawing_panel, plot_panels, program_panel};
    use cellseq_programs::svg;
    let dir = tempfile::tempdir().unwrap();
    // an SVG triangle pointing down (y grows down in SVG): its apex has the largest y, and
    // the y axis labels read as the file's y (not negated)
    let t = "<svg xmlns=\"http://www.w3.org/2000/svg\"><polygon points=\"20,60 30,60 25,70\" stroke=\"black\"/><line x1=\"0\" y1=\"0\" x2=\"5\" y2=\"0\" stroke=\"black\"/></svg>";
    let d = svg::read("t.svg", t, svg::ReadOptions::default()).unwrap();
    let p = drawing_panel("before", &d, &d.strokes);
    let k = d.mm_per_unit;
    assert_eq!(p.cuts.len(), 2);
    assert!((p.cuts[0].iter().map(|q| q.1).fold(0.0, f64::max) - 70.0 * k).abs() < 1e-9);
    assert_eq!(p.air.len(), 1);
    let out = dir.path().join("t.svg");
    plot_panels(&[p.clone(), p], true, false, &out).unwrap();
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.contains("y (mm, down)") && text.contains("before: air"));
    assert!(
        !text.contains(">-10<") && !text.contains(">-15<"),
        "labels negated"
    );
    // a G-code program: an arc is drawn as an arc, air moves between cuts
    let g = "G21 G90 G17\nG0 Z5\nG0 X0 Y0\nG1 Z-1 F100\nG1 X10 F500\nG2 X20 Y0 I5 J0\nG0 Z5\nG0 X0 Y20\nG1 Z-1\nG1 X10 Y20\nG0 Z5\nM2\n";
    let prog = cellseq_programs::gcode::interp::interpret(g).unwrap();
    let p = program_panel("g", &prog);
    assert!(p.cuts.iter().map(|c| c.len()).sum::<usize>() > 10);
    assert!(p.air.iter().any(|[a, b]| a.1 == 0.0 && b.1 == 20.0));
    // arc of a G2 from (10,0) to (20,0) around (15,0): clockwise, so over the top (y > 0)
    assert!(p.cuts.iter().flatten().any(|q| q.1 > 4.9));
    let png = dir.path().join("g.png");
    plot_panels(&[p], false, true, &png).unwrap();
    assert_eq!(&std::fs::read(&png).unwrap()[..4], b"\x89PNG");
}

#[test]
fn cli_plots_svg_with_optimized_side_by_side() {
    let exe = crate::common::BIN;
    let dir = tempfile::tempdir().unwrap();
    let pic = dir.path().join("s.png");
    let o = std::process::Command::new(exe)
        .args([
            "plot",
            crate::common::fixture_path("svg/shapes.svg")
                .to_str()
                .unwrap(),
            "--optimized",
            "-o",
            pic.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(&std::fs::read(&pic).unwrap()[..4], b"\x89PNG");
}

//! Regression tests for hostile drawings found by issue 26's campaign and by the mutation test
//! (`tests/mutations.rs`): each runs `cellseq optimize` on the input in a child process held to
//! 4 GB of address space and 30 s of CPU, and expects a clean refusal (exit 2) or a result (exit
//! 0), never a panic, an abort or a signal. Children are limited so that a regression cannot
//! take the machine down with it.

use std::path::Path;
use std::process::Command;

/// Runs `cellseq optimize INPUT -o OUTPUT` under the limits; asserts a clean exit.
fn optimize_is_clean(name: &str, text: &str, out_ext: &str) {
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join(name);
    std::fs::write(&input, text).unwrap();
    let output = d.path().join(format!("out.{out_ext}"));
    let out = limited(&input, &output);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{name}: panic: {err}");
    assert!(
        matches!(out.status.code(), Some(0) | Some(2)),
        "{name}: exit {:?} (a signal or an abort): {err}",
        out.status
    );
}

fn limited(input: &Path, output: &Path) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(r#"ulimit -v 4194304; ulimit -t 30; exec "$0" optimize "$1" -o "$2""#)
        .arg(crate::common::BIN)
        .arg(input)
        .arg(output)
        .output()
        .unwrap()
}

const SVG_HEAD: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 100 100">"#;

#[test]
fn svg_circle_of_radius_1e308_is_refused_within_memory() {
    let t = format!(r#"{SVG_HEAD}<circle cx="70" cy="30" r="1e308"/></svg>"#);
    optimize_is_clean("circle.svg", &t, "svg");
}

/// Found by `svg_reader_survives_mutations` at 3000 cases (case 1456: `rx` of
/// `tests/fixtures/svg/shapes.svg`'s rotated ellipse set to 2^64).
#[test]
fn svg_rotated_ellipse_of_radius_2_pow_64_is_refused_within_memory() {
    let t = format!(
        r#"{SVG_HEAD}<ellipse cx="70" cy="30" rx="18446744073709551616" ry="3" transform="rotate(30 70 30)"/></svg>"#
    );
    optimize_is_clean("ellipse.svg", &t, "svg");
}

#[test]
fn svg_50000_nested_groups_do_not_overflow_the_stack() {
    let t = format!(
        r#"{SVG_HEAD}{}<line x1="0" y1="0" x2="1" y2="1"/>{}</svg>"#,
        "<g>".repeat(50_000),
        "</g>".repeat(50_000)
    );
    optimize_is_clean("nested.svg", &t, "svg");
}

fn dxf(entities: &str) -> String {
    format!("  0\nSECTION\n  2\nENTITIES\n{entities}  0\nENDSEC\n  0\nEOF\n")
}

#[test]
fn dxf_closed_lwpolyline_without_vertices_is_refused_not_a_panic() {
    let t = dxf("  0\nLWPOLYLINE\n  8\n0\n 90\n0\n 70\n1\n");
    optimize_is_clean("empty-lw.dxf", &t, "svg");
}

#[test]
fn dxf_closed_polyline_without_vertices_is_refused_not_a_panic() {
    let t = dxf("  0\nPOLYLINE\n  8\n0\n 66\n1\n 70\n1\n  0\nSEQEND\n");
    optimize_is_clean("empty-poly.dxf", &t, "svg");
}

/// Inputs the other readers already refuse cleanly stay that way (and show the harness works).
#[test]
fn sane_rejections_stay_clean() {
    optimize_is_clean("empty.svg", "", "svg");
    optimize_is_clean("garbage.dxf", "  0\nSECTION\n  2\n", "svg");
    // coordinates beyond validation's 1e9 mm: refused, not an infinite or overflowing cost
    optimize_is_clean(
        "big.ngc",
        "G21 G90\nG0 Z5\nG0 X100000000000 Y0\nG1 Z-1 F100\nG1 X1\nG0 Z5\nM2\n",
        "ngc",
    );
}

/// A stand-in for issue 26's "2-entity temple drawing" (25.6 s; the file itself was never
/// published): one closed polyline of 100 000 vertices around one cubic spline of 20 000
/// control points. Flattening the spline rescanned its knots from the start for every sample,
/// and the containment test visited every polygon edge for every point: 131 s for
/// `-o x.ngc` before, about 2 s after. The CPU cap (30 s) is the test.
#[test]
fn dxf_of_two_long_entities_reads_and_sequences_within_the_cpu_cap() {
    let mut e = String::from("  0\nLWPOLYLINE\n  8\n0\n 90\n100000\n 70\n1\n");
    for k in 0..100_000 {
        let a = k as f64 * std::f64::consts::TAU / 100_000.0;
        let r = 100.0 + 5.0 * (41.0 * a).sin();
        e += &format!(" 10\n{:.4}\n 20\n{:.4}\n", r * a.cos(), r * a.sin());
    }
    let m = 20_000usize;
    e += &format!(
        "  0\nSPLINE\n  8\n0\n 70\n8\n 71\n3\n 72\n{}\n 73\n{m}\n",
        m + 4
    );
    e.extend((0..m + 4).map(|k| format!(" 40\n{}\n", k.saturating_sub(3).min(m - 3))));
    e.extend((0..m).map(|k| {
        let a = k as f64 * std::f64::consts::TAU / m as f64;
        format!(
            " 10\n{:.4}\n 20\n{:.4}\n 30\n0\n",
            50.0 * (2.0 * a).cos(),
            50.0 * (3.0 * a).sin()
        )
    }));
    let d = tempfile::tempdir().unwrap();
    let input = d.path().join("two.dxf");
    std::fs::write(&input, dxf(&e)).unwrap();
    let out = limited(&input, &d.path().join("out.ngc"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "exit {:?}: {err}", out.status);
}

//! The drawing pipeline on hostile and degenerate input (issue 50, item 2 and the drawing part
//! of item 4): every input is generated here, small enough to run fast, and ends in a clean
//! result or a clean refusal naming the file. The time-limit cases assert that the whole
//! command ends within the limit plus a generous margin (`MARGIN_S`; the promise and its
//! measured margin are in docs/drawings.md) — the only timed assertions.

use crate::common::{cellseq, s, stderr, write};
use cellseq::construct::greedy;
use cellseq::cost::CostModel;
use cellseq::model::{Objective, Visit};
use cellseq_programs::dxf::{self, ReadOptions as DxfOptions};
use cellseq_programs::optimize::strokes::{self as pipe, Options, blocks};
use cellseq_programs::svg::{self, ReadOptions};
use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// Seconds past `--time-limit` a command may take here: generous for a loaded machine (the
/// promise is the limit plus what writing and verifying take beyond their reserve).
const MARGIN_S: f64 = 8.0;

fn svg_doc(body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" \
         xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\" width=\"200mm\" \
         height=\"200mm\" viewBox=\"0 0 200 200\">\n{body}\n</svg>\n"
    )
}

/// A small deterministic generator of numbers in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// Runs `optimize FILE -o OUT --time-limit LIMIT`, asserts success within the limit plus
/// [`MARGIN_S`], and returns the seconds it took.
fn optimize_within(dir: &std::path::Path, input: &std::path::Path, limit: f64) -> f64 {
    let out = dir.join(format!(
        "out.{}",
        input.extension().unwrap().to_str().unwrap()
    ));
    let t0 = Instant::now();
    let o = cellseq()
        .args(["optimize", s(input), "-o", s(&out), "--time-limit"])
        .arg(limit.to_string())
        .output()
        .unwrap();
    let dt = t0.elapsed().as_secs_f64();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        dt <= limit + MARGIN_S,
        "{}: {dt:.1} s under --time-limit {limit}",
        input.display()
    );
    dt
}

#[test]
fn a_viewbox_of_fewer_than_four_numbers_is_ignored_not_a_panic() {
    for vb in ["", "none", "0 0 10", "0 0 nan 5", "0 0 1e999 1"] {
        let t = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"10mm\" viewBox=\"{vb}\">\
             <line x2=\"5\" stroke=\"black\"/></svg>"
        );
        let d = svg::read("v.svg", &t, ReadOptions::default()).unwrap();
        assert!(d.mm_per_unit.is_normal(), "viewBox '{vb}'");
        let dir = tempfile::tempdir().unwrap();
        let p = write(dir.path(), "v.svg", &t);
        let o = cellseq()
            .args(["optimize", s(&p), "-o", s(&dir.path().join("o.svg"))])
            .output()
            .unwrap();
        assert!(o.status.success(), "viewBox '{vb}': {}", stderr(&o));
    }
}

/// A DXF of the given ENTITIES section text (no header: millimetres assumed, a warning).
fn dxf_doc(entities: &str) -> String {
    format!("0\nSECTION\n2\nENTITIES\n{entities}0\nENDSEC\n0\nEOF\n")
}

#[test]
fn bad_dxf_values_are_refused_by_the_reader_with_the_file_and_the_line() {
    let line = "0\nLINE\n8\nA\n10\n0\n20\n0\n11\n10\n21\n0\n";
    let cases = [
        (
            "bulge.dxf",
            "0\nLWPOLYLINE\n8\nA\n90\n2\n70\n0\n10\n0\n20\n0\n42\nnan\n10\n10\n20\n0\n",
            "bulge NaN",
        ),
        (
            "radius.dxf",
            "0\nCIRCLE\n8\nA\n10\n5\n20\n5\n30\n0\n40\n-3\n",
            "radius -3",
        ),
        (
            "arc.dxf",
            "0\nARC\n8\nA\n10\n5\n20\n5\n30\n0\n40\n2\n50\nnan\n51\n90\n",
            "angles",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (name, bad, what) in cases {
        // the bad entity comes second: its line is 17 (after the header's 4 and the LINE's 12)
        let text = dxf_doc(&format!("{line}{bad}"));
        let e = dxf::read(name, text.as_bytes(), DxfOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.starts_with(&format!("{name}:17:")), "{e}");
        assert!(e.contains(what), "{e}");
        let p = write(dir.path(), name, &text);
        for cmd in [
            vec!["import", s(&p), "-o", s(&dir.path().join("i.json"))],
            vec!["optimize", s(&p), "-o", s(&dir.path().join("o.ngc"))],
        ] {
            let o = cellseq().args(&cmd).output().unwrap();
            let err = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{cmd:?}: {err}");
            assert!(err.contains(&format!("{name}:17:")), "{cmd:?}: {err}");
            assert!(
                !err.contains("<optimized>") && !err.contains("NaN I"),
                "{err}"
            );
        }
    }
}

#[test]
fn a_spline_of_degree_400_is_refused_before_it_is_evaluated() {
    let (deg, ncp) = (400usize, 401usize);
    let mut e = format!(
        "0\nSPLINE\n8\n0\n70\n8\n71\n{deg}\n72\n{}\n73\n{ncp}\n",
        ncp + deg + 1
    );
    for k in 0..ncp + deg + 1 {
        let _ = write!(e, "40\n{}\n", k.saturating_sub(deg).min(ncp - deg));
    }
    for i in 0..ncp {
        let _ = write!(e, "10\n{}\n20\n{}\n30\n0\n", i as f64, (i as f64).sin());
    }
    let err = dxf::read("s.dxf", dxf_doc(&e).as_bytes(), DxfOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("s.dxf:5:") && err.contains("degree 400"),
        "{err}"
    );
    // degree 3 with the same points reads
    let mut e = format!(
        "0\nSPLINE\n8\n0\n70\n8\n71\n3\n72\n{}\n73\n{ncp}\n",
        ncp + 4
    );
    for k in 0..ncp + 4 {
        let _ = write!(e, "40\n{}\n", k.saturating_sub(3).min(ncp - 3));
    }
    for i in 0..ncp {
        let _ = write!(e, "10\n{}\n20\n{}\n30\n0\n", i as f64, (i as f64).sin());
    }
    let d = dxf::read("s.dxf", dxf_doc(&e).as_bytes(), DxfOptions::default()).unwrap();
    assert_eq!(d.strokes.len(), 1);
}

#[test]
fn insert_arrays_nested_16_deep_over_empty_blocks_are_refused() {
    // B0 is empty; Bk inserts B(k-1) in an array of 100 columns: 100^16 cells in all
    let mut t = String::from("0\nSECTION\n2\nBLOCKS\n");
    t.push_str("0\nBLOCK\n8\n0\n2\nB0\n70\n0\n10\n0\n20\n0\n30\n0\n3\nB0\n0\nENDBLK\n8\n0\n");
    for k in 1..=16 {
        let _ = write!(
            t,
            "0\nBLOCK\n8\n0\n2\nB{k}\n70\n0\n10\n0\n20\n0\n30\n0\n3\nB{k}\n\
             0\nINSERT\n8\n0\n2\nB{}\n10\n0\n20\n0\n30\n0\n70\n100\n71\n1\n44\n1\n\
             0\nENDBLK\n8\n0\n",
            k - 1
        );
    }
    t.push_str("0\nENDSEC\n0\nSECTION\n2\nENTITIES\n");
    t.push_str("0\nINSERT\n8\n0\n2\nB16\n10\n0\n20\n0\n30\n0\n70\n100\n71\n1\n44\n1\n");
    t.push_str("0\nENDSEC\n0\nEOF\n");
    let e = dxf::read("n.dxf", t.as_bytes(), DxfOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("n.dxf:") && e.contains("entities"), "{e}");
}

#[test]
fn more_dxf_layers_than_the_reader_takes_are_refused_with_the_line() {
    let n = dxf::MAX_NAMES + 1;
    let mut e = String::new();
    for i in 0..n {
        let _ = write!(e, "0\nLINE\n8\nL{i}\n10\n{i}\n20\n0\n11\n{i}\n21\n1\n");
    }
    let err = dxf::read("l.dxf", dxf_doc(&e).as_bytes(), DxfOptions::default())
        .unwrap_err()
        .to_string();
    // the layer name of the last LINE
    let line = 4 + 12 * (n - 1) + 4;
    assert!(err.starts_with(&format!("l.dxf:{line}:")), "{err}");
    assert!(err.contains("layer names"), "{err}");
}

/// The scope order `inner_scopes_first` had before it was made linear: the first unplaced
/// scope with no unplaced predecessor, else (a cycle) the first unplaced one.
fn scopes_first_by_matrix(d: &svg::Drawing, sc: &[Vec<usize>], tol: f64) -> Vec<Vec<usize>> {
    let all: Vec<usize> = sc.iter().flatten().copied().collect();
    let mut scope_of = vec![0; d.strokes.len()];
    for (k, s) in sc.iter().enumerate() {
        for &i in s {
            scope_of[i] = k;
        }
    }
    let m = sc.len();
    let mut before = vec![vec![false; m]; m];
    for (a, b) in pipe::containment(d, &all, tol) {
        let (x, y) = (scope_of[all[a]], scope_of[all[b]]);
        if x != y {
            before[x][y] = true;
        }
    }
    let mut placed = vec![false; m];
    let mut out = Vec::new();
    while out.len() < m {
        let next = (0..m)
            .find(|&b| !placed[b] && (0..m).all(|a| placed[a] || a == b || !before[a][b]))
            .unwrap_or_else(|| (0..m).find(|&b| !placed[b]).unwrap());
        placed[next] = true;
        out.push(sc[next].clone());
    }
    out
}

#[test]
fn inner_scopes_first_is_the_order_of_the_matrix_rule_on_random_layers() {
    for seed in 1..=30u64 {
        let mut r = Lcg(seed);
        // squares on layers, some inside others, some crossing (cycles of containment)
        let mut e = String::new();
        for i in 0..25 {
            let (x, y, w) = (r.next() * 100.0, r.next() * 100.0, 1.0 + r.next() * 60.0);
            let layer = (r.next() * 8.0) as usize;
            let _ = write!(
                e,
                "0\nLWPOLYLINE\n8\nL{layer}\n90\n4\n70\n1\n10\n{x}\n20\n{y}\n10\n{}\n20\n{y}\n\
                 10\n{}\n20\n{}\n10\n{x}\n20\n{}\n",
                x + w,
                x + w,
                y + w,
                y + w
            );
            let _ = i;
        }
        let d = dxf::read("r.dxf", dxf_doc(&e).as_bytes(), DxfOptions::default()).unwrap();
        let sc = pipe::scopes(&d, true);
        let want = scopes_first_by_matrix(&d, &sc, 0.01);
        assert_eq!(pipe::inner_scopes_first(&d, sc, 0.01), want, "seed {seed}");
    }
}

#[test]
fn thousands_of_dxf_layers_in_cut_mode_keep_inner_layers_first() {
    // 2000 pairs of layers: an outer square, then a square inside it on the next layer;
    // inner-first puts each inner layer before its outer one and keeps the rest in order
    let n = 2000;
    let mut e = String::new();
    let square = |e: &mut String, layer: &str, x: f64, y: f64, w: f64| {
        let _ = write!(
            e,
            "0\nLWPOLYLINE\n8\n{layer}\n90\n4\n70\n1\n10\n{x}\n20\n{y}\n10\n{}\n20\n{y}\n\
             10\n{}\n20\n{}\n10\n{x}\n20\n{}\n",
            x + w,
            x + w,
            y + w,
            y + w
        );
    };
    for k in 0..n {
        let (x, y) = ((k % 50) as f64 * 10.0, (k / 50) as f64 * 10.0);
        square(&mut e, &format!("O{k}"), x, y, 8.0);
        square(&mut e, &format!("I{k}"), x + 2.0, y + 2.0, 4.0);
    }
    let d = dxf::read("c.dxf", dxf_doc(&e).as_bytes(), DxfOptions::default()).unwrap();
    let sc = pipe::inner_scopes_first(&d, pipe::scopes(&d, true), 0.01);
    let names: Vec<&str> = sc
        .iter()
        .map(|s| d.layers[d.strokes[s[0]].layer].label.as_str())
        .collect();
    let want: Vec<String> = (0..n)
        .flat_map(|k| [format!("I{k}"), format!("O{k}")])
        .collect();
    assert_eq!(names, want);
    let out = pipe::optimize(
        &d,
        &Options {
            cut: true,
            max_evals: Some(200_000),
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!(out.scopes, 2 * n);
    let first = d.layers[out.strokes[0].layer].label.as_str();
    assert_eq!(first, "I0");
}

#[test]
fn a_hundred_thousand_styles_are_read_and_written_back() {
    let mut body = String::new();
    for i in 0..100_000 {
        let _ = writeln!(
            body,
            "<path d=\"M{},{} l1,1\" stroke=\"#{:06x}\" stroke-width=\"0.{}\"/>",
            i % 200,
            i / 1000,
            i,
            i + 1
        );
    }
    let d = svg::read("st.svg", &svg_doc(&body), ReadOptions::default()).unwrap();
    assert_eq!(d.styles.len(), 100_000);
    let w = svg::write(&d, &d.strokes);
    assert_eq!(svg::verify(&d, "w.svg", &w).unwrap(), 100_000);
}

/// Greedy by a scan of every ready (cell, mode): the least (cost, node), as the k-d tree
/// version must choose it.
fn greedy_by_scan(m: &CostModel) -> Vec<Visit> {
    let n = m.n();
    let mut done = vec![false; n];
    let mut seq: Vec<Visit> = Vec::new();
    while seq.len() < n {
        let mut best = (f64::INFINITY, usize::MAX);
        for c in (0..n).filter(|&c| !done[c]) {
            for md in 0..m.modes(c) {
                let cost = match seq.last() {
                    None => m.start(c, md),
                    Some(p) => m.arc(p.cell, p.mode, c, md),
                };
                let nd = m.node(c, md);
                if cost < best.0 || (cost == best.0 && nd < best.1) {
                    best = (cost, nd);
                }
            }
        }
        let (c, md) = m.cell_mode(best.1);
        done[c] = true;
        seq.push(Visit::new(c, md));
    }
    seq
}

#[test]
fn greedy_on_coincident_strokes_is_the_scan_s_choice() {
    // 300 strokes on 7 distinct segments (many coincident), and a few free ones
    let mut r = Lcg(7);
    let segs: Vec<(f64, f64, f64, f64)> = (0..7)
        .map(|_| {
            (
                r.next() * 50.0,
                r.next() * 50.0,
                r.next() * 50.0,
                r.next() * 50.0,
            )
        })
        .collect();
    let mut body = String::new();
    for i in 0..300 {
        let (a, b, c, d) = if i % 10 == 9 {
            (
                r.next() * 50.0,
                r.next() * 50.0,
                r.next() * 50.0,
                r.next() * 50.0,
            )
        } else {
            segs[i % 7]
        };
        let _ = writeln!(body, "<path d=\"M{a},{b} L{c},{d}\" stroke=\"black\"/>");
    }
    let d = svg::read("g.svg", &svg_doc(&body), ReadOptions::default()).unwrap();
    let sc: Vec<usize> = (0..d.strokes.len()).collect();
    let (inst, _) = pipe::scope_instance(&d, &sc, [0.0, 0.0], &Options::default());
    let m = CostModel::new(&inst, Objective::Air);
    let got = greedy::geometric(&m, &mut |_| {});
    assert_eq!(got, greedy_by_scan(&m));
}

#[test]
fn forty_thousand_coincident_strokes_end_within_the_time_limit() {
    let body = "<path d=\"M10,10 L20,20\" stroke=\"black\"/>\n".repeat(40_000);
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "co.svg", &svg_doc(&body));
    optimize_within(dir.path(), &p, 2.0);
}

#[test]
fn a_hundred_thousand_sub_paths_end_within_the_time_limit() {
    let mut r = Lcg(3);
    let mut d = String::new();
    for _ in 0..100_000 {
        let _ = write!(d, "M{:.3},{:.3} l1,1 ", r.next() * 200.0, r.next() * 200.0);
    }
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "sp.svg",
        &svg_doc(&format!("<path d=\"{d}\" stroke=\"black\"/>")),
    );
    optimize_within(dir.path(), &p, 2.0);
}

#[test]
fn a_thousand_top_level_groups_end_within_the_time_limit() {
    let mut r = Lcg(5);
    let mut body = String::new();
    for g in 0..1000 {
        let _ = write!(body, "<g id=\"p-{g}\">");
        for _ in 0..5 {
            let _ = write!(
                body,
                "<path d=\"M{:.3},{:.3} l{:.3},{:.3}\" stroke=\"black\"/>",
                r.next() * 200.0,
                r.next() * 200.0,
                r.next() * 6.0 - 3.0,
                r.next() * 6.0 - 3.0
            );
        }
        body.push_str("</g>\n");
    }
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "g.svg", &svg_doc(&body));
    optimize_within(dir.path(), &p, 2.0);
}

#[test]
fn block_order_of_many_blocks_is_a_permutation_never_worse_and_stops_at_a_deadline() {
    let mut r = Lcg(11);
    let b: Vec<([f64; 2], [f64; 2])> = (0..20_000)
        .map(|_| {
            let p = [r.next() * 1000.0, r.next() * 1000.0];
            (p, [p[0] + r.next(), p[1] + r.next()])
        })
        .collect();
    let file: Vec<usize> = (0..b.len()).collect();
    let o = blocks::order([0.0, 0.0], &b, None);
    let mut sorted = o.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, file);
    let (t_file, t_new) = (
        blocks::travel([0.0, 0.0], &b, &file, None),
        blocks::travel([0.0, 0.0], &b, &o, None),
    );
    // random blocks: far shorter than the file's order
    assert!(t_new < 0.2 * t_file, "{t_new} vs {t_file}");
    // a deadline already passed: the file's order, at once
    let past = Instant::now() - Duration::from_millis(1);
    assert_eq!(blocks::order_until([0.0, 0.0], &b, None, Some(past)), file);
    // coincident blocks: every one at the same point
    let same = vec![([5.0, 5.0], [5.0, 5.0]); 20_000];
    let o = blocks::order([0.0, 0.0], &same, None);
    assert_eq!(o.len(), 20_000);
}

#[test]
fn twenty_thousand_nested_groups_with_kept_elements_stay_linear() {
    let n = 20_000;
    let mut body = String::new();
    for _ in 0..n {
        body.push_str("<g transform=\"translate(0.001,0)\"><text>t</text>");
    }
    body.push_str("<path d=\"M0,0 L1,1\" stroke=\"black\"/>");
    body.push_str(&"</g>".repeat(n));
    let text = svg_doc(&body);
    let d = svg::read("k.svg", &text, ReadOptions::default()).unwrap();
    assert_eq!(d.kept.len(), n);
    let out = pipe::optimize(&d, &Options::default()).unwrap();
    let w = svg::write(&d, &out.strokes);
    // each group is written once around the texts below it: linear, not n²/2 wrappers
    assert!(
        w.len() < 3 * text.len(),
        "{} bytes from {}",
        w.len(),
        text.len()
    );
    assert_eq!(svg::verify(&d, "w.svg", &w).unwrap(), 1);
    // a kept element lost on the way is still caught
    let mut lost = d.clone();
    lost.kept.pop();
    assert!(svg::verify(&d, "w.svg", &svg::write(&lost, &out.strokes)).is_err());
}

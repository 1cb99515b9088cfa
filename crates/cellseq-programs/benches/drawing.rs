//! Growth of the drawing pipeline (issue 50, item 2): reading, sequencing, writing and
//! verifying SVG drawings of 10^3, 10^4 and 10^5 strokes, top-level groups, Inkscape layers
//! (in cut mode: inner layers first) and stroke styles. Each drawing is generated here; the
//! solver gets an evaluation budget proportional to the drawing, so what is measured is how
//! the pipeline around it grows (linear or n log n: each step 10× the size should take about
//! 10× the time). Numbers and the command in notes/svg.md.
//!
//! `cargo bench --bench drawing` (one group: `cargo bench --bench drawing -- groups`).

use cellseq_programs::optimize::strokes::{self as pipe, Blocks, Options, Pens};
use cellseq_programs::svg::{self, ReadOptions};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::fmt::Write as _;
use std::hint::black_box;

const SIZES: [usize; 3] = [1_000, 10_000, 100_000];

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

fn doc(body: &str) -> String {
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" \
         xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\" width=\"500mm\" \
         height=\"500mm\" viewBox=\"0 0 500 500\">\n{body}</svg>\n"
    )
}

/// `n` short strokes scattered over the page, one colour, no groups.
fn strokes(n: usize) -> String {
    let mut r = Lcg(1);
    let mut b = String::new();
    for _ in 0..n {
        let (x, y) = (r.next() * 500.0, r.next() * 500.0);
        let _ = writeln!(
            b,
            "<path d=\"M{x:.3},{y:.3} l{:.3},{:.3}\" stroke=\"black\"/>",
            r.next() * 4.0 - 2.0,
            r.next() * 4.0 - 2.0
        );
    }
    doc(&b)
}

/// `n` plain top-level groups (parts) of 2 strokes each.
fn groups(n: usize) -> String {
    let mut r = Lcg(2);
    let mut b = String::new();
    for g in 0..n {
        let (x, y) = (r.next() * 500.0, r.next() * 500.0);
        let _ = writeln!(
            b,
            "<g id=\"p-{g}\"><path d=\"M{x:.3},{y:.3} l1,0\" stroke=\"black\"/>\
             <path d=\"M{x:.3},{:.3} l1,0\" stroke=\"blue\"/></g>",
            y + 1.0
        );
    }
    doc(&b)
}

/// `n` Inkscape layers in pairs: a square, then a smaller square inside it on the next layer
/// (cut mode puts each inner layer first).
fn layers(n: usize) -> String {
    let mut b = String::new();
    for k in 0..n / 2 {
        let (x, y) = ((k % 400) as f64 * 1.2, (k / 400) as f64 * 1.2);
        for (j, (d, w)) in [(0.0, 1.0), (0.25, 0.5)].into_iter().enumerate() {
            let _ = writeln!(
                b,
                "<g inkscape:groupmode=\"layer\" id=\"l{k}-{j}\"><rect x=\"{:.3}\" y=\"{:.3}\" \
                 width=\"{w}\" height=\"{w}\" stroke=\"black\" fill=\"none\"/></g>",
                x + d,
                y + d
            );
        }
    }
    doc(&b)
}

/// `n` strokes, each of its own colour and width.
fn styles(n: usize) -> String {
    let mut r = Lcg(4);
    let mut b = String::new();
    for i in 0..n {
        let (x, y) = (r.next() * 500.0, r.next() * 500.0);
        let _ = writeln!(
            b,
            "<path d=\"M{x:.3},{y:.3} l1,1\" stroke=\"#{:06x}\" stroke-width=\"{}\"/>",
            i * 97 % 0x100_0000,
            0.1 + i as f64 * 1e-6
        );
    }
    doc(&b)
}

/// Reads `text`, sequences it with `opts` (20 evaluations per stroke), writes and verifies.
fn pipeline(text: &str, opts: &Options) -> usize {
    let d = svg::read("bench.svg", text, ReadOptions::default()).expect("reads");
    let opts = Options {
        max_evals: Some(20 * d.strokes.len() as u64),
        ..opts.clone()
    };
    let mut out = pipe::optimize(&d, &opts).expect("sequences");
    let (_, segments) = pipe::render(&d, &mut out, pipe::Output::Svg).expect("verifies");
    segments
}

/// A family of drawings: its name, its maker by size, and the options it runs with.
type Case = (&'static str, fn(usize) -> String, Options);

fn growth(c: &mut Criterion) {
    let cases: [Case; 4] = [
        ("strokes", strokes, Options::default()),
        (
            "groups",
            groups,
            Options {
                pens: Pens::Colour,
                blocks: Blocks::Group,
                ..Options::default()
            },
        ),
        (
            "layers_cut",
            layers,
            Options {
                cut: true,
                ..Options::default()
            },
        ),
        ("styles", styles, Options::default()),
    ];
    for (name, make, opts) in cases {
        let mut g = c.benchmark_group(name);
        g.sample_size(10);
        for n in SIZES {
            let text = make(n);
            g.bench_with_input(BenchmarkId::from_parameter(n), &text, |b, t| {
                b.iter(|| pipeline(black_box(t), &opts))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, growth);
criterion_main!(benches);

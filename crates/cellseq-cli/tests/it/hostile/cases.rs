//! The hostile-input generator: seeded cases made from the repository's own files (instances,
//! fixtures, plans, the portfolio, tool library) by one hostile transformation each. The same
//! seed gives the same cases on every machine.
//!
//! Categories: numbers at the type limits, NaN and infinities, truncation at a section (or a
//! random byte), non-UTF-8 bytes, byte-order marks (UTF-8, UTF-16), NUL bytes, deep nesting
//! (JSON and TOML 10⁵ deep, SVG groups), XML entity bombs and external entities, DXF INSERT
//! cycles and huge INSERT arrays, hostile values of the fields a reader computes with (a
//! viewBox of fewer than four numbers, a NaN bulge, a negative radius, a spline of degree 400,
//! G92 and incremental moves of 10^300), seeded mutations (byte flips, duplicated, deleted and
//! swapped lines, repeated chunks), empty and blank files, one very long line or number, CR
//! and CRLF line ends, and special files (a link to `/dev/zero`, a directory).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::Path;

/// What a file is: it decides which commands read it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Kind {
    /// TSPLIB SOP instance.
    Sop,
    /// PCGLNS instance.
    Pcglns,
    /// PCGTSP instance.
    Pcgtsp,
    /// `cellseq-instance/1` JSON.
    Json,
    /// `cellseq-solution/1` JSON (of the seed instance `ESC07.sop`).
    Solution,
    /// Experiment plan.
    Plan,
    /// `auto` portfolio file.
    Portfolio,
    /// G-code program.
    Gcode,
    /// SVG drawing.
    Svg,
    /// DXF drawing.
    Dxf,
    /// Tool library of the `panel` generator.
    Tools,
    /// `bks.csv` beside `ESC07.sop`.
    Bks,
}

impl Kind {
    /// Every kind.
    pub const ALL: [Kind; 12] = [
        Kind::Sop,
        Kind::Pcglns,
        Kind::Pcgtsp,
        Kind::Json,
        Kind::Solution,
        Kind::Plan,
        Kind::Portfolio,
        Kind::Gcode,
        Kind::Svg,
        Kind::Dxf,
        Kind::Tools,
        Kind::Bks,
    ];

    /// The seed files of this kind, relative to the repository root.
    pub fn seeds(self) -> &'static [&'static str] {
        match self {
            Kind::Sop => &[
                "instances/tsplib-sop/ESC07.sop",
                "instances/tsplib-sop/br17.10.sop",
            ],
            Kind::Pcglns => &["instances/pcgtsplib/ESC07.pcglns"],
            Kind::Pcgtsp => &["tests/fixtures/pcgtsp/ESC07.pcgtsp"],
            Kind::Json => &[
                "instances/generated/panel-20.json",
                "instances/generated/cabin-20.json",
                "fuzz/seeds/json/closed-tour.json",
                "fuzz/seeds/json/matrix-first-last.json",
            ],
            Kind::Solution => &[],
            Kind::Plan => &["experiments/demo.toml"],
            Kind::Portfolio => &["crates/cellseq/src/solvers/auto/portfolio.toml"],
            Kind::Gcode => &[
                "tests/fixtures/gcode/mill.ngc",
                "tests/fixtures/gcode/arcs_inch.ngc",
                "tests/fixtures/gcode/laser.gcode",
                "tests/fixtures/gcode/grbl_dialect.nc",
            ],
            Kind::Svg => &[
                "tests/fixtures/svg/shapes.svg",
                "tests/fixtures/svg/vpype_multilayer_3layers.svg",
            ],
            Kind::Dxf => &["fuzz/seeds/dxf/shapes.dxf"],
            Kind::Tools => &["crates/cellseq/src/generate/default-tools.toml"],
            Kind::Bks => &[],
        }
    }

    /// The file name a case of this kind is written under.
    pub fn file_name(self, seed: &str) -> String {
        let stem = Path::new(seed)
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("input");
        match self {
            Kind::Solution => "solution.json".into(),
            Kind::Bks => "bks.csv".into(),
            Kind::Plan => "plan.toml".into(),
            _ => stem.to_string(),
        }
    }
}

/// One hostile input: a file of some kind, made from a seed by one transformation.
#[derive(Debug, Clone)]
pub struct Case {
    /// `kind/seed/category-number`, unique.
    pub id: String,
    /// The category of hostility.
    pub category: &'static str,
    /// What the file is.
    pub kind: Kind,
    /// The seed file it was made from (relative to the repository), or what it was made of.
    pub seed: String,
    /// Its file name.
    pub name: String,
    /// Its bytes (unused for special files).
    pub bytes: Vec<u8>,
    /// A special file instead of `bytes`: `zero` (a link to `/dev/zero`) or `dir`.
    pub special: Option<&'static str>,
}

/// The text of the plan every plan case starts from: small, fast solvers only, so a mutated
/// plan cannot ask for hours of legitimate work.
pub const PLAN: &str = r#"name = "hostile"
seed = 1
replicates = 2
reference = "greedy"

[budget]
evaluations = 20000
seconds = 2

[[instances]]
generator = "uniform"
seeds = [1, 2]
grid = { n = [8, 12], tools = 2, density = 0.05 }

[[instances]]
generator = "panel"
grid = { rows = 1, cols = 2 }

[[solvers]]
name = "greedy"

[[solvers]]
name = "insertion"
params = { k = 4 }

[max_cells]
insertion = 50
"#;

/// The `bks.csv` every bks case starts from (beside `ESC07.sop`).
pub const BKS: &str = "name,best_known,proven_optimal\nESC07,2125,true\nESC12,1675,true\n";

/// Seed bytes of `kind` (`root` is the repository), with the seed's name.
pub fn seed_bytes(root: &Path, kind: Kind, rng: &mut ChaCha8Rng) -> (String, Vec<u8>) {
    match kind {
        Kind::Plan => ("plan.toml".into(), PLAN.as_bytes().to_vec()),
        Kind::Bks => ("bks.csv".into(), BKS.as_bytes().to_vec()),
        Kind::Solution => ("panel-20-solution.json".into(), Vec::new()),
        _ => {
            let seeds = kind.seeds();
            let s = seeds[rng.random_range(0..seeds.len())];
            let bytes = std::fs::read(root.join(s)).unwrap_or_else(|e| panic!("{s}: {e}"));
            (s.to_string(), bytes)
        }
    }
}

/// Numbers at the limits of the types a reader might parse them into.
const LIMITS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "255",
    "256",
    "65535",
    "65536",
    "2147483647",
    "2147483648",
    "-2147483649",
    "4294967295",
    "4294967296",
    "9007199254740993",
    "9223372036854775807",
    "9223372036854775808",
    "-9223372036854775809",
    "18446744073709551615",
    "18446744073709551616",
    "340282366920938463463374607431768211456",
    "1.7976931348623157e308",
    "-1.7976931348623157e308",
    "1e308",
    "1e300",
    "-1e300",
    "2.2250738585072014e-308",
    "5e-324",
    "1e-320",
    "0.000000000000000000000000000001",
    // 1e308 and -1e300 spelled out, for readers (G-code) where an exponent is a word of its own
    concat!(
        "1",
        "000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000"
    ),
    "-1000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000",
];

/// Hostile values of the fields a reader interprets, per kind: a viewBox of fewer than four
/// numbers, a zero scale, a NaN bulge, a negative radius, a spline of degree 400, a dwell of
/// 10^300 s, a zero-radius arc, a peck of 0 (the places where a reader computes, not just
/// parses). Each is inserted where the file has such a field, or appended in the file's
/// syntax.
fn fields(kind: Kind, b: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let text = String::from_utf8_lossy(b).into_owned();
    let pick = |v: &[&str], rng: &mut ChaCha8Rng| v[rng.random_range(0..v.len())].to_string();
    match kind {
        Kind::Svg => {
            let attr = pick(
                &[
                    "viewBox=\"\"",
                    "viewBox=\"none\"",
                    "viewBox=\"0 0\"",
                    "viewBox=\"0 0 0 0\"",
                    "viewBox=\"0 0 -1 -1\"",
                    "viewBox=\"nan nan nan nan\"",
                    "width=\"0\" height=\"1e308mm\"",
                    "transform=\"scale(1e308)\"",
                    "transform=\"scale(0)\"",
                    "transform=\"matrix(0 0 0 0 0 0)\"",
                    "transform=\"rotate(nan)\"",
                ],
                rng,
            );
            let shape = pick(
                &[
                    "<path d=\"M0 0 A0 0 0 1 1 10 10\"/>",
                    "<path d=\"M0 0 A1e308 1e308 0 1 1 10 10\"/>",
                    "<circle cx=\"0\" cy=\"0\" r=\"-5\"/>",
                    "<rect x=\"0\" y=\"0\" width=\"-1\" height=\"1e308\" rx=\"nan\"/>",
                    "<polyline points=\"0,0 1e308,1e308 -1e308,0\"/>",
                    "<path d=\"M0 0 C 1e308 0 0 1e308 1 1 Z\"/>",
                ],
                rng,
            );
            let with_attr = text.replacen("<svg", &format!("<svg {attr}"), 1);
            match with_attr.rfind("</svg>") {
                Some(i) if rng.random_bool(0.5) => {
                    format!("{}{shape}{}", &with_attr[..i], &with_attr[i..]).into_bytes()
                }
                _ => with_attr.into_bytes(),
            }
        }
        Kind::Dxf => {
            let entity = pick(
                &[
                    "  0\nLWPOLYLINE\n  8\n0\n 90\n2\n 70\n0\n 10\n0\n 20\n0\n 42\nnan\n 10\n10\n 20\n0\n",
                    "  0\nLWPOLYLINE\n  8\n0\n 90\n2\n 70\n1\n 10\n0\n 20\n0\n 42\n1e308\n 10\n10\n 20\n0\n",
                    "  0\nCIRCLE\n  8\n0\n 10\n0\n 20\n0\n 40\n-5\n",
                    "  0\nCIRCLE\n  8\n0\n 10\n0\n 20\n0\n 40\n1e300\n",
                    "  0\nARC\n  8\n0\n 10\n0\n 20\n0\n 40\n5\n 50\nnan\n 51\n90\n",
                    "  0\nELLIPSE\n  8\n0\n 10\n0\n 20\n0\n 11\n0\n 21\n0\n 40\n0\n 41\n0\n 42\n6.28\n",
                    "  0\nSPLINE\n  8\n0\n 71\n400\n 72\n2\n 40\n0\n 40\n1\n 73\n2\n 10\n0\n 20\n0\n 10\n1\n 20\n1\n",
                    "  0\nLWPOLYLINE\n  8\n0\n 90\n4000000000\n 70\n0\n 10\n0\n 20\n0\n",
                ],
                rng,
            );
            match text.find("ENTITIES\n") {
                Some(i) => format!("{}{entity}{}", &text[..i + 9], &text[i + 9..]).into_bytes(),
                None => format!("  0\nSECTION\n  2\nENTITIES\n{entity}  0\nENDSEC\n  0\nEOF\n")
                    .into_bytes(),
            }
        }
        Kind::Gcode => {
            let line = pick(
                &[
                    "G92 X1000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000000\n",
                    "G91\nG1 X100000000000000000000000000000000000000000000000000 F100\nG1 X100000000000000000000000000000000000000000000000000\nG90\n",
                    "G1 Z-1 F0\n",
                    "G4 P1000000000000000000000000000000000000000000000000000000000000\n",
                    "G2 X10 Y0 I0 J0 F100\n",
                    "G2 X0 Y0 R0 F100\n",
                    "G83 X5 Y5 Z-10 R2 Q0 F100\nG80\n",
                    "G73 X5 Y5 Z-10 R2 Q-1 F100\nG80\n",
                    "G81 X5 Y5 Z-1000000000000000000000000000000 R2 F100\nG80\n",
                    "S100000000000000000000000000000000000000000000 M3\n",
                    "G1 X0.000000000000000000000000000000000000000001 F100\n",
                    "N99999999999999999999999 G0 X1\n",
                ],
                rng,
            );
            let lines: Vec<&str> = text.split_inclusive('\n').collect();
            let at = rng.random_range(0..=lines.len());
            let mut out = lines[..at].concat();
            out.push_str(&line);
            out.push_str(&lines[at..].concat());
            out.into_bytes()
        }
        _ => replace_numbers(b, LIMITS, rng),
    }
}

/// Non-finite spellings.
const NON_FINITE: &[&str] = &[
    "NaN",
    "nan",
    "-nan",
    "inf",
    "-inf",
    "+inf",
    "Infinity",
    "-Infinity",
    "1e999",
    "-1e999",
];

/// The byte spans of the numbers in `b`: digit runs with an optional sign, fraction and
/// exponent (also inside G-code words and SVG path data: `X10`, `M10,20`).
fn numbers(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts =
            b[i].is_ascii_digit() && (i == 0 || !(b[i - 1].is_ascii_digit() || b[i - 1] == b'.'));
        if !starts {
            i += 1;
            continue;
        }
        let start = if i > 0 && b[i - 1] == b'-' { i - 1 } else { i };
        while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
            i += 1;
        }
        if i + 1 < b.len()
            && (b[i] == b'e' || b[i] == b'E')
            && (b[i + 1].is_ascii_digit() || b[i + 1] == b'-')
        {
            i += 2;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
        out.push((start, i));
    }
    out
}

/// `b` with the span `(s, e)` replaced by `with`.
fn splice(b: &[u8], (s, e): (usize, usize), with: &[u8]) -> Vec<u8> {
    let mut out = b[..s].to_vec();
    out.extend_from_slice(with);
    out.extend_from_slice(&b[e..]);
    out
}

/// Replaces one to three numbers of `b` by values drawn from `pool`.
fn replace_numbers(b: &[u8], pool: &[&str], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut out = b.to_vec();
    for _ in 0..rng.random_range(1..=3) {
        let spans = numbers(&out);
        if spans.is_empty() {
            break;
        }
        let span = spans[rng.random_range(0..spans.len())];
        let v = pool[rng.random_range(0..pool.len())];
        out = splice(&out, span, v.as_bytes());
    }
    out
}

/// The places a file of `kind` changes section: where a truncation is most telling.
fn section_marks(kind: Kind) -> &'static [&'static str] {
    match kind {
        Kind::Sop | Kind::Pcglns | Kind::Pcgtsp => &[
            "DIMENSION",
            "EDGE_WEIGHT_SECTION",
            "GTSP_SETS",
            "GTSP_SET_SECTION",
            "EOF",
            "TYPE",
        ],
        Kind::Json | Kind::Solution => &[
            "\"cells\"",
            "\"modes\"",
            "\"precedence\"",
            "\"matrix\"",
            "\"machine\"",
            "\"sequence\"",
            "\"tools\"",
            "{",
            "[",
        ],
        Kind::Plan | Kind::Portfolio | Kind::Tools => &["[[", "[", "=", "\n"],
        Kind::Gcode => &["\nG", "\nM", "\nT", "("],
        Kind::Svg => &["<g", "<path", "<rect", "<circle", " d=\"", "viewBox", "</"],
        Kind::Dxf => &[
            "SECTION",
            "ENTITIES",
            "ENDSEC",
            "LWPOLYLINE",
            "VERTEX",
            "ARC",
            "EOF",
        ],
        Kind::Bks => &["\n", ","],
    }
}

/// `b` cut at a section mark (or, one time in four, at a random byte).
fn truncate(b: &[u8], kind: Kind, rng: &mut ChaCha8Rng) -> Vec<u8> {
    let marks: Vec<usize> = section_marks(kind)
        .iter()
        .flat_map(|m| {
            let m = m.as_bytes();
            (0..b.len().saturating_sub(m.len())).filter(move |&i| &b[i..i + m.len()] == m)
        })
        .collect();
    let at = if marks.is_empty() || rng.random_range(0..4) == 0 {
        rng.random_range(0..=b.len())
    } else {
        let m = marks[rng.random_range(0..marks.len())];
        // at the mark, or a few bytes into it
        (m + rng.random_range(0..4)).min(b.len())
    };
    b[..at].to_vec()
}

/// Inserts `what` at a random position of `b`.
fn insert_at_random(b: &[u8], what: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let at = rng.random_range(0..=b.len());
    splice(b, (at, at), what)
}

/// `b` as UTF-16 with a byte-order mark (little or big endian).
fn utf16(b: &[u8], big: bool) -> Vec<u8> {
    let text = String::from_utf8_lossy(b);
    let mut out = if big {
        vec![0xFE, 0xFF]
    } else {
        vec![0xFF, 0xFE]
    };
    for u in text.encode_utf16() {
        let [hi, lo] = u.to_be_bytes();
        if big {
            out.extend([hi, lo]);
        } else {
            out.extend([lo, hi]);
        }
    }
    out
}

/// Deep nesting of the file's own syntax, `depth` levels.
fn nesting(kind: Kind, b: &[u8], depth: usize, rng: &mut ChaCha8Rng) -> Vec<u8> {
    match kind {
        Kind::Json | Kind::Solution => {
            let deep = format!("{}{}", "[".repeat(depth), "]".repeat(depth));
            // as the value of a key, or as the whole file
            let text = String::from_utf8_lossy(b);
            match text.find(':') {
                Some(i) if rng.random_bool(0.7) => {
                    format!("{}: {deep},{}", &text[..i], &text[i + 1..]).into_bytes()
                }
                _ => deep.into_bytes(),
            }
        }
        Kind::Plan | Kind::Portfolio | Kind::Tools => {
            let deep = if rng.random_bool(0.5) {
                format!("x = {}1{}\n", "[".repeat(depth), "]".repeat(depth))
            } else {
                format!("x = {}1{}\n", "{ a = ".repeat(depth), " }".repeat(depth))
            };
            let mut out = deep.into_bytes();
            out.extend_from_slice(b);
            out
        }
        Kind::Svg => {
            let text = String::from_utf8_lossy(b);
            let inner = format!(
                "{}<line x1=\"0\" y1=\"0\" x2=\"5\" y2=\"5\"/>{}",
                "<g>".repeat(depth),
                "</g>".repeat(depth)
            );
            match text.rfind("</svg>") {
                Some(i) => format!("{}{inner}{}", &text[..i], &text[i..]).into_bytes(),
                None => inner.into_bytes(),
            }
        }
        _ => {
            // a line of brackets and parentheses: no nesting syntax of its own
            let mut out = b.to_vec();
            out.extend("(".repeat(depth).as_bytes());
            out.extend(b"\n");
            out
        }
    }
}

/// XML attacks on an SVG: an entity bomb, an external entity, a parameter entity.
fn xml_attack(b: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let text = String::from_utf8_lossy(b);
    let body = text.find("<svg").map_or(&text[..], |i| &text[i..]);
    let doctype = match rng.random_range(0..4) {
        0 => {
            let mut d = String::from("<!DOCTYPE svg [\n<!ENTITY a0 \"lol\">\n");
            for i in 1..10 {
                let p = i - 1;
                d.push_str(&format!(
                    "<!ENTITY a{i} \"&a{p};&a{p};&a{p};&a{p};&a{p};&a{p};&a{p};&a{p};&a{p};&a{p};\">\n"
                ));
            }
            d.push_str("]>\n");
            d
        }
        1 => "<!DOCTYPE svg [<!ENTITY x SYSTEM \"file:///etc/passwd\">]>\n".into(),
        2 => "<!DOCTYPE svg [<!ENTITY % p SYSTEM \"http://127.0.0.1:9/x.dtd\"> %p;]>\n".into(),
        _ => "<!DOCTYPE svg SYSTEM \"http://127.0.0.1:9/svg.dtd\">\n".into(),
    };
    let use_it = ["&a9;", "&x;", "", ""][rng.random_range(0..4)];
    let body = body.replacen("<svg", &format!("<svg data-x=\"{use_it}\""), 1);
    format!("<?xml version=\"1.0\"?>\n{doctype}{body}").into_bytes()
}

/// DXF blocks that insert each other (a cycle), or an INSERT array of huge counts.
fn dxf_insert(rng: &mut ChaCha8Rng) -> Vec<u8> {
    let ins = |block: &str, rows: &str, cols: &str| {
        format!(
            "  0\nINSERT\n  8\n0\n  2\n{block}\n 10\n0\n 20\n0\n 70\n{cols}\n 71\n{rows}\n 44\n10\n 45\n10\n"
        )
    };
    let block = |name: &str, body: &str| {
        format!("  0\nBLOCK\n  8\n0\n  2\n{name}\n 70\n0\n 10\n0\n 20\n0\n{body}  0\nENDBLK\n")
    };
    let line = "  0\nLINE\n  8\n0\n 10\n0\n 20\n0\n 11\n1\n 21\n1\n";
    let (blocks, entities) = match rng.random_range(0..4) {
        0 => (block("A", &ins("A", "1", "1")), ins("A", "1", "1")),
        1 => (
            block("A", &format!("{line}{}", ins("B", "1", "1"))) + &block("B", &ins("A", "1", "1")),
            ins("A", "1", "1"),
        ),
        2 => (block("A", line), ins("A", "30000", "30000")),
        _ => (
            block("A", &ins("B", "100", "100"))
                + &block("B", &ins("C", "100", "100"))
                + &block("C", line),
            ins("A", "100", "100"),
        ),
    };
    format!(
        "  0\nSECTION\n  2\nBLOCKS\n{blocks}  0\nENDSEC\n  0\nSECTION\n  2\nENTITIES\n{entities}  0\nENDSEC\n  0\nEOF\n"
    )
    .into_bytes()
}

/// One seeded mutation of the kind `tests/mutations.rs` makes: a byte flip, a duplicated,
/// deleted or swapped line, or a repeated chunk.
fn mutate(b: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut out = b.to_vec();
    if out.is_empty() {
        return out;
    }
    let lines: Vec<&[u8]> = b.split_inclusive(|&c| c == b'\n').collect();
    match rng.random_range(0..5) {
        0 => {
            for _ in 0..rng.random_range(1..8) {
                let i = rng.random_range(0..out.len());
                out[i] ^= 1 << rng.random_range(0..8);
            }
            out
        }
        1..=3 if lines.len() > 1 => {
            let (i, j) = (
                rng.random_range(0..lines.len()),
                rng.random_range(0..lines.len()),
            );
            let mut ls: Vec<&[u8]> = lines.clone();
            match rng.random_range(0..3) {
                0 => ls.insert(i, lines[i]),
                1 => {
                    ls.remove(i);
                }
                _ => ls.swap(i, j),
            }
            ls.concat()
        }
        _ => {
            let s = rng.random_range(0..out.len());
            let e = (s + rng.random_range(1..200)).min(out.len());
            let chunk = out[s..e].to_vec();
            let times = rng.random_range(2..200);
            let mut rep = Vec::new();
            for _ in 0..times {
                rep.extend_from_slice(&chunk);
            }
            splice(&out, (s, e), &rep)
        }
    }
}

/// Every category; each case gets one.
pub const CATEGORIES: &[&str] = &[
    "limits",
    "fields",
    "nonfinite",
    "truncate",
    "nonutf8",
    "bom",
    "nul",
    "nesting",
    "xml",
    "dxf-insert",
    "mutate",
    "empty",
    "longline",
    "line-ends",
    "special",
];

/// Applies `category` to seed `b` of `kind`; none when the category does not apply to it.
fn apply(
    category: &'static str,
    kind: Kind,
    b: &[u8],
    rng: &mut ChaCha8Rng,
) -> Option<(Vec<u8>, Option<&'static str>)> {
    let bytes = match category {
        "limits" => replace_numbers(b, LIMITS, rng),
        "fields" => fields(kind, b, rng),
        "nonfinite" => replace_numbers(b, NON_FINITE, rng),
        "truncate" => truncate(b, kind, rng),
        "nonutf8" => {
            let bad: &[&[u8]] = &[b"\xff", b"\xc3", b"\xc0\x80", b"\xed\xa0\x80", b"\xe9t\xe9"];
            insert_at_random(b, bad[rng.random_range(0..bad.len())], rng)
        }
        "bom" => match rng.random_range(0..3) {
            0 => [b"\xef\xbb\xbf".as_slice(), b].concat(),
            n => utf16(b, n == 2),
        },
        "nul" => insert_at_random(b, &b"\0".repeat(rng.random_range(1..4)), rng),
        "nesting" => {
            let depth = [1_000, 100_000][rng.random_range(0..2)];
            nesting(kind, b, depth, rng)
        }
        "xml" if kind == Kind::Svg => xml_attack(b, rng),
        "dxf-insert" if kind == Kind::Dxf => dxf_insert(rng),
        "xml" | "dxf-insert" => return None,
        "mutate" => mutate(b, rng),
        "empty" => [b"".as_slice(), b"\n", b"   \n\t\n"][rng.random_range(0..3)].to_vec(),
        "longline" => {
            let long = if rng.random_bool(0.5) {
                "9".repeat(100_000)
            } else {
                format!("; {}\n", "x".repeat(1 << 20))
            };
            match numbers(b).first() {
                Some(&span) if rng.random_bool(0.5) => splice(b, span, long.as_bytes()),
                _ => insert_at_random(b, long.as_bytes(), rng),
            }
        }
        "line-ends" => {
            let text = String::from_utf8_lossy(b);
            if rng.random_bool(0.5) {
                text.replace('\n', "\r\n").into_bytes()
            } else {
                text.replace('\n', "\r").into_bytes()
            }
        }
        "special" => return Some((Vec::new(), Some(["zero", "dir"][rng.random_range(0..2)]))),
        _ => unreachable!("unknown category {category}"),
    };
    Some((bytes, None))
}

/// `count` cases from `seed`, kinds and categories drawn in turn; `root` is the repository
/// and `solution` the bytes of a valid solution of `ESC07.sop` (the seed of solution cases).
pub fn cases(root: &Path, solution: &[u8], count: usize, seed: u64) -> Vec<Case> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(count);
    let mut tries = 0;
    while out.len() < count && tries < count * 10 {
        tries += 1;
        let kind = Kind::ALL[rng.random_range(0..Kind::ALL.len())];
        let category = CATEGORIES[rng.random_range(0..CATEGORIES.len())];
        let (seed_name, mut b) = seed_bytes(root, kind, &mut rng);
        if kind == Kind::Solution {
            b = solution.to_vec();
        }
        let Some((bytes, special)) = apply(category, kind, &b, &mut rng) else {
            continue;
        };
        let stem = Path::new(&seed_name)
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("x")
            .to_string();
        let id = format!("{kind:?}-{stem}-{category}-{}", out.len()).to_lowercase();
        out.push(Case {
            id,
            category,
            kind,
            name: kind.file_name(&seed_name),
            seed: seed_name,
            bytes,
            special,
        });
    }
    out
}

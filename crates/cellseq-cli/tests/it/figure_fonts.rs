//! Every report figure is also a PDF whose fonts are embedded (issue 29): the PDF is parsed and
//! every font it references must carry its font program (or be a Type 3 font, whose glyphs are
//! drawn in the file).

use cellseq_lab::plot::charts;
use std::collections::BTreeMap;

/// A PDF token: a name (`/Type`), a number or keyword, or a delimiter.
fn tokens(dict: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut cur = String::new();
    let flush = |cur: &mut String, out: &mut Vec<String>| {
        if !cur.is_empty() {
            out.push(std::mem::take(cur));
        }
    };
    let mut chars = dict.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            c if c.is_whitespace() => flush(&mut cur, &mut out),
            '/' => {
                flush(&mut cur, &mut out);
                cur.push('/');
            }
            '[' | ']' | '(' | ')' => {
                flush(&mut cur, &mut out);
                out.push(c.to_string());
            }
            '<' | '>' if chars.peek() == Some(&c) => {
                chars.next();
                flush(&mut cur, &mut out);
                out.push(format!("{c}{c}"));
            }
            _ => cur.push(c),
        }
    }
    flush(&mut cur, &mut out);
    out
}

/// Every object of the file: number -> the tokens of its dictionary (up to `stream`, if any),
/// and whether it has a stream.
fn objects(pdf: &[u8]) -> BTreeMap<u32, (Vec<String>, bool)> {
    let text: String = pdf.iter().map(|&b| b as char).collect(); // Latin-1: one char per byte
    let mut out = BTreeMap::new();
    let mut at = 0;
    while let Some(k) = text[at..].find(" 0 obj") {
        let start = at + k;
        let num: String = text[..start]
            .chars()
            .rev()
            .take_while(|c| c.is_ascii_digit())
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        let body_start = start + " 0 obj".len();
        let end = text[body_start..]
            .find("endobj")
            .map_or(text.len(), |e| body_start + e);
        let body = &text[body_start..end];
        let (dict, stream) = match body.find("stream") {
            Some(s) => (&body[..s], true),
            None => (body, false),
        };
        if let Ok(n) = num.parse() {
            out.insert(n, (tokens(dict), stream));
        }
        at = end;
    }
    out
}

/// The object referenced right after `key` (`key N 0 R`), if any.
fn reference(t: &[String], key: &str) -> Option<u32> {
    let i = t.iter().position(|x| x == key)?;
    let j = if t.get(i + 1).map(String::as_str) == Some("[") {
        i + 2
    } else {
        i + 1
    };
    (t.get(j + 2).map(String::as_str) == Some("R")).then(|| t[j].parse().ok())?
}

fn value<'a>(t: &'a [String], key: &str) -> Option<&'a str> {
    let i = t.iter().position(|x| x == key)?;
    t.get(i + 1).map(String::as_str)
}

/// The fonts of the PDF, each with whether its font program is in the file.
fn fonts(pdf: &[u8]) -> Vec<(u32, String, bool)> {
    let objs = objects(pdf);
    let embedded = |font: &[String]| -> bool {
        let Some(d) = reference(font, "/FontDescriptor").and_then(|n| objs.get(&n)) else {
            return false;
        };
        ["/FontFile", "/FontFile2", "/FontFile3"].iter().any(|k| {
            reference(&d.0, k)
                .and_then(|n| objs.get(&n))
                .is_some_and(|(_, stream)| *stream)
        })
    };
    let mut out = Vec::new();
    for (&n, (t, _)) in &objs {
        if value(t, "/Type") != Some("/Font") {
            continue;
        }
        let subtype = value(t, "/Subtype").unwrap_or("?").to_string();
        let ok = match subtype.as_str() {
            "/Type3" => true,
            "/Type0" => reference(t, "/DescendantFonts")
                .and_then(|d| objs.get(&d))
                .is_some_and(|(dt, _)| embedded(dt)),
            _ => embedded(t),
        };
        out.push((n, subtype, ok));
    }
    out
}

#[test]
fn figures_are_written_as_pdf_with_every_font_embedded() {
    let dir = tempfile::tempdir().unwrap();
    let groups: Vec<charts::Group> = vec![
        ("greedy".into(), 0, vec![1.0, 2.0, 3.5, 4.0]),
        ("ils τ ≤ 2".into(), 1, vec![2.0, 2.5, 3.0, 10.0]),
    ];
    let files = charts::box_plot(
        dir.path(),
        "box",
        "Reduction per trial",
        "reduction %",
        &groups,
    )
    .unwrap();
    let pdf = files
        .iter()
        .find(|p| p.extension().is_some_and(|e| e == "pdf"))
        .expect("a PDF among the figure's files");
    let bytes = std::fs::read(pdf).unwrap();
    assert!(
        bytes.starts_with(b"%PDF-"),
        "{} is not a PDF",
        pdf.display()
    );
    let fonts = fonts(&bytes);
    assert!(
        !fonts.is_empty(),
        "the figure has text, so its PDF must reference a font"
    );
    for (n, subtype, ok) in &fonts {
        assert!(
            ok,
            "font object {n} ({subtype}) is referenced but not embedded"
        );
    }
}

#[test]
fn the_checker_finds_a_font_that_is_not_embedded() {
    // a hand-made PDF fragment: one embedded TrueType font, one that names only its descriptor
    let pdf =
        b"%PDF-1.7\n1 0 obj\n<< /Type /Font /Subtype /TrueType /FontDescriptor 2 0 R >>\nendobj\n\
2 0 obj\n<< /Type /FontDescriptor /FontFile2 3 0 R >>\nendobj\n\
3 0 obj\n<< /Length 1 >>\nstream\nx\nendstream\nendobj\n\
4 0 obj\n<< /Type /Font /Subtype /Type0 /DescendantFonts [5 0 R] >>\nendobj\n\
5 0 obj\n<< /Type /Font /Subtype /CIDFontType2 /FontDescriptor 6 0 R >>\nendobj\n\
6 0 obj\n<< /Type /FontDescriptor /FontName /DejaVuSans >>\nendobj\n";
    let f = fonts(pdf);
    let by: BTreeMap<u32, bool> = f.iter().map(|(n, _, ok)| (*n, *ok)).collect();
    assert_eq!(by.get(&1), Some(&true));
    assert_eq!(by.get(&4), Some(&false));
    assert_eq!(by.get(&5), Some(&false));
}

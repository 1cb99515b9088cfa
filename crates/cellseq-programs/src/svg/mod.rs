//! SVG drawings (pen plotters, lasers): read strokes, write the drawing back in a new order and
//! verify that it draws exactly the same segments and keeps every element it does not sequence.
//! Sequencing is in [`crate::optimize::strokes`]; this codec imports no solver.
//!
//! [`read()`] parses the file (every subpath of every shape is one [`Stroke`], curves flattened
//! within a tolerance, transforms applied), [`write()`] emits one `<path>` per stroke grouped
//! per layer (kept elements first in their layer), [`verify`] compares the multisets of
//! segments (direction-insensitive, per layer label, stroke colour and width) and of kept
//! elements.

pub mod read;

use cellseq::error::{Error, Result};
use std::fmt::Write as _;

pub use crate::drawing::{Drawing, Kept, Layer, PenUp, Stroke, Style, Wrap, dist, num, pen_up};
use std::sync::Arc;

pub use read::{ReadOptions, read};

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Writes strokes as an SVG: one `<path>` per stroke, consecutive strokes of one layer in one
/// Inkscape layer group, stroke colour and width kept, no fill.
pub fn write(d: &Drawing, strokes: &[Stroke]) -> String {
    let mut o = String::with_capacity(strokes.len() * 64 + 512);
    o.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:inkscape=\"http://www.inkscape.org/namespaces/inkscape\"");
    for (prefix, uri) in &d.namespaces {
        if prefix != "inkscape" {
            let _ = write!(o, " xmlns:{prefix}=\"{}\"", esc(uri));
        }
    }
    for (k, v) in &d.root_attrs {
        let _ = write!(o, " {k}=\"{}\"", esc(v));
    }
    if d.root_attrs.is_empty() {
        // a page around the drawing, in mm
        let mut b = [
            f64::INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NEG_INFINITY,
        ];
        for p in strokes.iter().flat_map(|s| &s.points) {
            let y = if d.flip_y { -p[1] } else { p[1] };
            b = [b[0].min(p[0]), b[1].min(y), b[2].max(p[0]), b[3].max(y)];
        }
        if !b[0].is_finite() {
            b = [0.0, 0.0, 1.0, 1.0];
        }
        let (w, h) = ((b[2] - b[0]).max(1e-9), (b[3] - b[1]).max(1e-9));
        let _ = write!(
            o,
            " width=\"{}mm\" height=\"{}mm\" viewBox=\"{} {} {} {}\"",
            num(w * d.mm_per_unit),
            num(h * d.mm_per_unit),
            num(b[0]),
            num(b[1]),
            num(w),
            num(h)
        );
    }
    o.push_str(">\n");
    if d.flip_y {
        o.push_str("<g transform=\"scale(1,-1)\">\n");
    }
    // kept elements go first into their layer's first group, in document order
    let mut kept_of: Vec<Vec<&Kept>> = vec![Vec::new(); d.layers.len()];
    for k in &d.kept {
        kept_of[k.layer.min(d.layers.len() - 1)].push(k);
    }
    let mut opened = vec![false; d.layers.len()];
    let mut open_layer = |o: &mut String, layer: usize, kept_of: &mut Vec<Vec<&Kept>>| {
        open_group(o, &d.layers[layer], layer == 0, opened[layer]);
        opened[layer] = true;
        write_kept(o, &std::mem::take(&mut kept_of[layer]));
    };
    let mut cur: Option<usize> = None;
    for s in strokes {
        // a dot is a zero-length subpath, which renders only with round or square caps
        let cap = if s.is_dot() {
            ";stroke-linecap:round"
        } else {
            ""
        };
        if cur != Some(s.layer) {
            if cur.is_some() {
                o.push_str("</g>\n");
            }
            open_layer(&mut o, s.layer, &mut kept_of);
            cur = Some(s.layer);
        }
        let st = &d.styles[s.style];
        let _ = write!(
            o,
            "<path style=\"fill:none;stroke:{};stroke-width:{}{cap}\" d=\"M{},{}",
            esc(&st.stroke),
            num(st.width),
            num(s.points[0][0]),
            num(s.points[0][1])
        );
        if s.is_dot() {
            let _ = write!(o, " L{},{}", num(s.points[0][0]), num(s.points[0][1]));
        }
        for p in &s.points[1..] {
            let _ = write!(o, " L{},{}", num(p[0]), num(p[1]));
        }
        if s.closed {
            o.push_str(" Z");
        }
        o.push_str("\"/>\n");
    }
    if cur.is_some() {
        o.push_str("</g>\n");
    }
    for layer in 0..d.layers.len() {
        if !kept_of[layer].is_empty() {
            open_layer(&mut o, layer, &mut kept_of);
            o.push_str("</g>\n");
        }
    }
    if d.flip_y {
        o.push_str("</g>\n");
    }
    o.push_str("</svg>\n");
    o
}

/// Most wrapper groups a layer's kept elements get written in separately, each element in
/// its own; beyond, neighbours share them.
const SEPARATE_WRAPPERS_MAX: usize = 100_000;

/// Writes kept elements in document order, each inside one `<g>` per ancestor carrying that
/// ancestor's attributes. Up to [`SEPARATE_WRAPPERS_MAX`] wrappers in all, each element has
/// its own; beyond, neighbours with common ancestors share their wrappers, so the text is
/// linear in the file however deep the groups are nested.
fn write_kept(o: &mut String, items: &[&Kept]) {
    let wrappers: usize = items
        .iter()
        .map(|k| k.wrap.as_ref().map_or(0, |w| w.depth))
        .sum();
    if wrappers <= SEPARATE_WRAPPERS_MAX {
        // each element on its own line in its own wrappers (the usual case)
        for k in items {
            o.push_str(&k.wrapped());
            o.push('\n');
        }
        return;
    }
    // the wrappers open now, outermost first
    let mut open: Vec<&Arc<Wrap>> = Vec::new();
    for k in items {
        // the element's ancestors not yet open, innermost first
        let mut fresh: Vec<&Arc<Wrap>> = Vec::new();
        let mut at = k.wrap.as_ref();
        while let Some(w) = at.filter(|w| w.depth > open.len()) {
            fresh.push(w);
            at = w.parent.as_ref();
        }
        // close open wrappers until the top is the element's ancestor at that depth
        while let Some(top) = open.last() {
            match at {
                Some(w) if Arc::ptr_eq(w, top) => break,
                _ => {
                    open.pop();
                    o.push_str("</g>");
                    if let Some(w) = at.filter(|w| w.depth > open.len()) {
                        fresh.push(w);
                        at = w.parent.as_ref();
                    }
                }
            }
        }
        for w in fresh.into_iter().rev() {
            o.push_str("<g");
            o.push_str(&w.attrs);
            o.push('>');
            open.push(w);
        }
        o.push_str(&k.xml);
    }
    for _ in open {
        o.push_str("</g>");
    }
    if !items.is_empty() {
        o.push('\n');
    }
}

/// Opens the group of a layer as the original has it: an Inkscape layer with its label, a
/// plain group with its id (the root's own elements in an unnamed group). The id is written
/// only on the layer's first group, so ids stay unique when a layer's strokes are split
/// (`--no-scopes`); a later group of a plain layer carries its name as `inkscape:label`, which
/// the reader takes as the layer's label.
fn open_group(o: &mut String, l: &Layer, root: bool, again: bool) {
    let id = match (&l.id, again) {
        (Some(id), false) => format!(" id=\"{}\"", esc(id)),
        _ => String::new(),
    };
    if root {
        o.push_str("<g>\n");
    } else if l.inkscape {
        let _ = writeln!(
            o,
            "<g inkscape:groupmode=\"layer\"{id} inkscape:label=\"{}\">",
            esc(&l.label)
        );
    } else if l.label.is_empty() || (!id.is_empty() && l.id.as_deref() == Some(&l.label)) {
        let _ = writeln!(o, "<g{id}>");
    } else {
        let _ = writeln!(o, "<g{id} inkscape:label=\"{}\">", esc(&l.label));
    }
}

type SegKey = (u32, [u64; 4]);
type Interner = std::collections::HashMap<(String, String, u64), u32>;

/// Segment keys, sorted: (layer label, colour, width) interned, endpoints ordered.
/// `round` applies the writer's 6-decimal rounding (idempotent on written files).
fn seg_keys(d: &Drawing, strokes: &[Stroke], intern: &mut Interner, round: bool) -> Vec<SegKey> {
    let r = |v: f64| {
        // + 0.0 turns -0 into +0, so that keys compare by value
        if round {
            num(v).parse::<f64>().unwrap_or(v) + 0.0
        } else {
            v + 0.0
        }
    };
    let mut v = Vec::new();
    // the interned key of each (layer, style) met, so that each is built once
    let mut ids: std::collections::HashMap<(usize, usize), u32> = Default::default();
    for s in strokes {
        let id = *ids.entry((s.layer, s.style)).or_insert_with(|| {
            let st = &d.styles[s.style];
            let k = (
                d.layers[s.layer].label.clone(),
                st.stroke.clone(),
                num(st.width).parse::<f64>().unwrap_or(st.width).to_bits(),
            );
            let next = intern.len() as u32;
            *intern.entry(k).or_insert(next)
        });
        for (a, b) in s.segments() {
            let (a, b) = ([r(a[0]), r(a[1])], [r(b[0]), r(b[1])]);
            let (a, b) = if (a[0], a[1]) <= (b[0], b[1]) {
                (a, b)
            } else {
                (b, a)
            };
            v.push((
                id,
                [
                    a[0].to_bits(),
                    a[1].to_bits(),
                    b[0].to_bits(),
                    b[1].to_bits(),
                ],
            ));
        }
    }
    v.sort_unstable();
    v
}

/// Chains of wrapper groups ([`Wrap`]) as numbers: two chains get the same number when they
/// have the same attributes all the way up (0: no group). Each node is numbered once, so
/// comparing the kept elements of two drawings is linear however deep their groups are.
#[derive(Default)]
struct Chains {
    ids: std::collections::HashMap<(u32, String), u32>,
    seen: std::collections::HashMap<usize, u32>,
}

impl Chains {
    /// The number of a group with attributes `attrs` inside the chain numbered `parent`.
    fn intern(&mut self, parent: u32, attrs: &str) -> u32 {
        let next = self.ids.len() as u32 + 1;
        *self.ids.entry((parent, attrs.to_string())).or_insert(next)
    }
    /// The number of the chain ending at `w`, inside the chain numbered `base`.
    fn id(&mut self, w: Option<&Arc<Wrap>>, base: u32) -> u32 {
        let mut todo: Vec<&Wrap> = Vec::new();
        let mut at = w.map(|a| &**a);
        let mut id = base;
        while let Some(x) = at {
            if let Some(&i) = self.seen.get(&(x as *const Wrap as usize)) {
                id = i;
                break;
            }
            todo.push(x);
            at = x.parent.as_deref();
        }
        for x in todo.into_iter().rev() {
            id = self.intern(id, &x.attrs);
            self.seen.insert(x as *const Wrap as usize, id);
        }
        id
    }
}

/// Checks that `written` (an SVG text) draws the same multiset of segments as `orig`
/// (direction-insensitive; per layer label, colour and width; coordinates compared after the
/// writer's 6-decimal rounding). Returns the number of segments.
pub fn verify(orig: &Drawing, written_name: &str, written: &str) -> Result<usize> {
    let mut w = read(written_name, written, ReadOptions::default())?;
    if orig.flip_y {
        // the writer mirrors y-up drawings with scale(1,-1); mirror back (exact)
        for s in &mut w.strokes {
            for p in &mut s.points {
                p[1] = -p[1] + 0.0;
            }
        }
    }
    let mut intern = Interner::default();
    let a = seg_keys(orig, &orig.strokes, &mut intern, false);
    let b = seg_keys(&w, &w.strokes, &mut intern, false);
    let names: Vec<String> = {
        let mut v = vec![String::new(); intern.len()];
        for ((l, c, _), &i) in &intern {
            v[i as usize] = format!("layer '{l}' {c}");
        }
        v
    };
    // the writer puts each kept element inside its layer's group: one more `<g>` around it
    fn label(d: &Drawing, l: usize) -> &str {
        d.layers.get(l).map_or("", |x| x.label.as_str())
    }
    let mut chains = Chains::default();
    let layer_group = chains.intern(0, "");
    let mut ka: Vec<(&str, u32, &str)> = orig
        .kept
        .iter()
        .map(|k| {
            let c = chains.id(k.wrap.as_ref(), layer_group);
            (label(orig, k.layer), c, k.xml.as_str())
        })
        .collect();
    let mut kb: Vec<(&str, u32, &str)> = w
        .kept
        .iter()
        .map(|k| {
            (
                label(&w, k.layer),
                chains.id(k.wrap.as_ref(), 0),
                k.xml.as_str(),
            )
        })
        .collect();
    ka.sort_unstable();
    kb.sort_unstable();
    if ka != kb {
        return Err(Error::invalid(
            written_name,
            format!(
                "not equivalent to {}: {} elements kept as they were vs {}",
                orig.file,
                kb.len(),
                ka.len()
            ),
        ));
    }
    if a.len() != b.len() {
        return Err(Error::invalid(
            written_name,
            format!(
                "not equivalent to {}: {} segments vs {}",
                orig.file,
                b.len(),
                a.len()
            ),
        ));
    }
    if let Some(i) = (0..a.len()).find(|&i| a[i] != b[i]) {
        let f = |k: &SegKey| {
            format!(
                "{} ({},{})-({},{})",
                names[k.0 as usize],
                f64::from_bits(k.1[0]),
                f64::from_bits(k.1[1]),
                f64::from_bits(k.1[2]),
                f64::from_bits(k.1[3])
            )
        };
        return Err(Error::invalid(
            written_name,
            format!(
                "not equivalent to {}: segment {} differs from {}",
                orig.file,
                f(&b[i]),
                f(&a[i])
            ),
        ));
    }
    Ok(a.len())
}

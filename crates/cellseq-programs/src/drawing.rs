//! The drawing model that the SVG and DXF readers produce and the writers consume: layers,
//! stroke styles and strokes (pen-down polylines, closed or open, or dots) in the file's user
//! units, with millimetres per unit, plus the pen-up figures of a stroke order.

use serde::Serialize;
use std::collections::HashMap;
use std::sync::Arc;

/// A layer: an Inkscape layer, or (SVG) any other group that is a child of the root, which is
/// how plotter tools such as vpype read a file's layers. Index 0 is the document root, outside
/// any group.
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// `inkscape:label` (or id).
    pub label: String,
    /// Element id.
    pub id: Option<String>,
    /// Written as an Inkscape layer (`inkscape:groupmode="layer"`); otherwise as a plain group
    /// with its id, as the original has it.
    pub inkscape: bool,
}

/// Stroke style kept on output.
#[derive(Debug, Clone, PartialEq)]
pub struct Style {
    /// Normalized stroke colour (`#rrggbb`, or the raw value such as `none`).
    pub stroke: String,
    /// Stroke width in root user units (transform scale applied).
    pub width: f64,
}

/// One pen-down polyline in root user units.
#[derive(Debug, Clone, PartialEq)]
pub struct Stroke {
    /// Vertices (a dot has one).
    pub points: Vec<[f64; 2]>,
    /// Closed polygon (the closing segment is implicit; the first point is not repeated).
    pub closed: bool,
    /// Layer index into [`Drawing::layers`].
    pub layer: usize,
    /// Style index into [`Drawing::styles`].
    pub style: usize,
    /// Source line of the element.
    pub line: usize,
}

impl Stroke {
    /// Normalizes: a repeated closing vertex is dropped, an open polyline ending where it
    /// started (3+ vertices) is closed, a stroke whose points all coincide is a dot.
    pub fn new(
        mut points: Vec<[f64; 2]>,
        mut closed: bool,
        layer: usize,
        style: usize,
        line: usize,
    ) -> Stroke {
        for p in &mut points {
            *p = [round6(p[0]), round6(p[1])];
        }
        points.dedup();
        if points.len() >= 2 && points.first() == points.last() {
            points.pop();
            closed = points.len() >= 2;
        }
        if points.len() <= 1 {
            closed = false;
        }
        Stroke {
            points,
            closed,
            layer,
            style,
            line,
        }
    }
    /// True for a single point.
    pub fn is_dot(&self) -> bool {
        self.points.len() == 1
    }
    /// First point drawn.
    pub fn start(&self) -> [f64; 2] {
        self.points[0]
    }
    /// Last point drawn (the start for closed strokes).
    pub fn end(&self) -> [f64; 2] {
        if self.closed {
            self.points[0]
        } else {
            *self.points.last().expect("stroke has points")
        }
    }
    /// The segments drawn (a dot is one zero-length segment).
    pub fn segments(&self) -> Vec<([f64; 2], [f64; 2])> {
        let p = &self.points;
        if p.len() == 1 {
            return vec![(p[0], p[0])];
        }
        let mut v: Vec<_> = p.windows(2).map(|w| (w[0], w[1])).collect();
        if self.closed {
            v.push((p[p.len() - 1], p[0]));
        }
        v
    }
    /// Length in user units.
    pub fn length(&self) -> f64 {
        self.segments().iter().map(|(a, b)| dist(*a, *b)).sum()
    }
    /// The same stroke drawn backwards (open) or started at vertex `k` (closed).
    pub fn oriented(&self, reverse: bool, k: usize) -> Stroke {
        let mut s = self.clone();
        if self.closed {
            s.points.rotate_left(k % self.points.len());
        } else if reverse {
            s.points.reverse();
        }
        s
    }
}

/// Planar distance.
pub fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

/// A parsed drawing.
#[derive(Debug, Clone)]
pub struct Drawing {
    /// File name for messages.
    pub file: String,
    /// `width`, `height`, `viewBox` of the root, copied to the output.
    pub root_attrs: Vec<(String, String)>,
    /// Millimetres per root user unit.
    pub mm_per_unit: f64,
    /// Layers (index 0: outside any layer).
    pub layers: Vec<Layer>,
    /// Distinct styles.
    pub styles: Vec<Style>,
    /// Strokes in document order.
    pub strokes: Vec<Stroke>,
    /// Unsupported elements skipped (with `skip_unsupported`).
    pub skipped: Vec<String>,
    /// Warnings for the user (assumed units, …).
    pub warnings: Vec<String>,
    /// Coordinates are y-up (DXF): the SVG writer mirrors them with `scale(1,-1)`.
    pub flip_y: bool,
    /// The program that wrote the file, when the file says so in a way the reader knows
    /// (`boxes.py`, `Inkscape`); it tells which conventions its layers, colours and groups
    /// follow (`pipeline::drawing::semantics`).
    pub generator: Option<String>,
    /// Elements passed through unchanged (SVG text, images, `<use>`, definitions, metadata,
    /// foreign elements, invisible zero-length paths), in document order.
    pub kept: Vec<Kept>,
    /// Namespace declarations of the root (prefix, URI) that kept elements may use.
    pub namespaces: Vec<(String, String)>,
    /// The arcs that chords of the strokes lie on (DXF ARC, CIRCLE, bulges), by chord
    /// ([`chord_key`]); `None` where two different arcs share a chord. A G-code post writes
    /// runs of such chords as G2/G3 ([`Drawing::arc_of`]); everything else sees the chords.
    pub arcs: HashMap<ChordKey, Option<ArcOf>>,
}

/// A chord's endpoints as [`round6`] holds them, the lower point first: bits of x, y, x, y.
pub type ChordKey = [u64; 4];

/// The arc a chord of a stroke lies on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcOf {
    /// Centre (user units).
    pub center: [f64; 2],
    /// Radius (user units).
    pub radius: f64,
    /// Counter-clockwise when drawn from the key's first point to its second (in
    /// [`Drawing::arc_of`]: from `a` to `b`).
    pub ccw: bool,
}

/// The key of the chord a–b and whether it is drawn from its second point to its first.
pub fn chord_key(a: [f64; 2], b: [f64; 2]) -> (ChordKey, bool) {
    let (a, b) = ([round6(a[0]), round6(a[1])], [round6(b[0]), round6(b[1])]);
    let bits = |p: [f64; 2], q: [f64; 2]| [p[0], p[1], q[0], q[1]].map(f64::to_bits);
    if (a[0], a[1]) <= (b[0], b[1]) {
        (bits(a, b), false)
    } else {
        (bits(b, a), true)
    }
}

/// An element that is not sequenced and is written back as it was.
#[derive(Debug, Clone, PartialEq)]
pub struct Kept {
    /// Layer index into [`Drawing::layers`].
    pub layer: usize,
    /// Source line of the element.
    pub line: usize,
    /// Its source text.
    pub xml: String,
    /// Its innermost ancestor below the root (`None` for a child of the root); the writer
    /// wraps the element in one `<g>` per ancestor carrying that ancestor's attributes
    /// (transform, style), so that it renders as before.
    pub wrap: Option<Arc<Wrap>>,
}

impl Kept {
    /// The element wrapped in one `<g>` per ancestor, outermost first (its text as written
    /// on its own). Linear in the depth; the writer shares the wrappers of neighbouring
    /// elements instead.
    pub fn wrapped(&self) -> String {
        let chain = Wrap::chain(self.wrap.as_ref());
        let mut s = String::new();
        for w in &chain {
            s.push_str("<g");
            s.push_str(&w.attrs);
            s.push('>');
        }
        s.push_str(&self.xml);
        for _ in &chain {
            s.push_str("</g>");
        }
        s
    }
}

/// An ancestor group of kept elements: its attributes as the source has them (`id`,
/// namespace declarations and Inkscape attributes left out), its parent and its depth. Every
/// kept element below one group shares that group's node, so elements deep in nested groups
/// cost memory linear in the file, not in the depth times the number of elements.
pub struct Wrap {
    /// ` name="value"` for each attribute kept, in source order.
    pub attrs: String,
    /// The enclosing group below the root, if any.
    pub parent: Option<Arc<Wrap>>,
    /// 1 for a child of the root.
    pub depth: usize,
}

impl Wrap {
    /// A group below `parent` with attribute text `attrs`.
    pub fn new(attrs: String, parent: Option<Arc<Wrap>>) -> Arc<Wrap> {
        let depth = parent.as_ref().map_or(0, |p| p.depth) + 1;
        Arc::new(Wrap {
            attrs,
            parent,
            depth,
        })
    }
    /// `w` and its ancestors, outermost first.
    pub fn chain(w: Option<&Arc<Wrap>>) -> Vec<&Wrap> {
        let mut v = Vec::new();
        let mut at = w.map(|a| &**a);
        while let Some(x) = at {
            v.push(x);
            at = x.parent.as_deref();
        }
        v.reverse();
        v
    }
}

impl PartialEq for Wrap {
    /// Same attributes all the way up (compared without recursion).
    fn eq(&self, other: &Wrap) -> bool {
        let (mut a, mut b) = (self, other);
        loop {
            if std::ptr::eq(a, b) {
                return true;
            }
            if a.depth != b.depth || a.attrs != b.attrs {
                return false;
            }
            match (a.parent.as_deref(), b.parent.as_deref()) {
                (Some(x), Some(y)) => (a, b) = (x, y),
                (None, None) => return true,
                _ => return false,
            }
        }
    }
}

impl std::fmt::Debug for Wrap {
    /// This group only (a chain can be thousands of groups deep).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Wrap(depth {}, \"{}\")", self.depth, self.attrs)
    }
}

impl Drop for Wrap {
    /// Drops a deep chain without recursion: each parent held only here is unlinked before
    /// it is dropped.
    fn drop(&mut self) {
        let mut next = self.parent.take();
        while let Some(p) = next {
            match Arc::try_unwrap(p) {
                Ok(mut w) => next = w.parent.take(),
                Err(_) => break,
            }
        }
    }
}

impl Drawing {
    /// The arc under the chord drawn from `a` to `b` (its `ccw` for that direction), if the
    /// chord lies on exactly one arc of the file.
    pub fn arc_of(&self, a: [f64; 2], b: [f64; 2]) -> Option<ArcOf> {
        let (k, swapped) = chord_key(a, b);
        let arc = (*self.arcs.get(&k)?)?;
        Some(ArcOf {
            ccw: arc.ccw != swapped,
            ..arc
        })
    }
    /// Records that the chord drawn from `a` to `b` lies on `arc` (its `ccw` for that
    /// direction); a chord claimed by two different arcs gets none.
    pub fn add_arc(&mut self, a: [f64; 2], b: [f64; 2], arc: ArcOf) {
        let (k, swapped) = chord_key(a, b);
        if k[..2] == k[2..] {
            return;
        }
        let arc = ArcOf {
            ccw: arc.ccw != swapped,
            ..arc
        };
        self.arcs
            .entry(k)
            .and_modify(|e| {
                if *e != Some(arc) {
                    *e = None;
                }
            })
            .or_insert(Some(arc));
    }
}

/// Pen-up figures of a stroke order (millimetres).
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct PenUp {
    /// vpype's metric: sum of end→start distances between consecutive strokes of one layer.
    pub pen_up_mm: f64,
    /// Including travel between layers and from the origin to the first stroke.
    pub pen_up_total_mm: f64,
    /// Pen lifts (moves between strokes that do not start where the previous one ended).
    pub lifts: usize,
    /// Pen-down length.
    pub draw_mm: f64,
}

/// Pen-up figures of strokes drawn in this order.
pub fn pen_up(
    strokes: &[Stroke],
    mm_per_unit: f64,
    layer_key: impl Fn(&Stroke) -> String,
) -> PenUp {
    let mut within = 0.0;
    let mut total = 0.0;
    let mut lifts = 0;
    let mut draw = 0.0;
    let mut prev: Option<&Stroke> = None;
    for s in strokes {
        draw += s.length();
        match prev {
            None => {
                total += dist([0.0, 0.0], s.start());
                lifts += 1;
            }
            Some(p) => {
                let d = dist(p.end(), s.start());
                total += d;
                if layer_key(p) == layer_key(s) {
                    within += d;
                }
                if d > 0.0 {
                    lifts += 1;
                }
            }
        }
        prev = Some(s);
    }
    PenUp {
        pen_up_mm: within * mm_per_unit,
        pen_up_total_mm: total * mm_per_unit,
        lifts,
        draw_mm: draw * mm_per_unit,
    }
}

/// A coordinate as the writers print it ([`num`]) and read it back, so that a drawing and
/// its written copy hold the same numbers.
pub fn round6(v: f64) -> f64 {
    match micros(v) {
        // n / 10^6 correctly rounded: the number the printed decimal parses to
        Some(n) => n as f64 / 1e6 + 0.0,
        None => num_formatted(v).parse::<f64>().unwrap_or(v) + 0.0,
    }
}

/// Formats a coordinate with 6 decimals, trailing zeros trimmed.
pub fn num(v: f64) -> String {
    let Some(n) = micros(v) else {
        return num_formatted(v);
    };
    if n == 0 {
        return "0".into();
    }
    let sign = if n < 0 { "-" } else { "" };
    let a = n.unsigned_abs();
    let (int, frac) = (a / 1_000_000, a % 1_000_000);
    if frac == 0 {
        return format!("{sign}{int}");
    }
    let mut f = format!("{frac:06}");
    while f.ends_with('0') {
        f.pop();
    }
    format!("{sign}{int}.{f}")
}

/// [`num`] through the standard formatting (any value).
fn num_formatted(v: f64) -> String {
    let mut s = format!("{v:.6}");
    if s.contains('.') {
        while s.ends_with('0') {
            s.pop();
        }
        if s.ends_with('.') {
            s.pop();
        }
    }
    if s == "-0" { "0".into() } else { s }
}

/// `v` × 10^6 rounded to an integer as `format!("{v:.6}")` rounds it (half to even, on the
/// exact binary value), computed exactly in integers; `None` for |v| ≥ 9·10^9 (where the
/// result may pass 2^53) and for values that are not finite.
fn micros(v: f64) -> Option<i64> {
    if v.is_nan() || v.abs() >= 9.0e9 {
        return None;
    }
    let bits = v.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    // v = ±m · 2^e exactly
    let (m, e) = if exp == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), exp - 1075)
    };
    let p = i128::from(m) * 1_000_000;
    let n = if e >= 0 {
        p << e
    } else if -e >= 127 {
        0
    } else {
        let k = (-e) as u32;
        let (q, rem, half) = (p >> k, p & ((1i128 << k) - 1), 1i128 << (k - 1));
        if rem > half || (rem == half && q & 1 == 1) {
            q + 1
        } else {
            q
        }
    };
    let n = n as i64;
    Some(if bits >> 63 == 1 { -n } else { n })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_six_decimals_equal_the_standard_formatting() {
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut values = vec![
            0.0,
            -0.0,
            0.0078125,
            0.0234375,
            -0.0078125,
            0.25,
            1e-7,
            -1e-7,
            5e-7,
            4.9999999e-7,
            0.5,
            1.5,
            2.5,
            8.999_999_999e9,
            -8.999_999_999e9,
            9e9,
            1e300,
            f64::MIN_POSITIVE,
            5e-324,
            f64::NAN,
            f64::INFINITY,
            -f64::INFINITY,
            123.456_789_5,
            0.000_000_5,
        ];
        for _ in 0..200_000 {
            let r = next();
            // every magnitude from 1e-9 to 1e10, and ties k/2^j
            let mag = 10f64.powi((r % 20) as i32 - 9);
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
            values.push(u * mag);
            values.push((next() % 2_000_000) as f64 / f64::from(1u32 << (r % 24) as u32));
        }
        for v in values {
            assert_eq!(num(v), num_formatted(v), "{v:e}");
            let want = num_formatted(v).parse::<f64>().unwrap_or(v) + 0.0;
            let got = round6(v);
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "{v:e}: {got} vs {want}"
            );
        }
    }
}

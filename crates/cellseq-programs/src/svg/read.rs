//! SVG reader: XML via `roxmltree`, path data and transforms via `svgtypes`, flattening via
//! `kurbo`. Every drawable element becomes one [`Stroke`] per subpath, in page coordinates
//! (the root's user units, all transforms applied). Elements that are not sequenced (text,
//! images, `<use>`, definitions, metadata, foreign elements) are kept as they are
//! ([`crate::drawing::Kept`]). A document type declaration is accepted; entity
//! declarations are refused (no expansion, nothing is fetched). The tree is walked without
//! recursion, and flattening is bounded: the tolerance grows with the size of a huge shape
//! (at most [`MAX_SEGMENTS_PER_SIZE`] segment lengths per extent) and the total number of
//! points is capped ([`ReadOptions::max_points`]).

use super::{Drawing, Layer, Stroke, Style};
use crate::drawing::{Kept, Wrap};
use cellseq::error::{Error, Result};
use kurbo::{Affine, BezPath, PathEl, Point, Shape};
use roxmltree::{Document, Node, ParsingOptions};
use std::collections::HashMap;
use std::sync::Arc;
use svgtypes::{SimplePathSegment, SimplifyingPathParser};

const SVG_NS: &str = "http://www.w3.org/2000/svg";
const INKSCAPE_NS: &str = "http://www.inkscape.org/namespaces/inkscape";

/// Reader options.
#[derive(Debug, Clone, Copy)]
pub struct ReadOptions {
    /// Flattening tolerance in user units of the root element.
    pub tolerance: f64,
    /// Drop the elements that are not sequenced (`text`, `image`, `use`, …) from the output
    /// instead of keeping them.
    pub skip_unsupported: bool,
    /// Most points after flattening (a cap against hostile files).
    pub max_points: usize,
}

/// Default of [`ReadOptions::max_points`].
pub const MAX_POINTS: usize = 10_000_000;

/// A shape's flattening tolerance is at least its extent divided by this.
pub const MAX_SEGMENTS_PER_SIZE: f64 = 1e6;

/// Coordinates (after the transforms) beyond this magnitude are refused.
pub const MAX_COORD: f64 = 1e12;

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            tolerance: 0.01,
            skip_unsupported: false,
            max_points: MAX_POINTS,
        }
    }
}

struct Ctx<'a> {
    file: &'a str,
    text: &'a str,
    doc: &'a Lines<'a>,
    opts: ReadOptions,
    out: Drawing,
    points: usize,
    /// Index of each distinct style in `out.styles` (colour, width bits): a file may have a
    /// style per element, so the lookup is hashed, not a scan.
    styles: HashMap<(String, u64), usize>,
    /// The root viewport in user units (width, height), what percentage lengths refer to.
    viewport: Option<(f64, f64)>,
}

/// Inherited presentation state.
#[derive(Clone)]
struct Inherit {
    tf: Affine,
    stroke: String,
    width: f64,
    layer: usize,
    /// `stroke-linecap` is round or square: zero-length subpaths are drawn as dots.
    caps: bool,
    /// The innermost group below the root, for elements kept as they are.
    wrap: Option<Arc<Wrap>>,
}

/// Parses an SVG document into strokes.
pub fn read(file: &str, text: &str, opts: ReadOptions) -> Result<Drawing> {
    read_with(file, text, opts, None)
}

/// [`read`] with the flattening tolerance given in millimetres (`opts.tolerance` is then
/// ignored): the document is parsed once, its unit found on its root, and the tolerance
/// converted to user units before any curve is flattened.
pub fn read_mm(file: &str, text: &str, tolerance_mm: f64, opts: ReadOptions) -> Result<Drawing> {
    read_with(file, text, opts, Some(tolerance_mm))
}

fn read_with(
    file: &str,
    text: &str,
    mut opts: ReadOptions,
    tolerance_mm: Option<f64>,
) -> Result<Drawing> {
    if !(opts.tolerance > 0.0 && opts.tolerance.is_finite()) {
        return Err(Error::invalid(
            file,
            "flattening tolerance must be positive",
        ));
    }
    if let Some(i) = text.find("<!ENTITY") {
        let line = text[..i].matches('\n').count() + 1;
        return Err(Error::parse(
            file,
            line,
            "entity declarations are not supported (entities are never expanded)",
        ));
    }
    let doc = Document::parse_with_options(
        text,
        ParsingOptions {
            allow_dtd: true,
            nodes_limit: 50_000_000,
            ..ParsingOptions::default()
        },
    )
    .map_err(|e| {
        let p = e.pos();
        Error::parse(file, p.row as usize, format!("XML: {e}"))
    })?;
    let root = doc.root_element();
    let mut starts = vec![0];
    starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
    let lines = Lines { starts, _doc: &doc };
    if root.tag_name().name() != "svg" {
        return Err(Error::parse(
            file,
            line_of(&lines, root),
            format!("root element is <{}>, not <svg>", root.tag_name().name()),
        ));
    }
    let mut root_attrs = Vec::new();
    for a in ["width", "height", "viewBox"] {
        if let Some(v) = root.attribute(a) {
            root_attrs.push((a.to_string(), v.to_string()));
        }
    }
    let mm_per_unit = mm_per_unit(root);
    if let Some(t) = tolerance_mm {
        opts.tolerance = t / mm_per_unit;
    }
    let namespaces = root
        .namespaces()
        .filter_map(|ns| ns.name().map(|p| (p.to_string(), ns.uri().to_string())))
        .collect();
    let mut ctx = Ctx {
        file,
        text,
        points: 0,
        styles: HashMap::new(),
        viewport: viewport(root),
        doc: &lines,
        opts,
        out: Drawing {
            file: file.to_string(),
            root_attrs,
            mm_per_unit,
            layers: vec![Layer {
                label: String::new(),
                id: None,
                inkscape: false,
            }],
            styles: Vec::new(),
            strokes: Vec::new(),
            skipped: Vec::new(),
            warnings: Vec::new(),
            flip_y: false,
            generator: generator(text, root),
            kept: Vec::new(),
            namespaces,
            arcs: Default::default(),
        },
    };
    let inh = Inherit {
        tf: Affine::IDENTITY,
        stroke: "none".into(),
        width: 1.0,
        layer: 0,
        caps: false,
        wrap: None,
    };
    let inh = presentation(&ctx, root, &inh)?;
    walk(&mut ctx, root, inh)?;
    if let Some(s) = ctx
        .out
        .strokes
        .iter()
        .find(|s| !s.points.iter().flatten().all(|v| v.is_finite()))
    {
        return Err(Error::parse(
            file,
            s.line,
            "coordinates overflow after the transforms",
        ));
    }
    Ok(ctx.out)
}

/// The program that wrote the file, from what it leaves in it: boxes.py's comment and
/// metadata ("Created with Boxes.py"), Inkscape's `inkscape:version` on the root.
fn generator(text: &str, root: Node) -> Option<String> {
    if text.contains("Created with Boxes.py") || text.contains("boxes.hackerspace-bamberg.de") {
        return Some("boxes.py".into());
    }
    root.attribute((INKSCAPE_NS, "version"))
        .map(|_| "Inkscape".to_string())
}

/// Byte offsets of line starts, for line numbers in O(log n).
struct Lines<'a> {
    starts: Vec<usize>,
    _doc: &'a Document<'a>,
}

fn line_of(l: &Lines, n: Node) -> usize {
    l.starts.partition_point(|&s| s <= n.range().start)
}

/// The root's viewBox numbers (x, y, width, height), when there are four and the size is
/// positive and finite.
fn view_box(root: Node) -> Option<[f64; 4]> {
    let v = root.attribute("viewBox")?;
    let p: Vec<f64> = v
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .filter_map(|s| s.parse().ok())
        .collect();
    (p.len() == 4 && p.iter().all(|x| x.is_finite()) && p[2] > 0.0 && p[3] > 0.0)
        .then(|| [p[0], p[1], p[2], p[3]])
}

/// The viewport in user units that percentage lengths refer to: the viewBox's size, else the
/// root's width and height in px (user units without a viewBox).
fn viewport(root: Node) -> Option<(f64, f64)> {
    if let Some(vb) = view_box(root) {
        return Some((vb[2], vb[3]));
    }
    let px = |a: &str| {
        root.attribute(a)
            .and_then(length_mm)
            .map(|mm| mm * 96.0 / 25.4)
    };
    Some((px("width")?, px("height")?)).filter(|(w, h)| *w > 0.0 && *h > 0.0)
}

/// Millimetres per user unit from the root's width and viewBox (96 px per inch).
fn mm_per_unit(root: Node) -> f64 {
    let width_mm = root.attribute("width").and_then(length_mm);
    let vb_w = view_box(root).map(|vb| vb[2]);
    match (width_mm, vb_w) {
        (Some(w), Some(vb)) if w > 0.0 && (w / vb).is_normal() => w / vb,
        _ => 25.4 / 96.0,
    }
}

fn length_mm(s: &str) -> Option<f64> {
    let s = s.trim();
    let (num, unit) = match s.find(|c: char| c.is_ascii_alphabetic() || c == '%') {
        Some(i) => (&s[..i], &s[i..]),
        None => (s, ""),
    };
    let v: f64 = num.trim().parse().ok()?;
    let k = match unit {
        "" | "px" => 25.4 / 96.0,
        "mm" => 1.0,
        "cm" => 10.0,
        "in" => 25.4,
        "pt" => 25.4 / 72.0,
        "pc" => 25.4 / 6.0,
        _ => return None,
    };
    Some(v * k)
}

fn style_prop<'a>(n: Node<'a, 'a>, name: &str) -> Option<&'a str> {
    if let Some(st) = n.attribute("style") {
        for decl in st.split(';') {
            if let Some((k, v)) = decl.split_once(':')
                && k.trim() == name
            {
                return Some(v.trim());
            }
        }
    }
    n.attribute(name)
}

/// Applies the element's transform and stroke properties to the inherited state.
fn presentation(ctx: &Ctx, n: Node, inh: &Inherit) -> Result<Inherit> {
    let mut out = inh.clone();
    if let Some(t) = n.attribute("transform") {
        let t: svgtypes::Transform = t.parse().map_err(|e| {
            Error::parse(
                ctx.file,
                line_of(ctx.doc, n),
                format!("bad transform '{t}': {e}"),
            )
        })?;
        let a = Affine::new([t.a, t.b, t.c, t.d, t.e, t.f]);
        if !a.as_coeffs().iter().all(|v| v.is_finite()) {
            return Err(Error::parse(
                ctx.file,
                line_of(ctx.doc, n),
                "transform is not finite",
            ));
        }
        out.tf = inh.tf * a;
    }
    if let Some(s) = style_prop(n, "stroke") {
        out.stroke = normalize_colour(s);
    }
    if let Some(w) = style_prop(n, "stroke-width")
        && let Some(v) = number(w)
    {
        out.width = v;
    }
    if let Some(c) = style_prop(n, "stroke-linecap") {
        out.caps = matches!(c, "round" | "square");
    }
    Ok(out)
}

fn normalize_colour(s: &str) -> String {
    match s.parse::<svgtypes::Color>() {
        Ok(c) => format!("#{:02x}{:02x}{:02x}", c.red, c.green, c.blue),
        Err(_) => s.to_string(),
    }
}

/// A percentage length (`100%`) of the viewport, as SVG resolves it: of its width for `x`,
/// `width`, `cx`, `rx`, `x1`, `x2`; of its height for `y`, `height`, `cy`, `ry`, `y1`, `y2`; of
/// its normalized diagonal (√((w² + h²) / 2)) otherwise (`r`).
fn percent(ctx: &Ctx, name: &str, v: &str) -> Option<f64> {
    let p: f64 = v.trim().strip_suffix('%')?.trim().parse().ok()?;
    let (w, h) = ctx.viewport?;
    let base = match name {
        "x" | "width" | "cx" | "rx" | "x1" | "x2" => w,
        "y" | "height" | "cy" | "ry" | "y1" | "y2" => h,
        _ => ((w * w + h * h) / 2.0).sqrt(),
    };
    Some(p / 100.0 * base).filter(|x| x.is_finite())
}

fn number(s: &str) -> Option<f64> {
    let s = s.trim().trim_end_matches("px");
    s.parse::<f64>().ok().filter(|v| v.is_finite())
}

fn attr_num(ctx: &Ctx, n: Node, name: &str, default: Option<f64>) -> Result<f64> {
    match n.attribute(name) {
        Some(v) => number(v).or_else(|| percent(ctx, name, v)).ok_or_else(|| {
            Error::parse(
                ctx.file,
                line_of(ctx.doc, n),
                format!("<{}>: bad {name}='{v}'", n.tag_name().name()),
            )
        }),
        None => default.ok_or_else(|| {
            Error::parse(
                ctx.file,
                line_of(ctx.doc, n),
                format!("<{}>: missing {name}", n.tag_name().name()),
            )
        }),
    }
}

/// Walks the children of `root` in document order with an explicit stack (no recursion, so
/// deep nesting cannot overflow the call stack).
fn walk<'a>(ctx: &mut Ctx, root: Node<'a, 'a>, inh: Inherit) -> Result<()> {
    let mut stack: Vec<(Node<'a, 'a>, std::rc::Rc<Inherit>)> = Vec::new();
    let inh = std::rc::Rc::new(inh);
    for ch in root.children().filter(|c| c.is_element()).rev() {
        stack.push((ch, inh.clone()));
    }
    while let Some((n, inh)) = stack.pop() {
        if let Some(inner) = visit(ctx, n, &inh)? {
            let inner = std::rc::Rc::new(inner);
            for ch in n.children().filter(|c| c.is_element()).rev() {
                stack.push((ch, inner.clone()));
            }
        }
    }
    Ok(())
}

/// Handles one element; returns the state its children inherit when they are to be walked.
fn visit(ctx: &mut Ctx, n: Node, inh: &Inherit) -> Result<Option<Inherit>> {
    let ns = n.tag_name().namespace();
    let name = n.tag_name().name();
    if ns != Some(SVG_NS) {
        // foreign elements (sodipodi:namedview, plotter software's own metadata)
        keep(ctx, n, inh, &format!("foreign element <{name}>"));
        return Ok(None);
    }
    if n.attribute("display") == Some("none") || style_prop(n, "display") == Some("none") {
        keep(ctx, n, inh, &format!("hidden <{name}>"));
        return Ok(None);
    }
    let line = line_of(ctx.doc, n);
    match name {
        "defs" | "title" | "desc" | "metadata" | "style" | "clipPath" | "mask" | "symbol"
        | "marker" | "pattern" | "linearGradient" | "radialGradient" | "filter" | "script" => {
            keep(ctx, n, inh, &format!("<{name}>"));
            Ok(None)
        }
        "g" | "a" => {
            let mut inh = presentation(ctx, n, inh)?;
            inh.wrap = Some(Wrap::new(wrap_attrs(ctx, n), inh.wrap.take()));
            // an Inkscape layer, or any group that is a child of the root (the layers
            // plotter tools such as vpype read); the writer keeps them as they are
            let inkscape = n.attribute((INKSCAPE_NS, "groupmode")) == Some("layer");
            let top = n
                .parent_element()
                .is_some_and(|p| p.parent_element().is_none());
            if inkscape || (name == "g" && top) {
                let label = n
                    .attribute((INKSCAPE_NS, "label"))
                    .or(n.attribute("id"))
                    .unwrap_or("")
                    .to_string();
                ctx.out.layers.push(Layer {
                    label,
                    id: n.attribute("id").map(str::to_string),
                    inkscape,
                });
                inh.layer = ctx.out.layers.len() - 1;
            }
            Ok(Some(inh))
        }
        "line" | "polyline" | "polygon" | "rect" | "circle" | "ellipse" | "path" => {
            let inh = presentation(ctx, n, inh)?;
            let path = shape(ctx, n)?;
            if !emit(ctx, &path, &inh, line)? {
                keep(ctx, n, &inh, "invisible zero-length path");
            }
            Ok(None)
        }
        other => {
            keep(ctx, n, inh, &format!("<{other}> (not sequenced)"));
            Ok(None)
        }
    }
}

/// Keeps an element that is not sequenced, verbatim, with its ancestors' attributes (shared
/// with its siblings: [`Wrap`]); or, with `skip_unsupported`, drops it and says so.
fn keep(ctx: &mut Ctx, n: Node, inh: &Inherit, what: &str) {
    let line = line_of(ctx.doc, n);
    if ctx.opts.skip_unsupported {
        ctx.out.skipped.push(format!("line {line}: {what}"));
        return;
    }
    ctx.out.kept.push(Kept {
        layer: inh.layer,
        line,
        xml: ctx.text[n.range()].to_string(),
        wrap: inh.wrap.clone(),
    });
}

/// The attributes of a group that a kept element's wrapper carries: all but `id`, namespace
/// declarations and Inkscape's own, as the source writes them.
fn wrap_attrs(ctx: &Ctx, n: Node) -> String {
    let mut s = String::new();
    for at in n.attributes() {
        let qn = &ctx.text[at.range_qname()];
        if qn == "id" || qn.starts_with("xmlns") || at.namespace() == Some(INKSCAPE_NS) {
            continue;
        }
        s.push(' ');
        s.push_str(&ctx.text[at.range()]);
    }
    s
}

fn points_attr(ctx: &Ctx, n: Node) -> Result<Vec<Point>> {
    let s = n.attribute("points").unwrap_or("");
    let nums: Vec<&str> = s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .collect();
    let mut v = Vec::with_capacity(nums.len());
    for t in &nums {
        v.push(number(t).ok_or_else(|| {
            Error::parse(
                ctx.file,
                line_of(ctx.doc, n),
                format!("bad number '{t}' in points"),
            )
        })?);
    }
    if v.len() % 2 == 1 {
        return Err(Error::parse(
            ctx.file,
            line_of(ctx.doc, n),
            "odd number of coordinates in points",
        ));
    }
    Ok(v.chunks(2).map(|c| Point::new(c[0], c[1])).collect())
}

/// The element's outline as a Bézier path in its own coordinates.
fn shape(ctx: &Ctx, n: Node) -> Result<BezPath> {
    let line = line_of(ctx.doc, n);
    // kurbo turns circles, ellipses and rounded corners into cubics within a tolerance:
    // bound it by the shape's size, and refuse sizes no drawing has
    let sized = |extent: f64| -> Result<f64> {
        if extent.is_nan() || extent.abs() > MAX_COORD {
            return Err(Error::parse(
                ctx.file,
                line,
                format!(
                    "<{}>: size beyond {MAX_COORD:e} user units",
                    n.tag_name().name()
                ),
            ));
        }
        Ok((ctx.opts.tolerance / 4.0).max(extent.abs() / MAX_SEGMENTS_PER_SIZE))
    };
    let mut p = BezPath::new();
    match n.tag_name().name() {
        "line" => {
            let x1 = attr_num(ctx, n, "x1", Some(0.0))?;
            let y1 = attr_num(ctx, n, "y1", Some(0.0))?;
            let x2 = attr_num(ctx, n, "x2", Some(0.0))?;
            let y2 = attr_num(ctx, n, "y2", Some(0.0))?;
            p.move_to((x1, y1));
            p.line_to((x2, y2));
        }
        t @ ("polyline" | "polygon") => {
            let pts = points_attr(ctx, n)?;
            for (i, q) in pts.iter().enumerate() {
                if i == 0 {
                    p.move_to(*q);
                } else {
                    p.line_to(*q);
                }
            }
            if t == "polygon" && !pts.is_empty() {
                p.close_path();
            }
        }
        "rect" => {
            let x = attr_num(ctx, n, "x", Some(0.0))?;
            let y = attr_num(ctx, n, "y", Some(0.0))?;
            let w = attr_num(ctx, n, "width", None)?;
            let h = attr_num(ctx, n, "height", None)?;
            let rx = n
                .attribute("rx")
                .and_then(|v| number(v).or_else(|| percent(ctx, "rx", v)));
            let ry = n
                .attribute("ry")
                .and_then(|v| number(v).or_else(|| percent(ctx, "ry", v)));
            let r = rx.or(ry).unwrap_or(0.0).min(w / 2.0).min(h / 2.0).max(0.0);
            let tol = sized(w.abs().max(h.abs()))?;
            if w < 0.0 || h < 0.0 {
                return Err(Error::parse(ctx.file, line, "<rect>: negative size"));
            }
            if rx.is_some() && ry.is_some() && (rx != ry) {
                // elliptical corners: build from an ellipse-scaled rounded rect
                let (rx, ry) = (
                    rx.unwrap_or(0.0).min(w / 2.0),
                    ry.unwrap_or(0.0).min(h / 2.0),
                );
                let sy = if rx > 0.0 { ry / rx } else { 1.0 };
                let rr = kurbo::RoundedRect::new(0.0, 0.0, w, h / sy.max(1e-12), rx);
                let a = Affine::translate((x, y)) * Affine::scale_non_uniform(1.0, sy);
                p = a * rr.to_path(tol);
            } else if r > 0.0 {
                p = kurbo::RoundedRect::new(x, y, x + w, y + h, r).to_path(tol);
            } else {
                p.move_to((x, y));
                p.line_to((x + w, y));
                p.line_to((x + w, y + h));
                p.line_to((x, y + h));
                p.close_path();
            }
        }
        "circle" => {
            let cx = attr_num(ctx, n, "cx", Some(0.0))?;
            let cy = attr_num(ctx, n, "cy", Some(0.0))?;
            let r = attr_num(ctx, n, "r", None)?;
            if r < 0.0 {
                return Err(Error::parse(ctx.file, line, "<circle>: negative radius"));
            }
            let tol = sized(r)?;
            p = kurbo::Circle::new((cx, cy), r).to_path(tol);
        }
        "ellipse" => {
            let cx = attr_num(ctx, n, "cx", Some(0.0))?;
            let cy = attr_num(ctx, n, "cy", Some(0.0))?;
            let rx = attr_num(ctx, n, "rx", None)?;
            let ry = attr_num(ctx, n, "ry", None)?;
            if rx < 0.0 || ry < 0.0 {
                return Err(Error::parse(ctx.file, line, "<ellipse>: negative radius"));
            }
            let tol = sized(rx.max(ry))?;
            p = kurbo::Ellipse::new((cx, cy), (rx, ry), 0.0).to_path(tol);
        }
        "path" => {
            let d = n.attribute("d").unwrap_or("");
            for seg in SimplifyingPathParser::from(d) {
                let seg =
                    seg.map_err(|e| Error::parse(ctx.file, line, format!("path data: {e}")))?;
                match seg {
                    SimplePathSegment::MoveTo { x, y } => p.move_to((x, y)),
                    SimplePathSegment::LineTo { x, y } => p.line_to((x, y)),
                    SimplePathSegment::CurveTo {
                        x1,
                        y1,
                        x2,
                        y2,
                        x,
                        y,
                    } => p.curve_to((x1, y1), (x2, y2), (x, y)),
                    SimplePathSegment::Quadratic { x1, y1, x, y } => p.quad_to((x1, y1), (x, y)),
                    SimplePathSegment::ClosePath => p.close_path(),
                }
            }
        }
        _ => unreachable!("shape() is only called for shape elements"),
    }
    let finite = p.elements().iter().all(|e| match e {
        PathEl::MoveTo(a) | PathEl::LineTo(a) => a.is_finite(),
        PathEl::QuadTo(a, b) => a.is_finite() && b.is_finite(),
        PathEl::CurveTo(a, b, c) => a.is_finite() && b.is_finite() && c.is_finite(),
        PathEl::ClosePath => true,
    });
    if !finite {
        return Err(Error::parse(ctx.file, line, "non-finite coordinate"));
    }
    Ok(p)
}

/// The index of the style (`stroke`, `width`) in the drawing, added when new.
fn style_index(ctx: &mut Ctx, stroke: &str, width: f64) -> usize {
    // + 0.0: -0 and 0 are one width, as `==` has them
    let key = (stroke.to_string(), (width + 0.0).to_bits());
    if let Some(&i) = ctx.styles.get(&key) {
        return i;
    }
    ctx.out.styles.push(Style {
        stroke: key.0.clone(),
        width,
    });
    let i = ctx.out.styles.len() - 1;
    ctx.styles.insert(key, i);
    i
}

/// Flattens a path (after the transform) and appends one stroke per subpath. Zero-length
/// subpaths are drawn only with round or square caps; returns false when the element draws
/// nothing at all (it is then kept as it is).
fn emit(ctx: &mut Ctx, path: &BezPath, inh: &Inherit, line: usize) -> Result<bool> {
    let tf = inh.tf;
    let scale = tf.determinant().abs().sqrt();
    let width = inh.width * if scale > 0.0 { scale } else { 1.0 };
    let transformed = tf * path.clone();
    if transformed.elements().is_empty() {
        return Ok(false);
    }
    let bb = transformed.bounding_box();
    let reach = bb
        .x0
        .abs()
        .max(bb.x1.abs())
        .max(bb.y0.abs())
        .max(bb.y1.abs());
    if reach.is_nan() || reach > MAX_COORD {
        return Err(Error::parse(
            ctx.file,
            line,
            format!("coordinates beyond ±{MAX_COORD:e} user units are not supported"),
        ));
    }
    let extent = bb.width().max(bb.height());
    let tol = ctx.opts.tolerance.max(extent / MAX_SEGMENTS_PER_SIZE);
    let mut strokes: Vec<(Vec<[f64; 2]>, bool)> = Vec::new();
    let mut cur: Vec<[f64; 2]> = Vec::new();
    let mut after_close: Option<[f64; 2]> = None;
    let mut points = 0usize;
    kurbo::flatten(transformed.elements().iter().copied(), tol, |el| match el {
        PathEl::MoveTo(q) => {
            if !cur.is_empty() {
                strokes.push((std::mem::take(&mut cur), false));
            }
            after_close = None;
            cur.push([q.x, q.y]);
            points += 1;
        }
        PathEl::LineTo(q) => {
            if cur.is_empty()
                && let Some(s) = after_close.take()
            {
                cur.push(s);
            }
            cur.push([q.x, q.y]);
            points += 1;
        }
        PathEl::ClosePath => {
            if let Some(&f) = cur.first() {
                strokes.push((std::mem::take(&mut cur), true));
                after_close = Some(f);
            }
        }
        _ => {}
    });
    if !cur.is_empty() {
        strokes.push((cur, false));
    }
    ctx.points += points;
    if ctx.points > ctx.opts.max_points {
        return Err(Error::parse(
            ctx.file,
            line,
            format!(
                "more than {} points after flattening (raise the cap with --max-points, or use a larger --tolerance)",
                ctx.opts.max_points
            ),
        ));
    }
    let style = style_index(ctx, &inh.stroke, width);
    let before = ctx.out.strokes.len();
    for (pts, closed) in strokes {
        let s = Stroke::new(pts, closed, inh.layer, style, line);
        if s.is_dot() && !inh.caps {
            continue;
        }
        ctx.out.strokes.push(s);
    }
    Ok(ctx.out.strokes.len() > before)
}

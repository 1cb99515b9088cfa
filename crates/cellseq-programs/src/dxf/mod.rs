//! DXF drawings (2-D cutting) through the `dxf` crate: LINE, ARC, CIRCLE, ELLIPSE, LWPOLYLINE
//! and POLYLINE (with bulges), SPLINE (flattened), INSERT (blocks, nested, with scale, rotation,
//! arrays). Loose pieces are chained into contours per layer (endpoints within a tolerance are
//! snapped together). The result is a [`crate::drawing::Drawing`] (one layer per DXF layer, y up), so
//! sequencing, the SVG preview and verification are shared with SVG; [`write_gcode`] (in
//! [`post`]) is a simple configurable post. The chords of ARC, CIRCLE and bulge arcs are
//! recorded with their arc ([`crate::drawing::Drawing::arcs`]) so the post writes them as
//! G2/G3.

use crate::drawing::{ArcOf, Drawing, Layer, Stroke, Style};
use cellseq::error::{Error, Result};
use dxf::entities::EntityType;
use kurbo::Affine;
use std::collections::HashMap;

pub mod locate;
pub mod post;

pub use post::{Post, verify_gcode, write_gcode};

/// Reader options.
#[derive(Debug, Clone, Copy)]
pub struct ReadOptions {
    /// Flattening tolerance (drawing units).
    pub tolerance: f64,
    /// Endpoints closer than this are chained (drawing units).
    pub join: f64,
    /// Skip unsupported entities (text, hatches, dimensions, …) instead of refusing the file.
    pub skip_unsupported: bool,
    /// Millimetres per drawing unit when the file does not say (`$INSUNITS` missing or
    /// unitless); `None` assumes millimetres. Either way the drawing carries a warning.
    pub units: Option<f64>,
}

/// Millimetres per unit of a unit name (`mm`, `cm`, `m`, `in`, `ft`, `mil`, `um`).
pub fn unit_mm(name: &str) -> Option<f64> {
    Some(match name.trim().to_ascii_lowercase().as_str() {
        "mm" | "millimeter" | "millimeters" | "millimetre" | "millimetres" => 1.0,
        "cm" => 10.0,
        "m" => 1000.0,
        "in" | "inch" | "inches" => 25.4,
        "ft" | "foot" | "feet" => 304.8,
        "mil" | "mils" | "thou" => 0.0254,
        "um" | "micron" | "microns" => 0.001,
        _ => return None,
    })
}

/// Millimetres per unit of `$INSUNITS`; `Ok(None)` for unitless.
fn insunits_mm(file: &str, u: dxf::enums::Units) -> Result<Option<f64>> {
    use dxf::enums::Units as U;
    Ok(Some(match u {
        U::Unitless => return Ok(None),
        U::Inches => 25.4,
        U::Feet => 304.8,
        U::Miles => 1_609_344.0,
        U::Millimeters => 1.0,
        U::Centimeters => 10.0,
        U::Meters => 1000.0,
        U::Kilometers => 1e6,
        U::Microinches => 25.4e-6,
        U::Mils => 0.0254,
        U::Yards => 914.4,
        U::Angstroms => 1e-7,
        U::Nanometers => 1e-6,
        U::Microns => 1e-3,
        U::Decimeters => 100.0,
        U::Decameters => 1e4,
        U::Hectometers => 1e5,
        U::USSurveyFeet => 1_200_000.0 / 3937.0,
        U::USSurveyInch => 100_000.0 / 3937.0,
        U::USSurveyYard => 3_600_000.0 / 3937.0,
        U::USSurveyMile => 6_336_000_000.0 / 3937.0,
        other => {
            return Err(Error::invalid(
                file,
                format!("$INSUNITS {other:?} is not a unit for machining or plotting"),
            ));
        }
    }))
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            tolerance: 0.01,
            join: 1e-3,
            skip_unsupported: false,
            units: None,
        }
    }
}

struct Piece {
    layer: usize,
    pts: Vec<[f64; 2]>,
    closed: bool,
}

struct Ctx<'a> {
    file: &'a str,
    /// The file's bytes, to find an entity's line for a message ([`locate::Lines`]).
    bytes: &'a [u8],
    lines: Option<locate::Lines>,
    opts: ReadOptions,
    blocks: HashMap<String, &'a dxf::Block>,
    layers: Vec<String>,
    layer_ids: HashMap<String, usize>,
    /// Entities and array cells of inserts visited so far (bounded like `points`: nested
    /// arrays of empty blocks produce no points but can take forever).
    visits: usize,
    /// Spline evaluation work so far (samples × (degree + 1)²), bounded by
    /// [`MAX_SPLINE_WORK`].
    spline_work: f64,
    pieces: Vec<Piece>,
    skipped: Vec<String>,
    /// Points produced so far (bounded: nested arrays of inserts can explode).
    points: usize,
    /// Chords that lie on an arc: (from, to, the arc for that direction), page coordinates.
    arcs: Vec<([f64; 2], [f64; 2], ArcOf)>,
}

/// Chords `first .. first + count` of a piece (chord k joins point k to point k + 1, the
/// last wrapping to the first) lie on the circle (`center`, `radius`), counter-clockwise or
/// not, in the entity's coordinates.
#[derive(Debug, Clone, Copy)]
struct Run {
    first: usize,
    count: usize,
    center: [f64; 2],
    radius: f64,
    ccw: bool,
}

/// Scale and mirroring of a transform that maps circles to circles (rotation, uniform scale,
/// translation, reflection); `None` for one that does not (arcs become ellipses: chords only).
fn similarity(tf: Affine) -> Option<(f64, bool)> {
    let [a, b, c, d, _, _] = tf.as_coeffs();
    let det = a * d - b * c;
    let s = det.abs().sqrt();
    let eps = 1e-9 * s.max(1e-300);
    let rotation = (a - d).abs() <= eps && (b + c).abs() <= eps;
    let mirror = (a + d).abs() <= eps && (b - c).abs() <= eps;
    (s > 0.0 && s.is_finite() && (rotation || mirror)).then_some((s, det < 0.0))
}

/// Most distinct layer names, and line type names, in a DXF ([`locate::too_many_names`]).
pub const MAX_NAMES: usize = 10_000;

/// Most points a drawing may expand to (inserts and flattening included).
pub const MAX_POINTS: usize = 20_000_000;

/// Parses with the `dxf` crate, which can panic on some malformed values (for example an
/// out-of-range date in the header): the panic is caught, kept off stderr, and reported as
/// a clear error naming the file.
fn load_guarded(file: &str, bytes: &[u8]) -> Result<dxf::Drawing> {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let outcome = std::panic::catch_unwind(|| {
        let mut cur = std::io::Cursor::new(bytes);
        dxf::Drawing::load(&mut cur)
    });
    std::panic::set_hook(previous);
    match outcome {
        Ok(Ok(d)) => Ok(d),
        Ok(Err(e)) => Err(Error::invalid(file, format!("DXF: {e}"))),
        Err(_) => Err(Error::invalid(
            file,
            "DXF: malformed file (the DXF reader rejected a value it could not represent)",
        )),
    }
}

/// Reads a DXF file's bytes.
pub fn read(file: &str, bytes: &[u8], opts: ReadOptions) -> Result<Drawing> {
    if !(opts.tolerance > 0.0 && opts.tolerance.is_finite() && opts.join >= 0.0) {
        return Err(Error::invalid(file, "tolerances must be positive"));
    }
    if let Some((line, what)) = locate::too_many_names(bytes, MAX_NAMES) {
        return Err(Error::parse(
            file,
            line,
            format!(
                "more than {MAX_NAMES} {what} names (the DXF reader's time grows with the entities times the names)"
            ),
        ));
    }
    let dwg = load_guarded(file, bytes)?;
    let mut warnings = Vec::new();
    let mm = match insunits_mm(file, dwg.header.default_drawing_units)? {
        Some(mm) => {
            if let Some(u) = opts.units
                && u != mm
            {
                warnings.push(format!(
                    "the file's $INSUNITS ({:?}) wins over --units",
                    dwg.header.default_drawing_units
                ));
            }
            mm
        }
        None => match opts.units {
            Some(u) => {
                warnings.push(format!(
                    "the file does not say its units ($INSUNITS): {u} mm per unit from --units"
                ));
                u
            }
            None => {
                warnings.push(
                    "the file does not say its units ($INSUNITS): millimetres assumed (set them with --units)"
                        .to_string(),
                );
                1.0
            }
        },
    };
    let mut ctx = Ctx {
        file,
        bytes,
        lines: None,
        opts,
        blocks: dwg.blocks().map(|b| (b.name.clone(), b)).collect(),
        layers: Vec::new(),
        layer_ids: HashMap::new(),
        visits: 0,
        spline_work: 0.0,
        pieces: Vec::new(),
        skipped: Vec::new(),
        points: 0,
        arcs: Vec::new(),
    };
    for (top, e) in dwg.entities().enumerate() {
        let at = At { top, block: None };
        entity(&mut ctx, e, Affine::IDENTITY, None, 0, &at)?;
    }
    let Ctx {
        layers,
        pieces,
        skipped,
        arcs,
        ..
    } = ctx;
    let mut d = Drawing {
        file: file.to_string(),
        root_attrs: Vec::new(),
        mm_per_unit: mm,
        layers: std::iter::once(Layer {
            label: String::new(),
            id: None,
            inkscape: false,
        })
        .chain(layers.iter().map(|l| Layer {
            label: l.clone(),
            id: None,
            inkscape: true,
        }))
        .collect(),
        styles: vec![Style {
            stroke: "#000000".into(),
            width: 0.1 / mm,
        }],
        strokes: Vec::new(),
        skipped,
        warnings,
        flip_y: true,
        generator: None,
        kept: Vec::new(),
        namespaces: Vec::new(),
        arcs: Default::default(),
    };
    for (a, b, arc) in arcs {
        d.add_arc(a, b, arc);
    }
    let mut by_layer: Vec<Vec<&Piece>> = vec![Vec::new(); layers.len()];
    for p in &pieces {
        by_layer[p.layer].push(p);
    }
    for (li, mine) in by_layer.iter().enumerate() {
        for s in chain(mine, opts.join) {
            d.strokes.push(Stroke::new(s.0, s.1, li + 1, 0, 0));
        }
    }
    Ok(d)
}

fn layer_index(ctx: &mut Ctx, name: &str) -> usize {
    if let Some(&i) = ctx.layer_ids.get(name) {
        return i;
    }
    ctx.layers.push(name.to_string());
    ctx.layer_ids.insert(name.to_string(), ctx.layers.len() - 1);
    ctx.layers.len() - 1
}

/// Counter-clockwise sweep from angle `s` to `t` in (0, 2π] (2π when they coincide).
fn sweep_of(s: f64, t: f64) -> f64 {
    let tau = 2.0 * std::f64::consts::PI;
    let d = (t - s).rem_euclid(tau);
    if d > 0.0 && d.is_finite() { d } else { tau }
}

fn arc_points(c: [f64; 2], r: f64, a0: f64, sweep: f64, tol: f64) -> Vec<[f64; 2]> {
    // chord error r(1 - cos(θ/2)) <= tol, with at most ~10^4 segments per full turn of a
    // huge arc (the tolerance grows with the radius)
    let tol = tol.max(r.abs() * 1e-6);
    let step = if r > tol {
        2.0 * (1.0 - tol / r).acos()
    } else {
        std::f64::consts::PI / 2.0
    };
    let n = ((sweep.abs() / step.max(1e-6)).ceil() as usize).clamp(1, 100_000);
    (0..=n)
        .map(|i| {
            let a = a0 + sweep * i as f64 / n as f64;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// Points of a polyline with bulges (vertex i's bulge curves segment i → i+1), and the runs of
/// chords that lie on the bulges' arcs.
fn bulged(v: &[([f64; 2], f64)], closed: bool, tol: f64) -> (Vec<[f64; 2]>, Vec<Run>) {
    let mut out = Vec::new();
    let mut runs = Vec::new();
    let n = v.len();
    let segs = if closed { n } else { n.saturating_sub(1) };
    if n > 0 {
        out.push(v[0].0);
    }
    for i in 0..segs {
        let (p, b) = v[i];
        let q = v[(i + 1) % n].0;
        if b.abs() < 1e-12 || p == q {
            out.push(q);
            continue;
        }
        let theta = 4.0 * b.atan(); // signed sweep
        let chord = ((q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2)).sqrt();
        let r = chord / (2.0 * (theta / 2.0).sin().abs());
        // centre: from the chord midpoint along the normal
        let m = [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
        let h = r * (theta / 2.0).cos();
        let (ux, uy) = ((q[0] - p[0]) / chord, (q[1] - p[1]) / chord);
        let sgn = if theta > 0.0 { 1.0 } else { -1.0 };
        let c = [m[0] - sgn * uy * h, m[1] + sgn * ux * h];
        let a0 = (p[1] - c[1]).atan2(p[0] - c[0]);
        let mut pts = arc_points(c, r, a0, theta, tol);
        *pts.last_mut().expect("arc has points") = q;
        runs.push(Run {
            first: out.len() - 1,
            count: pts.len() - 1,
            center: c,
            radius: r,
            ccw: theta > 0.0,
        });
        out.extend(pts.into_iter().skip(1));
    }
    if closed && out.len() > 1 {
        out.pop(); // back at the start
    }
    (out, runs)
}

/// De Boor evaluation of a (rational) B-spline, sampled finely enough for `tol`; `allow` is
/// asked with the number of samples before any is evaluated (false: nothing is evaluated).
fn spline_points(
    s: &dxf::entities::Spline,
    tol: f64,
    allow: impl FnOnce(usize) -> bool,
) -> Option<Vec<[f64; 2]>> {
    let p = s.degree_of_curve.max(1) as usize;
    let cps: Vec<[f64; 2]> = s.control_points.iter().map(|c| [c.x, c.y]).collect();
    if cps.is_empty() {
        let fit: Vec<[f64; 2]> = s.fit_points.iter().map(|c| [c.x, c.y]).collect();
        return (!fit.is_empty()).then_some(fit);
    }
    let k = &s.knot_values;
    if k.len() != cps.len() + p + 1 {
        return None;
    }
    let w: Vec<f64> = if s.weight_values.len() == cps.len() {
        s.weight_values.clone()
    } else {
        vec![1.0; cps.len()]
    };
    let (t0, t1) = (k[p], k[cps.len()]);
    if t1.is_nan() || t0.is_nan() || t1 <= t0 {
        return None;
    }
    // samples come in increasing t, so the knot span only moves forward: it is carried over
    // from the previous sample (the same span a scan from the start finds, in O(1) amortized)
    let mut span = p;
    let mut eval = |t: f64| -> [f64; 2] {
        while span + 1 < cps.len() && k[span + 1] <= t {
            span += 1;
        }
        let mut d: Vec<[f64; 3]> = (0..=p)
            .map(|j| {
                let c = cps[span - p + j];
                let wj = w[span - p + j];
                [c[0] * wj, c[1] * wj, wj]
            })
            .collect();
        for r in 1..=p {
            for j in (r..=p).rev() {
                let i = span - p + j;
                let den = k[i + p + 1 - r] - k[i];
                let a = if den > 0.0 { (t - k[i]) / den } else { 0.0 };
                let prev = d[j - 1];
                for (x, p) in d[j].iter_mut().zip(prev) {
                    *x = (1.0 - a) * p + a * *x;
                }
            }
        }
        let q = d[p];
        if q[2] != 0.0 {
            [q[0] / q[2], q[1] / q[2]]
        } else {
            [q[0], q[1]]
        }
    };
    // control polygon length bounds the curve length; sample densely, then thin by tolerance
    let poly: f64 = cps
        .windows(2)
        .map(|c| ((c[1][0] - c[0][0]).powi(2) + (c[1][1] - c[0][1]).powi(2)).sqrt())
        .sum();
    let n = ((poly / tol.sqrt().max(1e-6)).ceil() as usize)
        .clamp((8 * cps.len()).min(200_000), 200_000);
    if !allow(n + 1) {
        return None;
    }
    let pts: Vec<[f64; 2]> = (0..=n)
        .map(|i| eval(t0 + (t1 - t0) * i as f64 / n as f64))
        .collect();
    Some(pts)
}

/// Where an entity's points go: its transform (inserts), its layer and its handle (for
/// messages).
struct Source<'a> {
    tf: Affine,
    layer: &'a str,
    handle: &'a str,
    /// The entity's type (`LINE`, `LWPOLYLINE`, …).
    kind: &'static str,
    at: &'a At<'a>,
}

/// Where an entity was reached from, for messages: its top-level entity (the entity itself,
/// or the INSERT whose block holds it) and that block's name.
struct At<'a> {
    top: usize,
    block: Option<&'a str>,
}

/// Most entities and INSERT array cells a drawing may expand to (nested arrays of blocks
/// that draw nothing produce no points, but visiting them takes time all the same).
pub const MAX_VISITS: usize = 10_000_000;

/// Highest SPLINE degree read (de Boor's evaluation costs (degree + 1)² per point; CAD
/// programs write degree 1–11).
pub const MAX_SPLINE_DEGREE: usize = 32;

/// Most spline evaluation work in a drawing: points sampled × (degree + 1)², summed over its
/// splines (about a second).
pub const MAX_SPLINE_WORK: f64 = 2e9;

/// The error for entity `src`: the file, the entity's line when it can be found (else none),
/// its type and handle, and the block it was reached through.
fn refuse(ctx: &mut Ctx, src: &Source, why: &str) -> Error {
    let bytes = ctx.bytes;
    let lines = ctx.lines.get_or_insert_with(|| locate::Lines::new(bytes));
    let mut what = src.kind.to_string();
    if lines.by_handle(src.handle, src.kind).is_some() {
        what.push_str(&format!(" (handle {})", src.handle));
    }
    if let Some(b) = src.at.block {
        what.push_str(&format!(" in block '{b}'"));
    }
    match lines.find(src.handle, src.kind, src.at.top) {
        Some(l) => Error::parse(ctx.file, l, format!("{what}: {why}")),
        None => Error::invalid(ctx.file, format!("{what}: {why}")),
    }
}

/// Adds one piece of an entity (its own coordinates) in page coordinates, with the chords
/// that lie on arcs (`runs`) recorded when the transform keeps circles circles.
fn add_piece(
    ctx: &mut Ctx,
    src: &Source,
    pts: Vec<[f64; 2]>,
    closed: bool,
    runs: &[Run],
) -> Result<()> {
    if pts.is_empty() {
        // a polyline without vertices draws nothing
        return Ok(());
    }
    ctx.points += pts.len();
    if ctx.points > MAX_POINTS {
        let why = format!("the drawing expands to more than {MAX_POINTS} points");
        return Err(refuse(ctx, src, &why));
    }
    let li = layer_index(ctx, src.layer);
    let tf = src.tf;
    let pts: Vec<[f64; 2]> = pts
        .into_iter()
        .map(|p| {
            let q = tf * kurbo::Point::new(p[0], p[1]);
            [q.x, q.y]
        })
        .collect();
    if !pts.iter().flatten().all(|v| v.is_finite()) {
        return Err(refuse(ctx, src, "non-finite coordinate"));
    }
    if let Some((scale, mirror)) = similarity(tf) {
        let n = pts.len();
        for r in runs {
            let c = tf * kurbo::Point::new(r.center[0], r.center[1]);
            let arc = ArcOf {
                center: [c.x, c.y],
                radius: r.radius * scale,
                ccw: r.ccw != mirror,
            };
            for k in r.first..r.first + r.count {
                ctx.arcs.push((pts[k % n], pts[(k + 1) % n], arc));
            }
        }
    }
    ctx.pieces.push(Piece {
        layer: li,
        pts,
        closed,
    });
    Ok(())
}

/// A CIRCLE's points (closed) and its one run of arc chords.
fn circle(c: &dxf::entities::Circle, tol: f64) -> (Vec<[f64; 2]>, Run) {
    let center = [c.center.x, c.center.y];
    let mut p = arc_points(center, c.radius, 0.0, 2.0 * std::f64::consts::PI, tol);
    p.pop();
    let run = Run {
        first: 0,
        count: p.len(),
        center,
        radius: c.radius,
        ccw: true,
    };
    (p, run)
}

/// An ARC's points (open, counter-clockwise) and its one run of arc chords.
fn arc(a: &dxf::entities::Arc, tol: f64) -> (Vec<[f64; 2]>, Run) {
    let deg = std::f64::consts::PI / 180.0;
    let s = a.start_angle * deg;
    let t = s + sweep_of(s, a.end_angle * deg);
    let center = [a.center.x, a.center.y];
    let p = arc_points(center, a.radius, s, t - s, tol);
    let run = Run {
        first: 0,
        count: p.len() - 1,
        center,
        radius: a.radius,
        ccw: true,
    };
    (p, run)
}

/// An ELLIPSE's points (flattened) and whether it is closed (a full turn).
fn ellipse(el: &dxf::entities::Ellipse, tol: f64) -> (Vec<[f64; 2]>, bool) {
    let (mx, my) = (el.major_axis.x, el.major_axis.y);
    let r = (mx * mx + my * my).sqrt();
    let rot = my.atan2(mx);
    let s = el.start_parameter;
    let t = s + sweep_of(s, el.end_parameter);
    let full = (t - s - 2.0 * std::f64::consts::PI).abs() < 1e-9;
    let unit = arc_points([0.0, 0.0], 1.0, s, t - s, tol / r.max(1e-9));
    let m = Affine::translate((el.center.x, el.center.y))
        * Affine::rotate(rot)
        * Affine::scale_non_uniform(r, r * el.minor_axis_ratio);
    let mut p: Vec<[f64; 2]> = unit
        .into_iter()
        .map(|q| {
            let q = m * kurbo::Point::new(q[0], q[1]);
            [q.x, q.y]
        })
        .collect();
    if full {
        p.pop();
    }
    (p, full)
}

/// The DXF name of an entity type this reader draws (`ENTITY` for any other).
fn kind_of(e: &EntityType) -> &'static str {
    match e {
        EntityType::Line(_) => "LINE",
        EntityType::Circle(_) => "CIRCLE",
        EntityType::Arc(_) => "ARC",
        EntityType::Ellipse(_) => "ELLIPSE",
        EntityType::LwPolyline(_) => "LWPOLYLINE",
        EntityType::Polyline(_) => "POLYLINE",
        EntityType::Spline(_) => "SPLINE",
        EntityType::Insert(_) => "INSERT",
        _ => "ENTITY",
    }
}

/// A radius that is a length: finite and not negative.
fn is_length(r: f64) -> bool {
    r.is_finite() && r >= 0.0
}

/// The first bulge of `bulges` that is not a finite number, with its vertex.
fn bad_bulge(bulges: impl Iterator<Item = f64>) -> Option<(usize, f64)> {
    bulges.enumerate().find(|(_, b)| !b.is_finite())
}

/// Reads one entity (a block's entities through [`insert`]) into pieces. Values no drawing
/// has (a negative or non-finite radius, a bulge or angle that is not a number) are refused
/// with the entity's line ([`refuse`]).
fn entity(
    ctx: &mut Ctx,
    e: &dxf::entities::Entity,
    tf: Affine,
    block_layer: Option<&str>,
    depth: usize,
    at: &At,
) -> Result<()> {
    let layer_name = match (e.common.layer.as_str(), block_layer) {
        ("0", Some(b)) => b.to_string(),
        (l, _) => l.to_string(),
    };
    let tol = ctx.opts.tolerance;
    let handle = format!("{:X}", e.common.handle.0);
    let src = Source {
        tf,
        layer: &layer_name,
        handle: &handle,
        kind: kind_of(&e.specific),
        at,
    };
    ctx.visits += 1;
    if ctx.visits > MAX_VISITS {
        let why = format!("the drawing expands to more than {MAX_VISITS} entities");
        return Err(refuse(ctx, &src, &why));
    }
    match &e.specific {
        EntityType::Line(l) => {
            let p = vec![[l.p1.x, l.p1.y], [l.p2.x, l.p2.y]];
            add_piece(ctx, &src, p, false, &[])
        }
        EntityType::Circle(c) => {
            if !is_length(c.radius) {
                let why = format!("radius {} is not a length", c.radius);
                return Err(refuse(ctx, &src, &why));
            }
            let (p, run) = circle(c, tol);
            add_piece(ctx, &src, p, true, &[run])
        }
        EntityType::Arc(a) => {
            if !(is_length(a.radius) && a.start_angle.is_finite() && a.end_angle.is_finite()) {
                let why = format!(
                    "radius {} or angles {}..{} are not numbers an arc can have",
                    a.radius, a.start_angle, a.end_angle
                );
                return Err(refuse(ctx, &src, &why));
            }
            let (p, run) = arc(a, tol);
            add_piece(ctx, &src, p, false, &[run])
        }
        EntityType::Ellipse(el) => {
            let nums = [el.minor_axis_ratio, el.start_parameter, el.end_parameter];
            if !nums.iter().all(|v| v.is_finite()) || el.minor_axis_ratio < 0.0 {
                let why = format!(
                    "axis ratio {} or parameters {}..{} are not numbers an ellipse can have",
                    nums[0], nums[1], nums[2]
                );
                return Err(refuse(ctx, &src, &why));
            }
            let (p, full) = ellipse(el, tol);
            add_piece(ctx, &src, p, full, &[])
        }
        EntityType::LwPolyline(pl) => {
            if let Some((k, b)) = bad_bulge(pl.vertices.iter().map(|v| v.bulge)) {
                return Err(refuse(ctx, &src, &format!("bulge {b} at vertex {}", k + 1)));
            }
            let v: Vec<([f64; 2], f64)> =
                pl.vertices.iter().map(|v| ([v.x, v.y], v.bulge)).collect();
            let closed = pl.is_closed();
            let (p, runs) = bulged(&v, closed, tol);
            add_piece(ctx, &src, p, closed, &runs)
        }
        EntityType::Polyline(pl) => {
            if let Some((k, b)) = bad_bulge(pl.vertices().map(|v| v.bulge)) {
                return Err(refuse(ctx, &src, &format!("bulge {b} at vertex {}", k + 1)));
            }
            let v: Vec<([f64; 2], f64)> = pl
                .vertices()
                .map(|v| ([v.location.x, v.location.y], v.bulge))
                .collect();
            let closed = pl.is_closed();
            let (p, runs) = bulged(&v, closed, tol);
            add_piece(ctx, &src, p, closed, &runs)
        }
        EntityType::Spline(s) => spline(ctx, s, &src),
        EntityType::Insert(ins) => insert(ctx, ins, &src, block_layer, depth),
        other => unsupported(
            ctx,
            &handle,
            &format!("{} is not supported", entity_name(other)),
        ),
    }
}

/// A SPLINE, flattened, after checking its degree and that the work of evaluating it stays
/// within [`MAX_SPLINE_WORK`] and the points within [`MAX_POINTS`].
fn spline(ctx: &mut Ctx, s: &dxf::entities::Spline, src: &Source) -> Result<()> {
    let degree = s.degree_of_curve.max(1) as usize;
    if degree > MAX_SPLINE_DEGREE && !s.control_points.is_empty() {
        let why = format!("degree {degree}: at most {MAX_SPLINE_DEGREE} is supported");
        return Err(refuse(ctx, src, &why));
    }
    let tol = ctx.opts.tolerance;
    let mut refusal = None;
    let pts = spline_points(s, tol, |samples| {
        let work = samples as f64 * ((degree + 1) * (degree + 1)) as f64;
        if ctx.points + samples > MAX_POINTS {
            refusal = Some(format!(
                "the drawing expands to more than {MAX_POINTS} points"
            ));
        } else if ctx.spline_work + work > MAX_SPLINE_WORK {
            refusal = Some(format!(
                "its splines take more than {MAX_SPLINE_WORK:e} steps to flatten (degree {degree}, {samples} points here; raise --tolerance)"
            ));
        } else {
            ctx.spline_work += work;
        }
        refusal.is_none()
    });
    if let Some(why) = refusal {
        return Err(refuse(ctx, src, &why));
    }
    match pts {
        Some(p) => add_piece(ctx, src, p, s.is_closed(), &[]),
        None => unsupported(
            ctx,
            src.handle,
            "SPLINE with inconsistent knots/control points",
        ),
    }
}

/// An INSERT: the block's entities under the insert's transform, once per array cell, on the
/// insert's layer where they are on layer 0. Every array cell counts toward [`MAX_VISITS`].
fn insert(
    ctx: &mut Ctx,
    ins: &dxf::entities::Insert,
    src: &Source,
    block_layer: Option<&str>,
    depth: usize,
) -> Result<()> {
    if depth > 16 {
        return Err(refuse(
            ctx,
            src,
            "blocks nested deeper than 16 (recursive?)",
        ));
    }
    let Some(b) = ctx.blocks.get(&ins.name).copied() else {
        let why = format!("unknown block '{}'", ins.name);
        return Err(refuse(ctx, src, &why));
    };
    let nums = [
        ins.location.x,
        ins.location.y,
        ins.rotation,
        ins.column_spacing,
        ins.row_spacing,
        ins.x_scale_factor,
        ins.y_scale_factor,
    ];
    if !nums.iter().all(|v| v.is_finite()) {
        return Err(refuse(ctx, src, "non-finite placement, scale or spacing"));
    }
    let (cols, rows) = (
        ins.column_count.max(1) as usize,
        ins.row_count.max(1) as usize,
    );
    if cols * rows > 100_000 {
        return Err(refuse(ctx, src, "array too large"));
    }
    let bl = if src.layer == "0" {
        block_layer.map(str::to_string)
    } else {
        Some(src.layer.to_string())
    };
    let at = At {
        top: src.at.top,
        block: Some(&b.name),
    };
    let deg = std::f64::consts::PI / 180.0;
    for r in 0..rows {
        for c in 0..cols {
            ctx.visits += 1;
            if ctx.visits > MAX_VISITS {
                let why = format!(
                    "the drawing expands to more than {MAX_VISITS} entities (nested arrays of blocks)"
                );
                return Err(refuse(ctx, src, &why));
            }
            let t = src.tf
                * Affine::translate((ins.location.x, ins.location.y))
                * Affine::rotate(ins.rotation * deg)
                * Affine::translate((c as f64 * ins.column_spacing, r as f64 * ins.row_spacing))
                * Affine::scale_non_uniform(ins.x_scale_factor, ins.y_scale_factor)
                * Affine::translate((-b.base_point.x, -b.base_point.y));
            for be in &b.entities {
                entity(ctx, be, t, bl.as_deref(), depth + 1, &at)?;
            }
        }
    }
    Ok(())
}

fn entity_name(e: &EntityType) -> String {
    let s = format!("{e:?}");
    s.split(['(', ' ', '{'])
        .next()
        .unwrap_or("entity")
        .to_uppercase()
}

fn unsupported(ctx: &mut Ctx, handle: &str, why: &str) -> Result<()> {
    if ctx.opts.skip_unsupported {
        ctx.skipped.push(format!("handle {handle}: {why}"));
        Ok(())
    } else {
        Err(Error::invalid(
            ctx.file,
            format!("entity with handle {handle}: {why} (--skip-unsupported skips it)"),
        ))
    }
}

/// The distinct endpoints of open pieces, on a grid of cells of twice the join tolerance, each
/// with its piece ends (piece, at its end) in piece order and a cursor past the used ones, so
/// that many pieces ending at one point cost no rescans.
struct Ends {
    cell: f64,
    points: Vec<[f64; 2]>,
    ends: Vec<Vec<(usize, bool)>>,
    next: Vec<usize>,
    grid: HashMap<(i64, i64), Vec<usize>>,
}

impl Ends {
    fn new(pieces: &[&Piece], tol: f64) -> Ends {
        let mut e = Ends {
            cell: tol.max(1e-12) * 2.0,
            points: Vec::new(),
            ends: Vec::new(),
            next: Vec::new(),
            grid: HashMap::new(),
        };
        let mut at: HashMap<[u64; 2], usize> = HashMap::new();
        for (i, p) in pieces.iter().enumerate() {
            if p.closed || p.pts.is_empty() {
                continue;
            }
            for (q, at_end) in [(p.pts[0], false), (*p.pts.last().expect("non-empty"), true)] {
                let id = *at
                    .entry([q[0].to_bits(), q[1].to_bits()])
                    .or_insert_with(|| {
                        e.points.push(q);
                        e.ends.push(Vec::new());
                        e.next.push(0);
                        let k = e.key(q);
                        e.grid.entry(k).or_default().push(e.points.len() - 1);
                        e.points.len() - 1
                    });
                e.ends[id].push((i, at_end));
            }
        }
        e
    }
    fn key(&self, p: [f64; 2]) -> (i64, i64) {
        (
            (p[0] / self.cell).floor() as i64,
            (p[1] / self.cell).floor() as i64,
        )
    }
    /// The unused piece end nearest `p` within `tol` (ties: the lower piece, its start
    /// first).
    fn near(&mut self, used: &[bool], p: [f64; 2], tol: f64) -> Option<(usize, bool)> {
        let (kx, ky) = self.key(p);
        let mut best: Option<(f64, usize, bool)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                let Some(sites) = self.grid.get(&(kx + dx, ky + dy)) else {
                    continue;
                };
                for &s in sites {
                    let list = &self.ends[s];
                    let k = &mut self.next[s];
                    while *k < list.len() && used[list[*k].0] {
                        *k += 1;
                    }
                    let Some(&(i, at_end)) = list.get(*k) else {
                        continue;
                    };
                    let q = self.points[s];
                    let d = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
                    if d <= tol && best.is_none_or(|b| (d, i) < (b.0, b.1)) {
                        best = Some((d, i, at_end));
                    }
                }
            }
        }
        best.map(|b| (b.1, b.2))
    }
}

/// Chains open pieces whose endpoints lie within `tol` (the joined vertex is the first
/// piece's); closed pieces pass through. Deterministic: pieces in file order. Linear in the
/// pieces (and the points) when many share an endpoint.
fn chain(pieces: &[&Piece], tol: f64) -> Vec<(Vec<[f64; 2]>, bool)> {
    let mut out = Vec::new();
    let mut ends = Ends::new(pieces, tol);
    let mut used = vec![false; pieces.len()];
    for (i, p) in pieces.iter().enumerate() {
        if p.closed {
            out.push((p.pts.clone(), true));
            continue;
        }
        if used[i] || p.pts.is_empty() {
            continue;
        }
        used[i] = true;
        let mut pts = p.pts.clone();
        // forward
        while let Some((j, at_end)) = ends.near(&used, *pts.last().expect("non-empty"), tol) {
            used[j] = true;
            let mut q = pieces[j].pts.clone();
            if at_end {
                q.reverse();
            }
            pts.extend(q.into_iter().skip(1));
        }
        // backward: the pieces found, put in front of the chain once at the end
        let mut front: Vec<[f64; 2]> = Vec::new();
        while let Some((j, at_end)) = ends.near(&used, front.last().copied().unwrap_or(pts[0]), tol)
        {
            used[j] = true;
            let q = &pieces[j].pts;
            // the piece drawn towards the chain, its last point (the joined vertex) dropped;
            // `front` holds the chain's front reversed
            let mut r: Vec<[f64; 2]> = if at_end {
                q.iter().rev().copied().collect()
            } else {
                q.clone()
            };
            r.remove(0);
            front.extend(r);
        }
        if !front.is_empty() {
            front.reverse();
            front.extend(pts);
            pts = front;
        }
        let closed = pts.len() >= 3 && {
            let (a, b) = (pts[0], *pts.last().expect("non-empty"));
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt() <= tol
        };
        if closed {
            pts.pop();
        }
        out.push((pts, closed));
    }
    out
}

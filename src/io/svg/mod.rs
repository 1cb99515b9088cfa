//! SVG drawings (pen plotters, lasers): read strokes, sequence them per scope (layer and
//! stroke colour) with a registry solver, optionally reversing them, write the drawing back
//! in the new order and verify that it draws exactly the same segments.
//!
//! [`read()`] parses the file (every subpath of every shape is one [`Stroke`], curves flattened
//! within a tolerance, transforms applied), [`optimize`] sequences, [`write()`] emits one
//! `<path>` per stroke grouped per layer, [`verify`] compares the multisets of segments
//! (direction-insensitive, per layer label, stroke colour and width).

pub mod read;
pub mod sequence;

use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{Cell, Instance, Machine, Metadata, Mode, Objective, StepKind, Tool, Visit};
use crate::solvers::{self, Budget, NoObserver};
use serde::Serialize;
use std::fmt::Write as _;

pub use read::{ReadOptions, read};

/// An Inkscape layer (index 0 is the document root, outside any layer).
#[derive(Debug, Clone, PartialEq)]
pub struct Layer {
    /// `inkscape:label` (or id).
    pub label: String,
    /// Element id.
    pub id: Option<String>,
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

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
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
    /// Coordinates are y-up (DXF): the SVG writer mirrors them with `scale(1,-1)`.
    pub flip_y: bool,
}

impl Drawing {
    fn style_index(&mut self, s: Style) -> usize {
        match self.styles.iter().position(|x| *x == s) {
            Some(i) => i,
            None => {
                self.styles.push(s);
                self.styles.len() - 1
            }
        }
    }
}

/// Name of the built-in drawing sequencer ([`sequence`]), the default for drawings.
pub const DRAWING_SOLVER: &str = "drawing";

/// Options of [`optimize`].
#[derive(Debug, Clone)]
pub struct Options {
    /// Solver name.
    pub solver: String,
    /// Total time limit (s), shared among scopes by size.
    pub time_limit: Option<f64>,
    /// Seed.
    pub seed: u64,
    /// Allow drawing strokes backwards / closed strokes from another vertex.
    pub reversible: bool,
    /// Layers and stroke colours are ordering scopes.
    pub scopes: bool,
    /// Cut mode: strokes inside a closed stroke come before it.
    pub cut: bool,
    /// Containment tolerance (user units).
    pub contain_tol: f64,
    /// Maximum start-vertex candidates of a closed stroke.
    pub max_starts: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            solver: DRAWING_SOLVER.to_string(),
            time_limit: None,
            seed: 1,
            reversible: true,
            scopes: true,
            cut: false,
            contain_tol: 0.01,
            max_starts: 8,
        }
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

/// Scopes in drawing order: each a list of stroke indices.
pub fn scopes(d: &Drawing, by_scope: bool) -> Vec<Vec<usize>> {
    if !by_scope {
        return vec![(0..d.strokes.len()).collect()];
    }
    let mut keys: Vec<(usize, String)> = Vec::new();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (i, s) in d.strokes.iter().enumerate() {
        let k = (s.layer, d.styles[s.style].stroke.clone());
        match keys.iter().position(|x| *x == k) {
            Some(g) => out[g].push(i),
            None => {
                keys.push(k);
                out.push(vec![i]);
            }
        }
    }
    let mut idx: Vec<usize> = (0..out.len()).collect();
    idx.sort_by_key(|&g| (keys[g].0, out[g][0]));
    idx.into_iter()
        .map(|g| std::mem::take(&mut out[g]))
        .collect()
}

/// Start-vertex candidates of a closed stroke (all when few, else evenly spaced).
fn starts_of(s: &Stroke, max: usize) -> Vec<usize> {
    let n = s.points.len();
    if !s.closed {
        return vec![0];
    }
    let k = n.min(max.max(1));
    (0..k).map(|i| i * n / k).collect()
}

fn bbox(s: &Stroke) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in &s.points {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Point in polygon (even-odd) or within `tol` of its boundary.
fn inside(p: [f64; 2], poly: &[[f64; 2]], tol: f64) -> bool {
    let n = poly.len();
    let mut c = false;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if seg_dist(p, a, b) <= tol {
            return true;
        }
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                c = !c;
            }
        }
    }
    c
}

/// Cut-mode precedence within a scope (local indices): a stroke whose points all lie inside a
/// closed stroke with a larger bounding box (with tolerance) comes before it.
pub fn containment(d: &Drawing, scope: &[usize], tol: f64) -> Vec<(usize, usize)> {
    let boxes: Vec<[f64; 4]> = scope.iter().map(|&i| bbox(&d.strokes[i])).collect();
    let area = |b: &[f64; 4]| (b[2] - b[0]).max(0.0) * (b[3] - b[1]).max(0.0);
    let mut outers: Vec<usize> = (0..scope.len())
        .filter(|&k| d.strokes[scope[k]].closed && d.strokes[scope[k]].points.len() >= 3)
        .collect();
    outers.sort_by(|&a, &b| area(&boxes[a]).total_cmp(&area(&boxes[b])));
    let mut edges = Vec::new();
    for a in 0..scope.len() {
        let ba = boxes[a];
        let aa = area(&ba);
        let sa = &d.strokes[scope[a]];
        for &b in &outers {
            let bb = boxes[b];
            if b == a || area(&bb) <= aa + tol * tol {
                continue;
            }
            if ba[0] < bb[0] - tol
                || ba[1] < bb[1] - tol
                || ba[2] > bb[2] + tol
                || ba[3] > bb[3] + tol
            {
                continue;
            }
            let poly = &d.strokes[scope[b]].points;
            if sa.points.iter().all(|&p| inside(p, poly, tol)) {
                edges.push((a, b));
            }
        }
    }
    edges
}

/// Cut mode: reorders scopes so that a scope whose closed strokes enclose strokes of another
/// scope comes after it (stable topological order; file order kept where containment is
/// cyclic or absent).
pub fn inner_scopes_first(d: &Drawing, sc: Vec<Vec<usize>>, tol: f64) -> Vec<Vec<usize>> {
    let all: Vec<usize> = sc.iter().flatten().copied().collect();
    let mut scope_of = vec![0usize; d.strokes.len()];
    for (k, s) in sc.iter().enumerate() {
        for &i in s {
            scope_of[i] = k;
        }
    }
    let m = sc.len();
    let mut before = vec![vec![false; m]; m]; // before[a][b]: a must precede b
    for (a, b) in containment(d, &all, tol) {
        let (sa, sb) = (scope_of[all[a]], scope_of[all[b]]);
        if sa != sb {
            before[sa][sb] = true;
        }
    }
    let mut placed = vec![false; m];
    let mut order = Vec::with_capacity(m);
    while order.len() < m {
        // the first unplaced scope with no unplaced predecessor; file order on a cycle
        let next = (0..m)
            .find(|&b| !placed[b] && (0..m).all(|a| placed[a] || a == b || !before[a][b]))
            .unwrap_or_else(|| (0..m).find(|&b| !placed[b]).expect("unplaced scope"));
        placed[next] = true;
        order.push(next);
    }
    let mut sc = sc;
    order
        .into_iter()
        .map(|k| std::mem::take(&mut sc[k]))
        .collect()
}

/// The instance of one scope, starting at `home`; also the (reverse, start vertex) of each
/// mode of each cell.
pub fn scope_instance(
    d: &Drawing,
    scope: &[usize],
    home: [f64; 2],
    opts: &Options,
) -> (Instance, Vec<Vec<(bool, usize)>>) {
    let mut orient = Vec::with_capacity(scope.len());
    let cells: Vec<Cell> = scope
        .iter()
        .map(|&i| {
            let s = &d.strokes[i];
            let p = |q: [f64; 2]| Point3::new(q[0], q[1], 0.0);
            let mut modes = Vec::new();
            let mut or = Vec::new();
            if s.closed {
                let ks = if opts.reversible {
                    starts_of(s, opts.max_starts)
                } else {
                    vec![0]
                };
                for k in ks {
                    modes.push(Mode::closed(p(s.points[k])));
                    or.push((false, k));
                }
            } else {
                modes.push(Mode::new(p(s.start()), p(s.end())));
                or.push((false, 0));
                if opts.reversible && !s.is_dot() {
                    modes.push(Mode::new(p(s.end()), p(s.start())));
                    or.push((true, 0));
                }
            }
            orient.push(or);
            let mut c = Cell::new(format!("s{}", i + 1), "pen", modes);
            c.reversible = opts.reversible && !s.closed && !s.is_dot();
            c.step = StepKind::Engrave;
            c.cut_length = s.length();
            c.layer = s.layer as u32;
            c.feature = Some(format!("line {}", s.line));
            c
        })
        .collect();
    let precedence = if opts.cut {
        containment(d, scope, opts.contain_tol)
    } else {
        Vec::new()
    };
    let n = cells.len();
    let inst = Instance {
        name: d.file.clone(),
        meta: Metadata {
            generator: Some("svg".into()),
            ..Metadata::default()
        },
        machine: Machine {
            home: Point3::new(home[0], home[1], 0.0),
            tool_change: Point3::new(home[0], home[1], 0.0),
            clearance: 0.0,
            initial_tool: Some("pen".into()),
            ..Machine::default()
        },
        tools: vec![Tool {
            id: "pen".into(),
            diameter: 1.0,
            name: None,
            feed: None,
        }],
        cells,
        precedence,
        as_given: Some((0..n).map(|i| Visit::new(i, 0)).collect()),
        ..Instance::default()
    };
    (inst, orient)
}

/// The whole drawing as one instance (scopes chained by precedence), for `cellseq import`.
pub fn import(d: &Drawing, opts: &Options) -> Result<Instance> {
    let mut sc = scopes(d, opts.scopes);
    if opts.cut && sc.len() > 1 {
        sc = inner_scopes_first(d, sc, opts.contain_tol);
    }
    let all: Vec<usize> = sc.iter().flatten().copied().collect();
    let (mut inst, _) = scope_instance(
        d,
        &all,
        [0.0, 0.0],
        &Options {
            cut: false,
            ..opts.clone()
        },
    );
    let mut edges = Vec::new();
    let mut start = 0;
    for (k, s) in sc.iter().enumerate() {
        if opts.cut {
            edges.extend(
                containment(d, s, opts.contain_tol)
                    .into_iter()
                    .map(|(a, b)| (a + start, b + start)),
            );
        }
        if k + 1 < sc.len() {
            if edges.len() + s.len() * sc[k + 1].len() > 20_000_000 {
                return Err(Error::invalid(
                    &d.file,
                    "too many scope precedence edges to export",
                ));
            }
            let next = start + s.len();
            for a in 0..s.len() {
                for b in 0..sc[k + 1].len() {
                    edges.push((start + a, next + b));
                }
            }
        }
        start += s.len();
    }
    inst.precedence = edges;
    Ok(inst)
}

/// The result of [`optimize`].
#[derive(Debug, Clone)]
pub struct Optimized {
    /// The strokes in the new order and orientation.
    pub strokes: Vec<Stroke>,
    /// Figures of the file's order.
    pub before: PenUp,
    /// Figures of the new order.
    pub after: PenUp,
    /// Solver seconds.
    pub solve_s: f64,
    /// Number of scopes.
    pub scopes: usize,
    /// Precedence edges (cut mode).
    pub edges: usize,
    /// The solver's order was worse than the file's in some scope; that scope kept its order.
    pub kept_original: usize,
}

fn layer_label(d: &Drawing) -> impl Fn(&Stroke) -> String + '_ {
    move |s: &Stroke| d.layers[s.layer].label.clone()
}

/// Sequences each scope with a registry solver (air-travel objective, start at the previous
/// scope's exit, the first at the origin).
pub fn optimize(d: &Drawing, opts: &Options) -> Result<Optimized> {
    let mut sc = scopes(d, opts.scopes);
    if opts.cut && sc.len() > 1 {
        sc = inner_scopes_first(d, sc, opts.contain_tol);
    }
    let total = d.strokes.len().max(1);
    let mut home = [0.0, 0.0];
    let mut out: Vec<Stroke> = Vec::with_capacity(d.strokes.len());
    let mut solve_s = 0.0;
    let mut edges = 0;
    let mut kept = 0;
    for s in &sc {
        let (inst, orient) = scope_instance(d, s, home, opts);
        edges += inst.precedence.len();
        crate::validate::validate(&inst, &d.file)?;
        let budget = Budget {
            time_limit: opts
                .time_limit
                .map(|t| std::time::Duration::from_secs_f64(t * s.len() as f64 / total as f64)),
            max_evals: None,
        };
        let (seq, cost) = if opts.solver == DRAWING_SOLVER {
            let t = std::time::Instant::now();
            let seq = sequence::solve(&inst, budget.time_limit.map(|d| d.as_secs_f64()));
            solve_s += t.elapsed().as_secs_f64();
            // the independent checker, as for registry solvers
            let rep =
                crate::check::check(&inst, &seq, Objective::Air).map_err(|v| Error::Solver {
                    solver: DRAWING_SOLVER.into(),
                    msg: format!("infeasible sequence: {v}"),
                })?;
            (seq, rep.cost)
        } else {
            let r = solvers::run(
                &opts.solver,
                &inst,
                Objective::Air,
                &Default::default(),
                opts.seed,
                budget,
                &mut NoObserver,
            )?;
            solve_s += r.elapsed_s;
            (r.outcome.sequence, r.report.cost)
        };
        let given = inst.as_given.clone().unwrap_or_default();
        let given_cost = crate::check::check(&inst, &given, Objective::Air)
            .map(|r| r.cost)
            .unwrap_or(f64::INFINITY);
        let seq: Vec<Visit> = if cost > given_cost + 1e-9 {
            kept += 1;
            given
        } else {
            seq
        };
        for v in &seq {
            let (rev, k) = orient[v.cell][v.mode];
            out.push(d.strokes[s[v.cell]].oriented(rev, k));
        }
        if let Some(l) = out.last() {
            home = l.end();
        }
    }
    let key = layer_label(d);
    Ok(Optimized {
        before: pen_up(&d.strokes, d.mm_per_unit, &key),
        after: pen_up(&out, d.mm_per_unit, &key),
        strokes: out,
        solve_s,
        scopes: sc.len(),
        edges,
        kept_original: kept,
    })
}

/// Formats a coordinate with 6 decimals, trailing zeros trimmed.
pub fn num(v: f64) -> String {
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
    let mut cur: Option<usize> = None;
    for s in strokes {
        if cur != Some(s.layer) {
            if cur.is_some() {
                o.push_str("</g>\n");
            }
            let l = &d.layers[s.layer];
            if s.layer == 0 {
                o.push_str("<g>\n");
            } else {
                let _ = writeln!(
                    o,
                    "<g inkscape:groupmode=\"layer\" inkscape:label=\"{}\">",
                    esc(&l.label)
                );
            }
            cur = Some(s.layer);
        }
        let st = &d.styles[s.style];
        let _ = write!(
            o,
            "<path style=\"fill:none;stroke:{};stroke-width:{}\" d=\"M{},{}",
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
    if d.flip_y {
        o.push_str("</g>\n");
    }
    o.push_str("</svg>\n");
    o
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
    for s in strokes {
        let st = &d.styles[s.style];
        let k = (
            d.layers[s.layer].label.clone(),
            st.stroke.clone(),
            num(st.width).parse::<f64>().unwrap_or(st.width).to_bits(),
        );
        let next = intern.len() as u32;
        let id = *intern.entry(k).or_insert(next);
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
    let a = seg_keys(orig, &orig.strokes, &mut intern, true);
    let b = seg_keys(&w, &w.strokes, &mut intern, false);
    let names: Vec<String> = {
        let mut v = vec![String::new(); intern.len()];
        for ((l, c, _), &i) in &intern {
            v[i as usize] = format!("layer '{l}' {c}");
        }
        v
    };
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

//! The DXF G-code post: per contour a rapid at the safe height, a plunge, the contour's feed
//! moves and a retract (a laser post: no Z words, `M4 S…`). Runs of chords that lie on one arc
//! of the file (ARC, CIRCLE, bulges; [`Drawing::arc_of`]) are written as one G2/G3 of at most
//! a half turn (a circle as two or more arcs), the rest as G1. [`verify_gcode`] reads the text
//! back with the G-code interpreter and checks it cuts exactly the drawing's segments: every
//! arc is traced back along the chords it replaces, each of which must lie on an arc of the
//! file with the same centre, radius and direction.

use crate::drawing::{self as svg, Drawing, Stroke};
use crate::gcode::interp::{self, CutKind};
use cellseq::error::{Error, Result};
use std::collections::HashMap;
use std::fmt::Write as _;

/// Parameters of the G-code post.
#[derive(Debug, Clone, Copy)]
pub struct Post {
    /// Safe (travel) height, mm.
    pub safe_height: f64,
    /// Cutting depth (Z = -depth), mm.
    pub depth: f64,
    /// Cutting feed, mm/min.
    pub feed: f64,
    /// Plunge feed, mm/min.
    pub plunge_feed: f64,
    /// Spindle speed (`M3 S…` before the first cut, `M5` at the end); 0 writes no spindle
    /// words (the operator's spindle state is left alone).
    pub spindle: f64,
    /// Laser power: a laser post (`M4 S…`, power scaled with speed on GRBL-style controllers,
    /// off on rapids; `M5` at the end) with no Z moves at all; 0 = not a laser post.
    pub laser_power: f64,
}

impl Default for Post {
    fn default() -> Self {
        Post {
            safe_height: 5.0,
            depth: 1.0,
            feed: 1000.0,
            plunge_feed: 300.0,
            spindle: 0.0,
            laser_power: 0.0,
        }
    }
}

/// Writes strokes (drawing units, converted to mm) as G-code: per stroke a rapid at the safe
/// height, a plunge, the feed moves, a retract; with a laser power, per stroke a rapid and
/// the feed moves (no Z words).
pub fn write_gcode(d: &Drawing, strokes: &[Stroke], post: &Post) -> String {
    let laser = post.laser_power > 0.0;
    let k = d.mm_per_unit;
    let f = |v: f64| svg::num(v * k);
    let mut o = String::new();
    let _ = writeln!(
        o,
        "(cellseq: {} strokes from {})",
        strokes.len(),
        d.file.replace(['(', ')'], "")
    );
    o.push_str("G21 G90 G17 G94\n");
    if laser {
        let _ = writeln!(o, "M4 S{}", svg::num(post.laser_power));
    } else {
        let _ = writeln!(o, "G0 Z{}", svg::num(post.safe_height));
        if post.spindle > 0.0 {
            let _ = writeln!(o, "M3 S{}", svg::num(post.spindle));
        }
    }
    let mut layer = usize::MAX;
    for s in strokes {
        if s.layer != layer {
            let _ = writeln!(
                o,
                "(layer {})",
                d.layers[s.layer].label.replace(['(', ')'], "")
            );
            layer = s.layer;
        }
        let p0 = s.points[0];
        let _ = writeln!(o, "G0 X{} Y{}", f(p0[0]), f(p0[1]));
        if !laser {
            let _ = writeln!(
                o,
                "G1 Z{} F{}",
                svg::num(-post.depth),
                svg::num(post.plunge_feed)
            );
        }
        if s.is_dot() {
            let _ = writeln!(o, "G1 X{} Y{} F{}", f(p0[0]), f(p0[1]), svg::num(post.feed));
        } else {
            feed_moves(&mut o, d, s, post);
        }
        if !laser {
            let _ = writeln!(o, "G0 Z{}", svg::num(post.safe_height));
        }
    }
    if post.spindle > 0.0 || laser {
        o.push_str("M5\n");
    }
    o.push_str("M2\n");
    o
}

/// The feed moves of one stroke: G1 per chord, G2/G3 per run of chords on one arc of the file
/// (same centre, radius and direction, at most a half turn), the feed on the first move.
fn feed_moves(o: &mut String, d: &Drawing, s: &Stroke, post: &Post) {
    let k = d.mm_per_unit;
    let f = |v: f64| svg::num(v * k);
    let segs = s.segments();
    let mut feed = format!(" F{}", svg::num(post.feed));
    let mut i = 0;
    while i < segs.len() {
        let (a, b) = segs[i];
        let Some(arc) = d.arc_of(a, b) else {
            let _ = writeln!(o, "G1 X{} Y{}{feed}", f(b[0]), f(b[1]));
            feed.clear();
            i += 1;
            continue;
        };
        let mut sweep = chord_angle(arc.radius, a, b);
        let mut j = i + 1;
        while let Some(&(p, q)) = segs.get(j) {
            let turn = chord_angle(arc.radius, p, q);
            if d.arc_of(p, q) != Some(arc) || sweep + turn > std::f64::consts::PI + 1e-9 {
                break;
            }
            sweep += turn;
            j += 1;
        }
        let end = segs[j - 1].1;
        let _ = writeln!(
            o,
            "{} X{} Y{} I{} J{}{feed}",
            if arc.ccw { "G3" } else { "G2" },
            f(end[0]),
            f(end[1]),
            f(arc.center[0] - a[0]),
            f(arc.center[1] - a[1])
        );
        feed.clear();
        i = j;
    }
}

/// The angle a chord a–b spans on a circle of radius `r`.
fn chord_angle(r: f64, a: [f64; 2], b: [f64; 2]) -> f64 {
    2.0 * (svg::dist(a, b) / (2.0 * r)).clamp(0.0, 1.0).asin()
}

/// A chord (mm): from, to.
type Chord = ([f64; 2], [f64; 2]);

/// Bits of a point in mm as the post writes it (6 decimals).
type PointKey = [u64; 2];

/// For each end of an arc chord (mm, 6 decimals): the other end, the centre and radius (mm) and
/// whether the chord runs counter-clockwise from this end.
type ArcChords = HashMap<PointKey, Vec<([f64; 2], [f64; 2], f64, bool)>>;

fn arc_chords(d: &Drawing, r: &impl Fn(f64) -> f64) -> ArcChords {
    let k = d.mm_per_unit;
    let mut m: ArcChords = HashMap::new();
    let mm = |p: [f64; 2]| [r(p[0] * k), r(p[1] * k)];
    for s in &d.strokes {
        for (a, b) in s.segments() {
            if let Some(arc) = d.arc_of(a, b) {
                let c = [arc.center[0] * k, arc.center[1] * k];
                let (a, b) = (mm(a), mm(b));
                let rad = arc.radius * k;
                m.entry(a.map(f64::to_bits))
                    .or_default()
                    .push((b, c, rad, arc.ccw));
                m.entry(b.map(f64::to_bits))
                    .or_default()
                    .push((a, c, rad, !arc.ccw));
            }
        }
    }
    m
}

/// The chords (mm) an arc move from `from` to `to` about `center` replaces: walked from
/// `from` along chords of the file on the same circle in the same direction until `to`.
fn trace_arc(
    chords: &ArcChords,
    from: [f64; 2],
    to: [f64; 2],
    center: [f64; 2],
    ccw: bool,
) -> std::result::Result<Vec<Chord>, String> {
    let radius = svg::dist(from, center);
    let tol = 1e-4 + 1e-7 * radius;
    if (svg::dist(to, center) - radius).abs() > tol {
        return Err(format!(
            "arc radius {radius} at its start differs from {} at its end",
            svg::dist(to, center)
        ));
    }
    let mut out = Vec::new();
    let mut at = from;
    let limit = chords.len() + 1;
    while out.is_empty() || at != to {
        let next = chords.get(&at.map(f64::to_bits)).and_then(|v| {
            v.iter().find(|(_, c, r, dir)| {
                *dir == ccw && svg::dist(*c, center) <= tol && (r - radius).abs() <= tol
            })
        });
        let Some(&(q, ..)) = next else {
            return Err(format!(
                "arc about ({}, {}) leaves the arcs of the drawing at ({}, {})",
                center[0], center[1], at[0], at[1]
            ));
        };
        out.push((at, q));
        at = q;
        if out.len() > limit {
            return Err("arc does not end on a chord end of the drawing".into());
        }
    }
    Ok(out)
}

/// Checks that a G-code text written by [`write_gcode`] cuts exactly the drawing's segments
/// (direction-insensitive multiset, mm, 6-decimal rounding) at the cutting depth; dots are
/// the zero-length feed move after the plunge. Returns the number of segments.
pub fn verify_gcode(d: &Drawing, name: &str, text: &str, post: &Post) -> Result<usize> {
    let prog = interp::interpret(text).map_err(|(l, m)| Error::parse(name, l, m))?;
    // the writer's rounding (num, read back)
    let r = crate::drawing::round6;
    let norm = |a: [f64; 2], b: [f64; 2]| {
        let (a, b) = if (a[0], a[1]) <= (b[0], b[1]) {
            (a, b)
        } else {
            (b, a)
        };
        [
            a[0].to_bits(),
            a[1].to_bits(),
            b[0].to_bits(),
            b[1].to_bits(),
        ]
    };
    let chords = arc_chords(d, &r);
    let mut got = Vec::new();
    for li in &prog.lines {
        for c in &li.cuts {
            let arc = match c.kind {
                CutKind::Line => None,
                CutKind::Arc {
                    center,
                    cw,
                    plane: 17,
                    turns: 1,
                } => Some((center, cw)),
                _ => {
                    return Err(Error::invalid(
                        name,
                        format!("line {}: unexpected arc or cycle", li.line),
                    ));
                }
            };
            if arc.is_none() && (c.from[2] - c.to[2]).abs() > 1e-9 {
                continue; // plunge
            }
            if post.laser_power <= 0.0 && (c.from[2] + post.depth).abs() > 1e-6 {
                return Err(Error::invalid(
                    name,
                    format!("line {}: feed move off the cutting depth", li.line),
                ));
            }
            let (from, to) = ([r(c.from[0]), r(c.from[1])], [r(c.to[0]), r(c.to[1])]);
            match arc {
                None => got.push(norm(from, to)),
                Some((center, cw)) => {
                    let path = trace_arc(&chords, from, to, [center[0], center[1]], !cw)
                        .map_err(|e| Error::invalid(name, format!("line {}: {e}", li.line)))?;
                    got.extend(path.into_iter().map(|(a, b)| norm(a, b)));
                }
            }
        }
    }
    let k = d.mm_per_unit;
    let mut want = Vec::new();
    for s in &d.strokes {
        for (a, b) in s.segments() {
            want.push(norm([r(a[0] * k), r(a[1] * k)], [r(b[0] * k), r(b[1] * k)]));
        }
    }
    got.sort_unstable();
    want.sort_unstable();
    if got != want {
        return Err(Error::invalid(
            name,
            format!(
                "not equivalent to {}: {} cutting segments vs {}",
                d.file,
                got.len(),
                want.len()
            ),
        ));
    }
    Ok(want.len())
}

//! Equivalence check between two programs and their travel figures.

use super::interp::{Cut, CutKind, Motion, Program};
use serde::Serialize;

/// Rapid rate assumed for time estimates (mm/min).
pub const RAPID_MM_MIN: f64 = 5000.0;
/// Time assumed per tool change (s).
pub const TOOL_CHANGE_S: f64 = 10.0;

/// Figures of one program.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Figures {
    /// Cutting moves.
    pub cuts: usize,
    /// Cut length (mm).
    pub cut_length: f64,
    /// Rapid (air) length (mm), moves with known ends.
    pub air_length: f64,
    /// Lifts: rises from below the safe height to it (Z programs) or feed→rapid switches (2-D).
    pub lifts: usize,
    /// Tool changes.
    pub tool_changes: usize,
    /// Estimated time (s): cuts at their feed, rapids at [`RAPID_MM_MIN`], changes at [`TOOL_CHANGE_S`].
    pub est_time_s: f64,
}

/// Measures a program; `safe` is the safe height for counting lifts (`None` for 2-D programs).
pub fn figures(p: &Program, safe: Option<f64>) -> Figures {
    let mut f = Figures::default();
    let mut cut_time = 0.0;
    let mut cutting = false;
    for li in &p.lines {
        f.air_length += li.rapid_len;
        if li.tool_change {
            f.tool_changes += 1;
        }
        for c in &li.cuts {
            f.cuts += 1;
            let len = c.length();
            f.cut_length += len;
            if c.feed > 0.0 {
                cut_time += len / c.feed * 60.0;
            }
        }
        match safe {
            Some(s) => {
                if let (Some(a), Some(b)) = (li.pos_before[2], li.pos_after[2])
                    && a < s - 1e-6
                    && b >= s - 1e-6
                {
                    f.lifts += 1;
                }
                if li.motion == Motion::Cycle {
                    f.lifts += 1;
                }
            }
            None => match li.motion {
                Motion::Feed => cutting = true,
                Motion::Rapid | Motion::Home if cutting => {
                    f.lifts += 1;
                    cutting = false;
                }
                _ => {}
            },
        }
    }
    f.est_time_s =
        cut_time + f.air_length / RAPID_MM_MIN * 60.0 + f.tool_changes as f64 * TOOL_CHANGE_S;
    f
}

fn key(c: &Cut, tol: f64) -> Vec<i64> {
    let q = |v: f64| (v / tol).round() as i64;
    let mut k = vec![c.tool as i64, c.offset as i64, q(c.feed), q(c.speed)];
    match c.kind {
        CutKind::Line => k.push(0),
        CutKind::Arc {
            center,
            cw,
            plane,
            turns,
        } => {
            k.extend([1, cw as i64, plane as i64, turns as i64]);
            k.extend(center.iter().map(|&v| q(v)));
        }
        CutKind::Cycle {
            code,
            r,
            p,
            q: qq,
            l,
        } => {
            k.extend([2, code as i64, q(r), q(p), q(qq), l as i64]);
        }
    }
    k.extend(c.from.iter().chain(c.to.iter()).map(|&v| q(v)));
    k
}

fn same(a: &Cut, b: &Cut, tol: f64) -> bool {
    let close = |x: f64, y: f64| (x - y).abs() <= tol;
    let pts = a
        .from
        .iter()
        .zip(&b.from)
        .chain(a.to.iter().zip(&b.to))
        .all(|(x, y)| close(*x, *y));
    let kinds = match (a.kind, b.kind) {
        (CutKind::Line, CutKind::Line) => true,
        (
            CutKind::Arc {
                center: c1,
                cw: w1,
                plane: p1,
                turns: t1,
            },
            CutKind::Arc {
                center: c2,
                cw: w2,
                plane: p2,
                turns: t2,
            },
        ) => w1 == w2 && p1 == p2 && t1 == t2 && c1.iter().zip(&c2).all(|(x, y)| close(*x, *y)),
        (
            CutKind::Cycle {
                code: c1,
                r: r1,
                p: p1,
                q: q1,
                l: l1,
            },
            CutKind::Cycle {
                code: c2,
                r: r2,
                p: p2,
                q: q2,
                l: l2,
            },
        ) => c1 == c2 && l1 == l2 && close(r1, r2) && close(p1, p2) && close(q1, q2),
        _ => false,
    };
    pts && kinds
        && a.tool == b.tool
        && a.offset == b.offset
        && close(a.feed, b.feed)
        && close(a.speed, b.speed)
}

fn describe(c: &Cut) -> String {
    format!(
        "T{} {:?} from ({:.4}, {:.4}, {:.4}) to ({:.4}, {:.4}, {:.4}) F{:.3} S{}",
        c.tool, c.kind, c.from[0], c.from[1], c.from[2], c.to[0], c.to[1], c.to[2], c.feed, c.speed
    )
}

/// The move in a direction-free form: straight moves and arcs run from their smaller end
/// (lexicographic on the `tol` grid) to the larger one, an arc flipped this way has its
/// direction swapped (same centre, same points cut); a full circle counts as counter-clockwise.
/// Canned-cycle holes are unchanged.
pub fn undirected(c: &Cut, tol: f64) -> Cut {
    if matches!(c.kind, CutKind::Cycle { .. }) {
        return *c;
    }
    let q = |p: &[f64; 3]| p.map(|v| (v / tol).round() as i64);
    let (f, t) = (q(&c.from), q(&c.to));
    let mut out = *c;
    if f > t {
        out.from = c.to;
        out.to = c.from;
        if let CutKind::Arc { cw, .. } = &mut out.kind {
            *cw = !*cw;
        }
    } else if f == t
        && let CutKind::Arc { cw, .. } = &mut out.kind
    {
        *cw = false;
    }
    out
}

/// Checks that both programs make the same multiset of cutting moves (per tool, with feed,
/// speed and work offset), within `tol` mm. Zero-length moves are ignored. With `undirected`,
/// a move cut backwards (see [`undirected`]) counts as the same move.
pub fn same_cuts(
    a: &Program,
    b: &Program,
    tol: f64,
    undirected_match: bool,
) -> Result<usize, String> {
    let collect = |p: &Program| {
        let mut v: Vec<(Vec<i64>, Cut)> = p
            .lines
            .iter()
            .flat_map(|l| l.cuts.iter())
            .filter(|c| !matches!(c.kind, CutKind::Line) || c.length() > 1e-9)
            .map(|c| {
                if undirected_match {
                    undirected(c, tol)
                } else {
                    *c
                }
            })
            .map(|c| (key(&c, tol), c))
            .collect();
        v.sort_by(|x, y| x.0.cmp(&y.0));
        v
    };
    let (ka, kb) = (collect(a), collect(b));
    if ka.len() != kb.len() {
        return Err(format!(
            "cutting move counts differ: {} vs {}",
            ka.len(),
            kb.len()
        ));
    }
    for (x, y) in ka.iter().zip(&kb) {
        if !same(&x.1, &y.1, tol) {
            return Err(format!(
                "cutting moves differ: first mismatch {} vs {}",
                describe(&x.1),
                describe(&y.1)
            ));
        }
    }
    Ok(ka.len())
}

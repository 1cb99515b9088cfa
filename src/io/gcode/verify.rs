//! Equivalence check between two programs and their travel figures.

use super::interp::{Cut, CutKind, LineInfo, Motion, Program, Tag};
use serde::Serialize;
use std::hash::{Hash, Hasher};

/// Straight moves shorter than this (mm) are not compared: they cut nothing.
pub const ZERO_MOVE: f64 = 1e-6;

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

impl Figures {
    /// True when these figures are no worse than `base` on air travel, lifts and estimated
    /// time, each one (to rounding).
    pub fn not_worse_than(&self, base: &Figures) -> bool {
        let le = |a: f64, b: f64| a <= b + 1e-9 * b.abs().max(1.0);
        le(self.air_length, base.air_length)
            && self.lifts <= base.lifts
            && le(self.est_time_s, base.est_time_s)
    }
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

fn hash128<T: Hash>(v: &T) -> u128 {
    let mut a = std::hash::DefaultHasher::new();
    v.hash(&mut a);
    let mut b = std::hash::DefaultHasher::new();
    0x9e37_79b9_7f4a_7c15_u64.hash(&mut b);
    v.hash(&mut b);
    ((a.finish() as u128) << 64) | b.finish() as u128
}

/// The state a line's cutting moves and events run in.
fn tag(li: &LineInfo) -> Tag {
    li.after.tag()
}

/// What two programs were found to share by [`equivalent`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Equivalence {
    /// Cutting moves matched, each with its machine state.
    pub cuts: usize,
    /// Events matched (dwells, pauses, tool changes, coordinate-system changes, user M codes,
    /// controller lines), each with its machine state.
    pub events: usize,
}

/// The full check of a rewritten program `b` against its original `a`: the same multiset of
/// cutting moves, each tagged with the machine state it runs in ([`Tag`]: spindle, speed,
/// coolant, feed, tool and length offset, units, plane, distance modes, work offset and
/// coordinate-system changes, path mode, cutter compensation, and which of them the program
/// set at all); the same multiset of events with their state (tool changes and moves to
/// machine positions: at most the original's, fewer when tool blocks were merged); and no new
/// motion: the original's motions before its first cut come first, unchanged, and every rapid
/// across in X/Y runs no lower than the original ever rapids across with that tool.
pub fn equivalent(
    a: &Program,
    b: &Program,
    tol: f64,
    undirected_match: bool,
) -> Result<Equivalence, String> {
    let cuts = same_cuts(a, b, tol, undirected_match)?;
    let events = same_events(a, b)?;
    no_new_motion(a, b, tol)?;
    Ok(Equivalence { cuts, events })
}

/// Checks that both programs make the same multiset of cutting moves, each in the same machine
/// state ([`Tag`]), within `tol` mm. Zero-length straight moves are ignored. With
/// `undirected_match`, a move cut backwards (see [`undirected`]) counts as the same move.
pub fn same_cuts(
    a: &Program,
    b: &Program,
    tol: f64,
    undirected_match: bool,
) -> Result<usize, String> {
    let cut = |c: &Cut| {
        if undirected_match {
            undirected(c, tol)
        } else {
            *c
        }
    };
    let collect = |p: &Program| {
        let mut v: Vec<(u128, u32, u32)> = Vec::new();
        for (i, li) in p.lines.iter().enumerate() {
            let t = tag(li);
            for (j, c) in li.cuts.iter().enumerate() {
                if matches!(c.kind, CutKind::Line) && c.length() <= ZERO_MOVE {
                    continue;
                }
                let c = cut(c);
                v.push((hash128(&(key(&c, tol), c.partial, t)), i as u32, j as u32));
            }
        }
        v.sort_unstable();
        v
    };
    let (ka, kb) = (collect(a), collect(b));
    // pair equal hashes; what is left (values that fell on both sides of a grid line) is
    // paired by the tolerance test itself
    let (mut ua, mut ub) = (Vec::new(), Vec::new());
    let (mut i, mut j) = (0, 0);
    while i < ka.len() || j < kb.len() {
        match (ka.get(i), kb.get(j)) {
            (Some(x), Some(y)) if x.0 == y.0 => {
                i += 1;
                j += 1;
            }
            (Some(x), Some(y)) if x.0 < y.0 => {
                ua.push(*x);
                i += 1;
            }
            (Some(x), None) => {
                ua.push(*x);
                i += 1;
            }
            (_, Some(y)) => {
                ub.push(*y);
                j += 1;
            }
            (None, None) => break,
        }
    }
    if ua.len() == ub.len() && ua.len() <= 10_000 {
        let get = |p: &Program, x: &(u128, u32, u32)| {
            let li = &p.lines[x.1 as usize];
            (cut(&li.cuts[x.2 as usize]), tag(li))
        };
        let mut taken = vec![false; ub.len()];
        let all = ua.iter().all(|x| {
            let (ca, ta) = get(a, x);
            let hit = ub.iter().enumerate().position(|(k, y)| {
                let (cb, tb) = get(b, y);
                !taken[k] && ta == tb && ca.partial == cb.partial && same(&ca, &cb, tol)
            });
            hit.map(|k| taken[k] = true).is_some()
        });
        if all {
            return Ok(ka.len());
        }
    }
    Err(mismatch(a, b, &ka, &kb, &cut))
}

/// Describes the first cutting move of one program that the other lacks.
fn mismatch(
    a: &Program,
    b: &Program,
    ka: &[(u128, u32, u32)],
    kb: &[(u128, u32, u32)],
    cut: &dyn Fn(&Cut) -> Cut,
) -> String {
    let (mut i, mut j) = (0, 0);
    let mut lone: Option<(bool, (u128, u32, u32))> = None;
    while i < ka.len() || j < kb.len() {
        match (ka.get(i), kb.get(j)) {
            (Some(x), Some(y)) if x.0 == y.0 => {
                i += 1;
                j += 1;
            }
            (Some(x), Some(y)) if x.0 < y.0 => {
                lone = Some((true, *x));
                break;
            }
            (Some(_), Some(y)) => {
                lone = Some((false, *y));
                break;
            }
            (Some(x), None) => {
                lone = Some((true, *x));
                break;
            }
            (None, Some(y)) => {
                lone = Some((false, *y));
                break;
            }
            (None, None) => break,
        }
    }
    let counts = format!("{} vs {} cutting moves", ka.len(), kb.len());
    let Some((in_a, x)) = lone else {
        return format!("cutting moves differ ({counts})");
    };
    let (p, q) = if in_a { (a, b) } else { (b, a) };
    let li = &p.lines[x.1 as usize];
    let c = cut(&li.cuts[x.2 as usize]);
    let (which, other) = if in_a {
        ("the original's", "the output")
    } else {
        ("the output's", "the original")
    };
    // the same move in another state?
    let twin = q.lines.iter().find_map(|l2| {
        l2.cuts
            .iter()
            .find(|c2| same(&cut(c2), &c, 1e-3))
            .map(|_| l2)
    });
    match twin {
        Some(l2) => format!(
            "{counts}; {which} line {} cuts {} with {}, {other} (line {}) with {}",
            li.line,
            describe(&c),
            state_words(&li.after, &l2.after),
            l2.line,
            state_words(&l2.after, &li.after),
        ),
        None => format!(
            "{counts}; {which} line {} cuts {}, which {other} never cuts",
            li.line,
            describe(&c)
        ),
    }
}

/// The elements of `s` that differ from `o`, in words.
fn state_words(s: &super::interp::State, o: &super::interp::State) -> String {
    use super::interp::el;
    let mut v = Vec::new();
    let (ts, to) = (s.tag(), o.tag());
    let diff = ts.set ^ to.set;
    for b in 0..16 {
        if diff & (1 << b) != 0 {
            v.push(format!(
                "{} {}",
                el::NAMES[b],
                if ts.set & (1 << b) != 0 {
                    "set"
                } else {
                    "unset"
                }
            ));
        }
    }
    if ts.flags != to.flags {
        v.push(format!(
            "modes [G21 G90 G90.1 M7 M8 G41/42 G98 G94] = {:?}",
            ts.flags
        ));
    }
    if ts.feed != to.feed {
        v.push(format!("F{}", s.feed));
    }
    if ts.speed != to.speed || ts.spindle != to.spindle {
        v.push(format!("S{} M{}", s.speed, s.spindle));
    }
    if ts.tool != to.tool || ts.tlc != to.tlc {
        v.push(format!("T{} H{:?}", s.tool, s.tlc));
    }
    if ts.offset != to.offset || ts.epoch != to.epoch {
        v.push(format!(
            "offset G{} (change {})",
            s.offset as f64 / 10.0,
            s.epoch
        ));
    }
    if ts.plane != to.plane || ts.path != to.path {
        v.push(format!("G{} {:?}", s.plane, s.path));
    }
    if v.is_empty() {
        "the same state".into()
    } else {
        v.join(", ")
    }
}

/// The events of a line: `(exact, key)`; `exact` false for those the output may have fewer
/// of (tool changes and moves to machine positions, dropped when tool blocks are merged).
fn events(li: &LineInfo, text: &str) -> Vec<(bool, u128)> {
    let t = tag(li);
    let mut v = Vec::new();
    let w = &li.words;
    if li.dialect {
        v.push((true, hash128(&(text.trim().to_ascii_uppercase(), t))));
        return v;
    }
    if li.tool_change {
        v.push((false, hash128(&("tool", li.after.tool, t))));
    }
    if li.motion == Motion::Home {
        let words: Vec<(char, i64)> = w
            .words
            .iter()
            .map(|&(c, x)| (c, (x * 1e6) as i64))
            .collect();
        v.push((false, hash128(&("home", words, t))));
    }
    if li.setup {
        let words: Vec<(char, i64)> = w
            .words
            .iter()
            .map(|&(c, x)| (c, (x * 1e6) as i64))
            .collect();
        v.push((true, hash128(&("setup", words, t))));
    }
    if li.dwell {
        v.push((
            true,
            // at its height (at the bottom of a hole, or where the spindle comes up to speed)
            hash128(&(
                "dwell",
                w.get('P').map(|x| (x * 1e6) as i64),
                li.pos_before[2].map(|z| (z * 1e3).round() as i64),
                t,
            )),
        ));
    }
    if li.pause || li.user_m {
        for m in w.all('M') {
            let m = m.round() as i64;
            if matches!(m, 0 | 1 | 60 | 48..=53 | 62..=68 | 100..=199) {
                v.push((true, hash128(&("m", m, t))));
            }
        }
    }
    v
}

/// Same events with the same state (see [`equivalent`]); returns how many were compared.
fn same_events(a: &Program, b: &Program) -> Result<usize, String> {
    let collect = |p: &Program| {
        let mut exact: Vec<(u128, usize)> = Vec::new();
        let mut fewer: Vec<(u128, usize)> = Vec::new();
        for (i, li) in p.lines.iter().enumerate() {
            for (e, h) in events(li, &p.text[i]) {
                if e {
                    exact.push((h, li.line));
                } else {
                    fewer.push((h, li.line));
                }
            }
        }
        exact.sort_unstable();
        fewer.sort_unstable();
        (exact, fewer)
    };
    let ((ea, fa), (eb, fb)) = (collect(a), collect(b));
    for (x, y) in ea.iter().zip(&eb) {
        if x.0 != y.0 {
            return Err(format!(
                "events differ (dwell, pause, user M code, coordinate-system change or \
                 controller line, with the machine state): original line {} vs line {}",
                x.1, y.1
            ));
        }
    }
    if ea.len() != eb.len() {
        return Err(format!(
            "event counts differ (dwells, pauses, user M codes, coordinate-system changes, \
             controller lines): {} vs {}",
            ea.len(),
            eb.len()
        ));
    }
    // fb must be a sub-multiset of fa
    let mut i = 0;
    for y in &fb {
        while i < fa.len() && fa[i].0 < y.0 {
            i += 1;
        }
        if i == fa.len() || fa[i].0 != y.0 {
            return Err(format!(
                "line {}: a tool change or move to a machine position the original does not \
                 make in that state",
                y.1
            ));
        }
        i += 1;
    }
    Ok(ea.len() + fb.len())
}

/// The motions (rapid targets, moves to machine positions) and tool changes before the first
/// cut, and per tool the lowest height of a rapid across in X/Y.
fn motion_profile(p: &Program, tol: f64) -> (Vec<u128>, std::collections::HashMap<u32, f64>) {
    let q = |v: Option<f64>| v.map(|x| (x / tol).round() as i64);
    let mut before = Vec::new();
    let mut cut = false;
    let mut low = std::collections::HashMap::new();
    for li in &p.lines {
        cut |= !li.cuts.is_empty();
        if !cut && (li.motion != Motion::None || li.tool_change) {
            let t = li.pos_after.map(q);
            before.push(hash128(&(li.motion as u8, li.tool_change, t)));
        }
        if let Some(z) = li.xy_rapid_z {
            let e = low.entry(li.before.tool).or_insert(z);
            *e = f64::min(*e, z);
        }
    }
    (before, low)
}

/// The no-new-motion rule of [`equivalent`].
fn no_new_motion(a: &Program, b: &Program, tol: f64) -> Result<(), String> {
    let (pa, low) = motion_profile(a, tol);
    let (pb, _) = motion_profile(b, tol);
    if pb.len() < pa.len() || pb[..pa.len()] != pa[..] {
        return Err(
            "the motions and tool changes before the first cut are not the original's".into(),
        );
    }
    if !a.has_z {
        return Ok(());
    }
    let floor = low.values().copied().fold(f64::INFINITY, f64::min);
    for li in &b.lines {
        if let Some(z) = li.xy_rapid_z {
            let min = low.get(&li.before.tool).copied().unwrap_or(floor);
            if z < min - tol {
                return Err(format!(
                    "line {}: a rapid across at Z{z:.4} mm, lower than the original ever \
                     rapids across with tool {} (Z{min:.4} mm)",
                    li.line, li.before.tool
                ));
            }
        }
    }
    Ok(())
}

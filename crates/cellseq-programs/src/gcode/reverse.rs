//! Reversal of G-code cells: which cells may be cut backwards, and their reversed body.
//!
//! A cell is reversible when its cutting part is a run of G1/G2/G3 feed moves (no canned
//! cycles, pauses, dwells or modal changes other than F and S between them). Before the first
//! feed move only rapids that move Z alone (the descent) and non-motion lines may come; after
//! the last feed move only Z-only rapids (the retract) and non-motion lines. In milling
//! programs (with Z) the feed moves must also cut at one depth: every move that changes X or Y
//! keeps Z constant, at one Z for the whole cell, and the feed part starts and ends at the same
//! height, so that the reversed cell plunges where the original retracted (and vice versa) and
//! never cuts a lower pass before an upper one.
//!
//! The reversed body cuts the same moves backwards: straight moves from end to start, arcs with
//! G2/G3 swapped and the centre given as I/J/K offsets from the new start (G91.1), in absolute
//! coordinates (G90) in the file's units, with each move's feed and speed; the distance modes,
//! F and S in force after the original feed moves are restored afterwards.

use super::cells::{GCell, Split};
use super::interp::{CutKind, Motion, Program, State, el, known, plane_axes};
use super::write::num;
use std::fmt::Write as _;

const EPS: f64 = 1e-6;

/// How a reversible cell is laid out (indices into the program's lines).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    /// First feed line.
    pub first: usize,
    /// Last feed line (inclusive).
    pub last: usize,
    /// Height (mm) where the feed moves start and end (milling).
    pub z: f64,
    /// Entry of the reversed cell (mm).
    pub entry: [f64; 3],
    /// Exit of the reversed cell (mm).
    pub exit: [f64; 3],
}

fn masked(s: &State) -> State {
    State {
        feed: 0.0,
        speed: 0.0,
        motion: None,
        set: 0,
        ..*s
    }
}

fn z_only_rapid(p: &Program, i: usize) -> bool {
    let li = &p.lines[i];
    match (known(&li.pos_before), known(&li.pos_after)) {
        (Some(a), Some(b)) => {
            li.motion == Motion::Rapid
                && (a[0] - b[0]).abs() < EPS
                && (a[1] - b[1]).abs() < EPS
                && masked(&li.before) == masked(&li.after)
        }
        _ => false,
    }
}

/// Whether cell `c` can be cut backwards, and how; `Err` says why not.
pub fn plan(p: &Program, split: Split, c: &GCell) -> Result<Plan, &'static str> {
    if c.cycle {
        return Err("canned cycle");
    }
    let body = c.start..c.end;
    let first = body
        .clone()
        .find(|&i| p.lines[i].motion == Motion::Feed)
        .ok_or("no feed moves")?;
    let last = body
        .clone()
        .rev()
        .find(|&i| p.lines[i].motion == Motion::Feed)
        .ok_or("no feed moves")?;
    if !p.lines[first].before.absolute {
        // the reversed moves are written in absolute coordinates: the machine state at the
        // cuts (distance mode) would differ from the original's
        return Err("incremental distance mode (G91)");
    }
    for i in (c.start..first).chain(last + 1..c.end) {
        let li = &p.lines[i];
        match li.motion {
            Motion::None if !li.pause && !li.words.has_g(4.0) => {}
            Motion::Rapid if z_only_rapid(p, i) => {}
            _ => return Err("moves other than Z-only rapids before or after the feed moves"),
        }
    }
    let mut depth: Option<f64> = None;
    for li in &p.lines[first..=last] {
        if li.pause || li.words.has_g(4.0) || li.tool_change || li.setup || li.end {
            return Err("pause, dwell or setup between the feed moves");
        }
        match li.motion {
            Motion::None => {
                if masked(&li.before) != masked(&li.after) {
                    return Err("modal change between the feed moves");
                }
            }
            Motion::Feed => {
                if masked(&li.before) != masked(&li.after) {
                    return Err("modal change on a feed move");
                }
                for cut in &li.cuts {
                    if !matches!(cut.kind, CutKind::Line | CutKind::Arc { .. }) {
                        return Err("not a straight or arc feed move");
                    }
                    if matches!(split, Split::Z { .. }) {
                        let xy = (cut.from[0] - cut.to[0]).abs() > EPS
                            || (cut.from[1] - cut.to[1]).abs() > EPS
                            || matches!(cut.kind, CutKind::Arc { .. });
                        if xy {
                            if (cut.from[2] - cut.to[2]).abs() > EPS {
                                return Err("Z changes while cutting in X/Y");
                            }
                            match depth {
                                None => depth = Some(cut.from[2]),
                                Some(d) if (d - cut.from[2]).abs() > EPS => {
                                    return Err("cuts at more than one depth");
                                }
                                _ => {}
                            }
                        }
                    }
                }
            }
            _ => return Err("rapid or cycle between the feed moves"),
        }
    }
    let a = known(&p.lines[first].pos_before).ok_or("unknown position")?;
    let b = known(&p.lines[last].pos_after).ok_or("unknown position")?;
    if matches!(split, Split::Z { .. }) {
        if (a[2] - b[2]).abs() > EPS {
            return Err("the feed moves start and end at different heights");
        }
        if depth.is_some_and(|d| d > a[2] - EPS) {
            // a rapid straight to the cut depth at the other end could hit uncut stock
            return Err("no feed plunge below the approach height");
        }
    }
    Ok(Plan {
        first,
        last,
        z: a[2],
        entry: [b[0], b[1], c.entry[2]],
        exit: [a[0], a[1], c.exit[2]],
    })
}

fn coord(st: &State, mm: f64) -> String {
    num(mm / st.scale(), 10)
}

fn exact(v: f64) -> String {
    let s = format!("{v}");
    if s == "-0" { "0".into() } else { s }
}

/// Writes the reversed body of cell `c` (planned by [`plan`]).
pub fn write_reversed(p: &Program, has_z: bool, c: &GCell, plan: &Plan, out: &mut String) {
    let st0 = p.lines[plan.first].before;
    let st1 = p.lines[plan.last].after;
    // non-motion lines before the feed moves, in order
    for i in c.start..plan.first {
        if p.lines[i].motion == Motion::None {
            out.push_str(&super::write::line_text(p, i));
            out.push('\n');
        }
    }
    // the reversed moves are absolute with centre offsets in the arc mode in force; only a
    // distance mode the program itself set to incremental is switched (and restored below)
    if !st0.absolute {
        out.push_str("G90\n");
    }
    if has_z && (plan.entry[2] - plan.z).abs() > EPS {
        let _ = writeln!(out, "G0 Z{}", coord(&st0, plan.z));
    }
    let mut feed: Option<f64> = None;
    let mut speed = st0.speed;
    for i in (plan.first..=plan.last).rev() {
        let li = &p.lines[i];
        if li.motion == Motion::None {
            if li.before == li.after {
                out.push_str(&super::write::line_text(p, i));
                out.push('\n');
            }
            continue;
        }
        let st = &li.after;
        for cut in li.cuts.iter().rev() {
            let mut s = String::new();
            match cut.kind {
                CutKind::Arc { cw, .. } => s.push_str(if cw { "G3" } else { "G2" }),
                _ => s.push_str("G1"),
            }
            let _ = write!(
                s,
                " X{} Y{}",
                coord(st, cut.from[0]),
                coord(st, cut.from[1])
            );
            if has_z {
                let _ = write!(s, " Z{}", coord(st, cut.from[2]));
            }
            if let CutKind::Arc {
                center,
                plane,
                turns,
                ..
            } = cut.kind
            {
                let (a, b, _) = plane_axes(plane);
                for ax in [a, b] {
                    let v = if st.arc_absolute {
                        center[ax]
                    } else {
                        center[ax] - cut.to[ax]
                    };
                    let _ = write!(s, " {}{}", ['I', 'J', 'K'][ax], coord(st, v));
                }
                if turns > 1 {
                    let _ = write!(s, " P{turns}");
                }
            }
            if feed != Some(st.feed) {
                let _ = write!(s, " F{}", exact(st.feed));
                feed = Some(st.feed);
            }
            if speed != st.speed {
                let _ = write!(s, " S{}", exact(st.speed));
                speed = st.speed;
            }
            out.push_str(&s);
            out.push('\n');
        }
    }
    if has_z && (plan.exit[2] - plan.z).abs() > EPS {
        let _ = writeln!(out, "G0 Z{}", coord(&st1, plan.exit[2]));
    }
    let mut s = String::new();
    if !st1.absolute {
        s.push_str(" G91");
    }
    if feed != Some(st1.feed) && st1.set & el::FEED != 0 {
        let _ = write!(s, " F{}", exact(st1.feed));
    }
    if speed != st1.speed {
        let _ = write!(s, " S{}", exact(st1.speed));
    }
    if !s.is_empty() {
        out.push_str(s.trim_start());
        out.push('\n');
    }
    // non-motion lines after the feed moves, in order (the Z-only rapids became one move)
    for i in plan.last + 1..c.end {
        if p.lines[i].motion == Motion::None {
            out.push_str(&super::write::line_text(p, i));
            out.push('\n');
        }
    }
}

//! Writing the program back in a new cell order.

use super::cells::{Layout, Split, is_motion_g};
use super::interp::{CutKind, Motion, Program, State};
use super::reverse::{Plan, write_reversed};
use std::fmt::Write as _;

/// Formats a number for G-code (no exponent, at most `dec` decimals, trailing zeros trimmed).
pub fn num(v: f64, dec: usize) -> String {
    let s = format!("{v:.dec$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" { "0".into() } else { s }
}

/// Exact shortest representation of a value read from the file.
fn exact(v: f64) -> String {
    let s = format!("{v}");
    if s == "-0" { "0".into() } else { s }
}

fn units(st: &State, mm: f64) -> String {
    num(mm / st.scale(), if st.metric { 4 } else { 6 })
}

/// Units, plane, offset, tool length compensation and absolute mode.
fn part_a(st: &State) -> String {
    let mut s = format!(
        "G{} G{} G{} G90",
        st.plane,
        if st.metric { 21 } else { 20 },
        offset_code(st.offset)
    );
    match st.tlc {
        Some(h) => {
            let _ = write!(s, " G43 H{}", exact(h));
        }
        None => s.push_str(" G49"),
    }
    s
}

fn offset_code(o: u16) -> String {
    if o.is_multiple_of(10) {
        format!("{}", o / 10)
    } else {
        format!("{}.{}", o / 10, o % 10)
    }
}

/// Distance modes, path mode, retract mode, feed, speed, spindle, coolant.
fn part_b(st: &State) -> String {
    let mut s = format!(
        "G{} G{} G{}",
        if st.absolute { 90 } else { 91 },
        if st.arc_absolute { "90.1" } else { "91.1" },
        if st.retract_old_z { 98 } else { 99 }
    );
    if let Some((c, p, q)) = st.path {
        let _ = write!(s, " G{}", offset_code(c));
        if let Some(p) = p {
            let _ = write!(s, " P{}", exact(p));
        }
        if let Some(q) = q {
            let _ = write!(s, " Q{}", exact(q));
        }
    }
    if st.feed > 0.0 {
        let _ = write!(s, " F{}", exact(st.feed));
    }
    let _ = write!(s, " S{} M{}", exact(st.speed), st.spindle);
    match (st.mist, st.flood) {
        (false, false) => s.push_str(" M9"),
        (true, false) => s.push_str(" M7"),
        (false, true) => s.push_str(" M8"),
        (true, true) => s.push_str("\nM7 M8"),
    }
    s
}

fn motion_code(m: u16) -> String {
    offset_code(m)
}

/// The line's text without a leading line number.
fn strip_n(text: &str) -> &str {
    let t = text.trim_start();
    if t.starts_with(['N', 'n']) {
        let rest = &t[1..];
        let k = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.' || c == ' '))
            .unwrap_or(rest.len());
        &rest[k..]
    } else {
        t
    }
}

/// A gap line with its motion removed (only its other words kept), or `None` when nothing is left.
fn stripped(p: &Program, i: usize) -> Option<String> {
    let w = &p.lines[i].words;
    let keep: Vec<String> = w
        .words
        .iter()
        .filter(|&&(c, v)| {
            !(matches!(c, 'X' | 'Y' | 'Z' | 'I' | 'J' | 'K' | 'R') || c == 'G' && is_motion_g(v))
        })
        .map(|&(c, v)| format!("{c}{}", exact(v)))
        .collect();
    (!keep.is_empty()).then(|| keep.join(" "))
}

fn gap_line(p: &Program, i: usize, out: &mut String) {
    if p.lines[i].motion == Motion::None {
        out.push_str(&p.text[i]);
        out.push('\n');
    } else if let Some(s) = stripped(p, i) {
        out.push_str(&s);
        out.push('\n');
    }
}

/// Writes the program with cells in `order` (indices into `layout.cells`); `rev[k]` holds the
/// reversal plan when `order[k]` is cut backwards (or is empty: nothing reversed).
pub fn write(
    p: &Program,
    l: &Layout,
    order: &[usize],
    rev: &[Option<Plan>],
    merge: bool,
) -> String {
    let mut out =
        String::with_capacity(p.text.iter().map(|t| t.len() + 1).sum::<usize>() + order.len() * 80);
    for t in &p.text[..l.header_end] {
        out.push_str(t);
        out.push('\n');
    }
    let travel = match l.split {
        Split::Z { travel, .. } => Some(travel),
        Split::Flat => None,
    };
    let mut block = l
        .cells
        .get(order.first().copied().unwrap_or(0))
        .map(|c| c.block)
        .unwrap_or(0);
    for (k, &ci) in order.iter().enumerate() {
        let c = &l.cells[ci];
        let plan = rev.get(k).copied().flatten();
        let entry = plan.map(|pl| pl.entry).unwrap_or(c.entry);
        let st = &c.state;
        if c.block != block
            && (!merge
                || c.tool != l.blocks[block].tool
                || l.blocks[c.block].epoch != l.blocks[block].epoch)
        {
            // entering another tool block: retract, then the original tool-change lines
            let b = &l.blocks[c.block];
            let gst = &p.lines[b.gap_start.min(p.lines.len() - 1)].before;
            out.push_str(&part_a(gst));
            out.push('\n');
            if let Some(h) = travel {
                let _ = writeln!(out, "G0 Z{}", units(gst, h));
            }
            out.push_str(&part_b(gst));
            out.push('\n');
            let last_change = b
                .preamble
                .iter()
                .rev()
                .find(|&&g| p.lines[g].tool_change || p.lines[g].setup)
                .copied()
                .unwrap_or(0);
            for &g in &b.preamble {
                if g <= last_change {
                    out.push_str(&p.text[g]);
                    out.push('\n');
                } else {
                    gap_line(p, g, &mut out);
                }
            }
        }
        block = c.block;
        let _ = writeln!(
            out,
            "(cellseq: cell {} from line {}{})",
            ci + 1,
            p.lines[c.start].line,
            if plan.is_some() { ", reversed" } else { "" }
        );
        out.push_str(&part_a(st));
        out.push('\n');
        let (x, y) = (units(st, entry[0]), units(st, entry[1]));
        match travel {
            Some(h) => {
                let top = h.max(entry[2]);
                let _ = writeln!(out, "G0 Z{}", units(st, top));
                let _ = writeln!(out, "G0 X{x} Y{y}");
                if !c.cycle && (top - entry[2]).abs() > 1e-9 {
                    let _ = writeln!(out, "G0 Z{}", units(st, entry[2]));
                }
            }
            None => {
                let _ = writeln!(out, "G0 X{x} Y{y}");
            }
        }
        for &g in &c.prefix {
            gap_line(p, g, &mut out);
        }
        out.push_str(&part_b(st));
        out.push('\n');
        if c.cycle {
            let li = &p.lines[c.start];
            let cut = li.cuts[0];
            if let CutKind::Cycle { code, l: reps, .. } = cut.kind {
                let s = li.after.scale();
                let mut line = format!(
                    "G{} X{} Y{} Z{} R{}",
                    motion_code(code),
                    num(cut.to[0] / s, 9),
                    num(cut.to[1] / s, 9),
                    exact(li.after.cycle[1].unwrap_or(0.0)),
                    exact(li.after.cycle[0].unwrap_or(0.0)),
                );
                if let Some(pv) = li.after.cycle[2] {
                    let _ = write!(line, " P{}", exact(pv));
                }
                if let Some(q) = li.after.cycle[3] {
                    let _ = write!(line, " Q{}", exact(q));
                }
                if reps > 1 {
                    let _ = write!(line, " L{reps}");
                }
                for &(ch, v) in &li.words.words {
                    if !matches!(ch, 'G' | 'X' | 'Y' | 'Z' | 'R' | 'P' | 'Q' | 'L') {
                        let _ = write!(line, " {ch}{}", exact(v));
                    }
                }
                out.push_str(&line);
                out.push('\n');
            }
            out.push_str("G80\n");
            continue;
        }
        match plan {
            Some(pl) => write_reversed(p, travel.is_some(), c, &pl, &mut out),
            None => body(p, c.start, c.end, &mut out),
        }
    }
    if l.footer_start < p.lines.len() {
        let fst = &p.lines[l.footer_start].before;
        out.push_str(&part_a(fst));
        out.push('\n');
        if let Some(h) = travel {
            let _ = writeln!(out, "G0 Z{}", units(fst, h));
        }
        out.push_str(&part_b(fst));
        out.push('\n');
        body(p, l.footer_start, p.lines.len(), &mut out);
    }
    out
}

/// Copies lines `[s, e)`, giving the first motion line its modal motion code explicitly
/// (the regenerated rapids before it changed the motion mode to G0).
fn body(p: &Program, s: usize, e: usize, out: &mut String) {
    let mut fixed = false;
    for i in s..e {
        let li = &p.lines[i];
        if !fixed && li.motion != Motion::None {
            fixed = true;
            let mode = li.before.motion.unwrap_or(0);
            if !li.explicit_motion && mode != 0 {
                let _ = writeln!(out, "G{} {}", motion_code(mode), strip_n(&p.text[i]));
                continue;
            }
        }
        out.push_str(&p.text[i]);
        out.push('\n');
    }
}

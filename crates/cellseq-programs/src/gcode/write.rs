//! Writing the program back in a new cell order.

use super::cells::{
    Block, Layout, Split, entry_state, free_bits, is_boundary, is_motion_g, vertical,
};
use super::interp::{Motion, Program, State, el, known};
use super::reverse::{Plan, write_reversed};
use std::borrow::Cow;
use std::fmt::Write as _;

mod cycles;

/// Line `i` as the output writes it: as written, or, when its values came from parameters or
/// expressions, with the numbers they had in the original ([`super::lex::Words::evaluated`]),
/// so that it moves the same wherever it is written.
pub fn line_text(p: &Program, i: usize) -> Cow<'_, str> {
    let w = &p.lines[i].words;
    if w.computed {
        Cow::Owned(w.evaluated(&p.text[i]))
    } else {
        Cow::Borrowed(&p.text[i])
    }
}

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

/// A coordinate in the file's units, precise enough that a move the original makes from this
/// point stays the same move (10 decimals: under 1e-9 mm off).
fn units(st: &State, mm: f64) -> String {
    num(mm / st.scale(), 10)
}

fn offset_code(o: u16) -> String {
    if o.is_multiple_of(10) {
        format!("{}", o / 10)
    } else {
        format!("{}.{}", o / 10, o % 10)
    }
}

/// The lines that take the machine from state `cur` to state `target`: only the elements the
/// program itself set in `target` and that differ. An element set in `cur` but never set by the
/// program in `target` cannot be handed back to the operator: that is an error (the grouping
/// of cells into runs never asks for it), unless it is in `free`: the cell sets it itself
/// before it cuts ([`free_bits`]).
pub fn transition(cur: &State, target: &State, free: u32) -> Result<Vec<String>, String> {
    let missing = cur.set & !target.set & !free;
    if missing != 0 {
        let names: Vec<&str> = (0..16)
            .filter(|b| missing & (1 << b) != 0)
            .map(|b| el::NAMES[b])
            .collect();
        return Err(format!(
            "a cell would run with {} set although the original leaves it to the operator there",
            names.join(", ")
        ));
    }
    let want = |bit: u32, same: bool| target.set & bit != 0 && (cur.set & bit == 0 || !same);
    if want(el::TOOL, cur.tool == target.tool) && cur.set & el::TOOL != 0 {
        return Err(format!(
            "a cell of tool {} would run with tool {}",
            target.tool, cur.tool
        ));
    }
    if want(el::CUTTER, cur.cutter_comp == target.cutter_comp) && target.cutter_comp {
        return Err("a cell would need cutter compensation turned on between cells".into());
    }
    let mut g: Vec<String> = Vec::new();
    if want(el::UNITS, cur.metric == target.metric) {
        g.push(if target.metric { "G21" } else { "G20" }.into());
    }
    if want(el::PLANE, cur.plane == target.plane) {
        g.push(format!("G{}", target.plane));
    }
    if want(el::DIST, cur.absolute == target.absolute) {
        g.push(if target.absolute { "G90" } else { "G91" }.into());
    }
    if want(el::ARC_DIST, cur.arc_absolute == target.arc_absolute) {
        g.push(
            if target.arc_absolute {
                "G90.1"
            } else {
                "G91.1"
            }
            .into(),
        );
    }
    if want(el::OFFSET, cur.offset == target.offset) {
        g.push(format!("G{}", offset_code(target.offset)));
    }
    if want(el::CUTTER, cur.cutter_comp == target.cutter_comp) {
        g.push("G40".into());
    }
    if want(el::RETRACT, cur.retract_old_z == target.retract_old_z) {
        g.push(if target.retract_old_z { "G98" } else { "G99" }.into());
    }
    if want(el::FEED_MODE, cur.feed_mode == target.feed_mode) {
        g.push("G94".into());
    }
    if want(el::TLC, cur.tlc == target.tlc) {
        g.push(match target.tlc {
            Some(h) => format!("G43 H{}", exact(h)),
            None => "G49".into(),
        });
    }
    if want(el::PATH, cur.path == target.path)
        && let Some((c, p, q)) = target.path
    {
        let mut w = format!("G{}", offset_code(c));
        if let Some(p) = p {
            let _ = write!(w, " P{}", exact(p));
        }
        if let Some(q) = q {
            let _ = write!(w, " Q{}", exact(q));
        }
        g.push(w);
    }
    if want(el::FEED, cur.feed == target.feed) {
        g.push(format!("F{}", exact(target.feed)));
    }
    if want(el::SPEED, cur.speed == target.speed) {
        g.push(format!("S{}", exact(target.speed)));
    }
    let mut lines = Vec::new();
    if !g.is_empty() {
        lines.push(g.join(" "));
    }
    if want(el::SPINDLE, cur.spindle == target.spindle) {
        lines.push(format!("M{}", target.spindle));
    }
    // coolant: only what the target has set (an element left to the cell itself stays)
    let (tm, tf) = (target.set & el::MIST != 0, target.set & el::FLOOD != 0);
    let (mut mist, mut flood) = (cur.mist, cur.flood);
    if (tm && mist && !target.mist) || (tf && flood && !target.flood) {
        lines.push("M9".into());
        (mist, flood) = (false, false);
    }
    if tm && target.mist && !mist {
        lines.push("M7".into());
    }
    if tf && target.flood && !flood {
        lines.push("M8".into());
    }
    Ok(lines)
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
        out.push_str(&line_text(p, i));
        out.push('\n');
    } else if let Some(s) = stripped(p, i) {
        out.push_str(&s);
        out.push('\n');
    }
}

struct Writer<'a> {
    p: &'a Program,
    out: String,
    /// The output's machine state.
    cur: State,
    /// The output's position (mm), when known.
    pos: Option<[f64; 3]>,
    /// The output's motion mode (×10, as in [`State::motion`]); `Some(u16::MAX)` when unknown.
    motion: Option<u16>,
    /// The initial level (mm) of the output's series of canned cycles in progress
    /// ([`State::cycle_il`]); `None` outside a series.
    il: Option<f64>,
    /// The canned-cycle words R, Z, P, Q the output keeps for its next hole
    /// ([`State::cycle`]).
    kept: [Option<f64>; 4],
}

impl Writer<'_> {
    fn line(&mut self, s: &str) {
        self.out.push_str(s);
        self.out.push('\n');
    }

    /// Lines `[s, e)` of the original, unchanged.
    fn verbatim(&mut self, s: usize, e: usize) {
        for i in s..e {
            self.out.push_str(&line_text(self.p, i));
            self.out.push('\n');
            let z0 = self.pos.map(|q| q[2]);
            if self.p.lines[i].motion != Motion::None {
                self.pos = self.track(i);
            }
            if self.p.lines[i].explicit_motion {
                self.motion = self.p.lines[i].after.motion;
            }
            self.note_series(i, z0);
        }
        if e > s {
            self.cur = self.p.lines[e - 1].after;
        }
    }

    /// The output's position after line `i` of the original, written as it is: the axes the
    /// line names move as in the original (to the same place in G90, by the same amount in
    /// G91), the others stay where the output is (which need not be where the original was).
    fn track(&self, i: usize) -> Option<[f64; 3]> {
        let li = &self.p.lines[i];
        let after = known(&li.pos_after);
        if !matches!(li.motion, Motion::Rapid | Motion::Feed) {
            return after;
        }
        let (Some(mut q), Some(b), Some(a)) = (self.pos, known(&li.pos_before), after) else {
            return after;
        };
        for (k, axis) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if (a[k] - b[k]).abs() > 1e-12 || li.words.has(axis) {
                q[k] = if li.after.absolute {
                    a[k]
                } else {
                    q[k] + (a[k] - b[k])
                };
            }
        }
        Some(q)
    }

    /// A gap line: as written when it does not move, else its other words only.
    fn gap(&mut self, g: usize) {
        gap_line(self.p, g, &mut self.out);
        let li = &self.p.lines[g];
        if li.motion == Motion::None && li.explicit_motion {
            self.motion = li.after.motion;
            self.note_series(g, None);
        }
    }

    /// What line `i`, written as it is with the output's height `z0` before it, does to the
    /// output's series of canned cycles: a cycle line starts one at `z0` where none is in
    /// progress (as LinuxCNC does) and keeps the words it used; any other motion, G80 and G53
    /// end the series.
    fn note_series(&mut self, i: usize, z0: Option<f64>) {
        let li = &self.p.lines[i];
        if li.motion == Motion::Cycle {
            if self.il.is_none() {
                self.il = z0;
            }
            self.kept = li.after.cycle;
        } else if li.explicit_motion
            || matches!(li.motion, Motion::Rapid | Motion::Feed)
            || (li.motion == Motion::Home && li.words.has_g(53.0))
        {
            self.il = None;
        }
    }

    /// Makes the output's motion mode the original's `want` before lines `[s, e)` are copied
    /// as written, when one of them moves without naming its motion code before one that
    /// does (G80 to leave a canned cycle, else the mode's code alone).
    fn motion_for(&mut self, lines: impl Iterator<Item = usize>, want: Option<u16>) {
        if self.motion == want {
            return;
        }
        let p = self.p;
        let needs = lines
            .filter(|&i| p.lines[i].motion != Motion::None || p.lines[i].explicit_motion)
            .take(1)
            .any(|i| !p.lines[i].explicit_motion);
        if !needs {
            return;
        }
        match want {
            None => self.line("G80"),
            Some(m) if m < 700 => self.line(&format!("G{}", motion_code(m))),
            // a cycle continued by the copied lines: they are the original's cells, never here
            Some(_) => return,
        }
        if want.is_none() || want.is_some_and(|m| m < 700) {
            self.il = None;
        }
        self.motion = want;
    }

    fn reach(&mut self, target: &State, free: u32) -> Result<(), String> {
        for l in transition(&self.cur, target, free)? {
            self.line(&l);
        }
        let (motion, cycle, selected) = (self.cur.motion, self.cur.cycle, self.cur.selected);
        self.cur = State {
            motion,
            cycle,
            selected,
            ..*target
        };
        Ok(())
    }

    /// Retract to `clear`, rapid over, plunge to `entry` (rapids only, in the state in force).
    fn link(&mut self, entry: [f64; 3], clear: Option<f64>, cycle: bool) {
        let st = self.cur;
        let mut lines: Vec<String> = Vec::new();
        let mut pos = self.pos;
        let mut zpos = pos.map(|q| q[2]);
        if let Some(h) = clear {
            let top = if cycle { h } else { h.max(entry[2]) };
            if zpos.is_none_or(|z| z < top - 1e-9) {
                lines.push(format!("G0 Z{}", units(&st, top)));
                pos = pos.map(|q| [q[0], q[1], top]);
                zpos = Some(top);
            }
        }
        if cycle {
            // the canned cycle moves over the hole itself, at the height it starts from
        } else {
            let z = zpos.unwrap_or(entry[2]);
            if pos.is_none_or(|q| (q[0] - entry[0]).abs() > 1e-9 || (q[1] - entry[1]).abs() > 1e-9)
            {
                lines.push(format!(
                    "G0 X{} Y{}",
                    units(&st, entry[0]),
                    units(&st, entry[1])
                ));
            }
            if clear.is_some() && (z - entry[2]).abs() > 1e-9 {
                lines.push(format!("G0 Z{}", units(&st, entry[2])));
            }
            pos = Some(entry);
        }
        if lines.is_empty() {
            return;
        }
        let incremental = !st.absolute;
        if incremental {
            self.line("G90");
        }
        for l in &lines {
            self.line(l);
        }
        if incremental {
            self.line("G91");
        }
        self.pos = pos;
        self.motion = Some(0);
        self.il = None;
    }

    /// The block's preamble when the output enters the block at another cell than its first:
    /// the lines up to its last boundary as written, then, up to the first move across, the
    /// rapids straight up, and those straight down to a height no lower than `low` (the
    /// block's own link height), as written (so that a dwell after the spindle start happens
    /// at the height the program gives it: pcb-gcode rises from its tool-zero touch at Z0 to
    /// its drilling height before it), then the other words without their motion.
    fn preamble(&mut self, b: &Block, first_start: usize, low: f64) {
        let p = self.p;
        let last = b
            .preamble
            .iter()
            .rev()
            .find(|&&g| is_boundary(p, g))
            .copied()
            .unwrap_or(0);
        let across = (last.max(b.gap_start)..first_start)
            .find(|&g| {
                g > last
                    && p.lines[g].motion != Motion::None
                    && !(vertical(p, g)
                        && (rises(p, g)
                            || p.lines[g].pos_after[2].is_some_and(|z| z >= low - 1e-9)))
            })
            .unwrap_or(first_start);
        let verbatim: Vec<usize> = b
            .preamble
            .iter()
            .copied()
            .filter(|&g| g <= last || g < across)
            .collect();
        self.motion_for(verbatim.iter().copied(), p.lines[b.gap_start].before.motion);
        for &g in &b.preamble {
            if g <= last || g < across {
                self.verbatim(g, g + 1);
            } else {
                self.gap(g);
            }
        }
        self.cur = p.lines[first_start].before;
    }
}

/// True for a rapid that ends no lower than it starts (a rise is safe wherever the tool is).
fn rises(p: &Program, g: usize) -> bool {
    let li = &p.lines[g];
    matches!((li.pos_before[2], li.pos_after[2]), (Some(a), Some(b)) if b >= a - 1e-9)
}

/// Writes the program with cells in `order` (indices into `layout.cells`); `rev[k]` holds the
/// reversal plan when `order[k]` is cut backwards (or is empty: nothing reversed).
///
/// The header and footer are copied as they are. Two cells that follow each other in the
/// original keep the lines between them as written. Elsewhere a cell gets: the modal words
/// that take the machine from the state the previous output cell leaves to the state the
/// original has at the start of this cell's gap ([`transition`]: only what the program set and
/// what the new order changed), a link of rapids (retract to the block's own clearance, over,
/// down to the cell's entry), the gap's non-motion words, and the cell as written.
pub fn write_checked(
    p: &Program,
    l: &Layout,
    order: &[usize],
    rev: &[Option<Plan>],
    merge: bool,
) -> Result<String, String> {
    let mut w = Writer {
        p,
        out: String::with_capacity(
            p.text.iter().map(|t| t.len() + 1).sum::<usize>() + order.len() * 40,
        ),
        cur: p.lines[l.header_end].before,
        pos: known(&p.lines[l.header_end].pos_before),
        motion: p.lines[l.header_end].before.motion,
        il: p.lines[l.header_end].before.cycle_il,
        kept: p.lines[l.header_end].before.cycle,
    };
    for i in 0..l.header_end {
        w.out.push_str(&line_text(p, i));
        w.out.push('\n');
    }
    let z = matches!(l.split, Split::Z { .. });
    // the lowest height at which the program rapids across (2-D splits of programs with Z)
    let lowest_across = p
        .lines
        .iter()
        .filter_map(|li| li.xy_rapid_z)
        .fold(f64::INFINITY, f64::min);
    let mut block = l.cells[0].block;
    let mut prev: Option<(usize, bool)> = None;
    for (k, &ci) in order.iter().enumerate() {
        let c = &l.cells[ci];
        let plan = rev.get(k).copied().flatten();
        let entry = plan.map(|pl| pl.entry).unwrap_or(c.entry);
        let adjacent = plan.is_none()
            && match prev {
                None => ci == 0,
                Some((pc, r)) => !r && pc + 1 == ci,
            };
        if adjacent {
            let from = prev.map_or(l.header_end, |(pc, _)| l.cells[pc].end);
            w.verbatim(from, c.start);
        } else {
            let enter = c.block != block
                && (!merge
                    || c.tool != l.blocks[block].tool
                    || l.blocks[c.block].epoch != l.blocks[block].epoch);
            let b = &l.blocks[c.block];
            let first = l
                .cells
                .iter()
                .position(|x| x.block == c.block)
                .unwrap_or(ci);
            if enter && first == ci && plan.is_none() {
                // the block's own approach to its first cell, as written
                w.reach(&p.lines[b.gap_start].before, 0)?;
                w.motion_for(b.gap_start..c.start, p.lines[b.gap_start].before.motion);
                w.verbatim(b.gap_start, c.start);
            } else {
                if enter {
                    w.reach(&p.lines[b.gap_start].before, 0)?;
                    let low = if z {
                        l.clearance[c.block]
                    } else {
                        lowest_across
                    };
                    w.preamble(b, l.cells[first].start, low);
                }
                if c.pinned {
                    return Err(format!(
                        "line {}: a cut that starts where G28/G30/G53 left the tool cannot move",
                        p.lines[c.start].line
                    ));
                }
                w.reach(&entry_state(p, c), free_bits(p, c))?;
                // the gap's words first (as in the original, the approach then runs in the
                // cell's own state: length offset, units, offset), then the link
                for &g in &c.prefix {
                    w.gap(g);
                }
                w.cur = p.lines[c.start].before;
                let clear = if z {
                    Some(l.clearance[c.block].max(l.clearance[block]))
                } else {
                    // a 2-D split of a program with Z (cuts at the travel height): the link
                    // goes over at the higher of here and the entry, then to the entry's Z
                    p.has_z.then_some(f64::NEG_INFINITY)
                };
                if !c.cycle {
                    // (a canned cycle makes its own approach: see `cycle_cell`)
                    w.link(entry, clear, false);
                }
            }
        }
        block = c.block;
        let before = &p.lines[c.start].before;
        let motion_ok = w.motion == before.motion;
        if c.cycle {
            w.cycle_cell(l, c);
        } else {
            match plan {
                Some(pl) => {
                    write_reversed(p, z, c, &pl, &mut w.out);
                    w.motion = Some(u16::MAX);
                }
                None => {
                    body(p, c.start, c.end, !motion_ok, &mut w.out);
                    w.motion = p.lines[c.end - 1].after.motion;
                }
            }
            w.il = None;
            w.pos = Some(plan.map(|pl| pl.exit).unwrap_or(c.exit));
        }
        w.cur = p.lines[c.end - 1].after;
        prev = Some((ci, plan.is_some()));
    }
    let n = p.lines.len();
    if l.footer_start < n {
        let last = l.cells.len() - 1;
        if prev != Some((last, false)) {
            // the footer runs with the tool (and its length offset) the last cell left: with
            // merged tool blocks that is not always the original's last tool
            let mut target = p.lines[l.footer_start].before;
            target.tool = w.cur.tool;
            target.tlc = w.cur.tlc;
            target.set = (target.set & !(el::TOOL | el::TLC)) | (w.cur.set & (el::TOOL | el::TLC));
            w.reach(&target, 0)?;
            if z {
                // up to the block's clearance, or to where the original's last cell left the
                // tool when that is higher (a footer's dwell then runs at the original's height)
                let h = l.clearance[block]
                    .max(p.lines[l.footer_start].pos_before[2].unwrap_or(f64::NEG_INFINITY));
                if w.pos.is_none_or(|q| q[2] < h - 1e-9) {
                    let s = format!("G0 Z{}", units(&w.cur, h));
                    if w.cur.absolute {
                        w.line(&s);
                    } else {
                        w.line(&format!("G90 {s}"));
                        w.line("G91");
                    }
                }
            }
        }
        w.motion_for(l.footer_start..n, p.lines[l.footer_start].before.motion);
        w.verbatim(l.footer_start, n);
    }
    Ok(w.out)
}

/// [`write_checked`] for callers that need text: where the order cannot be written (it would
/// hand a modal element back to the operator, see [`transition`]), the program as it is.
pub fn write(
    p: &Program,
    l: &Layout,
    order: &[usize],
    rev: &[Option<Plan>],
    merge: bool,
) -> String {
    write_checked(p, l, order, rev, merge).unwrap_or_else(|_| {
        let identity: Vec<usize> = (0..l.cells.len()).collect();
        write_checked(p, l, &identity, &[], false).unwrap_or_else(|_| p.text.join("\n") + "\n")
    })
}

/// Copies lines `[s, e)`; with `fix`, the first motion line gets its modal motion code
/// explicitly (a link before it changed the motion mode).
fn body(p: &Program, s: usize, e: usize, fix: bool, out: &mut String) {
    let mut fixed = !fix;
    for i in s..e {
        let li = &p.lines[i];
        if !fixed && li.motion != Motion::None {
            fixed = true;
            if !li.explicit_motion
                && let Some(mode) = li.before.motion
            {
                let _ = writeln!(out, "G{} {}", motion_code(mode), strip_n(&line_text(p, i)));
                continue;
            }
        }
        out.push_str(&line_text(p, i));
        out.push('\n');
    }
}

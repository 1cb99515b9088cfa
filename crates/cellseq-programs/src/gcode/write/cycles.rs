//! Writing a canned-cycle cell so that every hole moves as in the original.
//!
//! What a hole does depends on more than its words (see [`crate::gcode::interp`]'s
//! `cycle`): on the cycle's kept words (R, Z, P, Q), on the series it belongs to (G98 retracts
//! to the series' initial level, G91 R planes are relative to it), on the height it starts from
//! (the first approach) and, for a line without X or Y (or in G91), on where the tool is. The
//! hole is written as it is where the output is in exactly the original's cycle state there;
//! otherwise the series is ended (by the link's rapid, or `G80`), the tool is put where a new
//! series makes the hole retract exactly as in the original, and the line is written with every
//! word the hole uses.

use super::{Writer, motion_code, num, units};
use crate::gcode::cells::{GCell, Layout};
use crate::gcode::interp::{CutKind, el, known};
use crate::gcode::lex::exact;

const EPS: f64 = 1e-9;

impl Writer<'_> {
    /// Writes the canned-cycle cell `c` (one cycle line).
    pub(super) fn cycle_cell(&mut self, l: &Layout, c: &GCell) {
        let i = c.start;
        if self.continues(i) {
            self.verbatim(i, c.end);
            return;
        }
        let p = self.p;
        let li = &p.lines[i];
        // the line's own modal words (G90/G91, G98/G99) apply to its holes
        if li.after.absolute {
            self.rise_to_series_start(i);
        } else {
            // G91: the line's holes step from the original's position, R from its level
            let entry = known(&li.pos_before).unwrap_or(c.entry);
            let ended = self.il.is_none();
            let before = self.out.len();
            self.link(entry, Some(l.clearance[c.block]), false);
            if self.out.len() == before && !ended {
                self.line("G80");
            }
            self.il = None;
        }
        self.full_line(i);
        self.verbatim_rest(i + 1, c.end);
    }

    /// True when line `i` (a cycle) does in the output exactly what it does in the original
    /// if written as it is: the same series of cycles (or none) at the same level, the same
    /// kept words where the line relies on them (the same cycle in force before it), the same
    /// height, and the same position where the line leaves X or Y to it.
    fn continues(&self, i: usize) -> bool {
        let li = &self.p.lines[i];
        let b = &li.before;
        let same = |a: Option<f64>, b: Option<f64>| match (a, b) {
            (Some(x), Some(y)) => (x - y).abs() < EPS,
            (x, y) => x.is_none() && y.is_none(),
        };
        let here = self.pos.map(|q| q.map(Some)).unwrap_or([None; 3]);
        let xy_free = li.after.absolute && li.words.has('X') && li.words.has('Y');
        let relies = b.motion == li.after.motion;
        // G90 under G99: every hole retracts to R whatever the series, and crosses at the
        // height it starts from when above R (the R plane of the series otherwise)
        let level = if r_plane(&li.after) {
            here[2].is_some_and(|z| z >= hole_r(li) - EPS)
        } else {
            same(self.il, b.cycle_il) && same(here[2], li.pos_before[2])
        };
        level
            && (!relies || (self.motion == b.motion && self.kept == b.cycle))
            && (xy_free || (0..2).all(|k| here[k].is_some() && same(here[k], li.pos_before[k])))
    }

    /// G90: ends the output's series and puts the tool at the height from which a new series
    /// retracts as the original's hole does: under G99 the height the original starts the hole
    /// from (not below R), under G98 (or a mode the program never sets) the original series'
    /// initial level (not below R). Up straight where the tool is lower, else across at its
    /// height to the hole and down.
    fn rise_to_series_start(&mut self, i: usize) {
        let p = self.p;
        let li = &p.lines[i];
        let st = li.after;
        let Some(cut) = li.cuts.first() else { return };
        let CutKind::Cycle { r, .. } = cut.kind else {
            return;
        };
        let il = st.cycle_il.or(li.pos_before[2]).unwrap_or(r);
        let z = self.pos.map(|q| q[2]);
        if r_plane(&st) {
            // retracts to R whatever the series: only never below R (or from an unknown
            // height, up to where the original started the series)
            if z.is_none_or(|z| z < r - EPS) {
                let a = il.max(r);
                self.line(&format!("G0 Z{}", units(&st, a)));
                self.motion = Some(0);
                self.il = None;
                self.pos = self.pos.map(|q| [q[0], q[1], a]);
            }
            return;
        }
        let a = il.max(r);
        let mut moved = false;
        if z.is_none_or(|z| z < a - EPS) {
            self.line(&format!("G0 Z{}", units(&st, a)));
            moved = true;
        } else if z.is_some_and(|z| z > a + EPS) {
            self.line(&format!(
                "G0 X{} Y{}",
                units(&st, cut.to[0]),
                units(&st, cut.to[1])
            ));
            self.line(&format!("G0 Z{}", units(&st, a)));
            self.pos = Some([cut.to[0], cut.to[1], a]);
            moved = true;
        }
        if moved {
            self.motion = Some(0);
            self.pos = Some(
                self.pos
                    .map_or([cut.to[0], cut.to[1], a], |q| [q[0], q[1], a]),
            );
        } else if self.il.is_some() {
            self.line("G80");
            self.motion = None;
        }
        self.il = None;
    }

    /// The cycle line `i` with every word its holes use (in the original's units and distance
    /// mode), the line's other words as written; it starts a new series where the tool is.
    fn full_line(&mut self, i: usize) {
        let p = self.p;
        let li = &p.lines[i];
        let st = li.after;
        let code = st.motion.unwrap_or(810);
        let Some(cut) = li.cuts.first() else { return };
        let word = |c: char| li.words.get(c).map(exact);
        let mut s = format!("G{}", motion_code(code));
        if st.absolute {
            let x = word('X').unwrap_or_else(|| num(cut.to[0] / st.scale(), 10));
            let y = word('Y').unwrap_or_else(|| num(cut.to[1] / st.scale(), 10));
            s.push_str(&format!(" X{x} Y{y}"));
        } else {
            for c in ['X', 'Y'] {
                if let Some(v) = word(c) {
                    s.push_str(&format!(" {c}{v}"));
                }
            }
        }
        let kept = |k: usize| exact(st.cycle[k].unwrap_or(0.0));
        s.push_str(&format!(" Z{} R{}", kept(1), kept(0)));
        if matches!(code, 820 | 860 | 890) {
            s.push_str(&format!(" P{}", kept(2)));
        }
        if matches!(code, 730 | 830) {
            s.push_str(&format!(" Q{}", kept(3)));
        }
        for &(ch, v) in &li.words.words {
            let motion = ch == 'G' && super::is_motion_g(v);
            if !motion && !matches!(ch, 'X' | 'Y' | 'Z' | 'R' | 'P' | 'Q') {
                s.push_str(&format!(" {ch}{}", exact(v)));
            }
        }
        // a new series starts where the tool is; a series in progress goes on
        if self.il.is_none() {
            self.il = self.pos.map(|q| q[2]);
        }
        self.line(&s);
        self.motion = Some(code);
        self.kept = st.cycle;
        self.pos = known(&li.pos_after);
    }

    /// The cell's lines after its cycle line (none: a cycle cell is one line), as written.
    fn verbatim_rest(&mut self, s: usize, e: usize) {
        if e > s {
            self.verbatim(s, e);
        }
    }
}

/// True when the holes of a line in state `st` (after it) retract to R whatever the series:
/// G90 under a G99 the program set.
fn r_plane(st: &crate::gcode::interp::State) -> bool {
    st.absolute && st.set & el::RETRACT != 0 && !st.retract_old_z
}

/// The R plane (mm) of the first hole of cycle line `li`.
fn hole_r(li: &crate::gcode::interp::LineInfo) -> f64 {
    match li.cuts.first().map(|c| c.kind) {
        Some(CutKind::Cycle { r, .. }) => r,
        _ => f64::INFINITY,
    }
}

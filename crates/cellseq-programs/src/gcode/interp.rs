//! A modal RS-274 interpreter: executes lines, tracks state and position, and lists the
//! cutting moves each line makes (what verification compares).

mod cycle;
mod exec;
mod motion;

use super::lex::{Words, tokenize};
use exec::step;

/// Modal state that changes how a line is interpreted (and so must be re-established when
/// a cell is moved).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// G21 (true) or G20.
    pub metric: bool,
    /// G90 (true) or G91.
    pub absolute: bool,
    /// G90.1 (true) or G91.1 (default).
    pub arc_absolute: bool,
    /// 17, 18 or 19.
    pub plane: u8,
    /// Work offset ×10: 540 = G54 … 593 = G59.3.
    pub offset: u16,
    /// Feed (file units per minute).
    pub feed: f64,
    /// Spindle speed / laser power.
    pub speed: f64,
    /// 3, 4 or 5.
    pub spindle: u8,
    /// M7 on.
    pub mist: bool,
    /// M8 on.
    pub flood: bool,
    /// Tool length compensation: `Some(H)` for G43, `None` for G49.
    pub tlc: Option<f64>,
    /// Motion mode ×10 (0, 10, 20, 30, 730, 810 … 890); `None` after G80.
    pub motion: Option<u16>,
    /// G98 (true) or G99.
    pub retract_old_z: bool,
    /// Retained canned-cycle R, Z, P, Q words (file units), as LinuxCNC keeps them for the
    /// next hole of the same cycle.
    pub cycle: [Option<f64>; 4],
    /// The initial level (mm) of the series of canned cycles in progress (LinuxCNC's
    /// `cycle_il`: the Z where the first cycle of an unbroken series started; G98 retracts to
    /// it, G91 R planes are relative to it); `None` outside a series.
    pub cycle_il: Option<f64>,
    /// Tool in the spindle.
    pub tool: u32,
    /// Selected (T word) tool.
    pub selected: u32,
    /// Path control: 610 (G61), 611 (G61.1), 640 (G64) with optional P, Q.
    pub path: Option<(u16, Option<f64>, Option<f64>)>,
    /// Cutter radius compensation on (G41/G42).
    pub cutter_comp: bool,
    /// Feed mode set by G94 (the only one supported).
    pub feed_mode: bool,
    /// Elements the program has set so far ([`el`] bits); the others belong to the operator.
    pub set: u32,
    /// Coordinate-system changes (G10, G52, G92…) executed so far.
    pub epoch: u32,
}

/// Bits of [`State::set`]: the modal elements a program can establish.
pub mod el {
    /// G20/G21.
    pub const UNITS: u32 = 1;
    /// G90/G91.
    pub const DIST: u32 = 1 << 1;
    /// G90.1/G91.1.
    pub const ARC_DIST: u32 = 1 << 2;
    /// G17/G18/G19.
    pub const PLANE: u32 = 1 << 3;
    /// G54 … G59.3.
    pub const OFFSET: u32 = 1 << 4;
    /// F.
    pub const FEED: u32 = 1 << 5;
    /// S.
    pub const SPEED: u32 = 1 << 6;
    /// M3/M4/M5.
    pub const SPINDLE: u32 = 1 << 7;
    /// M7 (or M9).
    pub const MIST: u32 = 1 << 8;
    /// M8 (or M9).
    pub const FLOOD: u32 = 1 << 9;
    /// G43/G49.
    pub const TLC: u32 = 1 << 10;
    /// G61/G61.1/G64.
    pub const PATH: u32 = 1 << 11;
    /// G40/G41/G42.
    pub const CUTTER: u32 = 1 << 12;
    /// G98/G99.
    pub const RETRACT: u32 = 1 << 13;
    /// The tool in the spindle (M6, or T in programs without M6).
    pub const TOOL: u32 = 1 << 14;
    /// G94.
    pub const FEED_MODE: u32 = 1 << 15;
    /// Names of the bits, for messages.
    pub const NAMES: [&str; 16] = [
        "units (G20/G21)",
        "distance mode (G90/G91)",
        "arc distance mode (G90.1/G91.1)",
        "plane (G17/G18/G19)",
        "work offset (G54-G59.3)",
        "feed (F)",
        "spindle speed (S)",
        "spindle (M3/M4/M5)",
        "mist (M7/M9)",
        "flood (M8/M9)",
        "tool length offset (G43/G49)",
        "path mode (G61/G64)",
        "cutter compensation (G40-G42)",
        "canned-cycle retract (G98/G99)",
        "tool (M6)",
        "feed mode (G94)",
    ];
}

impl Default for State {
    fn default() -> Self {
        State {
            metric: true,
            absolute: true,
            arc_absolute: false,
            plane: 17,
            offset: 540,
            feed: 0.0,
            speed: 0.0,
            spindle: 5,
            mist: false,
            flood: false,
            tlc: None,
            motion: None,
            retract_old_z: true,
            cycle: [None; 4],
            cycle_il: None,
            tool: 0,
            selected: 0,
            path: None,
            cutter_comp: false,
            feed_mode: false,
            set: 0,
            epoch: 0,
        }
    }
}

impl State {
    /// mm per file unit.
    pub fn scale(&self) -> f64 {
        if self.metric { 1.0 } else { 25.4 }
    }

    /// The machine state that matters at a cutting move or an event, with what the program set:
    /// everything but the motion mode, canned-cycle words and the selected (not loaded) tool.
    /// Two moves run in the same state exactly when their tags are equal.
    pub fn tag(&self) -> Tag {
        let q = |v: f64| (v * 1e6).round() as i64;
        let (pc, pp, pq) = match self.path {
            Some((c, p, q2)) => (c as i64, p.map(q), q2.map(q)),
            None => (-1, None, None),
        };
        Tag {
            flags: [
                self.metric,
                self.absolute,
                self.arc_absolute,
                self.mist,
                self.flood,
                self.cutter_comp,
                self.retract_old_z,
                self.feed_mode,
            ],
            plane: self.plane,
            offset: self.offset,
            spindle: self.spindle,
            tool: self.tool,
            feed: q(self.feed * self.scale()),
            speed: q(self.speed),
            tlc: self.tlc.map(q),
            path: (pc, pp, pq),
            set: self.set,
            epoch: self.epoch,
        }
    }
}

/// The comparable machine state of [`State::tag`] (values quantized to 1e-6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Tag {
    /// metric, absolute, arc absolute, mist, flood, cutter compensation, G98, G94.
    pub flags: [bool; 8],
    /// Plane.
    pub plane: u8,
    /// Work offset ×10.
    pub offset: u16,
    /// 3, 4, 5.
    pub spindle: u8,
    /// Tool in the spindle.
    pub tool: u32,
    /// Feed in mm/min ×1e6.
    pub feed: i64,
    /// Speed ×1e6.
    pub speed: i64,
    /// Tool length offset H ×1e6.
    pub tlc: Option<i64>,
    /// Path mode code, P, Q.
    pub path: (i64, Option<i64>, Option<i64>),
    /// [`el`] bits set by the program.
    pub set: u32,
    /// Coordinate-system changes so far.
    pub epoch: u32,
}

/// What a cutting move is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CutKind {
    /// Straight feed.
    Line,
    /// Arc: centre (mm), clockwise, plane, turns.
    Arc {
        /// Centre (program coordinates, mm); the out-of-plane coordinate is 0.
        center: [f64; 3],
        /// G2.
        cw: bool,
        /// 17, 18, 19.
        plane: u8,
        /// P word (full turns), 1 by default.
        turns: u32,
    },
    /// A canned-cycle hole: cycle code ×10, R plane, P, Q, L and where it retracts to; the
    /// hole runs from `from` (at R) to `to` (the bottom).
    Cycle {
        /// 730, 810, 820, 830, 850, 860, 890.
        code: u16,
        /// R plane (mm).
        r: f64,
        /// Dwell P (s).
        p: f64,
        /// Peck Q (mm).
        q: f64,
        /// Repeats of the line (L).
        l: u32,
        /// Height the hole retracts to (mm): R under G99, the series' initial level under
        /// G98 (when above R); `None` when the program never sets G98/G99 and the two differ.
        clear: Option<f64>,
        /// Length fed (mm): the pecks, re-entries and feed-outs of the cycle.
        len: f64,
    },
}

/// One cutting move, in program coordinates (mm) with everything that decides what it cuts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cut {
    /// Tool number.
    pub tool: u32,
    /// Line or arc or hole.
    pub kind: CutKind,
    /// Start point (mm); for holes the hole position at the bottom Z.
    pub from: [f64; 3],
    /// End point (mm).
    pub to: [f64; 3],
    /// Feed (mm/min).
    pub feed: f64,
    /// Spindle speed or laser power, 0 when the spindle is off.
    pub speed: f64,
    /// Work offset ×10.
    pub offset: u16,
    /// True when the move started from a position the program does not know on some axis
    /// (after G28/G30/G53): the unknown start coordinates are taken from the end point.
    pub partial: bool,
    /// Axes the program does not know: bits 0–2 the start's X, Y, Z, bits 3–5 the end's (an
    /// unknown end coordinate is stored as 0). Such moves are compared with the mask.
    pub unknown: u8,
}

impl Cut {
    /// Length of the move (mm); holes count their depth below R.
    pub fn length(&self) -> f64 {
        match self.kind {
            CutKind::Line => dist(&self.from, &self.to),
            CutKind::Arc {
                center,
                plane,
                turns,
                cw,
            } => {
                let (a, b, c) = plane_axes(plane);
                let (sa, sb) = (self.from[a] - center[a], self.from[b] - center[b]);
                let (ea, eb) = (self.to[a] - center[a], self.to[b] - center[b]);
                let r = sa.hypot(sb);
                let mut ang = eb.atan2(ea) - sb.atan2(sa);
                if cw {
                    ang = -ang;
                }
                while ang <= 1e-12 {
                    ang += std::f64::consts::TAU;
                }
                ang += (turns.max(1) - 1) as f64 * std::f64::consts::TAU;
                (r * ang).hypot(self.to[c] - self.from[c])
            }
            CutKind::Cycle { len, .. } => len,
        }
    }
    /// XY bounding box `[xmin, ymin, xmax, ymax]` (arcs: conservative).
    pub fn bbox(&self) -> [f64; 4] {
        let mut b = [
            self.from[0].min(self.to[0]),
            self.from[1].min(self.to[1]),
            self.from[0].max(self.to[0]),
            self.from[1].max(self.to[1]),
        ];
        if let CutKind::Arc { center, plane, .. } = self.kind {
            let (a, bb, _) = plane_axes(plane);
            let r = (self.from[a] - center[a]).hypot(self.from[bb] - center[bb]);
            for ax in [a, bb] {
                if ax < 2 {
                    b[ax] = b[ax].min(center[ax] - r);
                    b[ax + 2] = b[ax + 2].max(center[ax] + r);
                }
            }
        }
        b
    }
    /// Points along the move (arcs flattened), for containment tests.
    pub fn polyline(&self, out: &mut Vec<[f64; 2]>) {
        if let CutKind::Arc {
            center,
            plane: 17,
            cw,
            ..
        } = self.kind
        {
            let (sa, sb) = (self.from[0] - center[0], self.from[1] - center[1]);
            let r = sa.hypot(sb);
            let len = self.length();
            let k = ((len / r.max(1e-9)) / 0.2).ceil().clamp(1.0, 256.0) as usize;
            let a0 = sb.atan2(sa);
            let sweep = len.min(r * 64.0) / r.max(1e-9);
            for i in 1..=k {
                let t = a0 + if cw { -1.0 } else { 1.0 } * sweep * i as f64 / k as f64;
                out.push([center[0] + r * t.cos(), center[1] + r * t.sin()]);
            }
            out.push([self.to[0], self.to[1]]);
        } else {
            out.push([self.to[0], self.to[1]]);
        }
    }
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// In-plane axes (a, b) and the linear axis of a plane, right-handed.
pub fn plane_axes(plane: u8) -> (usize, usize, usize) {
    match plane {
        18 => (2, 0, 1),
        19 => (1, 2, 0),
        _ => (0, 1, 2),
    }
}

/// How a line moves the tool.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Motion {
    /// No motion.
    None,
    /// G0.
    Rapid,
    /// G1/G2/G3.
    Feed,
    /// A canned-cycle hole.
    Cycle,
    /// G28/G30/G53: moves to a place the program does not know.
    Home,
}

/// Position with possibly unknown axes (after G28/G53), mm, program coordinates.
pub type Pos = [Option<f64>; 3];

/// Everything the interpreter learnt about one line.
#[derive(Debug, Clone)]
pub struct LineInfo {
    /// 1-based line number in the file.
    pub line: usize,
    /// The words.
    pub words: Words,
    /// State before the line.
    pub before: State,
    /// State after the line.
    pub after: State,
    /// Position before.
    pub pos_before: Pos,
    /// Position after.
    pub pos_after: Pos,
    /// How it moves.
    pub motion: Motion,
    /// True when the line carries an explicit motion G code (G0–G3, G73, G80–G89).
    pub explicit_motion: bool,
    /// M6 (or a T change in files without M6).
    pub tool_change: bool,
    /// M0/M1/M60 pause.
    pub pause: bool,
    /// M5.
    pub spindle_off: bool,
    /// M2/M30.
    pub end: bool,
    /// G10/G92/G52: changes coordinate systems.
    pub setup: bool,
    /// G4 dwell.
    pub dwell: bool,
    /// An M code with effects cellseq does not model (M48–M53 overrides, M62–M68 outputs,
    /// M100–M199 user codes): kept in place.
    pub user_m: bool,
    /// A controller system line (GRBL `$H`, `$X`, …): carried through unchanged, in place.
    pub dialect: bool,
    /// The cutting moves of the line.
    pub cuts: Vec<Cut>,
    /// Rapid length (mm) when both ends are known.
    pub rapid_len: f64,
    /// Highest Z (mm) the line's rapids pass through, when known.
    pub xy_rapid_z: Option<f64>,
}

/// The interpreted program.
#[derive(Debug, Clone)]
pub struct Program {
    /// Source lines (without line terminators).
    pub text: Vec<String>,
    /// One record per line.
    pub lines: Vec<LineInfo>,
    /// True when any motion line carries a Z word or a canned cycle.
    pub has_z: bool,
    /// True when any line carries M6.
    pub has_m6: bool,
}

/// Interprets a program. Errors: `(line, message)`.
pub fn interpret(src: &str) -> Result<Program, (usize, String)> {
    let text: Vec<String> = src
        .lines()
        .enumerate()
        .map(|(i, l)| {
            super::lex::normalize(l)
                .map(|c| c.into_owned())
                .map_err(|e| (i + 1, e))
        })
        .collect::<Result<_, _>>()?;
    let mut words = Vec::with_capacity(text.len());
    let mut has_m6 = false;
    let mut has_z = false;
    let mut read = Reader::new(&text);
    for (i, l) in text.iter().enumerate() {
        let w = read.line(i, l)?;
        has_m6 |= w.has_m(6.0);
        has_z |= w.has('Z') || is_cycle_line(&w);
        words.push(w);
    }
    let mut st = State::default();
    let mut pos: Pos = [Some(0.0); 3];
    let mut lines = Vec::with_capacity(text.len());
    for (i, w) in words.into_iter().enumerate() {
        let info = step(i + 1, w, &mut st, &mut pos, has_m6).map_err(|e| (i + 1, e))?;
        lines.push(info);
    }
    Ok(Program {
        text,
        lines,
        has_z,
        has_m6,
    })
}

/// Interprets a program like [`interpret`] without keeping it: `f` gets each line's index,
/// record and normalized text in order, and the records are dropped after the call (memory
/// stays constant; the verifier checks a rewritten program this way). The lines are read
/// twice: once for M6 and Z words (which decide how lines are read), once to execute them.
/// Returns `(has_z, has_m6)` as in [`Program`]. Errors: `(line, message)`.
pub fn interpret_each(
    src: &str,
    mut f: impl FnMut(usize, &LineInfo, &str),
) -> Result<(bool, bool), (usize, String)> {
    let mut has_m6 = false;
    let mut has_z = false;
    let first = src
        .lines()
        .map(|l| l.trim().to_string())
        .find(|l| !l.is_empty());
    let mut read = Reader::starting(first.as_deref());
    for (i, l) in src.lines().enumerate() {
        let l = super::lex::normalize(l).map_err(|e| (i + 1, e))?;
        let w = read.line(i, &l)?;
        has_m6 |= w.has_m(6.0);
        has_z |= w.has('Z') || is_cycle_line(&w);
    }
    let mut st = State::default();
    let mut pos: Pos = [Some(0.0); 3];
    let mut read = Reader::starting(first.as_deref());
    for (i, l) in src.lines().enumerate() {
        let l = super::lex::normalize(l).map_err(|e| (i + 1, e))?;
        let w = read.line(i, &l)?;
        let info = step(i + 1, w, &mut st, &mut pos, has_m6).map_err(|e| (i + 1, e))?;
        f(i, &info, &l);
    }
    Ok((has_z, has_m6))
}

/// Reads lines into words in program order: parameters carry from line to line, and in a
/// program that starts with a `%` line everything after the closing `%` is not part of the
/// program (LinuxCNC ignores it): such lines read as empty and are copied as they are.
struct Reader {
    params: super::expr::Params,
    /// The program's first non-blank line is `%`.
    percent: bool,
    /// The opening `%` has been read.
    opened: bool,
    /// The closing `%` has been read: the rest is not part of the program.
    ended: bool,
}

impl Reader {
    fn new(text: &[String]) -> Self {
        Reader::starting(text.iter().map(|l| l.trim()).find(|l| !l.is_empty()))
    }

    fn starting(first: Option<&str>) -> Self {
        Reader {
            params: Default::default(),
            percent: first == Some("%"),
            opened: false,
            ended: false,
        }
    }

    /// The words of line `i` (0-based), errors with the 1-based line number.
    fn line(&mut self, i: usize, l: &str) -> Result<Words, (usize, String)> {
        if self.ended {
            return Ok(Words::default());
        }
        if self.percent && l.trim() == "%" {
            self.ended = self.opened;
            self.opened = true;
            return Ok(Words::default());
        }
        tokenize(l, &mut self.params).map_err(|e| (i + 1, e))
    }
}

/// True when the line names a canned-cycle G code (its holes move in Z).
fn is_cycle_line(w: &Words) -> bool {
    w.all('G').any(|g| {
        let c = (g * 10.0).round() as i64;
        c == 730 || (810..=890).contains(&c)
    })
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-6
}

/// All three coordinates when known.
pub fn known(p: &Pos) -> Option<[f64; 3]> {
    Some([p[0]?, p[1]?, p[2]?])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arcs_r_and_ijk_agree() {
        let a = interpret("G21 G90 G17\nG0 X0 Y0 Z0\nG2 X2 Y0 R1 F100\nG0 X0 Y0\nG2 X2 Y0 I1 J0\n")
            .unwrap();
        let c1 = a.lines[2].cuts[0];
        let c2 = a.lines[4].cuts[0];
        match (c1.kind, c2.kind) {
            (CutKind::Arc { center: x, .. }, CutKind::Arc { center: y, .. }) => {
                assert!((x[0] - y[0]).abs() < 1e-9 && (x[1] - y[1]).abs() < 1e-9);
            }
            _ => panic!("not arcs"),
        }
        assert!((c1.length() - std::f64::consts::PI).abs() < 1e-9);
    }

    #[test]
    fn inch_and_incremental() {
        let p = interpret("G20 G90\nG0 X1 Y0 Z0\nG91 G1 X1 F10\n").unwrap();
        let c = p.lines[2].cuts[0];
        assert!((c.to[0] - 50.8).abs() < 1e-9);
        assert!((c.feed - 254.0).abs() < 1e-9);
    }
}

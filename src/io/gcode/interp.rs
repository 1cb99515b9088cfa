//! A modal RS-274 interpreter: executes lines, tracks state and position, and lists the
//! cutting moves each line makes (what verification compares).

use super::lex::{Words, tokenize};

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
    /// Retained canned-cycle R, Z, P, Q (file units).
    pub cycle: [Option<f64>; 4],
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
    /// A canned-cycle hole: cycle code ×10, R and bottom Z (mm), P, Q (mm), L.
    Cycle {
        /// 730, 810 … 890.
        code: u16,
        /// R plane (mm).
        r: f64,
        /// Dwell P (s).
        p: f64,
        /// Peck Q (mm).
        q: f64,
        /// Repeats.
        l: u32,
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
            CutKind::Cycle { r, l, .. } => (r - self.to[2]).abs() * l.max(1) as f64,
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
    for (i, l) in text.iter().enumerate() {
        let w = tokenize(l).map_err(|e| (i + 1, e))?;
        has_m6 |= w.has_m(6.0);
        has_z |= w.has('Z');
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
    for (i, l) in src.lines().enumerate() {
        let l = super::lex::normalize(l).map_err(|e| (i + 1, e))?;
        let w = tokenize(&l).map_err(|e| (i + 1, e))?;
        has_m6 |= w.has_m(6.0);
        has_z |= w.has('Z');
    }
    let mut st = State::default();
    let mut pos: Pos = [Some(0.0); 3];
    for (i, l) in src.lines().enumerate() {
        let l = super::lex::normalize(l).map_err(|e| (i + 1, e))?;
        let w = tokenize(&l).map_err(|e| (i + 1, e))?;
        let info = step(i + 1, w, &mut st, &mut pos, has_m6).map_err(|e| (i + 1, e))?;
        f(i, &info, &l);
    }
    Ok((has_z, has_m6))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() < 1e-6
}

fn step(
    line: usize,
    w: Words,
    st: &mut State,
    pos: &mut Pos,
    has_m6: bool,
) -> Result<LineInfo, String> {
    let before = *st;
    let pos_before = *pos;
    let mut info = LineInfo {
        line,
        words: Words::default(),
        before,
        after: before,
        pos_before,
        pos_after: pos_before,
        motion: Motion::None,
        explicit_motion: false,
        tool_change: false,
        pause: false,
        spindle_off: false,
        end: false,
        setup: false,
        dwell: false,
        user_m: false,
        dialect: w.dialect,
        cuts: Vec::new(),
        rapid_len: 0.0,
        xy_rapid_z: None,
    };
    if w.dialect {
        if w.homing {
            info.motion = Motion::Home;
            *pos = [None; 3];
        }
        return Ok(finish(info, w, st, pos));
    }
    for &(c, _) in &w.words {
        if !matches!(
            c,
            'G' | 'M'
                | 'X'
                | 'Y'
                | 'Z'
                | 'I'
                | 'J'
                | 'K'
                | 'R'
                | 'P'
                | 'Q'
                | 'L'
                | 'F'
                | 'S'
                | 'T'
                | 'H'
                | 'D'
        ) {
            return Err(format!(
                "word '{c}' is not supported (axes A/B/C/U/V/W, E are refused); remove it or use a 3-axis program"
            ));
        }
    }
    for c in [
        'X', 'Y', 'Z', 'I', 'J', 'K', 'R', 'F', 'S', 'T', 'H', 'P', 'Q', 'L',
    ] {
        if w.all(c).count() > 1 {
            return Err(format!("word '{c}' appears twice"));
        }
    }
    // classify G codes
    let mut motion_g: Option<u16> = None;
    let mut nonmodal: Option<u16> = None;
    for g in w.all('G') {
        let code = (g * 10.0).round() as i64;
        if !close(code as f64, g * 10.0) || code < 0 {
            return Err(format!("G{g} is not a G code"));
        }
        let code = code as u16;
        match code {
            0 | 10 | 20 | 30 | 730 | 810..=890 if code.is_multiple_of(10) || code == 730 => {
                if motion_g.is_some() {
                    return Err("two motion G codes on one line".into());
                }
                motion_g = Some(code);
            }
            800 => {
                if motion_g.is_some() {
                    return Err("G80 with another motion code".into());
                }
                motion_g = Some(800);
            }
            40 | 280 | 300 | 530 | 100 | 920 | 921 | 922 | 923 | 520 | 281 | 301 => {
                if nonmodal.is_some() && code != 530 {
                    return Err("two non-modal G codes on one line".into());
                }
                if code == 530 {
                    nonmodal = nonmodal.or(Some(530));
                } else {
                    nonmodal = Some(code);
                }
            }
            170 | 180 | 190 | 200 | 210 | 400 | 410 | 420 | 430 | 490 | 540 | 550 | 560 | 570
            | 580 | 590 | 591 | 592 | 593 | 610 | 611 | 640 | 900 | 910 | 901 | 911 | 940 | 980
            | 990 => {}
            930 | 950 => {
                return Err("inverse-time / per-revolution feed (G93/G95) is not supported; use units-per-minute feed (G94) instead".into());
            }
            _ => {
                return Err(format!(
                    "G{g} is not supported; remove it or replace it with plain moves and try again"
                ));
            }
        }
    }
    // feed, speed, tool
    if let Some(f) = w.get('F') {
        st.feed = f;
        st.set |= el::FEED;
    }
    if let Some(s) = w.get('S') {
        st.speed = s;
        st.set |= el::SPEED;
    }
    if let Some(t) = w.get('T') {
        if t < 0.0 || !close(t, t.round()) {
            return Err(format!("bad tool number T{t}"));
        }
        st.selected = t as u32;
        if !has_m6 && (st.tool != st.selected || st.set & el::TOOL == 0) {
            info.tool_change = st.tool != st.selected;
            st.tool = st.selected;
            st.set |= el::TOOL;
        }
    }
    for m in w.all('M') {
        let code = m.round() as i64;
        if !close(code as f64, m) {
            return Err(format!(
                "M{m} is not supported; remove it or replace it with a standard M code and try again"
            ));
        }
        match code {
            6 => {
                st.tool = st.selected;
                st.set |= el::TOOL;
                info.tool_change = true;
            }
            3 | 4 => {
                st.spindle = code as u8;
                st.set |= el::SPINDLE;
            }
            5 => {
                st.spindle = 5;
                st.set |= el::SPINDLE;
                info.spindle_off = true;
            }
            7 => {
                st.mist = true;
                st.set |= el::MIST;
            }
            8 => {
                st.flood = true;
                st.set |= el::FLOOD;
            }
            9 => {
                st.mist = false;
                st.flood = false;
                st.set |= el::MIST | el::FLOOD;
            }
            0 | 1 | 60 => info.pause = true,
            2 | 30 => info.end = true,
            48..=53 | 62..=68 | 100..=199 => info.user_m = true,
            _ => {
                return Err(format!(
                    "M{code} is not supported; remove it or replace it with a standard M code and try again"
                ));
            }
        }
    }
    // modal G codes in execution order
    for g in w.all('G') {
        let code = (g * 10.0).round() as u16;
        let bit = match code {
            170 | 180 | 190 => {
                st.plane = (code / 10) as u8;
                el::PLANE
            }
            200 | 210 => {
                st.metric = code == 210;
                el::UNITS
            }
            400 => {
                st.cutter_comp = false;
                el::CUTTER
            }
            410 | 420 => {
                st.cutter_comp = true;
                el::CUTTER
            }
            430 => {
                st.tlc = Some(w.get('H').unwrap_or(st.tool as f64));
                el::TLC
            }
            490 => {
                st.tlc = None;
                el::TLC
            }
            540..=593 => {
                st.offset = code;
                el::OFFSET
            }
            610 | 611 => {
                st.path = Some((code, None, None));
                el::PATH
            }
            640 => {
                st.path = Some((640, w.get('P'), w.get('Q')));
                el::PATH
            }
            900 | 910 => {
                st.absolute = code == 900;
                el::DIST
            }
            901 | 911 => {
                st.arc_absolute = code == 901;
                el::ARC_DIST
            }
            940 => {
                st.feed_mode = true;
                el::FEED_MODE
            }
            980 | 990 => {
                st.retract_old_z = code == 980;
                el::RETRACT
            }
            40 => {
                info.dwell = true;
                0
            }
            _ => 0,
        };
        st.set |= bit;
    }
    if let Some(m) = motion_g {
        info.explicit_motion = true;
        st.motion = if m == 800 { None } else { Some(m) };
    }
    let axes = w.has('X') || w.has('Y') || w.has('Z');
    let scale = st.scale();
    let target = |pos: &Pos, absolute: bool| -> Result<Pos, String> {
        let mut t = *pos;
        for (k, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if let Some(v) = w.get(c) {
                t[k] = if absolute {
                    Some(v * scale)
                } else {
                    Some(pos[k].ok_or("incremental move from an unknown position")? + v * scale)
                };
            }
        }
        Ok(t)
    };
    match nonmodal {
        Some(40) => {}
        Some(100) | Some(920) | Some(921) | Some(922) | Some(923) | Some(520) => {
            info.setup = true;
            st.epoch += 1;
            if matches!(nonmodal, Some(920) | Some(520)) {
                // the program position becomes what the words say
                *pos = target(pos, true)?;
            }
            info.words = w;
            info.after = *st;
            info.pos_after = *pos;
            return Ok(info);
        }
        Some(280) | Some(300) => {
            info.motion = Motion::Home;
            *pos = [None; 3];
            info.words = w;
            info.after = *st;
            info.pos_after = *pos;
            return Ok(info);
        }
        Some(281) | Some(301) => {}
        Some(530) if !axes => {
            // G53 without axis words moves nothing (LinuxCNC accepts `G53 G0 G17`)
        }
        Some(530) => {
            if !matches!(st.motion, Some(0) | Some(10)) {
                return Err("G53 needs G0 or G1".into());
            }
            info.motion = Motion::Home;
            for (k, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                if w.has(c) {
                    pos[k] = None;
                }
            }
            info.words = w;
            info.after = *st;
            info.pos_after = *pos;
            return Ok(info);
        }
        _ => {}
    }
    let arc_words = w.has('I') || w.has('J') || w.has('K') || w.has('R');
    let run_motion = axes || (info.explicit_motion && motion_g != Some(800));
    if run_motion {
        let mode = st
            .motion
            .ok_or("axis words with no motion mode (after G80)")?;
        let cut_base = |st: &State| Cut {
            tool: st.tool,
            kind: CutKind::Line,
            from: [0.0; 3],
            to: [0.0; 3],
            feed: st.feed * st.scale(),
            speed: if st.spindle == 5 { 0.0 } else { st.speed },
            offset: st.offset,
            partial: false,
        };
        match mode {
            0 | 10 => {
                if arc_words && mode != 0 {
                    return Err("I/J/K/R words on a straight move".into());
                }
                let t = target(pos, st.absolute)?;
                if mode == 0 {
                    info.motion = Motion::Rapid;
                    if let (Some(a), Some(b)) = (known(pos), known(&t)) {
                        info.rapid_len = dist(&a, &b);
                        if (a[0] - b[0]).abs() > 1e-9 || (a[1] - b[1]).abs() > 1e-9 {
                            info.xy_rapid_z = Some(a[2].max(b[2]));
                        }
                    }
                } else {
                    info.motion = Motion::Feed;
                    let to = known(&t).ok_or(
                        "feed move to a position the program does not know (after G28/G30/G53: \
                         give X, Y and Z in an absolute move first)",
                    )?;
                    // after G28/G30/G53 an axis the move does not name is where the controller
                    // left it: the move is kept in place and compared with that axis unknown
                    let from = [0, 1, 2].map(|k| pos[k].unwrap_or(to[k]));
                    if st.feed <= 0.0 {
                        return Err("feed move with no feed rate (F); add an F word before the first feed move and try again (LinuxCNC refuses it too)".into());
                    }
                    let mut c = cut_base(st);
                    c.from = from;
                    c.to = to;
                    c.partial = known(pos).is_none();
                    info.cuts.push(c);
                }
                *pos = t;
            }
            20 | 30 => {
                if !(axes || w.has('I') || w.has('J') || w.has('K')) {
                    return Err(
                        "G2/G3 with neither axis words nor I/J/K (LinuxCNC refuses it too); remove the line or give the arc its end point and centre".into(),
                    );
                }
                if st.feed <= 0.0 {
                    return Err("arc with no feed rate (F); add an F word before the first feed move and try again (LinuxCNC refuses it too)".into());
                }
                let from = known(pos).ok_or("arc from an unknown position (after G28/G53)")?;
                let t = target(pos, st.absolute)?;
                let to = known(&t).ok_or("arc to an unknown position")?;
                let (a, b, _) = plane_axes(st.plane);
                let cw = mode == 20;
                let letters = ['I', 'J', 'K'];
                let mut center = [0.0; 3];
                if let Some(r) = w.get('R') {
                    if w.has('I') || w.has('J') || w.has('K') {
                        return Err("arc with both R and I/J/K".into());
                    }
                    let r = r * scale;
                    let (da, db) = (to[a] - from[a], to[b] - from[b]);
                    let d = da.hypot(db);
                    if d < 1e-9 {
                        return Err("R-format arc with coincident start and end".into());
                    }
                    let half = d / 2.0;
                    let h2 = r * r - half * half;
                    if h2 < -(1e-3 * r.abs().max(1.0)) {
                        return Err(format!("arc radius R{} too small for the chord", r / scale));
                    }
                    let h = h2.max(0.0).sqrt();
                    let (ua, ub) = (da / d, db / d);
                    let (na, nb) = (-ub, ua);
                    let sign = if cw { -1.0 } else { 1.0 } * if r < 0.0 { -1.0 } else { 1.0 };
                    center[a] = (from[a] + to[a]) / 2.0 + sign * h * na;
                    center[b] = (from[b] + to[b]) / 2.0 + sign * h * nb;
                } else {
                    for ax in [a, b] {
                        let v = w.get(letters[ax]).unwrap_or(0.0) * scale;
                        center[ax] = if st.arc_absolute { v } else { from[ax] + v };
                    }
                    if !(w.has(letters[a]) || w.has(letters[b])) {
                        return Err("arc without centre words (I/J/K) or R".into());
                    }
                    let r1 = (from[a] - center[a]).hypot(from[b] - center[b]);
                    let r2 = (to[a] - center[a]).hypot(to[b] - center[b]);
                    // LinuxCNC's rule, measured with its `rs274` on arcs of radius 1 to 1000:
                    // refused when the radii differ by more than 0.1 % of the start radius and
                    // by more than 0.028 mm (G21) or 0.002 inch (G20)
                    let abs_tol = if st.metric { 0.028 } else { 0.002 * 25.4 };
                    if (r1 - r2).abs() > abs_tol && (r1 - r2).abs() > 1e-3 * r1 {
                        return Err(format!(
                            "arc radius to end point differs from radius to start point ({r1:.4} vs {r2:.4} mm; \
                             LinuxCNC refuses it too): correct the arc's end point or centre and try again"
                        ));
                    }
                }
                let turns = match w.get('P') {
                    Some(p) if p >= 1.0 && close(p, p.round()) => p as u32,
                    Some(p) => return Err(format!("bad arc turn count P{p}")),
                    None => 1,
                };
                info.motion = Motion::Feed;
                let mut c = cut_base(st);
                c.from = from;
                c.to = to;
                c.kind = CutKind::Arc {
                    center,
                    cw,
                    plane: st.plane,
                    turns,
                };
                info.cuts.push(c);
                *pos = t;
            }
            _ => {
                // canned cycle
                if !st.absolute {
                    return Err("canned cycles in incremental mode (G91) are not supported".into());
                }
                if st.plane != 17 {
                    return Err("canned cycles outside the XY plane (G17) are not supported".into());
                }
                if st.cutter_comp {
                    return Err("canned cycle with cutter compensation on".into());
                }
                for (k, c) in ['R', 'Z', 'P', 'Q'].into_iter().enumerate() {
                    if let Some(v) = w.get(c) {
                        st.cycle[k] = Some(v);
                    }
                }
                if !axes {
                    return Ok(finish(info, w, st, pos));
                }
                let r = st.cycle[0].ok_or("canned cycle without R")? * scale;
                let z = st.cycle[1].ok_or("canned cycle without Z")? * scale;
                if st.feed <= 0.0 {
                    return Err("canned cycle with no feed rate (F); add an F word before the first feed move and try again (LinuxCNC refuses it too)".into());
                }
                let l = match w.get('L') {
                    Some(l) if l >= 1.0 && close(l, l.round()) => l as u32,
                    Some(l) => return Err(format!("bad repeat count L{l}")),
                    None => 1,
                };
                let old = known(pos).ok_or("canned cycle from an unknown position")?;
                let x = w.get('X').map(|v| v * scale).unwrap_or(old[0]);
                let y = w.get('Y').map(|v| v * scale).unwrap_or(old[1]);
                let mut c = cut_base(st);
                c.from = [x, y, r];
                c.to = [x, y, z];
                c.kind = CutKind::Cycle {
                    code: mode,
                    r,
                    p: st.cycle[2].unwrap_or(0.0),
                    q: st.cycle[3].unwrap_or(0.0) * scale,
                    l,
                };
                info.cuts.push(c);
                info.motion = Motion::Cycle;
                let top = old[2].max(r);
                info.rapid_len = (old[0] - x).hypot(old[1] - y) + (top - r) * 2.0;
                info.xy_rapid_z = None;
                let endz = if st.retract_old_z { top } else { r };
                *pos = [Some(x), Some(y), Some(endz)];
            }
        }
    }
    Ok(finish(info, w, st, pos))
}

fn finish(mut info: LineInfo, w: Words, st: &State, pos: &Pos) -> LineInfo {
    info.words = w;
    info.after = *st;
    info.pos_after = *pos;
    info
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

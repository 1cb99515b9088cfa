//! Equivalence check between two programs and their travel figures.
//!
//! A program is summed up in one pass as a [`Digest`] (hashes of its state-tagged cutting
//! moves and events, sorted, its motions before the first cut, its rapids across, its
//! figures); two digests are compared, and the lines are read again only to pair moves that
//! fell on both sides of a grid line and to describe a difference. A program text can be
//! checked without ever holding its interpreted lines ([`Lines::Text`]).

use super::interp::{Cut, CutKind, LineInfo, Motion, Program, State, Tag};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
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
    let mut m = Measure::new(safe);
    p.lines.iter().for_each(|li| m.add(li));
    m.finish()
}

/// [`figures`] one line at a time.
#[derive(Debug, Clone, Copy)]
struct Measure {
    f: Figures,
    safe: Option<f64>,
    cut_time: f64,
    cutting: bool,
}

impl Measure {
    fn new(safe: Option<f64>) -> Self {
        Measure {
            f: Figures::default(),
            safe,
            cut_time: 0.0,
            cutting: false,
        }
    }

    fn add(&mut self, li: &LineInfo) {
        let f = &mut self.f;
        f.air_length += li.rapid_len;
        if li.tool_change {
            f.tool_changes += 1;
        }
        for c in &li.cuts {
            f.cuts += 1;
            let len = c.length();
            f.cut_length += len;
            if c.feed > 0.0 {
                self.cut_time += len / c.feed * 60.0;
            }
        }
        match self.safe {
            Some(s) => {
                if let (Some(a), Some(b)) = (li.pos_before[2], li.pos_after[2])
                    && a < s - 1e-6
                    && b >= s - 1e-6
                {
                    f.lifts += 1;
                }
                if li.motion == Motion::Cycle {
                    f.lifts += li.cuts.len();
                }
            }
            None => match li.motion {
                Motion::Feed => self.cutting = true,
                Motion::Rapid | Motion::Home if self.cutting => {
                    f.lifts += 1;
                    self.cutting = false;
                }
                _ => {}
            },
        }
    }

    fn finish(self) -> Figures {
        let mut f = self.f;
        f.est_time_s = self.cut_time
            + f.air_length / RAPID_MM_MIN * 60.0
            + f.tool_changes as f64 * TOOL_CHANGE_S;
        f
    }
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
            clear,
            ..
        } => {
            k.extend([2, code as i64, q(r), q(p), q(qq), l as i64]);
            k.extend(clear.map_or([0, 0], |c| [1, q(c)]));
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
                clear: e1,
                ..
            },
            CutKind::Cycle {
                code: c2,
                r: r2,
                p: p2,
                q: q2,
                l: l2,
                clear: e2,
                ..
            },
        ) => {
            c1 == c2
                && l1 == l2
                && close(r1, r2)
                && close(p1, p2)
                && close(q1, q2)
                && match (e1, e2) {
                    (Some(a), Some(b)) => close(a, b),
                    (a, b) => a.is_none() && b.is_none(),
                }
        }
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

/// The lines of a program for the checks: a program held in memory, or a program text that
/// is interpreted line by line and never held (how `optimize` checks its output, so a program
/// of 10^6 moves is not held twice).
#[derive(Debug, Clone, Copy)]
pub enum Lines<'a> {
    /// An interpreted program.
    Program(&'a Program),
    /// A program text, interpreted on each pass.
    Text(&'a str),
}

impl Lines<'_> {
    /// Calls `f(index, line, text)` for every line in order; returns the program's `has_z`.
    /// Errors: the interpreter's `(line, message)`.
    fn each(&self, mut f: impl FnMut(usize, &LineInfo, &str)) -> Result<bool, (usize, String)> {
        match self {
            Lines::Program(p) => {
                for (i, li) in p.lines.iter().enumerate() {
                    f(i, li, &p.text[i]);
                }
                Ok(p.has_z)
            }
            Lines::Text(t) => super::interp::interpret_each(t, f).map(|(z, _)| z),
        }
    }

    /// [`Lines::each`] for a program already read once (a second pass cannot fail unless the
    /// interpreter is not deterministic, which is then reported as a mismatch).
    fn again(&self, f: impl FnMut(usize, &LineInfo, &str)) -> Result<(), String> {
        self.each(f)
            .map(|_| ())
            .map_err(|(l, m)| format!("line {l} read differently on a second pass: {m}"))
    }
}

/// Everything the checks compare, gathered in one pass over a program, in compact form
/// (hashes of state-tagged moves and events, sorted; 32 bytes per cutting move): what is
/// kept of a program instead of its interpreted lines.
#[derive(Debug, Clone, PartialEq)]
pub struct Digest {
    /// Hash of each cutting move with its state, line index and index within the line; sorted.
    cuts: Vec<(u128, u32, u32)>,
    /// Events the output must have as many of (hash, line number); sorted.
    exact: Vec<(u128, usize)>,
    /// Events the output may have fewer of (tool changes, moves to machine positions); sorted.
    fewer: Vec<(u128, usize)>,
    /// Motions and tool changes before the first cut, in order.
    lead_in: Vec<u128>,
    /// Per tool, the lowest height of a rapid across in X/Y.
    low: BTreeMap<u32, f64>,
    /// Rapids across in X/Y: line number, tool, height.
    rapids: Vec<(usize, u32, f64)>,
    /// True when any motion line carries Z.
    has_z: bool,
    /// Travel figures.
    pub figures: Figures,
}

impl Digest {
    /// One pass over `src`. Moves are keyed on the `tol` grid, direction-free with
    /// `undirected_match` (see [`undirected`]); `safe` as in [`figures`].
    pub fn of(
        src: Lines,
        tol: f64,
        undirected_match: bool,
        safe: Option<f64>,
    ) -> Result<Digest, (usize, String)> {
        let q = |v: Option<f64>| v.map(|x| (x / tol).round() as i64);
        let mut m = Measure::new(safe);
        let mut d = Digest {
            cuts: Vec::new(),
            exact: Vec::new(),
            fewer: Vec::new(),
            lead_in: Vec::new(),
            low: BTreeMap::new(),
            rapids: Vec::new(),
            has_z: false,
            figures: Figures::default(),
        };
        let mut cut_seen = false;
        d.has_z = src.each(|i, li, text| {
            m.add(li);
            let t = tag(li);
            for (j, c) in li.cuts.iter().enumerate() {
                if matches!(c.kind, CutKind::Line) && c.length() <= ZERO_MOVE {
                    continue;
                }
                let c = oriented(c, tol, undirected_match);
                d.cuts
                    .push((hash128(&(key(&c, tol), c.unknown, t)), i as u32, j as u32));
            }
            for (e, h) in events(li, text) {
                if e {
                    d.exact.push((h, li.line));
                } else {
                    d.fewer.push((h, li.line));
                }
            }
            cut_seen |= !li.cuts.is_empty();
            if !cut_seen && (li.motion != Motion::None || li.tool_change) {
                let p = li.pos_after.map(q);
                d.lead_in
                    .push(hash128(&(li.motion as u8, li.tool_change, p)));
            }
            if let Some(z) = li.xy_rapid_z {
                let e = d.low.entry(li.before.tool).or_insert(z);
                *e = f64::min(*e, z);
                d.rapids.push((li.line, li.before.tool, z));
            }
        })?;
        d.cuts.sort_unstable();
        d.exact.sort_unstable();
        d.fewer.sort_unstable();
        d.figures = m.finish();
        Ok(d)
    }
}

/// The move as it is compared: direction-free with `undirected_match`.
fn oriented(c: &Cut, tol: f64, undirected_match: bool) -> Cut {
    if undirected_match {
        undirected(c, tol)
    } else {
        *c
    }
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
    let (la, lb) = (Lines::Program(a), Lines::Program(b));
    let da = Digest::of(la, tol, undirected_match, None).map_err(|(_, m)| m)?;
    let db = Digest::of(lb, tol, undirected_match, None).map_err(|(_, m)| m)?;
    compare((la, &da), (lb, &db), tol, undirected_match)
}

/// [`equivalent`] on digests made with the same `tol` and `undirected_match`; the lines are
/// read again only to pair moves that fell on both sides of a grid line and to describe a
/// difference.
pub fn compare(
    a: (Lines, &Digest),
    b: (Lines, &Digest),
    tol: f64,
    undirected_match: bool,
) -> Result<Equivalence, String> {
    let cuts = match_cuts(a, b, tol, undirected_match)?;
    let events = same_events(a.1, b.1)?;
    no_new_motion(a.1, b.1, tol)?;
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
    let (la, lb) = (Lines::Program(a), Lines::Program(b));
    let da = Digest::of(la, tol, undirected_match, None).map_err(|(_, m)| m)?;
    let db = Digest::of(lb, tol, undirected_match, None).map_err(|(_, m)| m)?;
    match_cuts((la, &da), (lb, &db), tol, undirected_match)
}

/// Moves by `(line index, index in line)`, oriented, with their state.
type Fetched = HashMap<(u32, u32), (Cut, Tag)>;

/// The moves at `(line index, index in line)` of `want`, oriented, with their state.
fn fetch(
    src: Lines,
    want: &[(u128, u32, u32)],
    tol: f64,
    undirected_match: bool,
) -> Result<Fetched, String> {
    let mut lines: HashMap<u32, Vec<u32>> = HashMap::new();
    for x in want {
        lines.entry(x.1).or_default().push(x.2);
    }
    let mut out = HashMap::new();
    src.again(|i, li, _| {
        if let Some(js) = lines.get(&(i as u32)) {
            for &j in js {
                if let Some(c) = li.cuts.get(j as usize) {
                    out.insert((i as u32, j), (oriented(c, tol, undirected_match), tag(li)));
                }
            }
        }
    })?;
    Ok(out)
}

/// [`same_cuts`] on digests: returns how many moves were matched.
fn match_cuts(
    (a, da): (Lines, &Digest),
    (b, db): (Lines, &Digest),
    tol: f64,
    undirected_match: bool,
) -> Result<usize, String> {
    let (ka, kb) = (&da.cuts, &db.cuts);
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
    if ua.is_empty() && ub.is_empty() {
        return Ok(ka.len());
    }
    if ua.len() == ub.len() && ua.len() <= 10_000 {
        let (ma, mb) = (
            fetch(a, &ua, tol, undirected_match)?,
            fetch(b, &ub, tol, undirected_match)?,
        );
        let get =
            |m: &HashMap<(u32, u32), (Cut, Tag)>, x: &(u128, u32, u32)| m.get(&(x.1, x.2)).copied();
        let mut taken = vec![false; ub.len()];
        let all = ua.iter().all(|x| {
            let Some((ca, ta)) = get(&ma, x) else {
                return false;
            };
            let hit = ub.iter().enumerate().position(|(k, y)| {
                !taken[k]
                    && get(&mb, y).is_some_and(|(cb, tb)| {
                        ta == tb && ca.unknown == cb.unknown && same(&ca, &cb, tol)
                    })
            });
            hit.map(|k| taken[k] = true).is_some()
        });
        if all {
            return Ok(ka.len());
        }
    }
    Err(mismatch((a, da), (b, db), tol, undirected_match))
}

/// Describes the first cutting move of one program that the other lacks.
fn mismatch(
    (a, da): (Lines, &Digest),
    (b, db): (Lines, &Digest),
    tol: f64,
    undirected_match: bool,
) -> String {
    let (ka, kb) = (&da.cuts, &db.cuts);
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
    // the lone move, its line number and state
    let mut found: Option<(usize, Cut, State)> = None;
    let read = p.again(|i, li, _| {
        if i as u32 == x.1
            && let Some(c) = li.cuts.get(x.2 as usize)
        {
            found = Some((li.line, oriented(c, tol, undirected_match), li.after));
        }
    });
    let Some((line, c, st)) = found.filter(|_| read.is_ok()) else {
        return format!("cutting moves differ ({counts})");
    };
    let (which, other) = if in_a {
        ("the original's", "the output")
    } else {
        ("the output's", "the original")
    };
    // the same move in another state?
    let mut twin: Option<(usize, State)> = None;
    let _ = q.again(|_, l2, _| {
        if twin.is_none()
            && l2
                .cuts
                .iter()
                .any(|c2| same(&oriented(c2, tol, undirected_match), &c, 1e-3))
        {
            twin = Some((l2.line, l2.after));
        }
    });
    match twin {
        Some((line2, st2)) => format!(
            "{counts}; {which} line {line} cuts {} with {}, {other} (line {line2}) with {}",
            describe(&c),
            state_words(&st, &st2),
            state_words(&st2, &st),
        ),
        None => format!(
            "{counts}; {which} line {line} cuts {}, which {other} never cuts",
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

/// A word's value as an event key holds it: in millionths (truncated).
fn micro(x: f64) -> i64 {
    (x * 1e6) as i64
}

/// A line's words as an event key holds them: letter and value in millionths ([`micro`]).
fn quantized(w: &crate::gcode::lex::Words) -> Vec<(char, i64)> {
    w.words.iter().map(|&(c, x)| (c, micro(x))).collect()
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
        v.push((false, hash128(&("home", quantized(w), t))));
    }
    if li.setup {
        v.push((true, hash128(&("setup", quantized(w), t))));
    }
    if li.dwell {
        v.push((
            true,
            // at its height (at the bottom of a hole, or where the spindle comes up to speed)
            hash128(&(
                "dwell",
                w.get('P').map(micro),
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
fn same_events(a: &Digest, b: &Digest) -> Result<usize, String> {
    let (ea, fa, eb, fb) = (&a.exact, &a.fewer, &b.exact, &b.fewer);
    // the first event of one program that the other lacks (sorted multisets)
    let lone = |line: usize, of: &str, other: &str| {
        format!(
            "events differ (dwell with its height, pause, user M code, coordinate-system change \
             or controller line, with the machine state): {of} line {line} has no match in \
             {other} ({} vs {} events)",
            ea.len(),
            eb.len()
        )
    };
    let (mut i, mut j) = (0, 0);
    while i < ea.len() || j < eb.len() {
        match (ea.get(i), eb.get(j)) {
            (Some(x), Some(y)) if x.0 == y.0 => (i, j) = (i + 1, j + 1),
            (Some(x), Some(y)) if x.0 < y.0 => {
                return Err(lone(x.1, "the original's", "the output"));
            }
            (Some(x), None) => return Err(lone(x.1, "the original's", "the output")),
            (_, Some(y)) => return Err(lone(y.1, "the output's", "the original")),
            (None, None) => break,
        }
    }
    // fb must be a sub-multiset of fa
    let mut i = 0;
    for y in fb {
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

/// The no-new-motion rule of [`equivalent`]: the original's motions and tool changes before
/// its first cut come first, and no rapid across in X/Y runs lower than the original's lowest
/// with that tool.
fn no_new_motion(a: &Digest, b: &Digest, tol: f64) -> Result<(), String> {
    let (pa, pb) = (&a.lead_in, &b.lead_in);
    if pb.len() < pa.len() || pb[..pa.len()] != pa[..] {
        return Err(
            "the motions and tool changes before the first cut are not the original's".into(),
        );
    }
    if !a.has_z {
        return Ok(());
    }
    let floor = a.low.values().copied().fold(f64::INFINITY, f64::min);
    for &(line, tool, z) in &b.rapids {
        let min = a.low.get(&tool).copied().unwrap_or(floor);
        if z < min - tol {
            return Err(format!(
                "line {line}: a rapid across at Z{z:.4} mm, lower than the original ever \
                 rapids across with tool {tool} (Z{min:.4} mm)"
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every G-code fixture: the digest of a text read line by line is the digest of the same
    /// text interpreted and held, in both direction rules, and a program matches itself.
    #[test]
    fn streamed_digest_equals_the_held_programs() {
        let dir =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures/gcode");
        let mut files: Vec<_> = ["", "real"]
            .iter()
            .flat_map(|d| std::fs::read_dir(dir.join(d)).unwrap())
            .map(|e| e.unwrap().path())
            .filter(|p| p.is_file() && p.extension().is_some_and(|x| x != "md"))
            .collect();
        files.sort();
        let mut checked = 0;
        for f in &files {
            let text = std::fs::read_to_string(f).unwrap();
            let Ok(p) = super::super::interp::interpret(&text) else {
                continue;
            };
            for und in [false, true] {
                let held = Digest::of(Lines::Program(&p), 1e-3, und, Some(1.0)).unwrap();
                let streamed = Digest::of(Lines::Text(&text), 1e-3, und, Some(1.0)).unwrap();
                assert_eq!(held, streamed, "{}", f.display());
                let eq = compare(
                    (Lines::Program(&p), &held),
                    (Lines::Text(&text), &streamed),
                    1e-3,
                    und,
                )
                .unwrap();
                assert_eq!(eq.cuts, held.cuts.len());
            }
            checked += 1;
        }
        assert!(checked >= 20, "only {checked} fixtures read");
    }

    /// A changed move in a streamed text is found and described with its line.
    #[test]
    fn streamed_mismatch_names_the_line() {
        let a = "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nG1 Y10\nG0 Z5\nM2\n";
        let b = a.replace("G1 Y10", "G1 Y10.5");
        let p = super::super::interp::interpret(a).unwrap();
        let da = Digest::of(Lines::Program(&p), 1e-3, false, None).unwrap();
        let db = Digest::of(Lines::Text(&b), 1e-3, false, None).unwrap();
        let e = compare(
            (Lines::Program(&p), &da),
            (Lines::Text(&b), &db),
            1e-3,
            false,
        )
        .unwrap_err();
        assert!(e.contains("line 5"), "{e}");
    }
}

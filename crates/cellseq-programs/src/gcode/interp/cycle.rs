//! Canned drilling cycles as LinuxCNC runs them (`interp_cycles.cc`, XY plane): G73 (chip
//! break), G81 (drill), G82 (drill, dwell), G83 (peck), G85 (bore, feed out), G86 (bore,
//! spindle stop, rapid out), G89 (bore, dwell, feed out).
//!
//! A cycle line drills L holes. Its R, Z, P (G82/G86/G89) and Q (G73/G83) are kept for the next
//! hole of the same cycle, and must be given when the cycle starts. The first cycle of an
//! unbroken series (no other motion between) fixes the initial level: G98 retracts to it (or
//! to R when it is lower), G99 to R, and in G91 the R plane is relative to it, Z to R, and X/Y
//! step from the current position on every repeat. Before the first hole the tool rises to R
//! if it is below; every hole starts with a rapid across (at the current height on the line's
//! first hole when that is above R, else at the retract height) and a rapid down to R.
//!
//! When the program never sets G98/G99 and the two would retract to different heights, where
//! the holes retract is the controller's setting: the holes are still read (what they cut does
//! not depend on it), the height after them is unknown, and the retract height of each hole is
//! recorded as unknown (`CutKind::Cycle::clear`).

use super::super::lex::Words;
use super::motion::in_range;
use super::{CutKind, LineInfo, Motion, Pos, State, close, el};

/// LinuxCNC's default peck clearance for G73 and G83: 0.010 inch.
const PECK_CLEARANCE_INCH: f64 = 0.010;
/// Most pecks one hole may take (a tiny Q would make the reading run without end).
const MAX_PECKS: usize = 100_000;
/// Most repeats (L) of one cycle line.
const MAX_REPEATS: f64 = 10_000.0;

/// `G81` etc. for messages.
fn name(mode: u16) -> String {
    format!("G{}", mode / 10)
}

/// The cycle's words in force for this hole: given on the line, or kept from the previous hole
/// of the same cycle; refused where LinuxCNC refuses them.
struct Words4 {
    r: f64,
    z: f64,
    p: Option<f64>,
    q: Option<f64>,
}

fn words(w: &Words, mode: u16, same: bool, st: &State) -> Result<Words4, String> {
    let n = name(mode);
    let kept = |k: usize, c: char, what: &str| -> Result<f64, String> {
        match w.get(c) {
            Some(v) => Ok(v),
            None if same => st.cycle[k].ok_or_else(|| format!("{n} without {c}")),
            None => Err(format!(
                "{n} without {c} ({what}) on the first hole of the cycle (LinuxCNC refuses it \
                 too); add the {c} word"
            )),
        }
    };
    let r = kept(0, 'R', "the R plane")?;
    let z = kept(1, 'Z', "the bottom of the hole")?;
    let p = match mode {
        820 | 860 | 890 => Some(kept(2, 'P', "the dwell")?),
        _ => None,
    };
    if p.is_some_and(|p| !(0.0..=1e9).contains(&p)) {
        return Err(format!(
            "{n} dwell P{} out of range (0 to 10^9 s)",
            p.unwrap_or(0.0)
        ));
    }
    let q = match mode {
        730 | 830 => Some(kept(3, 'Q', "the peck depth")?),
        _ => None,
    };
    if q.is_some_and(|q| q <= 0.0) {
        return Err(format!(
            "{n} with a peck depth Q that is not positive (LinuxCNC refuses it too); give Q > 0"
        ));
    }
    Ok(Words4 { r, z, p, q })
}

/// Where the tool is (file units, `None` where unknown) and the rapid length so far (mm).
struct Track {
    at: [Option<f64>; 3],
    scale: f64,
    rapid: f64,
    /// Lowest height (mm) of the line's rapids across in X/Y.
    low: Option<f64>,
}

impl Track {
    fn go(&mut self, to: [Option<f64>; 3]) {
        let (a, b) = (self.at, to);
        if let (Some(a), Some(b)) = (super::known(&a), super::known(&b)) {
            self.rapid += super::dist(&a, &b) * self.scale;
            if (a[0] - b[0]).abs() > 1e-12 || (a[1] - b[1]).abs() > 1e-12 {
                let z = a[2].max(b[2]) * self.scale;
                self.low = Some(self.low.map_or(z, |l| l.min(z)));
            }
        }
        self.at = to;
    }
}

/// The feed length of one hole from R (file units), adding the pecks' own rapids to `t`.
fn fed(
    mode: u16,
    w: &Words4,
    r: f64,
    cc: f64,
    delta: f64,
    clear: Option<f64>,
    t: &mut Track,
) -> Result<f64, String> {
    Ok(match mode {
        730 | 830 => {
            let q = w.q.unwrap_or(1.0);
            let (mut start, mut d, mut len, mut n) = (r, r - q, 0.0, 0);
            while d > cc {
                n += 1;
                if n > MAX_PECKS {
                    return Err(format!(
                        "{} with more than {MAX_PECKS} pecks per hole (Q{q} is too small for the \
                         depth); give a larger Q",
                        name(mode)
                    ));
                }
                len += start - d;
                let up = if mode == 830 {
                    (r - d) + (r - d - delta)
                } else {
                    delta
                };
                t.rapid += up.abs() * t.scale;
                start = d + delta;
                d -= q;
            }
            len + (start - cc)
        }
        850 => 2.0 * (r - cc),
        890 => (r - cc) + (clear.unwrap_or(r) - cc),
        _ => r - cc,
    })
}

/// The R plane, the bottom, the first hole's X and Y (file units) and the steps between
/// repeats: absolute, or in G91 R from the initial level `il`, Z from R and X/Y from `cur`.
fn placement(
    w: &Words,
    n: &str,
    absolute: bool,
    wd: &Words4,
    il: f64,
    cur: [Option<f64>; 3],
) -> Result<(f64, f64, f64, f64, f64, f64), String> {
    let known_xy = |k: usize, c: char| {
        cur[k].ok_or(format!(
            "{n} needs {c}: the program does not know where the tool is in {c} (after \
             G28/G30/G53); give {c} on the line"
        ))
    };
    Ok(if absolute {
        let aa = match w.get('X') {
            Some(v) => v,
            None => known_xy(0, 'X')?,
        };
        let bb = match w.get('Y') {
            Some(v) => v,
            None => known_xy(1, 'Y')?,
        };
        (wd.r, wd.z, aa, bb, 0.0, 0.0)
    } else {
        let r = wd.r + il;
        let (x, y) = (known_xy(0, 'X')?, known_xy(1, 'Y')?);
        (
            r,
            r + wd.z,
            x,
            y,
            w.get('X').unwrap_or(0.0),
            w.get('Y').unwrap_or(0.0),
        )
    })
}

/// Runs a canned-cycle line (motion mode `mode`): its holes, the retained words, the series'
/// initial level and the position after. Errors name what LinuxCNC would refuse.
pub(super) fn run(
    w: &Words,
    mode: u16,
    axes: bool,
    st: &mut State,
    pos: &mut Pos,
    info: &mut LineInfo,
) -> Result<(), String> {
    let n = name(mode);
    if !axes {
        return Err(format!(
            "{n} with no X, Y or Z word (LinuxCNC refuses it too: \"all axes missing with \
             motion code\"); give the hole's position or remove the line"
        ));
    }
    if st.plane != 17 {
        return Err(format!(
            "{n} outside the XY plane (G18/G19) is not supported; use G17 or plain moves instead"
        ));
    }
    if st.cutter_comp {
        return Err(format!(
            "{n} with cutter compensation on (LinuxCNC refuses it too); turn it off with G40 \
             first"
        ));
    }
    if st.feed <= 0.0 {
        return Err(format!(
            "{n} with no feed rate (F); add an F word before the first feed move and try again (LinuxCNC refuses it too)"
        ));
    }
    let same = info.before.motion == Some(mode);
    let wd = words(w, mode, same, st)?;
    let l = match w.get('L') {
        Some(l) if (1.0..=MAX_REPEATS).contains(&l) && close(l, l.round()) => l.round() as usize,
        Some(l) => {
            return Err(format!(
                "bad repeat count L{l} (a whole number from 1 to {MAX_REPEATS} expected)"
            ));
        }
        None => 1,
    };
    let s = st.scale();
    let il_mm = match st.cycle_il {
        Some(v) => v,
        None => pos[2].ok_or(
            "canned cycle from a height the program does not know (after G28/G30/G53): give Z \
             in an absolute move before the cycle",
        )?,
    };
    let il = il_mm / s;
    let cur = pos.map(|v| v.map(|v| v / s));
    let (r, cc, mut aa, mut bb, ai, bi) = placement(w, &n, st.absolute, &wd, il, cur)?;
    in_range('R', r * s)?;
    in_range('Z', cc * s)?;
    if r < cc {
        return Err(format!(
            "{n}: the R plane ({r}) is below the bottom Z ({cc}) (LinuxCNC refuses it too); \
             correct R or Z"
        ));
    }
    let mut t = Track {
        at: cur,
        scale: s,
        rapid: 0.0,
        low: None,
    };
    // the first motion of the cycle: from below R, straight up to R
    let mut old = il;
    let mut current = cur[2];
    if old < r {
        t.go([t.at[0], t.at[1], Some(r)]);
        old = r;
        current = Some(r);
    }
    let clear = if st.set & el::RETRACT != 0 {
        Some(if st.retract_old_z { old } else { r })
    } else if old <= r {
        Some(r)
    } else {
        None
    };
    if mode == 890 && clear.is_none() {
        return Err(
            "G89 feeds out to the retract height, which depends on G98/G99, and the program never \
             sets either; add G98 or G99 before the cycle"
                .into(),
        );
    }
    let delta = PECK_CLEARANCE_INCH * if st.metric { 25.4 } else { 1.0 };
    for k in 0..l {
        aa += ai;
        bb += bi;
        in_range('X', aa * s)?;
        in_range('Y', bb * s)?;
        if k == 0 && current.is_some_and(|c| c > r) {
            t.go([Some(aa), Some(bb), current]);
            t.go([Some(aa), Some(bb), Some(r)]);
        } else {
            t.go([Some(aa), Some(bb), clear]);
            t.go([Some(aa), Some(bb), Some(r)]);
        }
        let len = fed(mode, &wd, r, cc, delta, clear, &mut t)?;
        let end = match mode {
            850 => r,
            890 => clear.unwrap_or(r),
            _ => cc,
        };
        t.at = [Some(aa), Some(bb), Some(end)];
        t.go([Some(aa), Some(bb), clear]);
        let mut c = super::motion::cut_base(st);
        c.from = [aa * s, bb * s, r * s];
        c.to = [aa * s, bb * s, cc * s];
        c.kind = CutKind::Cycle {
            code: mode,
            r: r * s,
            p: wd.p.unwrap_or(0.0),
            q: wd.q.unwrap_or(0.0) * s,
            l: l as u32,
            clear: clear.map(|c| c * s),
            len: len * s,
        };
        info.cuts.push(c);
        current = clear;
    }
    *pos = [Some(aa * s), Some(bb * s), clear.map(|c| c * s)];
    st.cycle = [
        Some(wd.r),
        Some(wd.z),
        wd.p.or(st.cycle[2]),
        wd.q.or(st.cycle[3]),
    ];
    st.cycle_il = Some(il_mm);
    info.motion = Motion::Cycle;
    info.rapid_len = t.rapid;
    info.xy_rapid_z = t.low;
    Ok(())
}

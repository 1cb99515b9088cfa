//! One line executed: its words checked, its G codes classified, then applied in RS-274's
//! order — feed, speed and tool; M codes; modal G codes; the non-modal group — and its motion
//! run (see [`super::motion`]).

use super::super::lex::Words;
use super::motion;
use super::{LineInfo, Motion, Pos, State, close, el};

/// Executes one line: updates `st` and `pos` and returns what the line did. Errors name the
/// problem (the caller adds file and line).
pub(super) fn step(
    line: usize,
    w: Words,
    st: &mut State,
    pos: &mut Pos,
    has_m6: bool,
) -> Result<LineInfo, String> {
    let mut info = blank(line, *st, *pos, w.dialect);
    if w.dialect {
        if w.homing {
            info.motion = Motion::Home;
            *pos = [None; 3];
        }
        return Ok(finish(info, w, st, pos));
    }
    check_letters(&w)?;
    let (motion_g, nonmodal) = classify_g(&w)?;
    feed_speed_tool(&w, st, &mut info, has_m6)?;
    m_codes(&w, st, &mut info)?;
    if w.has_g(4.0) && !w.get('P').is_some_and(|p| (0.0..=1e9).contains(&p)) {
        return Err(
            "G4 dwell without a time P from 0 to 10^9 s (LinuxCNC refuses a missing or \
             negative one too); give P"
                .into(),
        );
    }
    modal_g(&w, st, &mut info);
    if let Some(m) = motion_g {
        info.explicit_motion = true;
        st.motion = if m == 800 { None } else { Some(m) };
    }
    let axes = w.has('X') || w.has('Y') || w.has('Z');
    if non_modal(nonmodal, axes, &w, st, pos, &mut info)? {
        return Ok(finish(info, w, st, pos));
    }
    let run_motion = axes || (info.explicit_motion && motion_g != Some(800));
    // any motion but a canned cycle (and G80) ends a series of cycles (LinuxCNC's
    // `cycle_il_flag`)
    if motion_g == Some(800) || (run_motion && st.motion.is_some_and(|m| m < 700)) {
        st.cycle_il = None;
    }
    if run_motion {
        motion::run(&w, axes, st, pos, &mut info)?;
    }
    Ok(finish(info, w, st, pos))
}

/// The record of a line that has done nothing yet.
fn blank(line: usize, before: State, pos_before: Pos, dialect: bool) -> LineInfo {
    LineInfo {
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
        dialect,
        cuts: Vec::new(),
        rapid_len: 0.0,
        xy_rapid_z: None,
    }
}

/// The record completed with the line's words and the state and position after it.
fn finish(mut info: LineInfo, w: Words, st: &State, pos: &Pos) -> LineInfo {
    info.words = w;
    info.after = *st;
    info.pos_after = *pos;
    info
}

/// Refuses letters a 3-axis program does not use and letters given twice.
fn check_letters(w: &Words) -> Result<(), String> {
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
    Ok(())
}

/// The line's motion G code and non-modal G code (both ×10), refusing unsupported codes and
/// two codes of one group.
fn classify_g(w: &Words) -> Result<(Option<u16>, Option<u16>), String> {
    let mut motion_g: Option<u16> = None;
    let mut nonmodal: Option<u16> = None;
    for g in w.all('G') {
        let code = (g * 10.0).round() as i64;
        if !close(code as f64, g * 10.0) || code < 0 {
            return Err(format!("G{g} is not a G code"));
        }
        let code = code as u16;
        match code {
            740 | 840 | 870 | 880 => {
                return Err(format!(
                    "canned cycle G{g} ({}) is not supported (supported: G73, G81, G82, G83, \
                     G85, G86, G89); replace it with plain moves",
                    match code {
                        740 | 840 => "tapping",
                        870 => "back boring",
                        _ => "boring with a manual stop",
                    }
                ));
            }
            0 | 10 | 20 | 30 | 730 | 810..=830 | 850 | 860 | 890 => {
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
    Ok((motion_g, nonmodal))
}

/// F, S and T words; in programs without M6 a T word is the tool change.
fn feed_speed_tool(
    w: &Words,
    st: &mut State,
    info: &mut LineInfo,
    has_m6: bool,
) -> Result<(), String> {
    if let Some(f) = w.get('F') {
        if !(f == 0.0 || (1e-3..=1e9).contains(&f)) {
            return Err(format!(
                "feed F{} out of range (0, or 0.001 to 10^9 per minute)",
                cellseq::validate::show(f)
            ));
        }
        st.feed = f;
        st.set |= el::FEED;
    }
    if let Some(s) = w.get('S') {
        if !(0.0..=1e9).contains(&s) {
            return Err(format!(
                "spindle speed S{} out of range (0 to 10^9)",
                cellseq::validate::show(s)
            ));
        }
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
    Ok(())
}

/// M codes: tool change, spindle, coolant, pauses, program end, and the user codes kept in
/// place.
fn m_codes(w: &Words, st: &mut State, info: &mut LineInfo) -> Result<(), String> {
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
    Ok(())
}

/// Modal G codes (plane, units, compensation, tool length offset, work offset, path mode,
/// distance modes, feed mode, retract mode) in line order, and the G4 dwell.
fn modal_g(w: &Words, st: &mut State, info: &mut LineInfo) {
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
}

/// The non-modal group: coordinate-system changes (G10, G52, G92…), homing (G28, G30) and
/// machine-coordinate moves (G53). Returns true when the line is done (no motion follows).
fn non_modal(
    nonmodal: Option<u16>,
    axes: bool,
    w: &Words,
    st: &mut State,
    pos: &mut Pos,
    info: &mut LineInfo,
) -> Result<bool, String> {
    match nonmodal {
        Some(100) | Some(920) | Some(921) | Some(922) | Some(923) | Some(520) => {
            info.setup = true;
            st.epoch += 1;
            if matches!(nonmodal, Some(920) | Some(520)) {
                // the program position becomes what the words say
                *pos = motion::target(w, st.scale(), pos, true)?;
            }
            Ok(true)
        }
        Some(280) | Some(300) => {
            // with axis words: to the point they name (the intermediate point), then only
            // those axes to the stored position; without: every axis
            info.motion = Motion::Home;
            for (k, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                if !axes || w.has(c) {
                    pos[k] = None;
                }
            }
            Ok(true)
        }
        Some(530) if axes => {
            if !matches!(st.motion, Some(0) | Some(10)) {
                return Err("G53 needs G0 or G1".into());
            }
            info.motion = Motion::Home;
            st.cycle_il = None;
            for (k, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
                if w.has(c) {
                    pos[k] = None;
                }
            }
            Ok(true)
        }
        // G4 (dwell, set in `modal_g`), G28.1/G30.1, and G53 without axis words, which moves
        // nothing (LinuxCNC accepts `G53 G0 G17`)
        _ => Ok(false),
    }
}

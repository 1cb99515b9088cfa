//! A line's motion in the current motion mode: straight moves (G0, G1), arcs (G2, G3) with
//! their centre from R or I/J/K; canned-cycle holes are [`super::cycle`]'s.

use super::super::lex::Words;
use super::{Cut, CutKind, LineInfo, Motion, Pos, State, close, dist, known, plane_axes};
use cellseq::validate::MAX_COORD;

/// The position the line's X, Y, Z words name (mm), absolute or relative to `pos`.
pub(super) fn target(w: &Words, scale: f64, pos: &Pos, absolute: bool) -> Result<Pos, String> {
    let mut t = *pos;
    for (k, c) in ['X', 'Y', 'Z'].into_iter().enumerate() {
        if let Some(v) = w.get(c) {
            let p = if absolute {
                v * scale
            } else {
                pos[k].ok_or("incremental move from an unknown position")? + v * scale
            };
            t[k] = Some(in_range(c, p)?);
        }
    }
    Ok(t)
}

/// A coordinate (mm) within the limit every command shares ([`MAX_COORD`]), else the error
/// naming the axis: the same rule `import` applies to the instance it builds.
pub(super) fn in_range(axis: char, mm: f64) -> Result<f64, String> {
    if mm.is_finite() && mm.abs() <= MAX_COORD {
        Ok(mm)
    } else {
        Err(format!(
            "{axis} coordinate {} mm is out of range (at most {} mm from the origin, after \
             offsets and incremental moves); correct the number",
            cellseq::validate::show(mm),
            cellseq::validate::show(MAX_COORD)
        ))
    }
}

/// Runs the motion of a line that has axis words or an explicit motion code.
pub(super) fn run(
    w: &Words,
    axes: bool,
    st: &mut State,
    pos: &mut Pos,
    info: &mut LineInfo,
) -> Result<(), String> {
    let mode = st
        .motion
        .ok_or("axis words with no motion mode (after G80)")?;
    match mode {
        0 | 10 => straight(w, mode, st, pos, info),
        20 | 30 => arc(w, mode, axes, st, pos, info),
        _ => super::cycle::run(w, mode, axes, st, pos, info),
    }
}

/// A cut in the current state, with its geometry still to be filled in.
pub(super) fn cut_base(st: &State) -> Cut {
    Cut {
        tool: st.tool,
        kind: CutKind::Line,
        from: [0.0; 3],
        to: [0.0; 3],
        feed: st.feed * st.scale(),
        speed: if st.spindle == 5 { 0.0 } else { st.speed },
        offset: st.offset,
        partial: false,
        unknown: 0,
    }
}

/// G0 (a rapid, with its length and the highest Z it passes) or G1 (a straight cut).
fn straight(
    w: &Words,
    mode: u16,
    st: &State,
    pos: &mut Pos,
    info: &mut LineInfo,
) -> Result<(), String> {
    let arc_words = w.has('I') || w.has('J') || w.has('K') || w.has('R');
    if arc_words && mode != 0 {
        return Err("I/J/K/R words on a straight move".into());
    }
    let t = target(w, st.scale(), pos, st.absolute)?;
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
        // after G28/G30/G53 an axis the program has not named since is where the controller
        // left it: the move is compared with that axis unknown (start and end), and the
        // cells keep such moves in place
        let to = [0, 1, 2].map(|k| t[k].unwrap_or(0.0));
        let from = [0, 1, 2].map(|k| pos[k].unwrap_or(to[k]));
        if st.feed <= 0.0 {
            return Err("feed move with no feed rate (F); add an F word before the first feed move and try again (LinuxCNC refuses it too)".into());
        }
        let mut c = cut_base(st);
        c.from = from;
        c.to = to;
        c.partial = known(pos).is_none();
        c.unknown = (0..3)
            .map(|k| (pos[k].is_none() as u8) << k | (t[k].is_none() as u8) << (k + 3))
            .fold(0, |a, b| a | b);
        info.cuts.push(c);
    }
    *pos = t;
    Ok(())
}

/// G2/G3: an arc cut, its turns from P.
fn arc(
    w: &Words,
    mode: u16,
    axes: bool,
    st: &State,
    pos: &mut Pos,
    info: &mut LineInfo,
) -> Result<(), String> {
    if !(axes || w.has('I') || w.has('J') || w.has('K')) {
        return Err(
            "G2/G3 with neither axis words nor I/J/K (LinuxCNC refuses it too); remove the line or give the arc its end point and centre".into(),
        );
    }
    if st.feed <= 0.0 {
        return Err("arc with no feed rate (F); add an F word before the first feed move and try again (LinuxCNC refuses it too)".into());
    }
    let from = known(pos).ok_or("arc from an unknown position (after G28/G53)")?;
    let t = target(w, st.scale(), pos, st.absolute)?;
    let to = known(&t).ok_or("arc to an unknown position")?;
    let cw = mode == 20;
    let center = arc_center(w, st, cw, from, to)?;
    for (k, v) in center.iter().enumerate() {
        in_range(['I', 'J', 'K'][k], *v)?;
    }
    let turns = match w.get('P') {
        Some(p) if (1.0..=1e6).contains(&p) && close(p, p.round()) => p as u32,
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
    Ok(())
}

/// An arc's centre (mm) from R (the short or, for negative R, the long way round) or from
/// I/J/K (absolute or relative to the start), refusing what LinuxCNC refuses.
fn arc_center(
    w: &Words,
    st: &State,
    cw: bool,
    from: [f64; 3],
    to: [f64; 3],
) -> Result<[f64; 3], String> {
    let scale = st.scale();
    let (a, b, _) = plane_axes(st.plane);
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
    Ok(center)
}

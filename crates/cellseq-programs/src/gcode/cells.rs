//! Splitting an interpreted program into cells, tool blocks, header and footer; default
//! precedence (overlap keeps order, inner closed contours first).

use super::interp::{CutKind, Motion, Program, State, el, known};

/// How cells are delimited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Split {
    /// Milling/drilling: a cell runs from a descent below `safe` to the next rise to it;
    /// travel is regenerated at `travel` (both mm).
    Z {
        /// Threshold height (the file's safe height).
        safe: f64,
        /// Travel height used for regenerated rapids (highest between-cell rapid).
        travel: f64,
    },
    /// 2-D (laser, plasma, plotter): a cell is a run of feed moves, ended by a rapid or M5.
    Flat,
}

/// One cell: a contiguous run of lines cut together.
#[derive(Debug, Clone)]
pub struct GCell {
    /// Body lines `[start, end)` (indices into the program's lines).
    pub start: usize,
    /// End (exclusive).
    pub end: usize,
    /// Gap lines emitted before the cell (non-motion, or motion lines to be stripped).
    pub prefix: Vec<usize>,
    /// First line of the gap before the cell in the original (the end of the previous cell);
    /// equal to `start` for the first cell of a block (its gap is the block's preamble).
    pub gap_start: usize,
    /// Run of cells that may be reordered among themselves: runs end where the program first
    /// sets a modal element (a cell cut before that line would run with the operator's state
    /// changed) and at pauses, coordinate-system changes, controller lines and user M codes.
    pub run: usize,
    /// True when the cell itself sets an element for the first time and opens its run: it must
    /// come first in its group (the cells after it rely on what it sets).
    pub lead: bool,
    /// True when the cell itself sets an element for the first time and closes its run: it
    /// must come last in its group (the cells before it run without what it sets).
    pub trail: bool,
    /// True when the cell starts from a position the program does not know (right after
    /// G28/G30/G53/`$H`): it keeps its place and its approach as written.
    pub pinned: bool,
    /// Tool block index.
    pub block: usize,
    /// Tool number.
    pub tool: u32,
    /// Entry point (mm).
    pub entry: [f64; 3],
    /// Exit point (mm).
    pub exit: [f64; 3],
    /// State before the first body line.
    pub state: State,
    /// True for a single canned-cycle hole.
    pub cycle: bool,
    /// XY bounding box of the cuts.
    pub bbox: [f64; 4],
    /// Length cut (mm).
    pub cut_length: f64,
    /// Lowest Z of the cuts (mm).
    pub depth: f64,
    /// XY outline when the cell is a closed contour.
    pub closed: Option<Vec<[f64; 2]>>,
}

/// A tool block: consecutive cells of one tool, with the lines that change to it.
#[derive(Debug, Clone)]
pub struct Block {
    /// Tool number.
    pub tool: u32,
    /// Gap lines holding the tool change (empty for the first block: it is in the header).
    pub preamble: Vec<usize>,
    /// Index of the first line of that gap.
    pub gap_start: usize,
    /// Number of coordinate-system changes (G10/G52/G92) before the block; blocks of
    /// different epochs never merge.
    pub epoch: usize,
}

/// The program cut into pieces.
#[derive(Debug, Clone)]
pub struct Layout {
    /// How cells were delimited.
    pub split: Split,
    /// Lines `[0, header_end)` are written unchanged first.
    pub header_end: usize,
    /// Lines `[footer_start, n)` are written unchanged last.
    pub footer_start: usize,
    /// Cells in program order.
    pub cells: Vec<GCell>,
    /// Tool blocks in program order.
    pub blocks: Vec<Block>,
    /// Position at the end of the header (mm), when known.
    pub start: Option<[f64; 3]>,
    /// Per block: the height (mm) the program itself rises to between two cells of the block
    /// (the highest rapid of those gaps); links between cells of the block retract to it.
    /// Zero for 2-D programs.
    pub clearance: Vec<f64>,
}

/// True for a line that cells never move across: a tool change, a coordinate-system change,
/// a move to a machine position (G28/G30/G53, `$H`), a pause, a controller line, a user M code.
pub fn is_boundary(p: &Program, i: usize) -> bool {
    let li = &p.lines[i];
    li.tool_change || li.setup || li.motion == Motion::Home || li.pause || li.dialect || li.user_m
}

/// A boundary that also ends a run (cells of different runs are never reordered, even when
/// blocks of one tool are merged): everything but tool changes and machine-position moves.
fn ends_run(p: &Program, i: usize) -> bool {
    let li = &p.lines[i];
    li.setup || li.pause || li.dialect || li.user_m
}

const EPS: f64 = 1e-6;

/// A cut's lines: start, end (exclusive), and whether it is a canned cycle.
type CutRange = (usize, usize, bool);

/// The line ranges `(start, end, canned cycle)` of the cuts, by the split's rule: under
/// [`Split::Z`] a cut runs from the first feed (or plunging rapid) below the safe height to the
/// motion back at or above it, a canned cycle is a cell of its own; under [`Split::Flat`] a
/// cut is a run of feed moves up to the next rapid, tool change, program end or spindle stop.
fn cut_ranges(p: &Program, split: Split, safe: f64) -> Result<Vec<CutRange>, (usize, String)> {
    let n = p.lines.len();
    let mut ranges: Vec<CutRange> = Vec::new();
    let mut open: Option<usize> = None;
    for (i, li) in p.lines.iter().enumerate() {
        let zafter = li.pos_after[2];
        if let Some(s) = open {
            match split {
                Split::Z { .. } => {
                    if li.motion == Motion::Cycle {
                        ranges.push((s, i, false));
                        ranges.push((i, i + 1, true));
                        open = None;
                        continue;
                    }
                    if li.motion == Motion::Home {
                        return Err((
                            li.line,
                            "G28/G30/G53 move while cutting (below the safe height); retract above the safe height before it and try again".into(),
                        ));
                    }
                    if li.tool_change {
                        let from = ranges.last().map_or(0, |r| r.1);
                        if touch_off(p, (from, s, i)) {
                            // part of the tool change, kept with it in the block's preamble
                            open = None;
                            continue;
                        }
                        return Err((li.line, "tool change while below the safe height; retract above the safe height before the tool change and try again".into()));
                    }
                    if li.motion != Motion::None && zafter.is_some_and(|z| z >= safe - EPS) {
                        ranges.push((s, i + 1, false));
                        open = None;
                    }
                }
                Split::Flat => {
                    if li.motion == Motion::Cycle {
                        ranges.push((s, i, false));
                        ranges.push((i, i + 1, true));
                        open = None;
                    } else if matches!(li.motion, Motion::Rapid | Motion::Home)
                        || li.tool_change
                        || li.end
                    {
                        ranges.push((s, i, false));
                        open = None;
                    } else if li.spindle_off {
                        ranges.push((s, i + 1, false));
                        open = None;
                    }
                }
            }
            continue;
        }
        let starts = match split {
            Split::Z { .. } => {
                if li.motion == Motion::Cycle {
                    ranges.push((i, i + 1, true));
                    continue;
                }
                (li.motion == Motion::Feed && cuts_something(li))
                    || (li.motion == Motion::Rapid
                        && matches!((li.pos_before[2], zafter), (Some(a), Some(b)) if b < safe - EPS && b < a - EPS))
            }
            Split::Flat => {
                if li.motion == Motion::Cycle {
                    ranges.push((i, i + 1, true));
                    continue;
                }
                li.motion == Motion::Feed && cuts_something(li)
            }
        };
        if starts {
            open = Some(i);
            if let (Split::Z { .. }, Some(z)) = (split, zafter)
                && z >= safe - EPS
            {
                ranges.push((i, i + 1, false));
                open = None;
            }
        }
    }
    if let Some(s) = open {
        // cut to the end: the trailing non-motion lines belong to the footer
        let mut e = n;
        while e > s + 1 && p.lines[e - 1].motion == Motion::None {
            e -= 1;
        }
        ranges.push((s, e, false));
    }
    Ok(ranges)
}

/// True when the lines `[s, i)` before the tool change on line `i` are a touch-off that
/// belongs to that tool change, not a cut: straight moves along Z only (pcb-gcode's tool-zero
/// step: `M06 T02`, `G01 Z0`, `M06`, then up), at an X and Y that an absolute move of the gap
/// `[from, s)` sets, so that they do not depend on which cell came before (in the header,
/// `from` is 0 and nothing comes before).
fn touch_off(p: &Program, (from, s, i): (usize, usize, usize)) -> bool {
    let along_z = p.lines[s..i].iter().all(|l| match l.motion {
        Motion::None => true,
        Motion::Rapid | Motion::Feed => {
            l.cuts.iter().all(|c| matches!(c.kind, CutKind::Line))
                && l.pos_before[0].is_some()
                && l.pos_before[1].is_some()
                && l.pos_before[0] == l.pos_after[0]
                && l.pos_before[1] == l.pos_after[1]
        }
        _ => false,
    });
    let placed = from == 0
        || p.lines[from..s].iter().any(|l| {
            matches!(l.motion, Motion::Rapid | Motion::Feed)
                && l.before.absolute
                && l.words.has('X')
                && l.words.has('Y')
        });
    along_z && placed
}

/// True when every cut of the range ends where the program knows the position.
fn grounded(p: &Program, r: &CutRange) -> bool {
    (r.0..r.1).all(|i| p.lines[i].cuts.iter().all(|c| c.unknown & 0b111000 == 0))
}

/// What the moves of a cell cover: the box of its cuts, their length, the deepest point, the
/// XY polyline from `entry` (for closed contours) and whether every arc is in G17.
struct Geometry {
    bbox: [f64; 4],
    cut_length: f64,
    depth: f64,
    pts: Vec<[f64; 2]>,
    planar: bool,
}

fn geometry(p: &Program, s: usize, e: usize, entry: [f64; 3]) -> Geometry {
    let mut bbox = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut cut_length = 0.0;
    let mut depth = f64::INFINITY;
    let mut pts: Vec<[f64; 2]> = vec![[entry[0], entry[1]]];
    let mut planar = true;
    for li in &p.lines[s..e] {
        if li.motion == Motion::Rapid
            && let Some(t) = known(&li.pos_after)
        {
            pts.push([t[0], t[1]]);
            depth = depth.min(t[2]);
        }
        for c in &li.cuts {
            let b = c.bbox();
            bbox = [
                bbox[0].min(b[0]),
                bbox[1].min(b[1]),
                bbox[2].max(b[2]),
                bbox[3].max(b[3]),
            ];
            cut_length += c.length();
            depth = depth.min(c.to[2]).min(c.from[2]);
            if matches!(c.kind, CutKind::Arc { plane, .. } if plane != 17) {
                planar = false;
            }
            c.polyline(&mut pts);
        }
    }
    Geometry {
        bbox,
        cut_length,
        depth,
        pts,
        planar,
    }
}

/// Splits a program. Errors: `(line, message)`.
pub fn split(p: &Program) -> Result<Layout, (usize, String)> {
    let split = choose_split(p);
    let safe = match split {
        Split::Z { safe, .. } => safe,
        Split::Flat => f64::INFINITY,
    };
    let mut ranges = cut_ranges(p, split, safe)?;
    ranges.retain(|r| r.1 > r.0);
    // cuts before the program first gives a full position (after G28 G91 Z0, say, a feed in X
    // and Y at the height only the controller knows) stay where they are, in the header
    let lead = ranges.iter().take_while(|r| !grounded(p, r)).count();
    ranges.drain(..lead);
    if let Some(r) = ranges.iter().find(|r| !grounded(p, r)) {
        let line = (r.0..r.1)
            .find(|&i| p.lines[i].cuts.iter().any(|c| c.unknown & 0b111000 != 0))
            .unwrap_or(r.0);
        return Err((
            p.lines[line].line,
            "feed move to a position the program does not know (after G28/G30/G53 between \
             cuts): give X, Y and Z in an absolute move before it"
                .into(),
        ));
    }
    if ranges.is_empty() {
        return Err((0, "no cutting moves found".into()));
    }
    let header_end = ranges[0].0;
    let footer_start = ranges[ranges.len() - 1].1;
    for li in &p.lines[header_end..footer_start] {
        if li.end {
            return Err((li.line, "program end (M2/M30) before the last cut; move M2/M30 to the end of the program or remove the cuts after it".into()));
        }
    }
    let mut cells: Vec<GCell> = Vec::with_capacity(ranges.len());
    let mut blocks = vec![Block {
        tool: p.lines[header_end].before.tool,
        preamble: Vec::new(),
        gap_start: 0,
        epoch: 0,
    }];
    let mut epoch = 0;
    let mut prev_end = header_end;
    for &(s, e, cycle) in &ranges {
        let gap_from = prev_end;
        let prefix = gap(p, (prev_end, s), !cells.is_empty(), &mut epoch, &mut blocks);
        prev_end = e;
        let block = blocks.len() - 1;
        let block_first = cells.last().is_none_or(|c| c.block != block);
        let place = Place {
            prefix,
            gap_start: if block_first { s } else { gap_from },
            block,
        };
        cells.push(cut_cell(p, (s, e, cycle), place)?);
    }
    let start = known(&p.lines[header_end].pos_before);
    assign_runs(p, &mut cells, &blocks);
    let clearance = clearances(p, split, &cells, &blocks);
    keep_high_exits_last(&mut cells, &clearance);
    Ok(Layout {
        split,
        header_end,
        footer_start,
        cells,
        blocks,
        start,
        clearance,
    })
}

/// How the program is delimited: by its safe height when it has one and cuts below it, else
/// like a 2-D program.
fn choose_split(p: &Program) -> Split {
    // no rapid across at a known height (a single helix, a wave): nothing to lift between, the
    // program is split like a 2-D one
    let z_split = if p.has_z {
        find_safe(p).unwrap_or(Split::Flat)
    } else {
        Split::Flat
    };
    match z_split {
        // every cut at or above the travel height (a pen or a silkscreen pass at Z0 with
        // rapids at Z0): the Z rule would make each move a cell; cells are runs of feed moves
        Split::Z { safe, .. } if !cuts_below(p, safe) => Split::Flat,
        s => s,
    }
}

/// The gap lines `[from, to)` before a cut: when they cross a boundary (tool change, setup,
/// pause …) they open a new block whose preamble they are (counting coordinate-system changes
/// in `epoch`); otherwise, between two cells, the returned lines are the cell's prefix (the
/// lines that are not plain motion).
fn gap(
    p: &Program,
    (from, to): (usize, usize),
    after_a_cell: bool,
    epoch: &mut usize,
    blocks: &mut Vec<Block>,
) -> Vec<usize> {
    let gap: Vec<usize> = (from..to).collect();
    let boundary = |g: usize| is_boundary(p, g);
    if gap.iter().any(|&g| p.lines[g].setup) {
        *epoch += 1;
    }
    if gap.iter().any(|&g| boundary(g)) {
        let last_change = *gap.iter().rev().find(|&&g| boundary(g)).unwrap_or(&to);
        blocks.push(Block {
            tool: p.lines[to].before.tool,
            preamble: gap
                .iter()
                .copied()
                .filter(|&g| {
                    g <= last_change
                        || p.lines[g].motion == Motion::None
                        || has_other_words(p, g)
                        || vertical(p, g)
                })
                .collect(),
            gap_start: from,
            epoch: *epoch,
        });
        Vec::new()
    } else if after_a_cell {
        gap.iter()
            .copied()
            .filter(|&g| p.lines[g].motion == Motion::None || has_other_words(p, g))
            .collect()
    } else {
        Vec::new()
    }
}

/// Where a cell sits among the gaps and blocks (see [`GCell`]).
struct Place {
    prefix: Vec<usize>,
    gap_start: usize,
    block: usize,
}

/// The cell of the body lines `[s, e)` (`cycle`: a single canned-cycle hole): its state,
/// entry and exit, geometry and closed outline.
fn cut_cell(
    p: &Program,
    (s, e, cycle): (usize, usize, bool),
    place: Place,
) -> Result<GCell, (usize, String)> {
    if cycle {
        return Ok(cycle_cell(p, s, place));
    }
    let first = &p.lines[s];
    let last = &p.lines[e - 1];
    let st = first.before;
    if st.cutter_comp {
        return Err((
            first.line,
            "cutter radius compensation (G41/G42) active at the start of a cut: cells cannot be reordered under it; turn it off (G40) before each retract, or use tool-centre paths instead".into(),
        ));
    }
    let pinned = known(&first.pos_before).is_none();
    let before = match known(&first.pos_before) {
        Some(b) => b,
        None => {
            // right after G28/G30/G53/$H: the axes the program has not named since are
            // where the controller left them; the cell keeps its place and approach
            let to = known(&first.pos_after).ok_or((
                first.line,
                "the first move after G28/G30/G53/$H does not name X, Y and Z; give all \
                 three in an absolute move before cutting"
                    .to_string(),
            ))?;
            [0, 1, 2].map(|k| first.pos_before[k].unwrap_or(to[k]))
        }
    };
    let exit = known(&last.pos_after).ok_or((
        last.line,
        "position unknown at the end of a cut".to_string(),
    ))?;
    let mut entry = before;
    if !cycle
        && first.motion == Motion::Rapid
        && st.absolute
        && let Some(t) = known(&first.pos_after)
    {
        entry = [t[0], t[1], before[2]];
    }
    let Geometry {
        mut bbox,
        cut_length,
        depth,
        pts,
        planar,
    } = geometry(p, s, e, entry);
    if !bbox[0].is_finite() {
        bbox = [entry[0], entry[1], entry[0], entry[1]];
    }
    let closed_xy = (pts[0][0] - exit[0]).hypot(pts[0][1] - exit[1]) < 1e-3;
    let closed = (planar && closed_xy && pts.len() >= 4 && area(&pts).abs() > 1e-6).then_some(pts);
    Ok(GCell {
        start: s,
        end: e,
        prefix: place.prefix,
        gap_start: place.gap_start,
        run: 0,
        lead: false,
        trail: false,
        pinned,
        block: place.block,
        tool: st.tool,
        entry,
        exit,
        state: st,
        cycle,
        bbox,
        cut_length,
        depth: if depth.is_finite() { depth } else { entry[2] },
        closed,
    })
}

/// The cell of a canned-cycle line `s` (its holes): entered over its first hole at the height
/// the original starts it from (in G91: where the original is, since its holes step from
/// there), left over its last hole at the height it retracts to (where the program never sets
/// G98/G99 and that height is not known, the higher of the two it can be). A cycle cell is
/// never pinned: what its holes cut does not depend on where the tool comes from, and the
/// writer puts the tool where each hole moves as in the original.
fn cycle_cell(p: &Program, s: usize, place: Place) -> GCell {
    let li = &p.lines[s];
    // the line's own G90/G91 and G98/G99 apply to its holes
    let st = li.after;
    let (first, last) = (li.cuts[0], li.cuts[li.cuts.len() - 1]);
    let r = match first.kind {
        CutKind::Cycle { r, .. } => r,
        _ => first.from[2],
    };
    let level = li.pos_before[2].or(st.cycle_il).unwrap_or(r);
    let entry = match known(&li.pos_before) {
        Some(b) if !st.absolute => b,
        _ => [first.to[0], first.to[1], level],
    };
    let high = st.cycle_il.unwrap_or(level).max(r);
    let exit = [last.to[0], last.to[1], li.pos_after[2].unwrap_or(high)];
    let Geometry {
        bbox,
        cut_length,
        depth,
        ..
    } = geometry(p, s, s + 1, entry);
    GCell {
        start: s,
        end: s + 1,
        prefix: place.prefix,
        gap_start: place.gap_start,
        run: 0,
        lead: false,
        trail: false,
        pinned: false,
        block: place.block,
        tool: st.tool,
        entry,
        exit,
        state: li.before,
        cycle: true,
        bbox,
        cut_length,
        depth,
        closed: None,
    }
}

/// The program's elements set at the start of a cell's gap (see [`GCell::gap_start`]).
pub fn entry_state(p: &Program, c: &GCell) -> State {
    p.lines[c.gap_start].before
}

/// Elements whose value does not change where a link's rapids go (feed, speed, spindle,
/// coolant, path and retract modes, plane, arc distance, cutter compensation, G94).
const LINK_NEUTRAL: u32 = el::FEED
    | el::SPEED
    | el::SPINDLE
    | el::MIST
    | el::FLOOD
    | el::PATH
    | el::RETRACT
    | el::PLANE
    | el::ARC_DIST
    | el::CUTTER
    | el::FEED_MODE;

/// Elements unset at the start of the cell's gap that the cell sets itself before anything it
/// cuts or does (so a cell before it may leave them set): those set by the gap's lines (written
/// before the link), and link-neutral ones set by the body before its first cut.
pub fn free_bits(p: &Program, c: &GCell) -> u32 {
    let a = entry_state(p, c).set;
    let tagged = |i: usize| {
        let li = &p.lines[i];
        li.cuts.iter().any(|x| {
            !matches!(x.kind, super::interp::CutKind::Line) || x.length() > super::verify::ZERO_MOVE
        }) || li.tool_change
            || li.pause
            || li.dwell
            || li.user_m
            || li.setup
            || li.dialect
    };
    let g = (c.gap_start..c.end)
        .find(|&i| tagged(i))
        .unwrap_or(c.end - 1);
    let t = p.lines[g].after.set;
    if g < c.start {
        return t & !a;
    }
    let body = p.lines[c.start].before.set;
    (body & !a) | (t & !body & LINK_NEUTRAL)
}

/// Numbers the runs (see [`GCell::run`]) and marks the cells that set an element for the
/// first time: a run's first cell may be such a cell (it then leads: the rest of the run
/// relies on it), any other such cell closes the run (it trails).
fn assign_runs(p: &Program, cells: &mut [GCell], blocks: &[Block]) {
    let entry = |c: &GCell| entry_state(p, c).set | free_bits(p, c);
    let setter = |c: &GCell| entry(c) != p.lines[c.end - 1].after.set;
    let mut run = 0;
    let mut start = 0;
    for k in 1..cells.len() {
        let (a, b) = (&cells[k - 1], &cells[k]);
        let prev_out = p.lines[a.end - 1].after.set;
        let this_in = entry(b);
        let barrier = if b.block != a.block {
            blocks[b.block].preamble.iter().any(|&g| ends_run(p, g))
        } else {
            (a.end..b.start).any(|g| ends_run(p, g))
        };
        let closes = setter(a) && start != k - 1;
        if barrier || closes || prev_out != this_in || a.pinned || b.pinned || other_series(p, a, b)
        {
            run += 1;
            start = k;
        }
        cells[k].run = run;
    }
    let n = cells.len();
    for k in 0..n {
        if setter(&cells[k]) {
            let first = k == 0 || cells[k - 1].run != cells[k].run;
            let last = k + 1 == n || cells[k + 1].run != cells[k].run;
            cells[k].lead = first && !last;
            cells[k].trail = !first;
        }
    }
}

/// True when cells `a` and `b` (in program order) are not holes of one kind of canned cycle:
/// a hole and a cell that is not, or holes of cycles that differ in code, distance mode,
/// retract mode or the words R, Z, P, Q. Such cells are not reordered among each other: the
/// cost model sees none of the heights the cycles retract to, so mixing them could only add
/// lifts (and the series they start).
fn other_series(p: &Program, a: &GCell, b: &GCell) -> bool {
    if !a.cycle && !b.cycle {
        return false;
    }
    if a.cycle != b.cycle {
        return true;
    }
    let (x, y) = (&p.lines[a.start].after, &p.lines[b.start].after);
    x.motion != y.motion
        || x.absolute != y.absolute
        || x.retract_old_z != y.retract_old_z
        || x.cycle != y.cycle
}

/// A run's last cell that rises above its block's clearance at its end (pcb2gcode's "all
/// done" retract to the tool-change height before the footer's `M5` and dwell) stays the last
/// of its run: elsewhere its rise would be followed by a descent, and the footer would need
/// a rise of its own.
fn keep_high_exits_last(cells: &mut [GCell], clearance: &[f64]) {
    let n = cells.len();
    for k in 0..n {
        let last = k + 1 == n || cells[k + 1].run != cells[k].run;
        let first = k == 0 || cells[k - 1].run != cells[k].run;
        let c = &mut cells[k];
        if last && !first && !c.lead && c.exit[2] > clearance[c.block] + EPS {
            c.trail = true;
        }
    }
}

/// Per block, the highest rapid between two of its cells (else of its approach, else the
/// safe height).
fn clearances(p: &Program, split: Split, cells: &[GCell], blocks: &[Block]) -> Vec<f64> {
    let Split::Z { safe, .. } = split else {
        return vec![0.0; blocks.len()];
    };
    let rapid_top = |r: std::ops::Range<usize>| {
        r.filter(|&g| p.lines[g].motion == Motion::Rapid)
            .filter_map(|g| p.lines[g].pos_after[2])
            .fold(None, |m: Option<f64>, z| Some(m.map_or(z, |m| m.max(z))))
    };
    let mut between: Vec<Option<f64>> = vec![None; blocks.len()];
    for k in 1..cells.len() {
        let (a, b) = (&cells[k - 1], &cells[k]);
        if a.block == b.block
            && let Some(z) = rapid_top(a.end..b.start)
        {
            let m = &mut between[b.block];
            *m = Some(m.map_or(z, |m| m.max(z)));
        }
    }
    blocks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            between[i]
                .or_else(|| {
                    b.preamble
                        .iter()
                        .filter_map(|&g| p.lines[g].xy_rapid_z)
                        .fold(None, |m: Option<f64>, z| Some(m.map_or(z, |m| m.max(z))))
                })
                .unwrap_or(safe)
        })
        .collect()
}

/// True when a line cuts anything: a feed line that does not move (`G01 F100`, a move to
/// where the tool already is) starts no cell, so no link is ever written before it (a header's
/// `G01 F200` before the first tool change stays in the header).
fn cuts_something(li: &super::interp::LineInfo) -> bool {
    li.cuts
        .iter()
        .any(|c| !matches!(c.kind, CutKind::Line) || c.length() > super::verify::ZERO_MOVE)
}

/// Where a block's preamble leaves the tool, when the preamble itself says so: the position
/// after its last move up to its last boundary (the tool change, written as it is whatever the
/// order), provided an absolute move of the preamble gave X and Y and nothing after it moved
/// them (pcb-gcode goes to `G00 X0 Y0` before each `M06`: the block starts from there, not
/// from the previous block's last hole). `None` when the preamble does not fix the position.
pub fn preamble_home(p: &Program, b: &Block) -> Option<[f64; 3]> {
    let last = *b.preamble.iter().rev().find(|&&g| is_boundary(p, g))?;
    let mut home: Option<[f64; 3]> = None;
    for &g in b.preamble.iter().filter(|&&g| g <= last) {
        let li = &p.lines[g];
        match li.motion {
            Motion::None => {}
            Motion::Rapid | Motion::Feed => {
                let set = li.before.absolute && li.words.has('X') && li.words.has('Y');
                let moved_xy =
                    li.pos_before[0] != li.pos_after[0] || li.pos_before[1] != li.pos_after[1];
                home = match (set, moved_xy) {
                    (true, _) => known(&li.pos_after),
                    (false, false) => home.and_then(|_| known(&li.pos_after)),
                    (false, true) => None,
                };
            }
            _ => home = None,
        }
    }
    home
}

/// True for a rapid that moves only in Z (a block's descent to its working height after a
/// tool change): the writer keeps it in a block's preamble so that what follows (a dwell while
/// the spindle comes up to speed) happens at the height the program gives it.
pub fn vertical(p: &Program, i: usize) -> bool {
    let li = &p.lines[i];
    li.motion == Motion::Rapid
        && li.cuts.is_empty()
        && !li.words.has('X')
        && !li.words.has('Y')
        && matches!((li.pos_before, li.pos_after), (a, b) if a[0] == b[0] && a[1] == b[1])
        && li.pos_after[2].is_some()
}

/// True when some cut runs below `safe`.
fn cuts_below(p: &Program, safe: f64) -> bool {
    p.lines
        .iter()
        .flat_map(|l| l.cuts.iter())
        .any(|c| c.from[2].min(c.to[2]) < safe - EPS)
}

/// True when a motion line also carries words other than motion and axes (M, S, F, T…).
pub fn has_other_words(p: &Program, i: usize) -> bool {
    p.lines[i].words.words.iter().any(|&(c, v)| {
        !(matches!(c, 'X' | 'Y' | 'Z' | 'I' | 'J' | 'K' | 'R') || c == 'G' && is_motion_g(v))
    })
}

/// G codes that move (dropped when a gap line is stripped of its motion).
pub fn is_motion_g(v: f64) -> bool {
    let c = (v * 10.0).round() as i64;
    matches!(c, 0 | 10 | 20 | 30 | 280 | 300 | 530 | 730 | 800..=890)
}

fn find_safe(p: &Program) -> Result<Split, (usize, String)> {
    use std::collections::BTreeMap;
    let mut counts: BTreeMap<i64, usize> = BTreeMap::new();
    for li in &p.lines {
        if let Some(z) = li.xy_rapid_z {
            *counts.entry((z * 1000.0).round() as i64).or_default() += 1;
        }
    }
    let Some((&best, _)) = counts.iter().max_by(|a, b| a.1.cmp(b.1).then(a.0.cmp(b.0))) else {
        return Err((
            0,
            "cannot find the safe height: no rapid XY moves at a known Z".into(),
        ));
    };
    let safe = best as f64 / 1000.0;
    let travel = counts
        .keys()
        .map(|&k| k as f64 / 1000.0)
        .filter(|&z| z >= safe)
        .fold(safe, f64::max);
    Ok(Split::Z { safe, travel })
}

/// Signed area of a closed polyline.
pub fn area(pts: &[[f64; 2]]) -> f64 {
    let mut a = 0.0;
    for i in 0..pts.len() {
        let p = pts[i];
        let q = pts[(i + 1) % pts.len()];
        a += p[0] * q[1] - q[0] * p[1];
    }
    a / 2.0
}

fn inside(poly: &[[f64; 2]], x: f64, y: f64) -> bool {
    let mut c = false;
    let n = poly.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (poly[i], poly[j]);
        if (a[1] > y) != (b[1] > y) && x < (b[0] - a[0]) * (y - a[1]) / (b[1] - a[1]) + a[0] {
            c = !c;
        }
        j = i;
    }
    c
}

/// True when closed cell `outer` strictly encloses every sample point of `inner`.
fn encloses(outer: &GCell, inner: &GCell, tol: f64) -> bool {
    let Some(poly) = &outer.closed else {
        return false;
    };
    let (a, b) = (outer.bbox, inner.bbox);
    if !(a[0] < b[0] - tol && a[1] < b[1] - tol && a[2] > b[2] + tol && a[3] > b[3] + tol) {
        return false;
    }
    let mut samples = vec![
        [inner.entry[0], inner.entry[1]],
        [inner.exit[0], inner.exit[1]],
    ];
    if let Some(q) = &inner.closed {
        let step = (q.len() / 16).max(1);
        samples.extend(q.iter().step_by(step).copied());
    }
    samples.push([b[0], b[1]]);
    samples.push([b[2], b[3]]);
    samples.iter().all(|s| inside(poly, s[0], s[1]))
}

/// Default precedence among `cells` (indices into the layout, in program order): pairs whose
/// XY boxes (grown by `margin`) overlap keep their order, except that a closed contour
/// enclosing the other cell goes after it. Returns edges over positions in `cells`, and
/// whether the inner-first rule had to be dropped because it contradicted the order rule.
pub fn precedence(l: &Layout, cells: &[usize], margin: f64) -> (Vec<(usize, usize)>, bool) {
    let mut by_x: Vec<usize> = (0..cells.len()).collect();
    by_x.sort_by(|&a, &b| l.cells[cells[a]].bbox[0].total_cmp(&l.cells[cells[b]].bbox[0]));
    let mut plain = Vec::new();
    let mut inverted = Vec::new();
    for (k, &a) in by_x.iter().enumerate() {
        let ba = l.cells[cells[a]].bbox;
        for &b in &by_x[k + 1..] {
            let bb = l.cells[cells[b]].bbox;
            if bb[0] > ba[2] + 2.0 * margin {
                break;
            }
            if bb[1] > ba[3] + 2.0 * margin || ba[1] > bb[3] + 2.0 * margin {
                continue;
            }
            let (i, j) = if a < b { (a, b) } else { (b, a) };
            let (ci, cj) = (&l.cells[cells[i]], &l.cells[cells[j]]);
            if encloses(ci, cj, margin.max(1e-3)) {
                inverted.push((j, i));
                plain.push((i, j));
            } else {
                plain.push((i, j));
            }
        }
    }
    if inverted.is_empty() {
        return (plain, false);
    }
    let inv: std::collections::HashSet<(usize, usize)> =
        inverted.iter().map(|&(j, i)| (i, j)).collect();
    let mixed: Vec<(usize, usize)> = plain
        .iter()
        .map(|&e| if inv.contains(&e) { (e.1, e.0) } else { e })
        .collect();
    let dag = cellseq::precedence::Dag::new(cells.len(), &mixed);
    if cellseq::precedence::topological_order(&dag).is_ok() {
        (mixed, false)
    } else {
        (plain, true)
    }
}

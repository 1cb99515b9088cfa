//! G-code (RS-274: LinuxCNC, Fanuc-style, GRBL): read a program, split it into cells, build
//! an [`Instance`], write the program back in a given order, and verify equivalence. This
//! codec runs no solver: [`crate::optimize::gcode`] does.
//!
//! [`lex`] tokenizes lines (whitespace made ASCII outside comments), [`interp`] executes them
//! with full modal state (and which elements the program set at all) and lists every cutting
//! move, [`cells`] splits the program (header, tool blocks, runs, cells, footer) and derives
//! the default precedence, [`write`](mod@write) re-emits it with only the state changes the
//! new order needs, [`verify`] compares two programs: cutting moves and events with their
//! machine state, as multisets, and no new motion; and measures air travel, lifts and time.

pub mod cells;
pub mod expr;
pub mod interp;
pub mod lex;
pub mod reverse;
pub mod verify;
pub mod write;

use cells::{Layout, Split};
use cellseq::error::{Error, Result};
use cellseq::geom::Point3;
use cellseq::model::{Cell, Instance, Machine, Metadata, Mode, StepKind, Tool, Visit};
use interp::Program;
pub use verify::Figures;

/// A parsed program with its cell layout.
#[derive(Debug, Clone)]
pub struct Parsed {
    /// File name (for messages).
    pub file: String,
    /// The interpreted lines.
    pub program: Program,
    /// Header, blocks, cells, footer.
    pub layout: Layout,
}

/// Interprets and splits a program; errors name the file and line.
pub fn parse(file: &str, text: &str) -> Result<Parsed> {
    let program = interp::interpret(text).map_err(|(l, m)| Error::parse(file, l, m))?;
    let layout = cells::split(&program).map_err(|(l, m)| {
        if l == 0 {
            Error::invalid(file, m)
        } else {
            Error::parse(file, l, m)
        }
    })?;
    Ok(Parsed {
        file: file.to_string(),
        program,
        layout,
    })
}

/// The units the program cuts in: `"mm"` (G21, or no G20), `"inch"` (G20 at every cut) or
/// `"mm and inch"`. Whatever they are, positions, lengths and feeds are read into mm, and
/// every figure cellseq reports for a program is in mm (and mm/min).
pub fn program_units(p: &Program) -> &'static str {
    let (mut mm, mut inch) = (false, false);
    for li in p.lines.iter().filter(|l| !l.cuts.is_empty()) {
        if li.after.metric {
            mm = true;
        } else {
            inch = true;
        }
    }
    match (mm, inch) {
        (_, false) => "mm",
        (false, true) => "inch",
        (true, true) => "mm and inch",
    }
}

/// The safe height used to count lifts (`None` for 2-D programs).
pub fn safe_height(p: &Parsed) -> Option<f64> {
    match p.layout.split {
        Split::Z { safe, .. } => Some(safe),
        Split::Flat => None,
    }
}

/// Groups of cells sequenced independently, in their fixed order: the runs of a tool block
/// (see [`cells::GCell::run`]), or (with `merge`) all cells of a tool within a run, tools in
/// first-use order.
pub fn groups(p: &Parsed, merge: bool) -> Vec<Vec<usize>> {
    let l = &p.layout;
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut keys: std::collections::HashMap<(usize, usize, u32), usize> = Default::default();
    for (i, c) in l.cells.iter().enumerate() {
        let k = if merge {
            (c.run, l.blocks[c.block].epoch, c.tool)
        } else {
            (c.run, c.block, 0)
        };
        match keys.get(&k) {
            Some(&g) => out[g].push(i),
            None => {
                keys.insert(k, out.len());
                out.push(vec![i]);
            }
        }
    }
    out
}

fn p3(a: [f64; 3]) -> Point3 {
    Point3::new(a[0], a[1], a[2])
}

/// Whether reversal is on for `p` given the option (`None`: on for 2-D programs without Z
/// words only).
pub fn reversal_on(p: &Parsed, reversible: Option<bool>) -> bool {
    reversible.unwrap_or(p.layout.split == Split::Flat && !p.program.has_z)
}

/// The reversal plan of every layout cell (`None`: one-mode), when reversal is `on`. Cells
/// whose entry and exit coincide gain nothing from a second mode and stay one-mode.
pub fn plans(p: &Parsed, on: bool) -> Vec<Option<reverse::Plan>> {
    p.layout
        .cells
        .iter()
        .map(|c| {
            if !on {
                return None;
            }
            let pl = reverse::plan(&p.program, p.layout.split, c).ok()?;
            let d = (0..3)
                .map(|k| (pl.entry[k] - c.entry[k]).abs())
                .fold(0.0, f64::max);
            (d > 1e-9).then_some(pl)
        })
        .collect()
}

/// The instance of a group of cells (indices into the layout), starting at `home`; cells with
/// a reversal plan in `plans` (indexed like the layout's cells) get a second, reversed mode.
/// Also returns whether the inner-first rule was dropped (it contradicted the overlap rule).
pub fn group_instance(
    p: &Parsed,
    cells: &[usize],
    home: [f64; 3],
    margin: f64,
    plans: &[Option<reverse::Plan>],
) -> (Instance, bool) {
    let l = &p.layout;
    let (precedence, dropped) = with_leads(l, cells, margin);
    let mut clearance = match l.split {
        Split::Z { travel, .. } => travel,
        Split::Flat => 0.0,
    };
    for &c in cells {
        clearance = clearance.max(l.cells[c].entry[2]).max(l.cells[c].exit[2]);
    }
    clearance = clearance.max(home[2]);
    let mut tools: Vec<Tool> = Vec::new();
    let out_cells: Vec<Cell> = cells
        .iter()
        .map(|&ci| {
            let c = &l.cells[ci];
            let tid = format!("T{}", c.tool);
            if !tools.iter().any(|t| t.id == tid) {
                tools.push(Tool {
                    id: tid.clone(),
                    diameter: 1.0,
                    name: None,
                    feed: None,
                });
            }
            let mut modes = vec![Mode::new(p3(c.entry), p3(c.exit))];
            if let Some(pl) = plans.get(ci).copied().flatten() {
                modes.push(Mode::new(p3(pl.entry), p3(pl.exit)));
            }
            let mut cell = Cell::new(format!("c{}", ci + 1), tid, modes);
            cell.reversible = cell.modes.len() == 2;
            cell.step = if c.cycle {
                StepKind::Hole
            } else {
                StepKind::Other
            };
            cell.z = c.depth;
            cell.cut_length = c.cut_length;
            cell.feature = Some(format!("line {}", p.program.lines[c.start].line));
            cell
        })
        .collect();
    let machine = Machine {
        home: p3(home),
        tool_change: p3(home),
        clearance,
        rapid_feed: verify::RAPID_MM_MIN,
        initial_tool: out_cells.first().map(|c| c.tool.clone()),
        ..Machine::default()
    };
    let n = out_cells.len();
    let inst = Instance {
        name: p.file.clone(),
        meta: Metadata {
            generator: Some("gcode".into()),
            ..Metadata::default()
        },
        machine,
        tools,
        cells: out_cells,
        precedence,
        as_given: Some((0..n).map(|i| Visit::new(i, 0)).collect()),
        ..Instance::default()
    };
    (inst, dropped)
}

/// [`cells::precedence`] plus the order the program's first settings impose: a leading cell
/// (see [`cells::GCell::lead`]) before every other cell of the group, a trailing one after.
/// When that contradicts inner-first, inner-first is dropped (reported like a contradiction
/// with the overlap rule).
fn with_leads(l: &Layout, cells: &[usize], margin: f64) -> (Vec<(usize, usize)>, bool) {
    let (mut edges, mut dropped) = cells::precedence(l, cells, margin);
    let mut extra = Vec::new();
    // a group is one run, so it has at most one leading and one trailing cell: O(n) edges
    let others = |i: usize| (0..cells.len()).filter(move |&j| j != i);
    for (i, &c) in cells.iter().enumerate() {
        if l.cells[c].lead {
            extra.extend(others(i).map(|j| (i, j)));
        }
        if l.cells[c].trail {
            extra.extend(others(i).map(|j| (j, i)));
        }
    }
    if extra.is_empty() {
        return (edges, dropped);
    }
    let mut all = edges.clone();
    all.extend(&extra);
    let dag = cellseq::precedence::Dag::new(cells.len(), &all);
    if cellseq::precedence::topological_order(&dag).is_err() {
        // keep every edge in program order (the overlap rule and the first settings agree)
        edges = edges
            .into_iter()
            .map(|(a, b)| (a.min(b), a.max(b)))
            .collect();
        dropped = true;
        all = edges;
        all.extend(&extra);
    }
    (all, dropped)
}

/// The whole program as one instance (groups chained by precedence), for `cellseq import`;
/// `reversible` as in [`crate::optimize::gcode::Options::reversible`].
pub fn import(p: &Parsed, merge: bool, margin: f64, reversible: Option<bool>) -> Result<Instance> {
    let gs = groups(p, merge);
    let all: Vec<usize> = gs.iter().flatten().copied().collect();
    let home = p.layout.start.unwrap_or(p.layout.cells[0].entry);
    let pl = plans(p, reversal_on(p, reversible));
    let (mut inst, _) = group_instance(p, &all, home, margin, &pl);
    // overlap edges only within a group; groups in order
    let mut pos = 0;
    let mut starts = Vec::new();
    for g in &gs {
        starts.push(pos);
        pos += g.len();
    }
    let mut edges: Vec<(usize, usize)> = Vec::new();
    for (k, g) in gs.iter().enumerate() {
        let local: Vec<usize> = g.clone();
        let (e, _) = cells::precedence(&p.layout, &local, margin);
        edges.extend(e.into_iter().map(|(a, b)| (a + starts[k], b + starts[k])));
        if k + 1 < gs.len() {
            let pairs = g.len() * gs[k + 1].len();
            if edges.len() + pairs > 20_000_000 {
                return Err(Error::invalid(
                    &p.file,
                    "too many tool-block precedence edges to export",
                ));
            }
            for a in 0..g.len() {
                for b in 0..gs[k + 1].len() {
                    edges.push((starts[k] + a, starts[k + 1] + b));
                }
            }
        }
    }
    inst.precedence = edges;
    Ok(inst)
}

/// Tolerance (mm) of the cutting-move comparison.
pub const TOLERANCE: f64 = 1e-3;

/// What [`verify_texts`] found.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Verification {
    /// Cutting moves matched (each in the same machine state).
    pub cuts: usize,
    /// Events matched (dwells, pauses, tool changes, …; each in the same machine state).
    pub events: usize,
    /// Original figures.
    pub before: Figures,
    /// New figures.
    pub after: Figures,
}

use serde::Serialize;

/// Interprets `new_text` and checks it against the original with [`verify::equivalent`]:
/// cutting moves and events with their machine state, in either direction (a move cut
/// backwards, arc direction swapped around the same centre, counts as the same move), and no
/// new motion. What `verify-gcode` does, since an optimized program may reverse cells.
pub fn verify_texts(orig: &Parsed, new_file: &str, new_text: &str) -> Result<Verification> {
    verify_with(orig, new_file, new_text, true)
}

/// [`verify_texts`] with the direction rule chosen: `undirected` false demands every move in
/// its original direction (what `optimize` checks when reversal is off).
pub fn verify_with(
    orig: &Parsed,
    new_file: &str,
    new_text: &str,
    undirected: bool,
) -> Result<Verification> {
    Verifier::new(orig, undirected)?.check(new_file, new_text)
}

/// The check of [`verify_with`] with the original's [`verify::Digest`] made once, for
/// checking several candidate programs against one original. A candidate text is
/// interpreted line by line and never held, so checking a program costs the memory of its
/// digest (32 bytes per cutting move), not of its interpreted lines.
#[derive(Debug, Clone)]
pub struct Verifier<'a> {
    orig: &'a Parsed,
    undirected: bool,
    digest: verify::Digest,
}

impl<'a> Verifier<'a> {
    /// Sums up the original; `undirected` as in [`verify_with`].
    pub fn new(orig: &'a Parsed, undirected: bool) -> Result<Self> {
        let lines = verify::Lines::Program(&orig.program);
        let digest = verify::Digest::of(lines, TOLERANCE, undirected, safe_height(orig))
            .map_err(|(l, m)| Error::parse(&orig.file, l, m))?;
        Ok(Verifier {
            orig,
            undirected,
            digest,
        })
    }

    /// Interprets `new_text` line by line and checks it against the original.
    pub fn check(&self, new_file: &str, new_text: &str) -> Result<Verification> {
        let lines = verify::Lines::Text(new_text);
        let safe = safe_height(self.orig);
        let digest = verify::Digest::of(lines, TOLERANCE, self.undirected, safe)
            .map_err(|(l, m)| Error::parse(new_file, l, m))?;
        let eq = verify::compare(
            (verify::Lines::Program(&self.orig.program), &self.digest),
            (lines, &digest),
            TOLERANCE,
            self.undirected,
        )
        .map_err(|m| {
            Error::invalid(
                new_file,
                format!("not equivalent to {}: {m}", self.orig.file),
            )
        })?;
        Ok(Verification {
            cuts: eq.cuts,
            events: eq.events,
            before: self.digest.figures,
            after: digest.figures,
        })
    }
}

/// `verify-gcode`: parses both files and compares them.
pub fn verify_files(
    orig_file: &str,
    orig_text: &str,
    new_file: &str,
    new_text: &str,
) -> Result<Verification> {
    let p = parse(orig_file, orig_text)?;
    verify_texts(&p, new_file, new_text)
}

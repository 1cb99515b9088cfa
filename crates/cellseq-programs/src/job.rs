//! One call from a program or drawing to its optimized text and report: what `cellseq
//! optimize` does, for Rust callers and the Python package alike.
//!
//! [`optimize_file`] reads a G-code program, an SVG or a DXF drawing ([`Format::of_path`]),
//! [`optimize_source`] takes its content in memory; both run the [`crate::optimize`] pipeline
//! within one [`Allowance`] (a time limit covers reading, solving, verifying and rendering) and
//! return a [`Job`]: the new text (verified against the original before it is returned) and a
//! typed [`Report`], whose JSON ([`Report::to_json`]) is the object `cellseq optimize --json`
//! prints. Writing the text is the caller's ([`Job::save`] writes atomically).
//!
//! ```no_run
//! use cellseq_programs::job::{self, Options};
//! let job = job::optimize_file("part.ngc".as_ref(), &Options::default())?;
//! println!("{}", job.report.to_json(None));
//! job.save("part.opt.ngc".as_ref(), Some("part.ngc".as_ref()), false)?;
//! # Ok::<(), cellseq::Error>(())
//! ```

use crate::dxf;
use crate::gcode::{self, Figures};
use crate::optimize::Allowance;
use crate::optimize::Timings;
use crate::optimize::gcode::{self as gpipe, Kept};
use crate::optimize::strokes::{self as spipe, Blocks, Pens, Reading};
use crate::svg::{self, Drawing, PenUp};
use cellseq::SolverKind;
use cellseq::error::{Error, Result};
use cellseq::files::{ensure_not_input, read_bytes, read_text, write_atomic};
use cellseq::params::{FloatRange, IntRange};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// The ranges of the numbers [`Options`] and [`DrawingOptions`] take (the command line's flags
/// of the same names check the same ranges).
pub mod limits {
    use super::{FloatRange, IntRange};
    /// `margin`, mm: the XY margin added to cell footprints for the overlap rule.
    pub const MARGIN: FloatRange = FloatRange::closed(0.0, 1e4);
    /// `tolerance`, mm: curve flattening.
    pub const TOLERANCE: FloatRange = FloatRange::closed(1e-6, 1e3);
    /// `contain_tol`, mm: containment tolerance of cut mode.
    pub const CONTAIN_TOL: FloatRange = FloatRange::closed(0.0, 1e3);
    /// `max_starts`: start-vertex candidates per closed stroke.
    pub const MAX_STARTS: IntRange = IntRange::new(1, 256);
    /// `max_points`: points of a drawing after flattening.
    pub const MAX_POINTS: IntRange = IntRange::new(1, 1_000_000_000);
    /// `join_tol`, mm: DXF pieces closer than this are chained.
    pub const JOIN_TOL: FloatRange = FloatRange::closed(0.0, 1e3);
    /// `safe_height`, mm, of the DXF G-code post.
    pub const SAFE_HEIGHT: FloatRange = FloatRange::above(0.0, 1e5);
    /// `cut_depth`, mm, of the DXF G-code post.
    pub const CUT_DEPTH: FloatRange = FloatRange::closed(0.0, 1e5);
    /// `feed` and `plunge_feed`, mm/min, of the DXF G-code post.
    pub const FEED: FloatRange = FloatRange::closed(cellseq::validate::MIN_FEED, 1e6);
    /// `spindle` (rpm) and `laser_power` (S) of the DXF G-code post; 0 writes none.
    pub const SPEED: FloatRange = FloatRange::closed(0.0, 1e6);
}

/// The kind of input, which decides the pipeline.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// A G-code program.
    Gcode,
    /// An SVG drawing.
    Svg,
    /// A DXF drawing.
    Dxf,
}

impl Format {
    /// The format `given` (`gcode`, `svg`, `dxf`, or a G-code extension), else the one of
    /// `path`'s extension (`.ngc`, `.nc`, `.gcode`, `.tap`, `.gco`, `.g`, `.cnc`, `.txt`,
    /// `.svg`, `.dxf`).
    pub fn of_path(path: &Path, given: Option<&str>) -> Result<Format> {
        let f = match given {
            Some(g) => g.to_ascii_lowercase(),
            None => path
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("")
                .to_ascii_lowercase(),
        };
        Ok(match f.as_str() {
            "gcode" | "ngc" | "nc" | "tap" | "gco" | "g" | "cnc" | "txt" => Format::Gcode,
            "svg" => Format::Svg,
            "dxf" => Format::Dxf,
            other => {
                return Err(Error::Invalid {
                    file: path.display().to_string(),
                    msg: format!(
                        "cannot tell the format from '{other}' (give the format: gcode, svg or dxf)"
                    ),
                });
            }
        })
    }
    /// `gcode`, `svg` or `dxf`.
    pub fn name(self) -> &'static str {
        match self {
            Format::Gcode => "gcode",
            Format::Svg => "svg",
            Format::Dxf => "dxf",
        }
    }
}

/// What [`optimize_source`] does, with the command line's defaults.
#[derive(Debug, Clone)]
pub struct Options {
    /// The solver; `None`: `auto` for G-code, `drawing` for drawings.
    pub solver: Option<SolverKind>,
    /// Seconds for the whole call (reading, solving, verifying, rendering), in (0, 1e6].
    pub time_limit: Option<f64>,
    /// Evaluation budget of the solver, shared among groups by size (deterministic results).
    pub max_evals: Option<u64>,
    /// Seed.
    pub seed: u64,
    /// Solver parameters, as `--param KEY=VALUE` gives them (drawings).
    pub params: BTreeMap<String, String>,
    /// Cutting cells backwards: `None` the format's default (drawings and 2-D G-code on,
    /// G-code with Z moves off).
    pub reversible: Option<bool>,
    /// G-code: merge blocks of the same tool (fewer tool changes).
    pub merge_tool_blocks: bool,
    /// G-code: XY margin (mm) added to cell footprints for the overlap rule
    /// ([`limits::MARGIN`]).
    pub margin: f64,
    /// Drawings: reading, ordering and (DXF) post options.
    pub drawing: DrawingOptions,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            solver: None,
            time_limit: None,
            max_evals: None,
            seed: 1,
            params: BTreeMap::new(),
            reversible: None,
            merge_tool_blocks: false,
            margin: 0.5,
            drawing: DrawingOptions::default(),
        }
    }
}

/// The options of SVG and DXF drawings (mm where a length).
#[derive(Debug, Clone)]
pub struct DrawingOptions {
    /// Curve flattening tolerance ([`limits::TOLERANCE`]).
    pub tolerance: f64,
    /// What a pen is (docs/drawings.md).
    pub pens: Pens,
    /// What a plain top-level group is.
    pub blocks: Blocks,
    /// Strokes inside a closed stroke first: `None` on for DXF, off for SVG.
    pub cut: Option<bool>,
    /// Plain top-level groups in the file's order.
    pub keep_group_order: bool,
    /// Containment tolerance of cut mode ([`limits::CONTAIN_TOL`]).
    pub contain_tol: f64,
    /// Start-vertex candidates per closed stroke ([`limits::MAX_STARTS`]).
    pub max_starts: usize,
    /// Unsupported elements: SVG drops them (instead of keeping them verbatim), DXF skips
    /// them (instead of refusing the file).
    pub skip_unsupported: bool,
    /// Most points after flattening ([`limits::MAX_POINTS`]).
    pub max_points: usize,
    /// DXF: chain pieces whose ends are closer than this ([`limits::JOIN_TOL`]).
    pub join_tol: f64,
    /// DXF: the drawing unit when the file does not say (mm, cm, m, in, ft, mil, um).
    pub units: Option<String>,
    /// DXF: write an SVG preview instead of G-code.
    pub svg_output: bool,
    /// DXF: the G-code post.
    pub post: dxf::Post,
}

impl Default for DrawingOptions {
    fn default() -> Self {
        DrawingOptions {
            tolerance: 0.01,
            pens: Pens::Auto,
            blocks: Blocks::Auto,
            cut: None,
            keep_group_order: false,
            contain_tol: 0.01,
            max_starts: 8,
            skip_unsupported: false,
            max_points: 10_000_000,
            join_tol: 0.001,
            units: None,
            svg_output: false,
            post: dxf::Post::default(),
        }
    }
}

/// `Err` naming `what` when `x` is outside `r`.
fn float_in(r: FloatRange, what: &str, x: f64) -> Result<()> {
    r.check(what, x).map(|_| ()).map_err(|msg| Error::Invalid {
        file: "<options>".into(),
        msg,
    })
}

/// `Err` naming `what` when `v` is outside `r`.
fn int_in(r: IntRange, what: &str, v: u64) -> Result<()> {
    r.check(what, v).map(|_| ()).map_err(|msg| Error::Invalid {
        file: "<options>".into(),
        msg,
    })
}

impl Options {
    /// Checks every number against its range ([`limits`]) and the combinations the pipeline
    /// cannot honour.
    pub fn check(&self) -> Result<()> {
        float_in(limits::MARGIN, "margin", self.margin)?;
        let d = &self.drawing;
        float_in(limits::TOLERANCE, "tolerance", d.tolerance)?;
        float_in(limits::CONTAIN_TOL, "contain_tol", d.contain_tol)?;
        int_in(limits::MAX_STARTS, "max_starts", d.max_starts as u64)?;
        int_in(limits::MAX_POINTS, "max_points", d.max_points as u64)?;
        float_in(limits::JOIN_TOL, "join_tol", d.join_tol)?;
        float_in(limits::SAFE_HEIGHT, "safe_height", d.post.safe_height)?;
        float_in(limits::CUT_DEPTH, "cut_depth", d.post.depth)?;
        float_in(limits::FEED, "feed", d.post.feed)?;
        float_in(limits::FEED, "plunge_feed", d.post.plunge_feed)?;
        float_in(limits::SPEED, "spindle", d.post.spindle)?;
        float_in(limits::SPEED, "laser_power", d.post.laser_power)?;
        if d.keep_group_order && d.blocks == Blocks::None {
            return Err(Error::Invalid {
                file: "<options>".into(),
                msg: "keep_group_order keeps plain groups as blocks: it cannot go with blocks none"
                    .into(),
            });
        }
        Ok(())
    }
}

/// An optimized program or drawing.
#[derive(Debug, Clone)]
pub struct Job {
    /// The input's format.
    pub format: Format,
    /// The new text: verified against the original before it was returned (the original's
    /// order where the new one was not better, as the report says).
    pub text: String,
    /// What was done and the figures before and after.
    pub report: Report,
}

impl Job {
    /// Writes the text to `path` atomically; writing over `input` (by any path or link) needs
    /// `overwrite_input`.
    pub fn save(&self, path: &Path, input: Option<&Path>, overwrite_input: bool) -> Result<()> {
        if let Some(i) = input {
            ensure_not_input(i, path, overwrite_input)?;
        }
        write_atomic(path, self.text.as_bytes())
    }
}

/// The report of a [`Job`], by format.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Report {
    /// A G-code program.
    Gcode(GcodeReport),
    /// An SVG drawing.
    Svg(SvgReport),
    /// A DXF drawing.
    Dxf(DxfReport),
}

impl Report {
    /// The object `cellseq optimize --json` prints, with `output` the file written (if any).
    pub fn to_json(&self, output: Option<&Path>) -> serde_json::Value {
        let mut v = serde_json::to_value(self).expect("a report is plain data");
        if let Some(m) = v.as_object_mut() {
            m.insert(
                "output".into(),
                output.map(|p| p.display().to_string()).into(),
            );
        }
        v
    }
    /// Seconds from the start of the call to the end of the work, or to `now` once the caller
    /// has written the result (`total_s`).
    pub fn set_total_s(&mut self, total_s: f64) {
        match self {
            Report::Gcode(r) => r.total_s = total_s,
            Report::Svg(r) => r.total_s = total_s,
            Report::Dxf(r) => r.total_s = total_s,
        }
    }
}

/// The report of a G-code program (figures in mm whatever the program's units).
#[derive(Debug, Clone, Serialize)]
pub struct GcodeReport {
    /// The input's name.
    pub input: String,
    /// The solver.
    pub solver: String,
    /// Cells found.
    pub cells: usize,
    /// Tool blocks.
    pub tool_blocks: usize,
    /// Groups sequenced independently.
    pub groups: usize,
    /// Cutting moves compared with the original's, each in the same machine state.
    pub verified_cutting_moves: usize,
    /// Non-motion events compared (dwells, pauses, tool changes).
    pub verified_events: usize,
    /// Groups where the inner-first rule contradicted the original order of overlapping cells.
    pub inner_first_dropped_groups: usize,
    /// True when any original order was kept.
    pub kept_original_order: bool,
    /// Where the original order was kept.
    pub kept: Kept,
    /// Why the whole program was kept, when it was.
    pub kept_note: Option<String>,
    /// True when reversal was on.
    pub reversal: bool,
    /// Cells that could have been reversed.
    pub reversible_cells: usize,
    /// Cells cut backwards.
    pub reversed_cells: usize,
    /// Where the time went.
    pub timings: Timings,
    /// Solver seconds.
    pub solve_s: f64,
    /// Seconds of the whole call.
    pub total_s: f64,
    /// Figures of the original.
    pub before: Figures,
    /// Figures of the new program.
    pub after: Figures,
    /// The unit of every figure: `mm`.
    pub units: &'static str,
    /// The program's own units (`mm` or `inch`).
    pub program_units: &'static str,
}

/// The reading of pens and blocks a drawing was sequenced under, and the others tried.
#[derive(Debug, Clone, Serialize)]
pub struct Semantics {
    /// What a pen was.
    pub pens: &'static str,
    /// What a plain top-level group was.
    pub blocks: &'static str,
    /// Each scope's strokes in containment order.
    pub inner_first: bool,
    /// Why this reading was considered.
    pub why: String,
    /// Every reading solved, with its pen-up travel in all.
    pub tried: Vec<Tried>,
    /// The readings as the pipeline has them: the kept one and every one tried (for
    /// [`Semantics::line`]; not in the JSON).
    #[serde(skip)]
    readings: (Reading, Vec<(Reading, f64)>),
}

/// One reading solved.
#[derive(Debug, Clone, Serialize)]
pub struct Tried {
    /// What a pen was.
    pub pens: &'static str,
    /// What a plain top-level group was.
    pub blocks: &'static str,
    /// Each scope's strokes in containment order.
    pub inner_first: bool,
    /// Pen-up travel in all, mm.
    pub pen_up_total_mm: f64,
}

impl Semantics {
    fn of(out: &spipe::Optimized) -> Semantics {
        let tried = |r: &Reading, up: f64| Tried {
            pens: r.pens.name(),
            blocks: r.blocks.name(),
            inner_first: r.inner_first,
            pen_up_total_mm: up,
        };
        Semantics {
            pens: out.reading.pens.name(),
            blocks: out.reading.blocks.name(),
            inner_first: out.reading.inner_first,
            why: out.semantics.clone(),
            tried: out.tried.iter().map(|(r, up)| tried(r, *up)).collect(),
            readings: (out.reading, out.tried.clone()),
        }
    }
    /// The line the command line prints: the reading kept, why, and the others tried.
    pub fn line(&self) -> String {
        let (kept, tried) = &self.readings;
        let others: Vec<String> = tried
            .iter()
            .filter(|(r, _)| r != kept)
            .map(|(r, up)| format!("{r}: {up:.1} mm"))
            .collect();
        let also = if others.is_empty() {
            String::new()
        } else {
            format!("; also tried {}", others.join(", "))
        };
        format!("{kept} ({}){also}", self.why)
    }
}

/// The report of an SVG drawing.
#[derive(Debug, Clone, Serialize)]
pub struct SvgReport {
    /// The input's name.
    pub input: String,
    /// The solver.
    pub solver: String,
    /// Strokes read.
    pub strokes: usize,
    /// Scopes sequenced.
    pub scopes: usize,
    /// Precedence edges (cut mode).
    pub precedence_edges: usize,
    /// Strokes could be drawn backwards.
    pub reversible: bool,
    /// Segments verified identical to the original's.
    pub verified_segments: usize,
    /// Elements the reader skipped.
    pub skipped: Vec<String>,
    /// Reading seconds.
    pub read_s: f64,
    /// Solver seconds.
    pub solve_s: f64,
    /// Seconds of the whole call.
    pub total_s: f64,
    /// Scopes that kept the file's order.
    pub kept_original_scopes: usize,
    /// Plain top-level groups drawn in another order than the file's.
    pub groups_reordered: bool,
    /// The reading of pens and blocks.
    pub semantics: Semantics,
    /// Why the whole drawing was kept, when it was.
    pub kept_note: Option<String>,
    /// Figures of the file's order.
    pub before: PenUp,
    /// Figures of the new order.
    pub after: PenUp,
}

/// The report of a DXF drawing.
#[derive(Debug, Clone, Serialize)]
pub struct DxfReport {
    /// The input's name.
    pub input: String,
    /// `gcode` (the post) or `svg` (a preview).
    pub output_kind: &'static str,
    /// The solver.
    pub solver: String,
    /// Contours read.
    pub contours: usize,
    /// Closed contours.
    pub closed_contours: usize,
    /// Layers.
    pub layers: usize,
    /// Scopes sequenced.
    pub scopes: usize,
    /// Inner-first precedence edges.
    pub inner_first_edges: usize,
    /// Contours could be cut backwards.
    pub reversible: bool,
    /// Segments verified identical to the original's.
    pub verified_segments: usize,
    /// Entities the reader skipped.
    pub skipped: Vec<String>,
    /// The reader's warnings.
    pub warnings: Vec<String>,
    /// Millimetres per drawing unit.
    pub mm_per_unit: f64,
    /// The reading of pens and blocks.
    pub semantics: Semantics,
    /// Why the whole drawing was kept, when it was.
    pub kept_note: Option<String>,
    /// Solver seconds.
    pub solve_s: f64,
    /// Seconds of the whole call.
    pub total_s: f64,
    /// Figures of the file's order.
    pub before: PenUp,
    /// Figures of the new order.
    pub after: PenUp,
}

/// Reads `path` and optimizes it in the format of its extension (or `given`).
pub fn optimize_file(path: &Path, opts: &Options) -> Result<Job> {
    optimize_file_as(path, None, opts)
}

/// [`optimize_file`] with the format `given` (`gcode`, `svg`, `dxf`).
pub fn optimize_file_as(path: &Path, given: Option<&str>, opts: &Options) -> Result<Job> {
    opts.check()?;
    let allowance = Allowance::new(opts.time_limit, opts.max_evals)?;
    let format = Format::of_path(path, given)?;
    // G-code and SVG are text (read_text refuses NUL bytes and non-UTF-8 by line); a DXF may
    // be binary
    let bytes = match format {
        Format::Dxf => read_bytes(path)?,
        _ => read_text(path)?.into_bytes(),
    };
    run(
        &path.display().to_string(),
        &bytes,
        format,
        opts,
        &allowance,
    )
}

/// Optimizes `content` (a G-code program or SVG as text, a DXF as text or bytes) named `file`
/// in errors and the report.
pub fn optimize_source(file: &str, content: &[u8], format: Format, opts: &Options) -> Result<Job> {
    opts.check()?;
    let allowance = Allowance::new(opts.time_limit, opts.max_evals)?;
    run(file, content, format, opts, &allowance)
}

/// `content` as text (G-code and SVG): refused, naming `file` and the line, at a NUL byte or
/// where it is not UTF-8.
fn text_of<'a>(file: &str, content: &'a [u8]) -> Result<&'a str> {
    let line_at = |at: usize| 1 + content[..at].iter().filter(|&&b| b == b'\n').count();
    if let Some(at) = content.iter().position(|&b| b == 0) {
        return Err(Error::parse(
            file,
            line_at(at),
            format!("a NUL byte at byte {}: not a text file", at + 1),
        ));
    }
    std::str::from_utf8(content).map_err(|e| {
        Error::parse(
            file,
            line_at(e.valid_up_to()),
            format!("not UTF-8 text (byte {})", e.valid_up_to()),
        )
    })
}

fn run(file: &str, content: &[u8], format: Format, opts: &Options, a: &Allowance) -> Result<Job> {
    match format {
        Format::Gcode => gcode_job(file, text_of(file, content)?, opts, a),
        Format::Svg => {
            let d = read_svg(file, text_of(file, content)?, &opts.drawing)?;
            drawing_job(file, d, Format::Svg, opts, a)
        }
        Format::Dxf => {
            let d = read_dxf(file, content, &opts.drawing)?;
            drawing_job(file, d, Format::Dxf, opts, a)
        }
    }
}

fn gcode_job(file: &str, text: &str, opts: &Options, a: &Allowance) -> Result<Job> {
    let parsed = gcode::parse(file, text)?;
    let parse_s = a.started.elapsed().as_secs_f64();
    let solver = opts.solver.unwrap_or_default();
    let o = gpipe::Options {
        solver,
        time_limit: opts.time_limit,
        max_evals: opts.max_evals,
        seed: opts.seed,
        merge: opts.merge_tool_blocks,
        margin: opts.margin,
        reversible: opts.reversible,
    };
    let mut out = gpipe::optimize_within(&parsed, &o, a)?;
    out.timings.parse_s = parse_s;
    let report = GcodeReport {
        input: file.into(),
        solver: solver.name().into(),
        cells: parsed.layout.cells.len(),
        tool_blocks: parsed.layout.blocks.len(),
        groups: out.groups,
        verified_cutting_moves: out.cuts,
        verified_events: out.events,
        inner_first_dropped_groups: out.inner_first_dropped,
        kept_original_order: out.kept_original(),
        kept: out.kept,
        kept_note: out.note.clone(),
        reversal: out.reversal_on,
        reversible_cells: out.reversible_cells,
        reversed_cells: out.reversed.iter().filter(|&&r| r).count(),
        timings: out.timings,
        solve_s: out.timings.solve_s,
        total_s: a.started.elapsed().as_secs_f64(),
        before: out.before,
        after: out.after,
        units: "mm",
        program_units: gcode::program_units(&parsed.program),
    };
    Ok(Job {
        format: Format::Gcode,
        text: out.text,
        report: Report::Gcode(report),
    })
}

/// Reads an SVG as the command line does (the tolerance is in mm; the reader works in user
/// units).
pub fn read_svg(file: &str, text: &str, o: &DrawingOptions) -> Result<Drawing> {
    svg::read::read_mm(
        file,
        text,
        o.tolerance,
        svg::ReadOptions {
            tolerance: o.tolerance,
            skip_unsupported: o.skip_unsupported,
            max_points: o.max_points,
        },
    )
}

/// Reads a DXF as the command line does (millimetre tolerances scaled to the drawing's unit).
pub fn read_dxf(file: &str, bytes: &[u8], o: &DrawingOptions) -> Result<Drawing> {
    let units = match &o.units {
        Some(u) => Some(dxf::unit_mm(u).ok_or_else(|| Error::Invalid {
            file: file.into(),
            msg: format!("units '{u}': use mm, cm, m, in, ft, mil or um"),
        })?),
        None => None,
    };
    let mut r = dxf::ReadOptions {
        tolerance: o.tolerance,
        join: o.join_tol,
        skip_unsupported: o.skip_unsupported,
        units,
    };
    let d = dxf::read(file, bytes, r)?;
    if d.mm_per_unit == 1.0 {
        return Ok(d);
    }
    r.tolerance /= d.mm_per_unit;
    r.join /= d.mm_per_unit;
    dxf::read(file, bytes, r)
}

/// The pipeline options of drawing `d` under `opts`.
pub fn drawing_options(d: &Drawing, format: Format, opts: &Options) -> spipe::Options {
    let o = &opts.drawing;
    spipe::Options {
        solver: opts.solver.unwrap_or(spipe::DRAWING_SOLVER),
        time_limit: opts.time_limit,
        max_evals: opts.max_evals,
        params: opts.params.clone(),
        seed: opts.seed,
        reversible: opts.reversible.unwrap_or(true),
        // pens none and blocks none is one scope (the command line's --no-scopes)
        scopes: !(o.pens == Pens::None && o.blocks == Blocks::None),
        pens: o.pens,
        blocks: o.blocks,
        cut: o.cut.unwrap_or(format == Format::Dxf),
        free_groups: !o.keep_group_order,
        contain_tol: o.contain_tol / d.mm_per_unit,
        max_starts: o.max_starts,
    }
}

fn drawing_job(
    file: &str,
    d: Drawing,
    format: Format,
    opts: &Options,
    a: &Allowance,
) -> Result<Job> {
    let read_s = a.started.elapsed().as_secs_f64();
    let po = drawing_options(&d, format, opts);
    let mut out = spipe::optimize_within(&d, &po, a)?;
    let gcode_out = format == Format::Dxf && !opts.drawing.svg_output;
    let kind = if gcode_out {
        spipe::Output::Gcode(&opts.drawing.post)
    } else {
        spipe::Output::Svg
    };
    let (text, segments) = spipe::render(&d, &mut out, kind)?;
    let total_s = a.started.elapsed().as_secs_f64();
    let semantics = Semantics::of(&out);
    let report = if format == Format::Svg {
        Report::Svg(SvgReport {
            input: file.into(),
            solver: po.solver.name().into(),
            strokes: d.strokes.len(),
            scopes: out.scopes,
            precedence_edges: out.edges,
            reversible: po.reversible,
            verified_segments: segments,
            skipped: d.skipped.clone(),
            read_s,
            solve_s: out.solve_s,
            total_s,
            kept_original_scopes: out.kept_original,
            groups_reordered: out.groups_reordered,
            semantics,
            kept_note: out.note.clone(),
            before: out.before,
            after: out.after,
        })
    } else {
        Report::Dxf(DxfReport {
            input: file.into(),
            output_kind: if gcode_out { "gcode" } else { "svg" },
            solver: po.solver.name().into(),
            contours: d.strokes.len(),
            closed_contours: d.strokes.iter().filter(|s| s.closed).count(),
            layers: d.layers.len() - 1,
            scopes: out.scopes,
            inner_first_edges: out.edges,
            reversible: po.reversible,
            verified_segments: segments,
            skipped: d.skipped.clone(),
            warnings: d.warnings.clone(),
            mm_per_unit: d.mm_per_unit,
            semantics,
            kept_note: out.note.clone(),
            solve_s: out.solve_s,
            total_s,
            before: out.before,
            after: out.after,
        })
    };
    Ok(Job {
        format,
        text,
        report,
    })
}

//! `optimize`, `import` and `verify-gcode`: real programs in, better programs out.

use super::rows::{Table, say_wrote, write_output};
use anyhow::bail;
use cellseq::files::ensure_not_input;
use cellseq::files::read_text;
use cellseq::formats::save_instance;
use cellseq_programs::gcode::{self, Figures};
use cellseq_programs::job::{self, Report};
use cellseq_programs::optimize::gcode::Kept;
use clap::Args;
use std::path::{Path, PathBuf};

/// Arguments of `optimize`.
#[derive(Args, Debug)]
pub struct OptimizeArgs {
    /// Input program (.ngc, .nc, .gcode, .tap, .gco, …).
    pub input: PathBuf,
    /// Output file (default: report only).
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
    /// Allow the output to be the input file itself (by any path or link).
    #[arg(long)]
    pub overwrite_input: bool,
    /// Solver from the registry (default for G-code: `auto`, the registry's default portfolio;
    /// for SVG/DXF `drawing`: greedy, 2-opt/Or-opt with reversal, iterated local search).
    #[arg(long)]
    pub solver: Option<String>,
    /// Time limit in seconds for the whole command (reading, solving, checking, writing);
    /// the solver's part is shared among groups of cells by size.
    #[arg(long, value_name = "S", value_parser = super::ranges::time_limit)]
    pub time_limit: Option<f64>,
    /// Evaluation budget of the solver, shared among groups by size (deterministic results);
    /// without this or a time limit, each group gets 20 000 evaluations per cell.
    #[arg(long, value_name = "N", value_parser = super::ranges::max_evals)]
    pub max_evals: Option<u64>,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Allow cutting cells in the opposite direction (default for drawings and 2-D G-code:
    /// laser, plasma, plotter; off by default for milling, where it swaps climb and
    /// conventional milling).
    #[arg(long, conflicts_with = "no_reversible")]
    pub reversible: bool,
    /// Never reverse cells (default for G-code with Z moves).
    #[arg(long)]
    pub no_reversible: bool,
    /// Keep tool blocks in their original order (default).
    #[arg(long, conflicts_with = "merge_tool_blocks")]
    pub keep_tool_order: bool,
    /// Merge blocks of the same tool (fewer tool changes).
    #[arg(long)]
    pub merge_tool_blocks: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Input format (default: from the extension).
    #[arg(long, value_name = "gcode|svg|dxf")]
    pub format: Option<String>,
    /// XY margin (mm) added to cell footprints for the overlap rule.
    #[arg(long, default_value_t = 0.5, value_parser = super::ranges::margin)]
    pub margin: f64,
    #[command(flatten)]
    pub drawing: super::strokes::DrawingArgs,
}

/// Arguments of `import`.
#[derive(Args, Debug)]
pub struct ImportArgs {
    /// Input program.
    pub input: PathBuf,
    /// Instance file to write.
    #[arg(short = 'o', long)]
    pub output: PathBuf,
    /// Allow the output to be the input file itself (by any path or link).
    #[arg(long)]
    pub overwrite_input: bool,
    /// Merge blocks of the same tool.
    #[arg(long)]
    pub merge_tool_blocks: bool,
    /// XY margin (mm) added to cell footprints for the overlap rule.
    #[arg(long, default_value_t = 0.5, value_parser = super::ranges::margin)]
    pub margin: f64,
    /// Input format (default: from the extension).
    #[arg(long, value_name = "gcode|svg|dxf")]
    pub format: Option<String>,
    /// Never reverse cells (drawings; 2-D G-code).
    #[arg(long)]
    pub no_reversible: bool,
    #[command(flatten)]
    pub drawing: super::strokes::DrawingArgs,
}

/// Arguments of `verify-gcode`.
#[derive(Args, Debug)]
pub struct VerifyArgs {
    /// The original program.
    pub original: PathBuf,
    /// The program to check against it.
    pub optimized: PathBuf,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

pub(super) fn format_of(path: &Path, given: Option<&str>) -> anyhow::Result<&'static str> {
    Ok(job::Format::of_path(path, given)?.name())
}

fn print_figures(before: &Figures, after: &Figures) {
    let t = Table::new(16);
    t.saved("air length mm", before.air_length, after.air_length);
    t.counts("lifts", before.lifts, after.lifts);
    t.counts("tool changes", before.tool_changes, after.tool_changes);
    t.saved("est. time s", before.est_time_s, after.est_time_s);
    t.values("cut length mm", before.cut_length, after.cut_length);
}

/// Says that the figures are in mm when the program is not (they are converted).
fn say_units(program: &str) {
    if program != "mm" {
        say!("units: the program is in {program} (G20); every figure above is converted to mm");
    }
}

/// Runs `optimize`.
pub fn optimize(a: OptimizeArgs) -> anyhow::Result<()> {
    if let Some(o) = &a.output {
        ensure_not_input(&a.input, o, a.overwrite_input)?;
    }
    let fmt = format_of(&a.input, a.format.as_deref())?;
    if fmt != "gcode" {
        return super::strokes::optimize(&a, fmt);
    }
    optimize_gcode(&a)
}

/// Output extensions that are not G-code: an optimized program is never written into them.
fn refuse_non_gcode_output(o: &Path) -> anyhow::Result<()> {
    let ext = o
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if matches!(
        ext.as_str(),
        "svg" | "dxf" | "png" | "pdf" | "json" | "csv" | "toml"
    ) {
        bail!(
            "{}: an optimized G-code program is not written into a .{ext} file; give a G-code \
             name (.ngc, .nc, .gcode, …), or draw it with `cellseq plot`",
            o.display()
        );
    }
    Ok(())
}

fn optimize_gcode(a: &OptimizeArgs) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    if let Some(o) = &a.output {
        refuse_non_gcode_output(o)?;
    }
    let opts = super::strokes::job_options(a, "gcode")?;
    let mut j = job::optimize_file_as(&a.input, Some("gcode"), &opts)?;
    let Report::Gcode(r) = &mut j.report else {
        bail!("{}: not read as G-code", a.input.display());
    };
    if a.output.is_some() {
        let t = std::time::Instant::now();
        write_output(a.output.as_deref(), &j.text)?;
        r.timings.write_s += t.elapsed().as_secs_f64();
    }
    r.total_s = t0.elapsed().as_secs_f64();
    if a.json {
        let v = j.report.to_json(a.output.as_deref());
        say!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    say!(
        "{}: {} cells in {} tool blocks, {} groups; solver {}; {} cutting moves and {} events verified in the same machine state",
        r.input,
        r.cells,
        r.tool_blocks,
        r.groups,
        r.solver,
        r.verified_cutting_moves,
        r.verified_events
    );
    if r.reversal {
        if r.reversible_cells == 0 {
            say!("reversal: on, but no cell could be reversed");
        } else {
            say!(
                "reversal: {} of {} reversible cells cut backwards",
                r.reversed_cells,
                r.reversible_cells
            );
        }
    }
    match r.kept {
        Kept::Whole => say!(
            "note: the program is kept in its original order ({})",
            r.kept_note
                .as_deref()
                .unwrap_or("the solver found no better order")
        ),
        Kept::Groups(g) => say!(
            "note: the original order was kept in {g} of {} group(s) (the new order was not better there)",
            r.groups
        ),
        Kept::Nothing => {}
    }
    if r.inner_first_dropped_groups > 0 {
        say!(
            "note: in {} group(s) inner-first contradicted the original order of overlapping cells; original order kept",
            r.inner_first_dropped_groups
        );
    }
    print_figures(&r.before, &r.after);
    say_units(r.program_units);
    let t = &r.timings;
    say!(
        "time: parse {:.3} s, solve {:.3} s, verify {:.3} s, write {:.3} s",
        t.parse_s,
        t.solve_s,
        t.verify_s,
        t.write_s
    );
    say_wrote(a.output.as_deref());
    Ok(())
}

/// Runs `import`.
pub fn import(a: ImportArgs) -> anyhow::Result<()> {
    ensure_not_input(&a.input, &a.output, a.overwrite_input)?;
    let fmt = format_of(&a.input, a.format.as_deref())?;
    if fmt != "gcode" {
        return super::strokes::import(&a, fmt);
    }
    let file = a.input.display().to_string();
    let text = read_text(&a.input)?;
    let parsed = gcode::parse(&file, &text)?;
    let inst = gcode::import(
        &parsed,
        a.merge_tool_blocks,
        a.margin,
        a.no_reversible.then_some(false),
    )?;
    cellseq::validate::validate(&inst, &file)?;
    save_instance(&a.output, &inst)?;
    say!(
        "{}: {} cells, {} precedence edges -> {}",
        file,
        inst.n(),
        inst.precedence.len(),
        a.output.display()
    );
    Ok(())
}

/// Runs `verify-gcode`.
pub fn verify(a: VerifyArgs) -> anyhow::Result<()> {
    let (fa, fb) = (
        a.original.display().to_string(),
        a.optimized.display().to_string(),
    );
    let ta = read_text(&a.original)?;
    let tb = read_text(&a.optimized)?;
    let v = gcode::verify_files(&fa, &ta, &fb, &tb)?;
    if a.json {
        say!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        say!(
            "equivalent: {} cutting moves and {} events match, each in the same machine state (in either direction); no new motion",
            v.cuts,
            v.events
        );
        print_figures(&v.before, &v.after);
        if let Ok(p) = gcode::interp::interpret(&ta) {
            say_units(gcode::program_units(&p));
        }
    }
    Ok(())
}

//! `plot`: pictures of instances and solutions.

use anyhow::{Context as _, Result};
use cellseq::formats::json;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PlotArgs {
    /// Instance file, or a program or drawing (.ngc/.nc/.gcode/…, .svg, .dxf): its cutting
    /// and air moves.
    file: PathBuf,
    /// Programs and drawings: draw this file (the same kind) as "after", beside the input.
    #[arg(long, value_name = "FILE", conflicts_with = "optimized")]
    after: Option<PathBuf>,
    /// Programs and drawings: draw the optimized result (`optimize` with its defaults) as
    /// "after", beside the input.
    #[arg(long)]
    optimized: bool,
    /// Before and after in one picture (air moves of both, cutting moves of "after") instead
    /// of side by side.
    #[arg(long)]
    overlay: bool,
    /// Solution to draw (cellseq-solution/1 JSON): its air moves, in order.
    #[arg(long, value_name = "SOLUTION.json")]
    solution: Option<PathBuf>,
    /// Output picture (.svg or .png).
    #[arg(short, long, value_name = "OUT.svg|OUT.png")]
    out: PathBuf,
    /// Allow the picture to be written over the instance or solution file.
    #[arg(long)]
    overwrite_input: bool,
}

pub fn plot(a: PlotArgs) -> Result<()> {
    cellseq_lab::plot::PictureFormat::of(&a.out)?;
    for input in std::iter::once(&a.file).chain(&a.solution).chain(&a.after) {
        cellseq::files::ensure_not_input(input, &a.out, a.overwrite_input)?;
    }
    let ext = a
        .file
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext != "json"
        && ext != "sop"
        && ext != "pcglns"
        && let Ok(fmt) = super::gcode::format_of(&a.file, None)
    {
        return plot_program(&a, fmt);
    }
    let inst = super::solve::load(&a.file)?;
    let mut caption = format!(
        "{} — {} cells, {} tools",
        inst.name,
        inst.n(),
        inst.used_tools().len()
    );
    let seq = match &a.solution {
        None => None,
        Some(path) => {
            let spath = path.display().to_string();
            let text = cellseq::files::read_text(path)?;
            let sol = json::parse_solution(&spath, &text)?;
            let seq = json::from_refs(&inst, &sol.sequence, &spath)?;
            let objective = super::solve::objective_of(&inst, Some(&sol.objective))
                .unwrap_or(inst.default_objective());
            let rep = cellseq::check(&inst, &seq, objective)
                .map_err(|v| anyhow::anyhow!("{spath}: infeasible: {v}"))?;
            caption = format!(
                "{} — {}: air {:.0} mm, {} lifts, {} tool changes, {:.1} s",
                inst.name,
                sol.solver,
                rep.air_length,
                rep.lifts,
                rep.tool_changes,
                rep.machining_time
            );
            Some(seq)
        }
    };
    cellseq_lab::plot::plot(&inst, seq.as_ref(), &caption, &a.out)
        .with_context(|| format!("plotting {}", a.file.display()))?;
    say!("wrote {}", a.out.display());
    Ok(())
}

/// The panel of a program or drawing file, and the optimized panel when asked.
fn panels_of(
    path: &std::path::Path,
    fmt: &str,
    title: &str,
    optimized: bool,
) -> Result<Vec<cellseq_lab::plot::Panel>> {
    use cellseq_programs::optimize::strokes as pipe;
    use cellseq_programs::{dxf, gcode, svg};
    let file = path.display().to_string();
    let mut out = Vec::new();
    match fmt {
        "gcode" => {
            let text = cellseq::files::read_text(path)?;
            let parsed = gcode::parse(&file, &text)?;
            // coordinates are drawn in mm whatever the program's units: the title says so
            let units = gcode::program_units(&parsed.program);
            let title = if units == "mm" {
                title.to_string()
            } else {
                format!("{title} ({units} program, drawn in mm)")
            };
            out.push(cellseq_lab::plot::program_panel(&title, &parsed.program));
            if optimized {
                let o = cellseq_programs::optimize::gcode::optimize(
                    &parsed,
                    &cellseq_programs::optimize::gcode::Options::default(),
                )?;
                let prog = gcode::interp::interpret(&o.text)
                    .map_err(|(l, m)| anyhow::anyhow!("<optimized>:{l}: {m}"))?;
                out.push(cellseq_lab::plot::program_panel("optimized", &prog));
            }
        }
        _ => {
            let d = if fmt == "svg" {
                svg::read(
                    &file,
                    &cellseq::files::read_text(path)?,
                    svg::ReadOptions::default(),
                )?
            } else {
                let bytes = cellseq::files::read_bytes(path)?;
                dxf::read(&file, &bytes, dxf::ReadOptions::default())?
            };
            out.push(cellseq_lab::plot::drawing_panel(title, &d, &d.strokes));
            if optimized {
                let opts = pipe::Options {
                    cut: fmt == "dxf",
                    ..pipe::Options::default()
                };
                let o = pipe::optimize(&d, &opts)?;
                out.push(cellseq_lab::plot::drawing_panel(
                    "optimized",
                    &d,
                    &o.strokes,
                ));
            }
        }
    }
    Ok(out)
}

fn plot_program(a: &PlotArgs, fmt: &str) -> Result<()> {
    let mut panels = panels_of(&a.file, fmt, "before", a.optimized)?;
    if let Some(after) = &a.after {
        let f2 = super::gcode::format_of(after, None)?;
        if f2 != fmt {
            anyhow::bail!(
                "{}: --after must be a {fmt} file like {}",
                after.display(),
                a.file.display()
            );
        }
        panels.extend(panels_of(after, f2, "after", false)?);
    }
    if panels.len() == 1 {
        panels[0].title = a.file.display().to_string();
    }
    cellseq_lab::plot::plot_panels(&panels, fmt == "svg", a.overlay, &a.out)
        .with_context(|| format!("plotting {}", a.file.display()))?;
    say!("wrote {}", a.out.display());
    Ok(())
}

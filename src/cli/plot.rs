//! `plot`: pictures of instances and solutions.

use anyhow::{Context as _, Result};
use cellseq::formats::{self, json};
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct PlotArgs {
    /// Instance file.
    file: PathBuf,
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
    cellseq::plot::PictureFormat::of(&a.out)?;
    for input in std::iter::once(&a.file).chain(&a.solution) {
        formats::write::ensure_not_input(input, &a.out, a.overwrite_input)?;
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
            let text = formats::read_text(path)?;
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
    cellseq::plot::plot(&inst, seq.as_ref(), &caption, &a.out)
        .with_context(|| format!("plotting {}", a.file.display()))?;
    say!("wrote {}", a.out.display());
    Ok(())
}

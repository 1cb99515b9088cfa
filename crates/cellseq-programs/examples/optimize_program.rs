//! Optimizes a G-code program, an SVG or a DXF drawing as `cellseq optimize` does: the new
//! text is verified against the original before it is returned, the report is the object of
//! `cellseq optimize --json`.
//!
//! ```sh
//! cargo run --release -p cellseq-programs --example optimize_program -- tests/fixtures/gcode/mill.ngc mill.opt.ngc
//! ```

use cellseq_programs::job::{self, Options, Report};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let input = PathBuf::from(
        args.next()
            .ok_or("usage: optimize_program INPUT [OUTPUT]")?,
    );
    let output = args.next().map(PathBuf::from);
    let opts = Options {
        time_limit: Some(5.0), // the whole call: reading, solving, verifying
        ..Options::default()
    };
    let job = job::optimize_file(&input, &opts)?;
    match &job.report {
        Report::Gcode(r) => println!(
            "air {:.1} -> {:.1} mm, {} cutting moves verified",
            r.before.air_length, r.after.air_length, r.verified_cutting_moves
        ),
        Report::Svg(r) => println!(
            "pen-up {:.1} -> {:.1} mm ({})",
            r.before.pen_up_total_mm,
            r.after.pen_up_total_mm,
            r.semantics.line()
        ),
        Report::Dxf(r) => println!(
            "travel {:.1} -> {:.1} mm",
            r.before.pen_up_total_mm, r.after.pen_up_total_mm
        ),
    }
    if let Some(out) = output {
        job.save(&out, Some(&input), false)?;
        println!("wrote {}", out.display());
    }
    Ok(())
}

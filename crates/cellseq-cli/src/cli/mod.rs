//! Command-line interface: argument definitions and dispatch. One module per command group.

/// `println!` for the CLI's standard output that ends the process quietly (status 0) when the
/// reader has gone away (`cellseq solve F | head`), instead of panicking on the broken pipe;
/// any other write error ends it with status 2 and a message.
macro_rules! say {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($arg)*) {
            $crate::cli::stdout_failed(e);
        }
    }};
}

mod bound;
mod demo;
mod gcode;
mod harness;
mod limits;
mod plot;
mod ranges;
mod rows;
mod solve;
mod strokes;

use clap::{Parser, Subcommand};

/// Sequencing of CNC machining cells.
#[derive(Parser, Debug)]
#[command(name = "cellseq", version = cellseq_lab::provenance::VERSION, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Summary of an instance: cells, modes, tools, precedence.
    Info(solve::InfoArgs),
    /// Validate an instance file: prints `ok` or the error.
    Validate(solve::ValidateArgs),
    /// Solve an instance with a named solver.
    Solve(solve::SolveArgs),
    /// Check and report a given solution.
    Eval(solve::EvalArgs),
    /// List every solver with its parameters and defaults (`--markdown`: docs/solvers.md).
    Solvers(solve::SolversArgs),
    /// Generate an instance from a seeded generator.
    Generate(solve::GenerateArgs),
    /// Lower bounds on the optimum of an instance.
    Bound(bound::BoundArgs),
    /// Run the built-in demonstration on a generated instance (no files needed).
    Demo(demo::DemoArgs),
    /// Reorder a G-code program's cells, verify it cuts the same, and write it.
    Optimize(gcode::OptimizeArgs),
    /// Extract the cell instance of a G-code program as JSON.
    Import(gcode::ImportArgs),
    /// Check that two G-code programs make the same cutting moves; report travel.
    VerifyGcode(gcode::VerifyArgs),
    /// Draw an instance (and a solution's air moves) to an SVG or PNG picture.
    Plot(plot::PlotArgs),
    /// Validate an experiment plan (or an `auto` portfolio file) without running it.
    Check(harness::CheckArgs),
    /// Run (or resume) an experiment plan.
    Run(harness::RunArgs),
    /// Merge result directories or shards, dropping duplicate trials.
    Merge(harness::MergeArgs),
    /// Tables, tests and plots from a results directory.
    Report(harness::ReportArgs),
    /// Every range and limit of a number cellseq takes: flags, plan keys, file values,
    /// solver and generator parameters (`--markdown`: the list in docs/bad-input.md).
    Limits(limits::LimitsArgs),
}

/// Parses a count given as an integer (`200000000`, `200_000_000`) or in exponent notation
/// (`2e8`, `1.5e6`) when that names a whole number that fits in a `u64`.
pub(crate) fn parse_count(s: &str) -> Result<u64, String> {
    let t = s.trim().replace('_', "");
    if let Ok(v) = t.parse::<u64>() {
        return Ok(v);
    }
    let (mant, exp) = t
        .split_once(['e', 'E'])
        .ok_or_else(|| format!("`{s}` is not a whole number (examples: 200000000, 2e8)"))?;
    let exp: u32 = exp
        .parse()
        .map_err(|_| format!("`{s}`: the exponent must be a small non-negative integer"))?;
    let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
    let digits = format!("{int}{frac}");
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return Err(format!(
            "`{s}` is not a whole number (examples: 200000000, 2e8)"
        ));
    }
    let shift = exp
        .checked_sub(frac.len() as u32)
        .ok_or_else(|| format!("`{s}` is not a whole number"))?;
    let base: u64 = digits.parse().map_err(|_| format!("`{s}` is too large"))?;
    10u64
        .checked_pow(shift)
        .and_then(|p| base.checked_mul(p))
        .ok_or_else(|| format!("`{s}` is too large"))
}

/// Runs the parsed command.
pub fn dispatch(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Info(a) => solve::info(a),
        Command::Validate(a) => solve::validate(a),
        Command::Solve(a) => solve::solve(a),
        Command::Eval(a) => solve::eval(a),
        Command::Solvers(a) => solve::solvers(a),
        Command::Generate(a) => solve::generate(a),
        Command::Bound(a) => bound::bound(a),
        Command::Demo(a) => demo::demo(a),
        Command::Optimize(a) => gcode::optimize(a),
        Command::Import(a) => gcode::import(a),
        Command::VerifyGcode(a) => gcode::verify(a),
        Command::Plot(a) => plot::plot(a),
        Command::Check(a) => harness::check(a),
        Command::Run(a) => harness::run(a),
        Command::Merge(a) => harness::merge(a),
        Command::Report(a) => harness::report(a),
        Command::Limits(a) => limits::limits(a),
    }
}

/// Ends the process after a failed write to standard output: quietly when the reader closed
/// the pipe (what `head` does), with a message otherwise.
pub(crate) fn stdout_failed(e: std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    eprintln!("error: writing to standard output: {e}");
    std::process::exit(2);
}

#[cfg(test)]
mod tests {
    use super::parse_count;

    #[test]
    fn counts_in_integer_and_exponent_notation() {
        assert_eq!(parse_count("200000000"), Ok(200_000_000));
        assert_eq!(parse_count("200_000_000"), Ok(200_000_000));
        assert_eq!(parse_count("2e8"), Ok(200_000_000));
        assert_eq!(parse_count("1.5E6"), Ok(1_500_000));
        assert_eq!(parse_count("0"), Ok(0));
        for bad in ["", "e8", "1.25e1", "2e", "-3", "1e30", "x", "2e-1"] {
            assert!(parse_count(bad).is_err(), "{bad} accepted");
        }
    }
}

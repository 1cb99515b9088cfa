//! Command-line interface: argument definitions and dispatch. One module per command group.

mod bound;
mod demo;
mod solve;

use clap::{Parser, Subcommand};

/// Sequencing of CNC machining cells.
#[derive(Parser, Debug)]
#[command(name = "cellseq", version, about, long_about = None)]
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
    /// List every solver with its parameters and defaults.
    Solvers,
    /// Generate an instance from a seeded generator.
    Generate(solve::GenerateArgs),
    /// Lower bounds on the optimum of an instance.
    Bound(bound::BoundArgs),
    /// Run the built-in demonstration on a generated instance (no files needed).
    Demo(demo::DemoArgs),
}

/// Runs the parsed command.
pub fn dispatch(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Info(a) => solve::info(a),
        Command::Validate(a) => solve::validate(a),
        Command::Solve(a) => solve::solve(a),
        Command::Eval(a) => solve::eval(a),
        Command::Solvers => solve::solvers(),
        Command::Generate(a) => solve::generate(a),
        Command::Bound(a) => bound::bound(a),
        Command::Demo(a) => demo::demo(a),
    }
}

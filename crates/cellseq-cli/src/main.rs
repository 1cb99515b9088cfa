//! The `cellseq` command-line tool.
//!
//! Each subcommand lives in its own module under `src/cli/`; this file only declares them and
//! turns every error into one line on stderr and a non-zero exit.

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    if let Err(e) = cli::dispatch(args) {
        eprintln!("error: {e:#}");
        std::process::exit(2);
    }
}

//! The `cellseq` command-line tool.
//!
//! Each subcommand lives in its own module under `src/cli/`; this file only declares them and
//! turns every error into one line on stderr and a non-zero exit.

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::try_parse().unwrap_or_else(|e| {
        use clap::error::ErrorKind;
        if matches!(
            e.kind(),
            ErrorKind::ValueValidation | ErrorKind::InvalidValue
        ) {
            // a value out of range: one line naming the flag and the range (clap's own
            // rendering adds a hint about --help below it)
            let text = e.render().to_string();
            eprintln!("{}", text.lines().next().unwrap_or("error: invalid value"));
            std::process::exit(2);
        }
        e.exit()
    });
    if let Err(e) = cli::dispatch(args) {
        eprintln!("error: {e:#}");
        std::process::exit(2);
    }
}

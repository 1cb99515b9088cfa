//! What `optimize` and `verify-gcode` print for programs and drawings alike: the before/after
//! table and the output file.

use anyhow::Context as _;
use cellseq::files::write_atomic;
use std::fmt::Display;
use std::path::Path;

/// A before/after table whose labels are `width` characters wide.
pub(super) struct Table {
    width: usize,
}

/// Percentage saved from `before` to `after` (0 when `before` is 0).
fn saved(before: f64, after: f64) -> f64 {
    if before > 0.0 {
        100.0 * (before - after) / before
    } else {
        0.0
    }
}

impl Table {
    /// Prints the header line.
    pub(super) fn new(width: usize) -> Table {
        say!(
            "{:<width$} {:>14} {:>14} {:>8}",
            "",
            "before",
            "after",
            "saved"
        );
        Table { width }
    }

    /// A row of lengths or times with the share saved.
    pub(super) fn saved(&self, label: &str, before: f64, after: f64) {
        let w = self.width;
        say!(
            "{label:<w$} {before:>14.1} {after:>14.1} {:>7.1}%",
            saved(before, after)
        );
    }

    /// A row of lengths or times, nothing saved to show.
    pub(super) fn values(&self, label: &str, before: f64, after: f64) {
        let w = self.width;
        say!("{label:<w$} {before:>14.1} {after:>14.1}");
    }

    /// A row of counts.
    pub(super) fn counts(&self, label: &str, before: impl Display, after: impl Display) {
        let w = self.width;
        say!("{label:<w$} {before:>14} {after:>14}");
    }
}

/// Writes `text` to `output` (safely, see `cellseq::files::write_atomic`), if one was given.
pub(super) fn write_output(output: Option<&Path>, text: &str) -> anyhow::Result<()> {
    if let Some(o) = output {
        write_atomic(o, text.as_bytes()).with_context(|| format!("writing {}", o.display()))?;
    }
    Ok(())
}

/// The last line of a human-readable report: where the output went, if anywhere.
pub(super) fn say_wrote(output: Option<&Path>) {
    if let Some(o) = output {
        say!("wrote {}", o.display());
    }
}

//! Steps the fuzz targets share.

use cellseq::formats::{self, Format};
use cellseq::{Solve, SolverKind};

/// Parses `data` as an instance file of `format`; when it parses and validates (and has at
/// most 200 cells), solves it with `greedy` under an evaluation budget and panics if that
/// fails: validation must leave nothing a solver fails on.
pub fn parse_validate_solve(data: &[u8], format: Format) {
    let text = String::from_utf8_lossy(data);
    let Ok(inst) = formats::parse_instance("fuzz", &text, format) else {
        return;
    };
    if cellseq::validate::validate(&inst, "fuzz").is_err() || inst.n() > 200 {
        return;
    }
    if let Err(e) = Solve::new(SolverKind::Greedy).max_evals(20_000).run(&inst) {
        panic!("validated instance, but greedy fails: {e}");
    }
}

/// The time limit the pipeline targets give `optimize` (seconds).
pub const LIMIT_S: f64 = 0.5;

/// How far past [`LIMIT_S`] a pipeline target may end (libFuzzer's own `-timeout` is the
/// hang guard; this catches a limit that is not kept).
pub const MARGIN_S: f64 = 2.0;

/// Occurrences of non-finite words (`NaN`, `inf`, `Infinity`) in `text`.
pub fn non_finite(text: &str) -> usize {
    text.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .filter(|w| matches!(*w, "NaN" | "nan" | "inf" | "Inf" | "INF" | "Infinity" | "infinity"))
        .count()
}

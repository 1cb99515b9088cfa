//! Steps the fuzz targets share.

use cellseq::formats::{self, Format};
use cellseq::solvers::{self, Budget, NoObserver};

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
    let budget = Budget {
        time_limit: None,
        max_evals: Some(20_000),
    };
    let obj = inst.default_objective();
    let opts = Default::default();
    if let Err(e) = solvers::run("greedy", &inst, obj, &opts, 1, budget, &mut NoObserver) {
        panic!("validated instance, but greedy fails: {e}");
    }
}

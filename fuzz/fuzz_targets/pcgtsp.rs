//! Fuzzes the PCGTSP reader: parse, validate and, when valid, solve with greedy (validation
//! must leave nothing a solver fails on).
#![no_main]

use cellseq::formats::{self, Format};
use cellseq::solvers::{self, Budget, NoObserver};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(inst) = formats::parse_instance("fuzz", &text, Format::Pcgtsp) else {
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
});

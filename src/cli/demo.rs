//! `demo`: the built-in default job — needs no files.

use anyhow::Result;
use cellseq::solvers::{self, Budget, NoObserver};
use clap::Args;
use std::collections::BTreeMap;

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Seed of the generated instance and of the solvers.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn demo(a: DemoArgs) -> Result<()> {
    let params: BTreeMap<String, String> = [("n", "14"), ("tools", "2"), ("density", "0.05")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let inst = cellseq::generate::generate("uniform", &params, a.seed)?;
    let objective = inst.default_objective();
    println!(
        "instance {} ({} cells), objective {}",
        inst.name,
        inst.n(),
        objective.name()
    );
    println!(
        "{:<12} {:>12} {:>12} {:>6} {:>6}",
        "solver", "time_s", "air_mm", "lifts", "tools"
    );
    for s in solvers::registry() {
        let budget = Budget {
            time_limit: None,
            max_evals: Some(2_000_000),
        };
        match solvers::run(
            s.name,
            &inst,
            objective,
            &BTreeMap::new(),
            a.seed,
            budget,
            &mut NoObserver,
        ) {
            Ok(r) => println!(
                "{:<12} {:>12.3} {:>12.3} {:>6} {:>6}",
                s.name,
                r.report.machining_time,
                r.report.air_length,
                r.report.lifts,
                r.report.tool_changes
            ),
            Err(e) => println!("{:<12} failed: {e}", s.name),
        }
    }
    Ok(())
}

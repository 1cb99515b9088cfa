//! Generate a seeded instance of a machining family, list the registry's solvers, race three
//! of them under the same evaluation budget, and compare with the lower bounds.
//!
//! `cargo run --release -p cellseq --example generate_and_bound`

use cellseq::prelude::*;
use cellseq::{BoundOptions, lower_bounds};
use std::collections::BTreeMap;

fn main() -> Result<()> {
    let params: BTreeMap<String, String> = [("n", "60"), ("tools", "3"), ("density", "0.05")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    let inst = cellseq::generate::generate("uniform", &params, 42)?;
    println!("{}: {} cells", inst.name, inst.n());

    for info in cellseq::registry::all() {
        println!("  {:<13} {}", info.name, info.summary);
    }

    let objective = inst.default_objective();
    for kind in [SolverKind::Greedy, SolverKind::LocalSearch, SolverKind::Ils] {
        let s = Solve::new(kind).max_evals(500_000).run(&inst)?;
        println!("{:<13} {:.3} s machining time", kind.name(), s.cost());
    }
    let bounds = lower_bounds(&inst, objective, &BoundOptions::default())?;
    for b in &bounds.parts {
        println!("bound {:<12} {:.3} ({:.3} s)", b.name, b.value, b.seconds);
    }
    println!("best lower bound {:.3} ({})", bounds.best, bounds.best_name);
    Ok(())
}

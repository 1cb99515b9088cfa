//! Solve an instance file and save the verified solution.
//!
//! `cargo run --release -p cellseq --example solve_file -- instances/tsplib-sop/ESC07.sop [SECONDS]`
//!
//! Reads a TSPLIB SOP, PCGLNS, PCGTSP or cellseq JSON instance, runs the default solver
//! (`auto`) for the given seconds (default 2), computes a lower bound, prints the independent
//! checker's figures and writes `solution.json` beside the working directory.

use cellseq::prelude::*;
use std::path::Path;

fn main() -> Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file = args
        .first()
        .map(String::as_str)
        .unwrap_or("instances/tsplib-sop/ESC07.sop");
    let seconds: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(2.0);

    let inst = cellseq::load(Path::new(file))?;
    let solved = Solve::new(SolverKind::Auto)
        .budget(Budget::seconds(seconds)?)
        .seed(1)
        .lower_bound(true)
        .run(&inst)?;

    println!("{}: {} cells", inst.name, inst.n());
    println!("cost          {}", solved.cost());
    println!("lower bound   {:?}", solved.lower_bound);
    println!("certified gap {:?} %", solved.certified_gap_percent());
    println!("proven        {}", solved.proven_optimal);
    solved.save(&inst, Path::new("solution.json"))?;
    println!("wrote solution.json");
    Ok(())
}

//! Build an instance in memory from a cost matrix and precedence pairs, solve it exactly and
//! with a heuristic under an evaluation budget, and check both independently.
//!
//! `cargo run --release -p cellseq --example from_matrix`

use cellseq::prelude::*;

fn main() -> Result<()> {
    // 8 cells on a line: cutting cell j after cell i costs |i - j| plus 1 when going left
    let n = 8;
    let mut costs = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let d = (i as f64 - j as f64).abs();
            costs[i * n + j] = if j < i { d + 1.0 } else { d };
        }
    }
    // rough before finish: cell 6 before cell 1, cell 7 before cell 2
    let inst = Instance::from_matrix("line", n, costs, &[(6, 1), (7, 2)])?;

    let exact = Solve::new(SolverKind::Exact)
        .max_evals(10_000_000)
        .run(&inst)?;
    let ils = Solve::new(SolverKind::Ils)
        .param("k", 6)
        .max_evals(200_000)
        .seed(7)
        .run(&inst)?;
    for s in [&exact, &ils] {
        // the checker recomputes everything from the instance; it shares no code with the
        // solvers' cost model
        let report = cellseq::check(&inst, &s.sequence, s.objective).expect("feasible");
        let order: Vec<usize> = s.sequence.iter().map(|v| v.cell).collect();
        println!(
            "{:<6} cost {} (checker {}), proven optimal: {}, order {order:?}",
            s.solver.name(),
            s.cost(),
            report.cost,
            s.proven_optimal
        );
    }
    assert!(ils.cost() >= exact.cost());
    Ok(())
}

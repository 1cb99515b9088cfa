//! Scale probe: generate a `uniform` instance of N cells in memory and time a solver on it,
//! printing wall time, air length and peak resident memory.
//!
//! `cargo run --release --example scale -- 1000000 greedy [KEY=VALUE...]`
//!
//! `KEY=VALUE` arguments are solver parameters, except `gen.KEY=VALUE` (generator parameters,
//! e.g. `gen.preds=1`), `seconds=S` (wall-clock budget; default none), `evals=E` (evaluation
//! budget) and `csv=PATH` (append one
//! row `n,preds,solver,params,seconds,air,greedy_air,elapsed_s,solver_s,peak_rss_mib,lift` to PATH,
//! with a header if the file is new; `greedy_air` is the greedy air length measured in the same
//! process after the solver, so the peak memory is the solver's).

use cellseq::{Budget, Objective, Solve, SolverKind};
use std::collections::BTreeMap;
use std::time::Instant;

fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map(|kb| kb / 1024.0)
        .unwrap_or(f64::NAN)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args
        .first()
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(100_000);
    let solver = args.get(1).cloned().unwrap_or_else(|| "greedy".into());
    let mut gp: BTreeMap<String, String> = BTreeMap::new();
    gp.insert("n".into(), n.to_string());
    let mut sp = BTreeMap::new();
    let mut csv: Option<String> = None;
    let mut budget = Budget::default();
    for kv in &args[2.min(args.len())..] {
        if let Some((k, v)) = kv.split_once('=') {
            if k == "csv" {
                csv = Some(v.to_string());
            } else if k == "evals" {
                budget.max_evals = Some(v.parse()?);
            } else if k == "seconds" {
                budget.time_limit = Budget::seconds(v.parse()?)?.time_limit;
            } else if let Some(g) = k.strip_prefix("gen.") {
                gp.insert(g.into(), v.into());
            } else {
                sp.insert(k.to_string(), v.to_string());
            }
        }
    }
    let t = Instant::now();
    let inst = cellseq::generate::generate("uniform", &gp, 1)?;
    println!(
        "generated {} cells in {:.2} s",
        inst.n(),
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let r = Solve::new(solver.parse()?)
        .params_text(&sp)
        .budget(budget)
        .objective(Objective::Air)
        .run(&inst)?;
    let elapsed = t.elapsed().as_secs_f64();
    let peak = peak_rss_mib();
    println!(
        "{solver}: air {:.0} mm in {:.2} s (solver {:.2} s incl. check, {} evaluations), peak RSS {:.0} MiB",
        r.report.air_length, elapsed, r.elapsed_s, r.evaluations, peak
    );
    if let Some(path) = csv {
        let greedy_air = if solver == "greedy" {
            r.report.air_length
        } else {
            Solve::new(SolverKind::Greedy)
                .objective(Objective::Air)
                .run(&inst)?
                .report
                .air_length
        };
        let params: Vec<String> = sp.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let new = !std::path::Path::new(&path).exists();
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)?;
        use std::io::Write;
        if new {
            writeln!(
                f,
                "n,preds,solver,params,seconds,air,greedy_air,elapsed_s,solver_s,peak_rss_mib,lift"
            )?;
        }
        writeln!(
            f,
            "{},{},{},{},{},{:.3},{:.3},{:.3},{:.3},{:.1},{}",
            inst.n(),
            gp.get("preds").map(String::as_str).unwrap_or("0"),
            solver,
            params.join(";"),
            budget
                .time_limit
                .map(|d| d.as_secs_f64().to_string())
                .unwrap_or_default(),
            r.report.air_length,
            greedy_air,
            elapsed,
            r.elapsed_s,
            peak,
            gp.get("lift").map(String::as_str).unwrap_or("7"),
        )?;
    }
    Ok(())
}

//! Scale probe: generate a `uniform` instance of N cells in memory and time a solver on it,
//! printing wall time, air length and peak resident memory.
//!
//! `cargo run --release --example scale -- 1000000 greedy [KEY=VALUE...]`

use cellseq::model::Objective;
use cellseq::solvers::{self, Budget, NoObserver};
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
    for kv in &args[2.min(args.len())..] {
        if let Some((k, v)) = kv.split_once('=') {
            if let Some(g) = k.strip_prefix("gen.") {
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
    let r = solvers::run(
        &solver,
        &inst,
        Objective::Air,
        &sp,
        1,
        Budget::default(),
        &mut NoObserver,
    )?;
    println!(
        "{solver}: air {:.0} mm in {:.2} s (solver {:.2} s incl. check), peak RSS {:.0} MiB",
        r.report.air_length,
        t.elapsed().as_secs_f64(),
        r.elapsed_s,
        peak_rss_mib()
    );
    Ok(())
}

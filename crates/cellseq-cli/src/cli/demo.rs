//! `demo`: the built-in campaign — needs no files. Runs the plan embedded from
//! `experiments/demo.toml` and writes results, report and plots into `results/demo/`.

use anyhow::Result;
use cellseq_lab::plan::Plan;
use cellseq_lab::run::RunOptions;
use cellseq_lab::{DEMO_PLAN, report};
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, default_value = "results/demo")]
    out: PathBuf,
    /// Worker threads (default: all cores).
    #[arg(long, value_parser = super::ranges::threads)]
    threads: Option<usize>,
}

pub fn demo(a: DemoArgs) -> Result<()> {
    let plan = Plan::parse(
        "experiments/demo.toml (built in)",
        DEMO_PLAN,
        Path::new("."),
    )?;
    say!(
        "demo campaign: {} instances x {} solvers x {} replicates ({} trials, evaluation budget {})",
        plan.instances.len(),
        plan.solvers.len(),
        plan.file.replicates,
        plan.trial_count(),
        plan.file.budget.label()
    );
    let opts = RunOptions {
        threads: a.threads,
        shard: None,
        out: a.out.clone(),
        progress: true,
        throttle_ms: 0,
        replace_foreign: true,
    };
    super::harness::execute(&plan, &opts)?;
    let r = report::report(&a.out, &a.out.join("report"))?;
    say!("report    {}", r.markdown.display());
    say!("plots     {}", a.out.join("report").join("plots").display());
    Ok(())
}

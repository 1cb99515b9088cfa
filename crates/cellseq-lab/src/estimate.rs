//! How long a plan takes, for `cellseq check --shards N --threads C` and the `--time` of a
//! cluster job: under a time budget (`seconds`, or `calibration_units` times this machine's
//! calibration kernel) every trial stops at its budget, so a shard of `t` trials on `c` threads
//! needs about `⌈t / c⌉` budgets. Under an evaluation budget the wall time depends on the machine
//! and the solver, and no number is invented: the estimate says to time one shard first.

use super::plan::Plan;
use cellseq::error::Result;

/// A plan's size and, under time budgets, its duration per shard.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Trials of the whole plan.
    pub trials: usize,
    /// Shards.
    pub shards: usize,
    /// Threads per shard.
    pub threads: usize,
    /// Trials of the largest shard (shards take every N-th trial).
    pub per_shard: usize,
    /// Seconds one trial may run (`None` under an evaluation budget alone).
    pub trial_seconds: Option<f64>,
}

impl Estimate {
    /// Wall seconds of the largest shard when every trial uses its whole budget.
    pub fn shard_seconds(&self) -> Option<f64> {
        self.trial_seconds
            .map(|s| self.per_shard.div_ceil(self.threads.max(1)) as f64 * s)
    }
}

/// The estimate for `shards` shards of `threads` threads; `calibration` gives the seconds of
/// the calibration kernel (called only for `calibration_units` budgets).
pub fn estimate(
    plan: &Plan,
    shards: usize,
    threads: usize,
    calibration: impl FnOnce() -> Result<f64>,
) -> Result<Estimate> {
    let trials = usize::try_from(plan.trial_count()).unwrap_or(usize::MAX);
    let shards = shards.max(1);
    let b = &plan.file.budget;
    let calib = match b.calibration_units {
        Some(_) => calibration()?,
        None => 0.0,
    };
    let limit =
        super::plan::trial_seconds(b, calib).map_err(|e| cellseq::Error::invalid(&plan.path, e))?;
    Ok(Estimate {
        trials,
        shards,
        threads: threads.max(1),
        per_shard: trials.div_ceil(shards),
        trial_seconds: limit,
    })
}

/// A year in seconds (365.25 days).
const YEAR_S: f64 = 365.25 * 86400.0;

/// Above this many seconds per shard the estimate gives years and no SLURM time: a year.
const LONGEST_SHARD_S: f64 = YEAR_S;

/// A SLURM `--time` (`D-HH:MM:SS` or `HH:MM:SS`) with room to spare: 1.5 × `seconds` plus
/// 5 minutes for loading instances, checking the plan and writing results.
pub fn slurm_time(seconds: f64) -> String {
    let total = (seconds.max(0.0) * 1.5 + 300.0).ceil() as u64;
    let (d, h, m, s) = (
        total / 86400,
        total % 86400 / 3600,
        total % 3600 / 60,
        total % 60,
    );
    if d > 0 {
        format!("{d}-{h:02}:{m:02}:{s:02}")
    } else {
        format!("{h:02}:{m:02}:{s:02}")
    }
}

impl std::fmt::Display for Estimate {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "estimate: {} shard(s) of at most {} trial(s) on {} thread(s) each",
            self.shards, self.per_shard, self.threads
        )?;
        match self.shard_seconds() {
            Some(s) if s > LONGEST_SHARD_S => write!(
                f,
                "; each trial stops at its budget of {:.3} s, so a shard needs up to about {:.0} \
                 years: more than a year, so split the plan into more shards, or shorten the \
                 budget",
                self.trial_seconds.unwrap_or(0.0),
                s / YEAR_S
            ),
            Some(s) => write!(
                f,
                "; each trial stops at its budget of {:.3} s, so a shard needs at most about \
                 {:.0} s; suggested time per shard (x1.5 + 5 min): {}",
                self.trial_seconds.unwrap_or(0.0),
                s,
                slurm_time(s)
            ),
            None => write!(
                f,
                "; under an evaluation budget the wall time depends on the machine: time one \
                 shard first (`cellseq run PLAN --shard 1/{} --threads {}`) and give the others \
                 1.5 times that",
                self.shards, self.threads
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const PLAN: &str = r#"
name = "e"
replicates = 2
[budget]
seconds = 10
[[instances]]
generator = "uniform"
seeds = [1, 2, 3]
grid = { n = 10 }
[[solvers]]
name = "greedy"
[[solvers]]
name = "ils"
"#;

    #[test]
    fn time_budgets_give_a_time_per_shard() {
        let plan = Plan::parse("p.toml", PLAN, std::path::Path::new(".")).unwrap();
        // 3 instances x 2 solvers x 2 replicates = 12 trials; 5 shards -> at most 3 each
        let e = estimate(&plan, 5, 2, || unreachable!()).unwrap();
        assert_eq!((e.trials, e.per_shard), (12, 3));
        assert_eq!(e.shard_seconds(), Some(20.0));
        assert!(e.to_string().contains("00:05:30"), "{e}");
        let evals = PLAN.replace("seconds = 10", "evaluations = 1000");
        let plan = Plan::parse("p.toml", &evals, std::path::Path::new(".")).unwrap();
        let e = estimate(&plan, 1, 1, || unreachable!()).unwrap();
        assert_eq!(e.shard_seconds(), None);
        assert!(e.to_string().contains("time one shard first"), "{e}");
        let calib = PLAN.replace("seconds = 10", "calibration_units = 100");
        let plan = Plan::parse("p.toml", &calib, std::path::Path::new(".")).unwrap();
        let e = estimate(&plan, 12, 1, || Ok(0.02)).unwrap();
        assert_eq!(e.shard_seconds(), Some(2.0));
    }

    #[test]
    fn shards_longer_than_a_year_are_told_in_years() {
        let long = PLAN
            .replace("seconds = 10", "seconds = 1e6")
            .replace("replicates = 2", "replicates = 200");
        let plan = Plan::parse("p.toml", &long, std::path::Path::new(".")).unwrap();
        let e = estimate(&plan, 1, 1, || unreachable!()).unwrap();
        let text = e.to_string();
        assert!(
            text.contains("years") && !text.contains("suggested"),
            "{text}"
        );
        // 1200 trials of 10^6 s on one thread: 1.2e9 s, about 38 years
        assert!(text.contains("about 38 years"), "{text}");
    }

    #[test]
    fn calibration_units_that_overflow_a_clock_are_refused() {
        let calib = PLAN.replace("seconds = 10", "calibration_units = 1e9");
        let plan = Plan::parse("p.toml", &calib, std::path::Path::new(".")).unwrap();
        let e = estimate(&plan, 1, 1, || Ok(0.02)).unwrap_err().to_string();
        assert!(
            e.starts_with("p.toml") && e.contains("calibration_units"),
            "{e}"
        );
    }

    #[test]
    fn slurm_times() {
        assert_eq!(slurm_time(0.0), "00:05:00");
        assert_eq!(slurm_time(3600.0), "01:35:00");
        assert_eq!(slurm_time(86400.0), "1-12:05:00");
    }
}

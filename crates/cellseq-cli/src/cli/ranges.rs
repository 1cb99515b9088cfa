//! Every number the command line takes: the flag, the commands that take it, the range it
//! must lie in and why. Each flag's clap value parser checks its range, so a value out of
//! range (`--time-limit 1e300`, `--margin nan`, `--threads 1000000`) is refused with the
//! flag's name and exit status 2 before any file is read. `cellseq limits` prints this table
//! with every other range (plan keys, solver and generator parameters, file values); the
//! section of `docs/bad-input.md` between its markers is that output.

use cellseq::params::{FloatRange, IntRange, float_text};

/// The values a flag accepts.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Range {
    /// A whole number (also in exponent notation, `2e8`).
    Int(IntRange),
    /// A finite number.
    Float(FloatRange),
}

impl std::fmt::Display for Range {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Range::Int(r) => write!(f, "int {r}"),
            Range::Float(r) => write!(f, "float {r}"),
        }
    }
}

/// One numeric flag.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Flag {
    /// The flag, `--time-limit`.
    pub name: &'static str,
    /// The commands that take it.
    pub commands: &'static str,
    /// What it accepts.
    pub range: Range,
    /// Its unit and why the range is what it is.
    pub why: &'static str,
}

impl Flag {
    /// A float flag's value from text, checked against its range.
    fn float(&self, s: &str) -> Result<f64, String> {
        let Range::Float(r) = self.range else {
            return Err(format!("{} takes a whole number", self.name));
        };
        let x: f64 = s
            .trim()
            .parse()
            .map_err(|_| format!("'{s}' is not a number; {}", self.wants()))?;
        if r.contains(x) {
            Ok(x)
        } else {
            Err(format!("got {}; {}", float_text(x), self.wants()))
        }
    }

    /// A whole-number flag's value from text (`200000000`, `2e8`), checked against its range.
    fn int(&self, s: &str) -> Result<u64, String> {
        let Range::Int(r) = self.range else {
            return Err(format!("{} takes a number", self.name));
        };
        let v = super::parse_count(s).map_err(|e| format!("{e}; {}", self.wants()))?;
        if r.contains(v) {
            Ok(v)
        } else {
            Err(format!("got {v}; {}", self.wants()))
        }
    }

    /// "it must lie in …" with the range and the reason.
    fn wants(&self) -> String {
        let what = match self.range {
            Range::Int(_) => "a whole number",
            Range::Float(_) => "a finite number",
        };
        let range = match self.range {
            Range::Int(r) => r.to_string(),
            Range::Float(r) => r.to_string(),
        };
        format!("{} must be {what} in {range} ({})", self.name, self.why)
    }
}

/// Declares the flags: a constant for each (its table entry), a clap value parser for each
/// that checks the range, and [`FLAGS`], the list `cellseq limits` prints.
macro_rules! flags {
    ($($konst:ident, $parse:ident -> $ty:ident = $flag:expr;)*) => {
        $(
            #[doc = concat!("The table entry of `", stringify!($parse), "`.")]
            pub(crate) const $konst: Flag = $flag;
            #[doc = concat!("Parses and range-checks the value of `", stringify!($konst), "`.")]
            pub(crate) fn $parse(s: &str) -> Result<$ty, String> {
                flags!(@get $ty, $konst, s)
            }
        )*
        /// Every numeric flag, in the order of `cellseq limits`.
        pub(crate) static FLAGS: &[Flag] = &[$($konst),*];
    };
    (@get f64, $k:ident, $s:ident) => { $k.float($s) };
    (@get u64, $k:ident, $s:ident) => { $k.int($s) };
    (@get usize, $k:ident, $s:ident) => {
        $k.int($s).and_then(|v| usize::try_from(v).map_err(|e| e.to_string()))
    };
}

const fn secs() -> Range {
    Range::Float(FloatRange::above(0.0, cellseq::solve::MAX_SECONDS))
}

const fn mm(min: f64, max: f64) -> Range {
    Range::Float(FloatRange::closed(min, max))
}

flags! {
    TIME_LIMIT, time_limit -> f64 = Flag {
        name: "--time-limit",
        commands: "solve, optimize",
        range: secs(),
        why: "seconds; longer limits (over 11 days) are refused rather than overflowing a clock",
    };
    MAX_EVALS, max_evals -> u64 = Flag {
        name: "--max-evals",
        commands: "solve, optimize",
        range: Range::Int(IntRange::new(1, u64::MAX)),
        why: "evaluations; `2e8` is accepted",
    };
    THREADS, threads -> usize = Flag {
        name: "--threads",
        commands: "run, demo, check",
        range: Range::Int(IntRange::new(1, cellseq_lab::run::MAX_THREADS as u64)),
        why: "worker threads; each holds a solver's memory, and more threads than cores only add memory",
    };
    SHARDS, shards -> usize = Flag {
        name: "--shards",
        commands: "check",
        range: Range::Int(cellseq_lab::plan::MAX_TRIALS),
        why: "shards of the plan, for the estimate; at most one trial each",
    };
    MAX_TRIALS, max_trials -> u64 = Flag {
        name: "--max-trials",
        commands: "check, run",
        range: Range::Int(cellseq_lab::plan::MAX_TRIALS),
        why: "trials a plan may have; the trials are listed in memory (about 0.6 KB each)",
    };
    MAX_FILES, max_files -> u64 = Flag {
        name: "--max-files",
        commands: "check, run",
        range: Range::Int(cellseq_lab::plan::MAX_FILES),
        why: "directory entries one file pattern may visit",
    };
    ITERATIONS, iterations -> usize = Flag {
        name: "--iterations",
        commands: "bound",
        range: Range::Int(IntRange::new(0, 1_000_000)),
        why: "subgradient steps of the Lagrangian bound, each O(n^2); 0 skips it",
    };
    MARGIN, margin -> f64 = Flag {
        name: "--margin",
        commands: "optimize, import",
        range: mm(0.0, 1e4),
        why: "mm added to cell footprints for the overlap rule",
    };
    TOLERANCE, tolerance -> f64 = Flag {
        name: "--tolerance",
        commands: "optimize, import (SVG, DXF)",
        range: mm(1e-6, 1e3),
        why: "mm of curve flattening; finer tolerances only add points (capped by --max-points)",
    };
    CONTAIN_TOL, contain_tol -> f64 = Flag {
        name: "--contain-tol",
        commands: "optimize, import (SVG, DXF)",
        range: mm(0.0, 1e3),
        why: "mm of slack in cut mode's containment test",
    };
    MAX_STARTS, max_starts -> usize = Flag {
        name: "--max-starts",
        commands: "optimize, import (SVG, DXF)",
        range: Range::Int(IntRange::new(1, 256)),
        why: "start vertices per closed stroke; each is a mode of the stroke's cell",
    };
    MAX_POINTS, max_points -> usize = Flag {
        name: "--max-points",
        commands: "optimize, import (SVG, DXF)",
        range: Range::Int(IntRange::new(1, 1_000_000_000)),
        why: "points after flattening; 10^9 points take about 32 GB",
    };
    JOIN_TOL, join_tol -> f64 = Flag {
        name: "--join-tol",
        commands: "optimize, import (DXF)",
        range: mm(0.0, 1e3),
        why: "mm between endpoints chained into one contour",
    };
    SAFE_HEIGHT, safe_height -> f64 = Flag {
        name: "--safe-height",
        commands: "optimize (DXF to G-code)",
        range: Range::Float(FloatRange::above(0.0, 1e5)),
        why: "mm above Z0 for rapid moves",
    };
    CUT_DEPTH, cut_depth -> f64 = Flag {
        name: "--cut-depth",
        commands: "optimize (DXF to G-code)",
        range: mm(0.0, 1e5),
        why: "mm below Z0",
    };
    FEED, feed -> f64 = Flag {
        name: "--feed",
        commands: "optimize (DXF to G-code)",
        range: mm(cellseq::validate::MIN_FEED, 1e6),
        why: "mm/min; the instance limits' least feed up to 1 km/min",
    };
    PLUNGE_FEED, plunge_feed -> f64 = Flag {
        name: "--plunge-feed",
        commands: "optimize (DXF to G-code)",
        range: mm(cellseq::validate::MIN_FEED, 1e6),
        why: "mm/min",
    };
    SPINDLE, spindle -> f64 = Flag {
        name: "--spindle",
        commands: "optimize (DXF to G-code)",
        range: mm(0.0, 1e6),
        why: "rev/min; 0 writes no spindle words",
    };
    LASER_POWER, laser_power -> f64 = Flag {
        name: "--laser-power",
        commands: "optimize (DXF to G-code)",
        range: mm(0.0, 1e6),
        why: "the S word of a laser; 0 means no laser",
    };
    THROTTLE_MS, throttle_ms -> u64 = Flag {
        name: "--throttle-ms",
        commands: "run (hidden testing hook)",
        range: Range::Int(IntRange::new(0, 60_000)),
        why: "milliseconds slept after each trial",
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flags_refuse_what_lies_outside_their_range_by_name() {
        assert_eq!(time_limit("2.5"), Ok(2.5));
        for bad in ["0", "-1", "1e300", "nan", "inf", "x", ""] {
            let e = time_limit(bad).unwrap_err();
            assert!(
                e.contains("--time-limit must be a finite number in (0, 1e6]"),
                "{e}"
            );
        }
        assert_eq!(threads("4"), Ok(4));
        assert!(threads("0").is_err() && threads("1000000").is_err());
        assert!(margin("nan").unwrap_err().contains("--margin"));
        assert_eq!(max_evals("2e8"), Ok(200_000_000));
        assert!(max_evals("0").is_err());
        assert!(join_tol("inf").is_err() && join_tol("0").is_ok());
    }

    #[test]
    fn every_flag_has_a_sane_range() {
        for f in FLAGS {
            assert!(f.name.starts_with("--") && !f.why.is_empty(), "{f:?}");
            match f.range {
                Range::Int(r) => assert!(r.min <= r.max, "{f:?}"),
                Range::Float(r) => assert!(r.min.is_finite() && r.min < r.max, "{f:?}"),
            }
        }
    }
}

//! Running a command on a hostile input and classifying how it ended: a clean result, a
//! clean refusal naming the file, a refusal naming no input, a crash (panic, abort, signal,
//! an exit status other than 0 or 2), a hang (killed at the cap), overtime (past its
//! `--time-limit` plus [`OVERTIME_MARGIN_S`]) or a non-finite number (`NaN`, `inf`) in its
//! output that its input did not hold.

use super::cases::{Case, Kind};
use crate::common::BIN;
use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How far past its `--time-limit` a command may end (reading, the bound after `solve`,
/// writing, a loaded machine) before it counts as overtime: 10 s.
pub const OVERTIME_MARGIN_S: f64 = 10.0;

/// A command without a time limit is killed (a hang) after this long; one with a limit after
/// the limit plus this.
pub const HANG_CAP_S: f64 = 40.0;

/// Address space each child may use (`ulimit -v`, KiB): 4 GiB, so an unbounded allocation
/// ends in an abort (a crash) instead of taking the machine down.
pub const MEMORY_KIB: u64 = 4 << 20;

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Class {
    /// Exit 0.
    Result,
    /// Exit 2 with a message naming one of the command's input files.
    Refusal,
    /// Exit 2 with a message naming none of its inputs.
    Anonymous,
    /// A panic, an abort, a signal or another exit status.
    Crash,
    /// Killed at the cap.
    Hang,
    /// Ended past its time limit plus the margin.
    Overtime,
    /// Printed or wrote `NaN` or `inf` its input did not hold.
    NonFinite,
}

impl Class {
    /// Every class, in table order.
    pub const ALL: [Class; 7] = [
        Class::Result,
        Class::Refusal,
        Class::Anonymous,
        Class::Crash,
        Class::Hang,
        Class::Overtime,
        Class::NonFinite,
    ];

    /// True for the classes the suite allows.
    pub fn clean(self) -> bool {
        matches!(self, Class::Result | Class::Refusal)
    }
}

/// One command line to run in a case's directory.
#[derive(Debug, Clone)]
pub struct Cmd {
    /// The command's name (`solve`, `optimize`, …).
    pub label: &'static str,
    /// Its arguments.
    pub args: Vec<String>,
    /// The time limit it promises to keep, if any.
    pub limit: Option<f64>,
    /// Files it writes (checked for non-finite numbers).
    pub outputs: Vec<String>,
    /// Names of its input files (a refusal must name one).
    pub inputs: Vec<String>,
}

fn cmd(label: &'static str, args: &[&str], limit: Option<f64>, inputs: &[&str]) -> Cmd {
    let outputs = args
        .iter()
        .filter(|a| a.starts_with("out"))
        .map(|a| a.to_string())
        .collect();
    Cmd {
        label,
        args: args.iter().map(|a| a.to_string()).collect(),
        limit,
        outputs,
        inputs: inputs.iter().map(|a| a.to_string()).collect(),
    }
}

/// The commands that read a case's file (its name `f`), with their arguments.
pub fn commands(case: &Case) -> Vec<Cmd> {
    let f = case.name.as_str();
    match case.kind {
        Kind::Sop | Kind::Pcglns | Kind::Pcgtsp | Kind::Json => vec![
            cmd("validate", &["validate", f], None, &[f]),
            cmd(
                "solve",
                &[
                    "solve",
                    f,
                    "--time-limit",
                    "1",
                    "--json",
                    "--out",
                    "out.json",
                ],
                Some(1.0),
                &[f],
            ),
            cmd("bound", &["bound", f, "--iterations", "50"], None, &[f]),
            cmd("eval", &["eval", f, "sol.json"], None, &[f, "sol.json"]),
            cmd("plot", &["plot", f, "-o", "out.svg"], None, &[f]),
        ],
        Kind::Solution => vec![
            cmd(
                "eval",
                &["eval", "panel-20.json", f],
                None,
                &[f, "panel-20.json"],
            ),
            cmd(
                "plot",
                &["plot", "panel-20.json", "--solution", f, "-o", "out.svg"],
                None,
                &[f, "panel-20.json"],
            ),
        ],
        Kind::Plan => vec![
            cmd("check", &["check", f, "--threads", "1"], None, &[f]),
            cmd(
                "run",
                &["run", f, "--threads", "1", "--out", "outdir"],
                None,
                &[f],
            ),
        ],
        Kind::Portfolio => vec![
            cmd("check", &["check", f], None, &[f]),
            cmd(
                "solve",
                &["solve", "ESC07.sop", "--portfolio", f, "--time-limit", "1"],
                Some(1.0),
                &[f],
            ),
        ],
        Kind::Gcode | Kind::Svg | Kind::Dxf => {
            let out = if case.kind == Kind::Svg {
                "out.svg"
            } else {
                "out.ngc"
            };
            vec![
                cmd(
                    "optimize",
                    &["optimize", f, "--time-limit", "2", "-o", out],
                    Some(2.0),
                    &[f],
                ),
                cmd("import", &["import", f, "-o", "out.json"], None, &[f]),
                cmd("plot", &["plot", f, "-o", "out.svg"], None, &[f]),
            ]
        }
        Kind::Tools => vec![cmd(
            "generate",
            &[
                "generate",
                "panel",
                "--param",
                &format!("tools={f}"),
                "-o",
                "out.json",
            ],
            None,
            &[f],
        )],
        Kind::Bks => vec![
            cmd(
                "solve",
                &["solve", "ESC07.sop", "--max-evals", "20000", "--json"],
                None,
                &[f],
            ),
            cmd("info", &["info", "ESC07.sop"], None, &[f]),
            cmd("eval", &["eval", "ESC07.sop", "sol.json"], None, &[f]),
        ],
    }
}

/// What one run did.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Its class.
    pub class: Class,
    /// Wall seconds.
    pub wall: f64,
    /// Exit status (none when killed by a signal).
    pub code: Option<i32>,
    /// The end of its standard error.
    pub stderr: String,
}

/// Occurrences of non-finite values (`NaN`, `inf`, `-Infinity`, …) in `text`: tokens between
/// white space and punctuation that are such a value on their own, so that text which merely
/// contains the letters (a tool id `EM+inf` echoed from the input) is not counted.
pub fn non_finite(text: &[u8]) -> usize {
    String::from_utf8_lossy(text)
        .split(|c: char| c.is_whitespace() || "\"',:;=()[]{}<>%/|".contains(c))
        .filter(|w| {
            let w = w.trim_start_matches(['+', '-']);
            matches!(
                w,
                "NaN" | "nan" | "NAN" | "inf" | "Inf" | "INF" | "Infinity" | "infinity"
            )
        })
        .count()
}

/// Runs `c` in `dir` under the memory limit and the hang cap; `input` is the case's bytes
/// (non-finite words it holds are not counted against the output).
pub fn run(dir: &Path, c: &Cmd, input: &[u8]) -> Outcome {
    let out_path = dir.join(format!(".{}.stdout", c.label));
    let err_path = dir.join(format!(".{}.stderr", c.label));
    let stdout = std::fs::File::create(&out_path).unwrap();
    let stderr = std::fs::File::create(&err_path).unwrap();
    let t0 = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {MEMORY_KIB} 2>/dev/null; exec \"$0\" \"$@\""
        ))
        .arg(BIN)
        .args(&c.args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .expect("spawn cellseq");
    let cap = c.limit.map_or(HANG_CAP_S, |l| l + HANG_CAP_S);
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break Some(s);
        }
        if t0.elapsed().as_secs_f64() > cap {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let wall = t0.elapsed().as_secs_f64();
    let err = std::fs::read(&err_path).unwrap_or_default();
    let out = std::fs::read(&out_path).unwrap_or_default();
    let err_text = String::from_utf8_lossy(&err).into_owned();
    let tail: String = {
        let chars: Vec<char> = err_text.chars().collect();
        chars[chars.len().saturating_sub(600)..].iter().collect()
    };
    let code = status.and_then(|s| s.code());
    let class = classify(dir, c, input, status, wall, &out, &err_text);
    Outcome {
        class,
        wall,
        code,
        stderr: tail,
    }
}

fn classify(
    dir: &Path,
    c: &Cmd,
    input: &[u8],
    status: Option<std::process::ExitStatus>,
    wall: f64,
    out: &[u8],
    err: &str,
) -> Class {
    let Some(status) = status else {
        return Class::Hang;
    };
    let crashed = status.signal().is_some()
        || !matches!(status.code(), Some(0) | Some(2))
        || err.contains("panicked")
        || err.contains("memory allocation of")
        || err.contains("stack overflow");
    if crashed {
        return Class::Crash;
    }
    if c.limit.is_some_and(|l| wall > l + OVERTIME_MARGIN_S) {
        return Class::Overtime;
    }
    let held = non_finite(input);
    let written = c
        .outputs
        .iter()
        .map(|o| output_bytes(&dir.join(o)))
        .any(|b| non_finite(&b) > held);
    if non_finite(out) > held || written {
        return Class::NonFinite;
    }
    if status.code() == Some(0) {
        return Class::Result;
    }
    if c.inputs.iter().any(|f| err.contains(f.as_str())) {
        Class::Refusal
    } else {
        Class::Anonymous
    }
}

/// The bytes of an output file, or of every table in an output directory.
fn output_bytes(p: &Path) -> Vec<u8> {
    if p.is_dir() {
        let mut all = Vec::new();
        for e in std::fs::read_dir(p).into_iter().flatten().flatten() {
            let q: PathBuf = e.path();
            if q.extension().is_some_and(|x| x == "csv") {
                all.extend(std::fs::read(q).unwrap_or_default());
            }
        }
        all
    } else {
        std::fs::read(p).unwrap_or_default()
    }
}

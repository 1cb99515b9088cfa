//! The hostile suite (issue 50): seeded hostile inputs ([`cases`]) run through every command
//! that reads files — validate, solve, bound, eval, check, run, optimize, import, plot (and
//! generate with a tool library, info with a `bks.csv`) — each run classified ([`exec`]):
//! a clean result, a clean refusal naming the file, a refusal naming no input, a crash, a
//! hang, overtime, or NaN/inf in the output. Only the first two are allowed.
//!
//! CI runs a seeded sample ([`CI_CASES`] cases, about 2.5 runs each) two at a time. A larger
//! local campaign: `scripts/hostile.sh --full` (or `CELLSEQ_HOSTILE=full`, with
//! `CELLSEQ_HOSTILE_CASES=N`, `CELLSEQ_HOSTILE_SEED=S`, `CELLSEQ_HOSTILE_JOBS=J`). Every run
//! that is not clean leaves its case directory (the input, the command, its stderr) under
//! `$CARGO_TARGET_TMPDIR/hostile/`; clean ones are removed.

mod cases;
mod exec;

use crate::common::{BIN, root};
use cases::{Case, Kind};
use exec::{Class, Cmd, Outcome};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Cases in the CI sample.
const CI_CASES: usize = 120;
/// Cases of `--full`.
const FULL_CASES: usize = 1500;
/// The seed of the CI sample.
const SEED: u64 = 50;

/// An environment number, or `default`.
fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// A valid solution of `instance` (the seed of solution cases and of `eval`'s second file).
fn solution_of(instance: &Path, dir: &Path) -> Vec<u8> {
    let out = dir.join("solution-of-seed.json");
    let o = std::process::Command::new(BIN)
        .args(["solve", instance.to_str().unwrap(), "--max-evals", "2000"])
        .args([
            "--no-bound",
            "--overwrite-input",
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(&out).unwrap()
}

/// Writes a case into `dir`: its file (or special file) and the files its commands read
/// beside it.
fn lay_out(case: &Case, dir: &Path, sols: &BTreeMap<String, Vec<u8>>, seed: &str) {
    std::fs::create_dir_all(dir).unwrap();
    let f = dir.join(&case.name);
    match case.special {
        Some("zero") => std::os::unix::fs::symlink("/dev/zero", &f).unwrap(),
        Some(_) => std::fs::create_dir(&f).unwrap(),
        None => std::fs::write(&f, &case.bytes).unwrap(),
    }
    let copy = |rel: &str, name: &str| {
        std::fs::copy(root().join(rel), dir.join(name)).unwrap();
    };
    match case.kind {
        Kind::Sop | Kind::Pcglns | Kind::Pcgtsp | Kind::Json => {
            std::fs::write(dir.join("sol.json"), &sols[seed]).unwrap();
        }
        Kind::Solution => copy("instances/generated/panel-20.json", "panel-20.json"),
        Kind::Portfolio => copy("instances/tsplib-sop/ESC07.sop", "ESC07.sop"),
        Kind::Bks => {
            copy("instances/tsplib-sop/ESC07.sop", "ESC07.sop");
            std::fs::write(
                dir.join("sol.json"),
                &sols["instances/tsplib-sop/ESC07.sop"],
            )
            .unwrap();
        }
        _ => {}
    }
}

/// One run of the campaign.
struct Done {
    case: usize,
    cmd: Cmd,
    out: Outcome,
}

/// Runs every command of every case on `jobs` threads.
fn campaign(
    cases: &[(Case, String)],
    base: &Path,
    sols: &BTreeMap<String, Vec<u8>>,
    jobs: usize,
) -> Vec<Done> {
    let next = AtomicUsize::new(0);
    let done = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..jobs {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some((case, seed)) = cases.get(i) else {
                        break;
                    };
                    let dir = base.join(&case.id);
                    lay_out(case, &dir, sols, seed);
                    for c in exec::commands(case) {
                        let out = exec::run(&dir, &c, &case.bytes);
                        done.lock().unwrap().push(Done {
                            case: i,
                            cmd: c,
                            out,
                        });
                    }
                }
            });
        }
    });
    let mut v = done.into_inner().unwrap();
    v.sort_by_key(|d| (d.case, d.cmd.label));
    v
}

/// The table of classes per command, and the lines of every run that is not clean.
fn report(cases: &[(Case, String)], done: &[Done], base: &Path) -> (String, Vec<String>) {
    let mut table: BTreeMap<&str, BTreeMap<Class, usize>> = BTreeMap::new();
    let mut bad = Vec::new();
    for d in done {
        *table
            .entry(d.cmd.label)
            .or_default()
            .entry(d.out.class)
            .or_default() += 1;
        if !d.out.class.clean() {
            let case = &cases[d.case].0;
            let dir = base.join(&case.id);
            let _ = std::fs::write(
                dir.join(format!("{}.command.txt", d.cmd.label)),
                format!("cellseq {}\n", d.cmd.args.join(" ")),
            );
            bad.push(format!(
                "{:?}: {} (category {}, seed {}) `cellseq {}` exit {:?} after {:.2} s in {}: {}",
                d.out.class,
                case.id,
                case.category,
                cases[d.case].1,
                d.cmd.args.join(" "),
                d.out.code,
                d.out.wall,
                dir.display(),
                d.out.stderr.trim().replace('\n', " | ")
            ));
        }
    }
    let mut text = format!("{:<10}", "command");
    for c in Class::ALL {
        text.push_str(&format!("{:>10}", format!("{c:?}")));
    }
    text.push('\n');
    for (label, counts) in &table {
        text.push_str(&format!("{label:<10}"));
        for c in Class::ALL {
            text.push_str(&format!("{:>10}", counts.get(&c).copied().unwrap_or(0)));
        }
        text.push('\n');
    }
    (text, bad)
}

#[test]
fn hostile_inputs_end_cleanly_in_every_command() {
    let full = std::env::var("CELLSEQ_HOSTILE").is_ok_and(|v| v == "full");
    let count = env_or(
        "CELLSEQ_HOSTILE_CASES",
        if full { FULL_CASES } else { CI_CASES },
    );
    let seed = env_or("CELLSEQ_HOSTILE_SEED", SEED);
    let jobs = env_or("CELLSEQ_HOSTILE_JOBS", if full { 4 } else { 2 }).max(1);
    let base: PathBuf = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hostile/seed-{seed}"));
    let _ = std::fs::remove_dir_all(&base);
    std::fs::create_dir_all(&base).unwrap();
    // valid solutions of every instance seed, for `eval` and the solution cases
    let mut sols = BTreeMap::new();
    for k in [Kind::Sop, Kind::Pcglns, Kind::Pcgtsp, Kind::Json] {
        for s in k.seeds() {
            sols.insert(s.to_string(), solution_of(&root().join(s), &base));
        }
    }
    let panel = solution_of(&root().join("instances/generated/panel-20.json"), &base);
    let cases: Vec<(Case, String)> = cases::cases(root(), &panel, count, seed)
        .into_iter()
        .map(|c| {
            let from = c.seed.clone();
            (c, from)
        })
        .collect();
    let t0 = std::time::Instant::now();
    let done = campaign(&cases, &base, &sols, jobs);
    let (table, bad) = report(&cases, &done, &base);
    eprintln!(
        "hostile suite: {} cases, {} runs, seed {seed}, {jobs} jobs, {:.0} s\n{table}",
        cases.len(),
        done.len(),
        t0.elapsed().as_secs_f64()
    );
    // clean cases leave nothing behind
    for (i, (case, _)) in cases.iter().enumerate() {
        if done
            .iter()
            .filter(|d| d.case == i)
            .all(|d| d.out.class.clean())
        {
            let _ = std::fs::remove_dir_all(base.join(&case.id));
        }
    }
    assert!(
        bad.is_empty(),
        "{} of {} runs did not end cleanly:\n{}",
        bad.len(),
        done.len(),
        bad.join("\n")
    );
}

/// Runs `args` in `dir` the way the suite does; its outcome.
fn one(dir: &Path, args: &[&str], limit: Option<f64>, inputs: &[&str], input: &[u8]) -> Outcome {
    let c = Cmd {
        label: "regression",
        args: args.iter().map(|a| a.to_string()).collect(),
        limit,
        outputs: args
            .iter()
            .filter(|a| a.starts_with("out"))
            .map(|a| a.to_string())
            .collect(),
        inputs: inputs.iter().map(|a| a.to_string()).collect(),
    };
    exec::run(dir, &c, input)
}

/// Findings of the campaigns, each fixed, each a run that must end cleanly.
#[test]
fn findings_of_the_campaigns_end_cleanly() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    // a DXF coordinate of 1.8e308: `plot` looped in plotters' axis ticks
    let dxf = std::fs::read_to_string(root().join("fuzz/seeds/dxf/shapes.dxf"))
        .unwrap()
        .replacen(" 10\n10\n", " 10\n1.7976931348623157e308\n", 1);
    std::fs::write(dir.join("huge.dxf"), &dxf).unwrap();
    let o = one(
        dir,
        &["plot", "huge.dxf", "-o", "out.svg"],
        None,
        &["huge.dxf"],
        dxf.as_bytes(),
    );
    assert_eq!(o.class, Class::Refusal, "{o:?}");
    // a drawing that is /dev/zero: 4 GiB were read before the cap
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.dxf")).unwrap();
    std::os::unix::fs::symlink("/dev/zero", dir.join("zero.sop")).unwrap();
    for args in [
        &["optimize", "zero.dxf", "-o", "out.ngc"][..],
        &["import", "zero.dxf", "-o", "out.json"],
        &["validate", "zero.sop"],
    ] {
        let o = one(dir, args, None, &[args[1]], b"");
        assert_eq!(o.class, Class::Refusal, "{args:?}: {o:?}");
        assert!(o.wall < 5.0, "{args:?} took {:.1} s", o.wall);
    }
    // a tool library without a drill small enough: the refusal names the library
    let tools =
        std::fs::read_to_string(root().join("crates/cellseq/src/generate/default-tools.toml"))
            .unwrap();
    let no_drills = &tools[..tools.find("kind = \"drill\"").unwrap()];
    let no_drills = &no_drills[..no_drills.rfind("[[tool]]").unwrap()];
    std::fs::write(dir.join("mills.toml"), no_drills).unwrap();
    let args = [
        "generate",
        "panel",
        "--param",
        "tools=mills.toml",
        "-o",
        "out.json",
    ];
    let o = one(dir, &args, None, &["mills.toml"], no_drills.as_bytes());
    assert_eq!(o.class, Class::Refusal, "{o:?}");
    // a best-known value of 1e-320 made the gap infinite
    std::fs::copy(
        root().join("instances/tsplib-sop/ESC07.sop"),
        dir.join("ESC07.sop"),
    )
    .unwrap();
    let bks = "name,best_known,proven_optimal\nESC07,1e-320,false\n";
    std::fs::write(dir.join("bks.csv"), bks).unwrap();
    for args in [
        &["solve", "ESC07.sop", "--max-evals", "2000"][..],
        &["solve", "ESC07.sop", "--max-evals", "2000", "--json"],
        &["bound", "ESC07.sop", "--iterations", "5"],
    ] {
        let o = one(dir, args, None, &["bks.csv"], bks.as_bytes());
        assert_eq!(o.class, Class::Result, "{args:?}: {o:?}");
    }
}

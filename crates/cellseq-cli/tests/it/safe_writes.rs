//! Every write of the command line is safe: planted links are never followed, FIFOs and devices
//! stay what they are, the input is never overwritten without `--overwrite-input`, a signal
//! during a write leaves no temporary file, and plans cannot write or read outside their place.

use std::os::unix::fs::{FileTypeExt, symlink};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use crate::common::{BIN, root, run, s, stderr, tiny_plan};

/// Copies a repository file into `dir`.
fn copy(dir: &Path, rel: &str) -> PathBuf {
    let src = root().join(rel);
    let dst = dir.join(src.file_name().unwrap());
    std::fs::copy(&src, &dst).unwrap();
    dst
}

/// Every name in `dir`, hidden ones included.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn optimize_refuses_to_write_over_its_input() {
    let d = tempfile::tempdir().unwrap();
    let ngc = copy(d.path(), "tests/fixtures/gcode/mill.ngc");
    let before = std::fs::read(&ngc).unwrap();
    let o = run(&["optimize", s(&ngc), "-o", s(&ngc)]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("--overwrite-input") && e.contains("mill.ngc"),
        "{e}"
    );
    assert!(!e.contains("panicked"), "{e}");
    assert_eq!(std::fs::read(&ngc).unwrap(), before);
    // the same file through a hard link
    let hard = d.path().join("hard.ngc");
    std::fs::hard_link(&ngc, &hard).unwrap();
    let o = run(&["optimize", s(&ngc), "-o", s(&hard)]);
    assert!(!o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read(&ngc).unwrap(), before);
    // import too
    let o = run(&["import", s(&ngc), "-o", s(&ngc)]);
    assert!(stderr(&o).contains("--overwrite-input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&ngc).unwrap(), before);
    // with the flag the input is replaced by the optimized program
    let o = run(&["optimize", s(&ngc), "-o", s(&ngc), "--overwrite-input"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(names(d.path()), ["hard.ngc", "mill.ngc"]);
}

#[test]
fn solve_refuses_to_write_its_solution_over_the_instance() {
    let d = tempfile::tempdir().unwrap();
    let sop = copy(d.path(), "instances/tsplib-sop/ESC07.sop");
    let before = std::fs::read(&sop).unwrap();
    let o = run(&["solve", s(&sop), "--solver", "greedy", "--out", s(&sop)]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--overwrite-input"), "{}", stderr(&o));
    assert_eq!(std::fs::read(&sop).unwrap(), before);
}

#[test]
fn planted_symlink_at_the_output_is_replaced_not_followed() {
    let d = tempfile::tempdir().unwrap();
    let sop = copy(d.path(), "instances/tsplib-sop/ESC07.sop");
    let victim = d.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    let out = d.path().join("sol.json");
    symlink(&victim, &out).unwrap();
    let o = run(&["solve", s(&sop), "--solver", "greedy", "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
    assert!(std::fs::symlink_metadata(&out).unwrap().is_file());
    assert!(
        std::fs::read_to_string(&out)
            .unwrap()
            .contains("cellseq-solution")
    );
    assert_eq!(names(d.path()), ["ESC07.sop", "sol.json", "victim.txt"]);
}

#[test]
fn dev_null_output_stays_a_device() {
    let d = tempfile::tempdir().unwrap();
    let sop = copy(d.path(), "instances/tsplib-sop/ESC07.sop");
    let o = run(&["solve", s(&sop), "--solver", "greedy", "--out", "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = run(&["generate", "uniform", "--param", "n=20", "-o", "/dev/null"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = std::fs::symlink_metadata("/dev/null").unwrap();
    assert!(m.file_type().is_char_device());
}

#[test]
fn output_onto_a_directory_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let o = run(&["generate", "uniform", "--param", "n=20", "-o", s(d.path())]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("is a directory"), "{}", stderr(&o));
    assert!(names(d.path()).is_empty());
}

#[test]
fn sigterm_during_a_write_leaves_no_temporary_file() {
    let d = tempfile::tempdir().unwrap();
    let marker = d.path().join("paused");
    let out = d.path().join("u.json");
    let mut child = Command::new(BIN)
        .args(["generate", "uniform", "--param", "n=2000", "-o", s(&out)])
        .env("CELLSEQ_TEST_PAUSE_WRITE", &marker)
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !marker.exists() {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the write never paused"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // half the file is in a temporary sibling now
    let temps: Vec<String> = names(d.path())
        .into_iter()
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert_eq!(temps.len(), 1, "{:?}", names(d.path()));
    // SAFETY: plain kill(2) on our own child.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGTERM) },
        0
    );
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(128 + libc::SIGTERM), "{status:?}");
    assert_eq!(names(d.path()), ["paused"], "temporary file left behind");
}

#[test]
fn plan_names_that_are_paths_are_refused_by_check_and_run() {
    let d = tempfile::tempdir().unwrap();
    for bad in ["../../escaped", "/tmp/escaped", ".hidden", ""] {
        let plan = d.path().join("p.toml");
        std::fs::write(&plan, tiny_plan(bad)).unwrap();
        for cmd in ["check", "run"] {
            let o = Command::new(BIN)
                .args([cmd, s(&plan)])
                .current_dir(d.path())
                .output()
                .unwrap();
            assert!(!o.status.success(), "{cmd} accepted {bad:?}");
            let e = stderr(&o);
            assert!(e.contains("plan name") && e.contains("p.toml"), "{e}");
        }
    }
    assert_eq!(names(d.path()), ["p.toml"], "something was written");
}

#[test]
fn check_and_run_refuse_a_million_replicates_alike() {
    let d = tempfile::tempdir().unwrap();
    let plan = d.path().join("p.toml");
    let text = tiny_plan("big").replace("[budget]", "replicates = 1000000\n[budget]");
    std::fs::write(&plan, text).unwrap();
    for cmd in ["check", "run"] {
        let o = Command::new(BIN)
            .args([cmd, s(&plan)])
            .current_dir(d.path())
            .output()
            .unwrap();
        assert!(!o.status.success(), "{cmd} accepted");
        assert!(stderr(&o).contains("--max-trials"), "{}", stderr(&o));
    }
    let o = run(&["check", s(&plan), "--max-trials", "1e6"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("= 1000000 trials"));
    assert_eq!(names(d.path()), ["p.toml"]);
}

#[test]
fn run_refuses_a_planted_results_symlink() {
    let d = tempfile::tempdir().unwrap();
    let plan = d.path().join("p.toml");
    std::fs::write(&plan, tiny_plan("t")).unwrap();
    let out = d.path().join("out");
    std::fs::create_dir(&out).unwrap();
    let victim = d.path().join("victim.txt");
    std::fs::write(&victim, "precious").unwrap();
    symlink(&victim, out.join("traces.csv")).unwrap();
    let o = run(&["run", s(&plan), "--out", s(&out), "--threads", "1"]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("symbolic link"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&victim).unwrap(), "precious");
}

#[test]
fn a_write_that_runs_out_of_room_leaves_no_temporary_file() {
    // RLIMIT_FSIZE makes the kernel refuse writes past 16 KiB (EFBIG), as a full disk refuses
    // them with ENOSPC: the write fails part-way, and the temporary file must go.
    use std::os::unix::process::CommandExt;
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("u.json");
    std::fs::write(&out, "old").unwrap();
    let mut cmd = Command::new(BIN);
    cmd.args(["generate", "uniform", "--param", "n=5000", "-o", s(&out)]);
    // SAFETY: only async-signal-safe calls (signal, setrlimit) between fork and exec.
    unsafe {
        cmd.pre_exec(|| {
            libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
            let lim = libc::rlimit {
                rlim_cur: 16 * 1024,
                rlim_max: 16 * 1024,
            };
            if libc::setrlimit(libc::RLIMIT_FSIZE, &lim) != 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    let o = cmd.output().unwrap();
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(e.contains("u.json") && e.contains("too large"), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "old");
    assert_eq!(names(d.path()), ["u.json"], "temporary file left behind");
}

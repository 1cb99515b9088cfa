//! Build script: records the git commit the binary is built from, for `cellseq --version` and
//! the run manifest (`src/provenance.rs`). The commit and the dirty flag are the workspace's
//! (the repository two levels up), not this crate's alone.
//!
//! Emits `CELLSEQ_GIT_COMMIT` (full hash, or `unknown` outside a git checkout or without git),
//! `CELLSEQ_GIT_DIRTY` (`true` when tracked files differ from the commit, `false`, or `unknown`)
//! and `CELLSEQ_VERSION` (`0.1.0 (commit 66a4426c0ffe, dirty)`). A source tarball without
//! `.git` can set `CELLSEQ_GIT_COMMIT` in the environment instead.

use std::path::{Path, PathBuf};
use std::process::Command;

fn git(dir: &Path, args: &[&str]) -> Option<String> {
    // --no-optional-locks: `git status` must not refresh the index, which is watched below
    let out = Command::new("git")
        .arg("--no-optional-locks")
        .arg("-C")
        .arg(dir)
        .args(args)
        .output()
        .ok()?;
    if !out.status.success() {
        return None;
    }
    Some(String::from_utf8(out.stdout).ok()?.trim().to_string())
}

fn main() {
    let here = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into()));
    // the workspace root: crates/cellseq-lab/../..
    let root = here.join("../..");
    println!("cargo:rerun-if-env-changed=CELLSEQ_GIT_COMMIT");
    // Sources whose change can make the tree dirty or the commit different. Listing any path
    // replaces Cargo's default (rerun on every package file), so the list is explicit.
    for p in ["Cargo.toml", "Cargo.lock", "crates", "experiments"] {
        println!("cargo:rerun-if-changed={}", root.join(p).display());
    }
    let env_commit = std::env::var("CELLSEQ_GIT_COMMIT")
        .ok()
        .filter(|s| !s.trim().is_empty());
    let head = git(&root, &["rev-parse", "HEAD"]).filter(|h| h.len() >= 7);
    if head.is_some() {
        // Rerun when HEAD moves (commit, checkout) or the index changes (staging, commit).
        for what in ["HEAD", "index"] {
            if let Some(p) = git(&root, &["rev-parse", "--git-path", what]) {
                println!("cargo:rerun-if-changed={}", root.join(p).display());
            }
        }
        // Only the ref HEAD points at: watching all of `refs/` would rebuild this worktree
        // whenever any other branch or worktree of the repository commits.
        if let Some(common) = git(&root, &["rev-parse", "--git-common-dir"]) {
            let common = root.join(common);
            // Cargo treats a missing path as changed on every build, so only existing files
            // are named: the loose ref, or packed-refs when the ref is packed.
            let loose = git(&root, &["symbolic-ref", "-q", "HEAD"]).map(|r| common.join(r));
            let packed = common.join("packed-refs");
            for p in [loose, Some(packed)].into_iter().flatten() {
                if p.is_file() {
                    println!("cargo:rerun-if-changed={}", p.display());
                    break;
                }
            }
        }
    }
    let (commit, dirty) = match (env_commit, head) {
        (Some(c), _) => (c.trim().to_string(), "unknown".to_string()),
        (None, Some(h)) => {
            let dirty = match git(&root, &["status", "--porcelain", "--untracked-files=no"]) {
                Some(s) if s.is_empty() => "false",
                Some(_) => "true",
                None => "unknown",
            };
            (h, dirty.to_string())
        }
        (None, None) => ("unknown".to_string(), "unknown".to_string()),
    };
    let pkg = std::env::var("CARGO_PKG_VERSION").unwrap_or_else(|_| "?".into());
    let version = if commit == "unknown" {
        format!("{pkg} (commit unknown: built outside a git checkout)")
    } else {
        let short: String = commit.chars().take(12).collect();
        let mark = if dirty == "true" { ", dirty" } else { "" };
        format!("{pkg} (commit {short}{mark})")
    };
    println!("cargo:rustc-env=CELLSEQ_GIT_COMMIT={commit}");
    println!("cargo:rustc-env=CELLSEQ_GIT_DIRTY={dirty}");
    println!("cargo:rustc-env=CELLSEQ_VERSION={version}");
}

//! Instance file patterns of a plan: confined, loop-free and capped glob expansion.
//!
//! A pattern is a path whose components may hold the wildcards `*`, `?`, `[...]` and a whole
//! component `**` (any number of directories). Rules:
//!
//! - A **relative** pattern is read from the plan's directory. It may climb out of it only
//!   through leading `..` steps (`../instances/*.sop`), and a pattern that climbs may not use
//!   `**`; `..` anywhere else is refused. So a recursive walk stays inside the plan's directory
//!   tree, and a relative pattern can never walk the whole filesystem.
//! - An **absolute** pattern (`/data/**/*.sop`) is taken as written, on purpose.
//! - The walk starts at the pattern's literal prefix (the components before the first
//!   wildcard), never descends into a directory through a symbolic link (so links cannot make
//!   it loop), and gives up with an error naming the pattern once it has looked at more than
//!   `cap` directory entries. Links to files are matched like files.

use std::path::{Component, Path, PathBuf};

/// Default cap on the directory entries one pattern may visit (plan key `max_files`).
pub const DEFAULT_MAX_FILES: u64 = 100_000;

fn has_wildcard(s: &str) -> bool {
    s.contains(['*', '?', '['])
}

/// The files matching `pattern`, read from `base`, sorted. `Err` is the message (the caller
/// names the plan and the instance entry).
pub fn expand(base: &Path, pattern: &str, cap: u64) -> Result<Vec<PathBuf>, String> {
    if pattern.is_empty() {
        return Err("empty file pattern".into());
    }
    if pattern.chars().any(char::is_control) {
        return Err(format!("pattern {pattern:?} holds a control character"));
    }
    let pat = Path::new(pattern);
    let absolute = pat.is_absolute();
    // literal prefix and the wildcard rest
    let mut root = if absolute {
        PathBuf::new()
    } else {
        base.to_path_buf()
    };
    let mut rest: Vec<String> = Vec::new();
    let mut climbed = false;
    let mut seen_normal = false;
    for c in pat.components() {
        match c {
            Component::RootDir | Component::Prefix(_) => root.push(c.as_os_str()),
            Component::CurDir => {
                if rest.is_empty() {
                    root.push(".");
                }
            }
            Component::ParentDir => {
                if absolute {
                    if !rest.is_empty() {
                        return Err(format!("'..' after a wildcard in '{pattern}'"));
                    }
                    root.push("..");
                    continue;
                }
                if seen_normal {
                    return Err(format!(
                        "'..' inside '{pattern}': a relative pattern may climb out of the \
                         plan's directory only through leading '../' steps"
                    ));
                }
                climbed = true;
                root.push("..");
            }
            Component::Normal(s) => {
                seen_normal = true;
                let s = s
                    .to_str()
                    .ok_or_else(|| format!("pattern {pattern:?} is not UTF-8"))?;
                if rest.is_empty() && !has_wildcard(s) {
                    root.push(s);
                } else {
                    rest.push(s.to_string());
                }
            }
        }
    }
    if rest.is_empty() {
        // a plain file name
        return Ok(if root.is_file() { vec![root] } else { vec![] });
    }
    let recursive = rest.iter().any(|s| s == "**");
    if recursive && climbed {
        return Err(format!(
            "'{pattern}' climbs out of the plan's directory with '..' and walks with '**'; \
             a recursive walk outside the plan's directory tree needs an absolute pattern"
        ));
    }
    let glob = globset::GlobBuilder::new(&rest.join("/"))
        .literal_separator(true)
        .backslash_escape(true)
        .build()
        .map_err(|e| format!("bad pattern '{pattern}': {e}"))?
        .compile_matcher();
    let walk_root = if root.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        root.clone()
    };
    let mut walker = walkdir::WalkDir::new(&walk_root)
        .follow_links(false)
        .min_depth(1);
    if !recursive {
        walker = walker.max_depth(rest.len());
    }
    let mut out = Vec::new();
    let mut visited: u64 = 0;
    for entry in walker {
        // unreadable directories are skipped, as a shell glob skips them
        let Ok(entry) = entry else { continue };
        visited += 1;
        if visited > cap {
            return Err(format!(
                "'{pattern}' looks at more than {cap} directory entries; narrow the pattern, \
                 or raise the cap with the plan key max_files or the --max-files flag"
            ));
        }
        let Ok(rel) = entry.path().strip_prefix(&walk_root) else {
            continue;
        };
        if !glob.is_match(rel) {
            continue;
        }
        let ft = entry.file_type();
        let is_file = ft.is_file() || (ft.is_symlink() && entry.path().is_file());
        if is_file {
            out.push(root.join(rel));
        }
    }
    out.sort();
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn touch(p: &Path) {
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, b"x").unwrap();
    }

    fn names(v: &[PathBuf], base: &Path) -> Vec<String> {
        v.iter()
            .map(|p| p.strip_prefix(base).unwrap().display().to_string())
            .collect()
    }

    #[test]
    fn expands_like_a_shell_glob() {
        let d = tempfile::tempdir().unwrap();
        let b = d.path();
        for f in ["a.sop", "b.sop", "c.json", "sub/d.sop", "sub/deeper/e.sop"] {
            touch(&b.join(f));
        }
        assert_eq!(
            names(&expand(b, "*.sop", 100).unwrap(), b),
            ["a.sop", "b.sop"]
        );
        assert_eq!(
            names(&expand(b, "**/*.sop", 100).unwrap(), b),
            ["a.sop", "b.sop", "sub/d.sop", "sub/deeper/e.sop"]
        );
        assert_eq!(
            names(&expand(b, "sub/*.sop", 100).unwrap(), b),
            ["sub/d.sop"]
        );
        assert_eq!(names(&expand(b, "c.json", 100).unwrap(), b), ["c.json"]);
        assert!(expand(b, "nothing.sop", 100).unwrap().is_empty());
    }

    #[test]
    fn leading_parent_steps_keep_the_path_as_written() {
        let d = tempfile::tempdir().unwrap();
        touch(&d.path().join("instances/x.sop"));
        std::fs::create_dir(d.path().join("experiments")).unwrap();
        let base = d.path().join("experiments");
        let got = expand(&base, "../instances/*.sop", 100).unwrap();
        assert_eq!(got, vec![base.join("../instances/x.sop")]);
    }

    #[test]
    fn relative_patterns_cannot_walk_out_of_the_plan_tree() {
        let d = tempfile::tempdir().unwrap();
        let base = d.path().join("p");
        std::fs::create_dir(&base).unwrap();
        for bad in ["../**/*.sop", "../../**/*", "a/../../x.sop", "*/../x.sop"] {
            assert!(expand(&base, bad, 100).is_err(), "{bad} accepted");
        }
    }

    #[test]
    fn symlink_loops_are_not_followed() {
        let d = tempfile::tempdir().unwrap();
        let b = d.path();
        touch(&b.join("a/x.sop"));
        std::os::unix::fs::symlink(b, b.join("a/loop")).unwrap();
        std::os::unix::fs::symlink(b.join("a/x.sop"), b.join("a/y.sop")).unwrap();
        let got = expand(b, "**/*.sop", 1000).unwrap();
        assert_eq!(names(&got, b), ["a/x.sop", "a/y.sop"]);
    }

    #[test]
    fn the_walk_is_capped() {
        let d = tempfile::tempdir().unwrap();
        for i in 0..30 {
            touch(&d.path().join(format!("f{i}.sop")));
        }
        let e = expand(d.path(), "*.sop", 20).unwrap_err();
        assert!(e.contains("more than 20") && e.contains("max_files"), "{e}");
        assert_eq!(expand(d.path(), "*.sop", 30).unwrap().len(), 30);
    }

    #[test]
    fn absolute_root_walk_stops_at_the_cap() {
        let e = expand(Path::new("."), "/**/*", 2000).unwrap_err();
        assert!(e.contains("more than 2000"), "{e}");
    }
}

//! Provenance of a run: which cellseq (version, commit, dirty tree) ran where (host, OS,
//! kernel, CPU model and count) and when (UTC start and end). [`stamp`] adds it to a run's
//! `manifest.json`; [`VERSION`] is what `cellseq --version` prints.
//!
//! The commit is the one the binary was built from (recorded by `build.rs`), not the one of the
//! directory the run happens to start in. Everything is read from `/proc` and `/etc/os-release`
//! on Linux, with `uname` and the compile-time OS name as fallbacks elsewhere; a field that
//! cannot be read is `unknown`, never an error.

use serde::Serialize;
use std::path::Path;

/// `cellseq --version`: the crate version and the commit it was built from, e.g.
/// `0.1.0 (commit 66a4426c0ffe, dirty)`; `commit unknown` when built outside a git checkout.
pub const VERSION: &str = env!("CELLSEQ_VERSION");
/// Full hash of the commit the binary was built from, or `unknown`.
pub const GIT_COMMIT: &str = env!("CELLSEQ_GIT_COMMIT");
/// `true` when tracked files differed from [`GIT_COMMIT`] at build time, `false`, or `unknown`.
pub const GIT_DIRTY: &str = env!("CELLSEQ_GIT_DIRTY");

const UNKNOWN: &str = "unknown";

/// Where and with what a run happened.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Provenance {
    /// Crate version (`Cargo.toml`).
    pub cellseq_version: String,
    /// Commit the binary was built from.
    pub git_commit: String,
    /// Whether the build tree had uncommitted changes (`true`, `false`, `unknown`).
    pub git_dirty: String,
    /// Host name.
    pub host: String,
    /// Operating system (`PRETTY_NAME` of `/etc/os-release` on Linux).
    pub os: String,
    /// Kernel release.
    pub kernel: String,
    /// CPU architecture.
    pub arch: String,
    /// CPU model name.
    pub cpu_model: String,
    /// Logical CPUs available to the process.
    pub cpu_count: usize,
}

fn read_trimmed(path: &str) -> Option<String> {
    let s = std::fs::read_to_string(path).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

fn command(cmd: &str, args: &[&str]) -> Option<String> {
    let out = std::process::Command::new(cmd).args(args).output().ok()?;
    if !out.status.success() {
        return None;
    }
    let s = String::from_utf8(out.stdout).ok()?.trim().to_string();
    (!s.is_empty()).then_some(s)
}

/// `PRETTY_NAME` (else `NAME VERSION_ID`) of an os-release file's text.
pub fn os_release_name(text: &str) -> Option<String> {
    let field = |key: &str| {
        text.lines()
            .filter_map(|l| l.split_once('='))
            .find(|(k, _)| k.trim() == key)
            .map(|(_, v)| v.trim().trim_matches('"').to_string())
            .filter(|v| !v.is_empty())
    };
    field("PRETTY_NAME").or_else(|| {
        let name = field("NAME")?;
        Some(match field("VERSION_ID") {
            Some(v) => format!("{name} {v}"),
            None => name,
        })
    })
}

/// The first `model name` of a `/proc/cpuinfo` text.
pub fn cpuinfo_model(text: &str) -> Option<String> {
    text.lines()
        .filter(|l| l.starts_with("model name") || l.starts_with("Model"))
        .find_map(|l| l.split_once(':'))
        .map(|(_, v)| v.trim().to_string())
        .filter(|v| !v.is_empty())
}

/// Reads the provenance of this process on this machine.
pub fn gather() -> Provenance {
    let os = std::fs::read_to_string("/etc/os-release")
        .ok()
        .and_then(|t| os_release_name(&t))
        .or_else(|| command("uname", &["-s"]))
        .unwrap_or_else(|| std::env::consts::OS.to_string());
    Provenance {
        cellseq_version: env!("CARGO_PKG_VERSION").to_string(),
        git_commit: GIT_COMMIT.to_string(),
        git_dirty: GIT_DIRTY.to_string(),
        host: read_trimmed("/proc/sys/kernel/hostname")
            .or_else(|| command("hostname", &[]))
            .unwrap_or_else(|| UNKNOWN.into()),
        os,
        kernel: read_trimmed("/proc/sys/kernel/osrelease")
            .or_else(|| command("uname", &["-r"]))
            .unwrap_or_else(|| UNKNOWN.into()),
        arch: std::env::consts::ARCH.to_string(),
        cpu_model: std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| cpuinfo_model(&t))
            .unwrap_or_else(|| UNKNOWN.into()),
        cpu_count: std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
    }
}

/// The current UTC time, RFC 3339 to the second (`2026-11-26T10:50:07Z`).
pub fn utc_now() -> String {
    chrono::Utc::now().format("%Y-%m-%dT%H:%M:%SZ").to_string()
}

/// Adds the provenance to a manifest object: the fields of [`Provenance`] (`git_commit` becomes
/// the commit of the binary), `started_utc` and `ended_utc`. A run writes its manifest when it
/// starts (`finished` false: `started_utc` now, `ended_utc` null) and again when it ends
/// (`finished` true: `started_utc` read back from the manifest at `path`, `ended_utc` now).
pub fn stamp(manifest: &mut serde_json::Value, path: &Path, finished: bool) {
    let now = utc_now();
    let started = if finished {
        std::fs::read_to_string(path)
            .ok()
            .and_then(|t| serde_json::from_str::<serde_json::Value>(&t).ok())
            .and_then(|m| m["started_utc"].as_str().map(String::from))
            .unwrap_or_else(|| now.clone())
    } else {
        now.clone()
    };
    let Some(obj) = manifest.as_object_mut() else {
        return;
    };
    if let Ok(serde_json::Value::Object(p)) = serde_json::to_value(gather()) {
        obj.extend(p);
    }
    obj.insert("started_utc".into(), started.into());
    obj.insert(
        "ended_utc".into(),
        if finished {
            now.into()
        } else {
            serde_json::Value::Null
        },
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn os_release_and_cpuinfo_fields() {
        let t = "NAME=\"Debian GNU/Linux\"\nVERSION_ID=\"12\"\nPRETTY_NAME=\"Debian GNU/Linux 12 (bookworm)\"\n";
        assert_eq!(
            os_release_name(t).as_deref(),
            Some("Debian GNU/Linux 12 (bookworm)")
        );
        assert_eq!(
            os_release_name("NAME=Alpine\nVERSION_ID=3.20\n").as_deref(),
            Some("Alpine 3.20")
        );
        assert_eq!(os_release_name("ID=x\n"), None);
        let c = "processor\t: 0\nvendor_id\t: GenuineIntel\nmodel name\t: Intel(R) Xeon(R) CPU @ 2.20GHz\n";
        assert_eq!(
            cpuinfo_model(c).as_deref(),
            Some("Intel(R) Xeon(R) CPU @ 2.20GHz")
        );
        assert_eq!(cpuinfo_model("processor : 0\n"), None);
    }

    #[test]
    fn utc_now_is_rfc3339_seconds() {
        let s = utc_now();
        assert_eq!(s.len(), 20, "{s}");
        assert!(chrono::DateTime::parse_from_rfc3339(&s).is_ok(), "{s}");
    }

    #[test]
    fn stamp_keeps_the_start_of_the_run() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("manifest.json");
        let mut start = serde_json::json!({"threads": 2});
        stamp(&mut start, &path, false);
        assert!(start["ended_utc"].is_null());
        let started = start["started_utc"].as_str().unwrap().to_string();
        let mut old = start.clone();
        old["started_utc"] = "2000-01-01T00:00:00Z".into();
        std::fs::write(&path, serde_json::to_string(&old).unwrap()).unwrap();
        let mut end = serde_json::json!({"threads": 2});
        stamp(&mut end, &path, true);
        assert_eq!(end["started_utc"], "2000-01-01T00:00:00Z");
        assert!(end["ended_utc"].as_str().unwrap() >= started.as_str());
        for k in [
            "host",
            "os",
            "kernel",
            "cpu_model",
            "git_commit",
            "git_dirty",
        ] {
            assert!(end[k].as_str().is_some_and(|s| !s.is_empty()), "{k}: {end}");
        }
        assert!(end["cpu_count"].as_u64().unwrap() >= 1);
        assert_eq!(end["threads"], 2);
    }
}

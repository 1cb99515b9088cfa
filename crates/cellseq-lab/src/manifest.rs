//! The run manifest (`manifest.json`) as the report reads it: typed, and lenient field by field,
//! so that a field of the wrong type reads as absent (the report prints `?` for it) instead of
//! losing the whole manifest. `run::write_manifest` and `results::merge` write it.

use serde::{Deserialize, Deserializer, de::DeserializeOwned};
use std::path::Path;

/// A field that reads as `None` when it is missing, `null` or of another type.
fn lenient<'de, D: Deserializer<'de>, T: DeserializeOwned>(d: D) -> Result<Option<T>, D::Error> {
    let v = serde_json::Value::deserialize(d)?;
    Ok(serde_json::from_value(v).ok())
}

/// What the report uses of a manifest (other fields are ignored).
#[derive(Debug, Clone, Default, Deserialize)]
pub struct Manifest {
    /// The plan text (TOML) the run executed.
    #[serde(default, deserialize_with = "lenient")]
    pub plan: Option<String>,
    /// The plan's reference solver.
    #[serde(default, deserialize_with = "lenient")]
    pub reference: Option<String>,
    /// Version of the crate that ran.
    #[serde(default, deserialize_with = "lenient")]
    pub crate_version: Option<String>,
    /// Commit the binary was built from.
    #[serde(default, deserialize_with = "lenient")]
    pub git_commit: Option<String>,
    /// `"true"` when the tree was dirty.
    #[serde(default, deserialize_with = "lenient")]
    pub git_dirty: Option<String>,
    /// Hash of the plan.
    #[serde(default, deserialize_with = "lenient")]
    pub plan_hash: Option<String>,
    /// Worker threads.
    #[serde(default, deserialize_with = "lenient")]
    pub threads: Option<u64>,
    /// Logical CPUs of the host.
    #[serde(default, deserialize_with = "lenient")]
    pub cpu_count: Option<u64>,
    /// CPU model.
    #[serde(default, deserialize_with = "lenient")]
    pub cpu_model: Option<String>,
    /// Operating system.
    #[serde(default, deserialize_with = "lenient")]
    pub os: Option<String>,
    /// Kernel release.
    #[serde(default, deserialize_with = "lenient")]
    pub kernel: Option<String>,
    /// Seconds of one calibration unit on the host.
    #[serde(default, deserialize_with = "lenient")]
    pub calibration_seconds: Option<f64>,
    /// Host name.
    #[serde(default, deserialize_with = "lenient")]
    pub host: Option<String>,
    /// UTC start of the run.
    #[serde(default, deserialize_with = "lenient")]
    pub started_utc: Option<String>,
    /// UTC end of the run (absent while it runs or when it was interrupted).
    #[serde(default, deserialize_with = "lenient")]
    pub ended_utc: Option<String>,
    /// The manifests of merged shards or directories (`cellseq merge`).
    #[serde(default, deserialize_with = "lenient")]
    pub merged_from: Option<Vec<Manifest>>,
}

impl Manifest {
    /// Reads `path`; `None` when it is missing or not a JSON object.
    pub fn read(path: &Path) -> Option<Manifest> {
        let text = std::fs::read_to_string(path).ok()?;
        serde_json::from_str(&text).ok()
    }

    /// The parts of the run: the merged manifests, or this one alone.
    pub fn parts(&self) -> Vec<&Manifest> {
        match &self.merged_from {
            Some(m) if !m.is_empty() => m.iter().collect(),
            _ => vec![self],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_field_of_another_type_reads_as_absent() {
        let m: Manifest = serde_json::from_str(
            r#"{"threads": "two", "host": "h", "cpu_count": 4, "merged_from": 3, "extra": 1}"#,
        )
        .unwrap();
        assert_eq!(m.threads, None);
        assert_eq!(m.host.as_deref(), Some("h"));
        assert_eq!(m.cpu_count, Some(4));
        assert!(m.merged_from.is_none());
        assert_eq!(m.parts().len(), 1);
    }

    #[test]
    fn merged_parts_are_the_merged_manifests() {
        let m: Manifest = serde_json::from_str(
            r#"{"merged_from": [{"host": "a", "started_utc": "x"}, {"host": "b"}]}"#,
        )
        .unwrap();
        let hosts: Vec<_> = m.parts().iter().map(|p| p.host.clone()).collect();
        assert_eq!(hosts, [Some("a".into()), Some("b".into())]);
    }
}

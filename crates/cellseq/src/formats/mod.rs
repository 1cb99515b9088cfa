//! Reading and writing instances and solutions.
//!
//! [`load_instance`] picks the reader from the extension (`.json`, `.sop`, `.pcglns`, `.pcgtsp`) or, failing
//! that, from the `TYPE:` header, and validates the result. Every file cellseq writes goes
//! through [`crate::files`] ([`crate::files::write_atomic`]).

pub mod json;
pub mod pcgtsp;
mod sections;
pub mod tsplib;

use crate::error::{Error, Result};
use crate::files::{read_text, write_atomic};
use crate::model::Instance;
use std::path::Path;

/// The instance formats cellseq reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// `cellseq-instance/1` JSON.
    Json,
    /// TSPLIB SOP.
    Sop,
    /// PCGLNS (integer PCGTSPLIB layout).
    Pcglns,
    /// PCGTSP (original PCGTSPLIB layout: float costs, node weights, `NODE_GROUP_SECTION`).
    Pcgtsp,
}

/// Guesses the format from the file name, then from the content.
pub fn detect(path: &Path, text: &str) -> Option<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
    {
        Some(e) if e == "json" => return Some(Format::Json),
        Some(e) if e == "sop" => return Some(Format::Sop),
        Some(e) if e == "pcglns" => return Some(Format::Pcglns),
        Some(e) if e == "pcgtsp" => return Some(Format::Pcgtsp),
        _ => {}
    }
    let head = text.trim_start();
    if head.starts_with('{') {
        return Some(Format::Json);
    }
    for line in text.lines().take(20) {
        if let Some((k, v)) = line.split_once(':')
            && k.trim().eq_ignore_ascii_case("TYPE")
        {
            match v.trim() {
                "SOP" => return Some(Format::Sop),
                "PCGLNS" => return Some(Format::Pcglns),
                "PCGTSP" => return Some(Format::Pcgtsp),
                _ => {}
            }
        }
    }
    None
}

/// Parses instance text in a known format (no validation).
pub fn parse_instance(file: &str, text: &str, format: Format) -> Result<Instance> {
    if text.trim().is_empty() {
        return Err(Error::invalid(file, "file is empty"));
    }
    match format {
        Format::Json => json::parse_instance(file, text),
        Format::Sop => tsplib::parse_sop(file, text),
        Format::Pcglns => tsplib::parse_pcglns(file, text),
        Format::Pcgtsp => pcgtsp::parse_pcgtsp(file, text),
    }
}

/// Loads and validates an instance file.
pub fn load_instance(path: &Path) -> Result<Instance> {
    let file = path.display().to_string();
    let text = read_text(path)?;
    let format = detect(path, &text).ok_or_else(|| {
        Error::invalid(
            &file,
            "unknown instance format (expected .json, .sop, .pcglns or .pcgtsp)",
        )
    })?;
    let inst = parse_instance(&file, &text, format)?;
    crate::validate::validate(&inst, &file)?;
    Ok(inst)
}

/// Saves an instance as `cellseq-instance/1` JSON (atomically).
pub fn save_instance(path: &Path, inst: &Instance) -> Result<()> {
    write_atomic(path, json::instance_to_json(inst).as_bytes())
}

/// The name an instance file is known by in `bks.csv`: the file name without its extension.
pub fn stem_name(path: &Path) -> String {
    let name = path.file_name().and_then(|s| s.to_str()).unwrap_or("");
    for ext in [".json", ".sop", ".pcglns", ".pcgtsp"] {
        if let Some(s) = name.strip_suffix(ext) {
            return s.to_string();
        }
    }
    name.to_string()
}

/// Best-known value and whether it is proven optimal, from a `bks.csv` beside the file.
pub fn best_known(path: &Path) -> Option<(f64, bool)> {
    let dir = path.parent()?;
    let bks = dir.join("bks.csv");
    let mut rdr = csv::Reader::from_path(bks).ok()?;
    let headers = rdr.headers().ok()?.clone();
    let col = |n: &str| headers.iter().position(|h| h == n);
    let (name_c, best_c) = (col("name")?, col("best_known")?);
    let proven_c = col("proven_optimal");
    let stem = stem_name(path);
    for rec in rdr.records().flatten() {
        if rec.get(name_c) == Some(stem.as_str()) {
            let v: f64 = rec.get(best_c)?.trim().parse().ok()?;
            let proven = proven_c
                .and_then(|c| rec.get(c))
                .is_some_and(|p| p.trim() == "true");
            return Some((v, proven));
        }
    }
    None
}

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
use crate::model::{Cell, CostMatrix, Instance, Metadata, Mode};
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

/// Best-known value and whether it is proven optimal, from a `bks.csv` beside the file; none
/// when there is no such file or row, or when the row's value is not a finite number ≥ 0
/// ([`best_known_checked`] tells why).
pub fn best_known(path: &Path) -> Option<(f64, bool)> {
    best_known_checked(path).ok().flatten()
}

/// Largest `bks.csv` read (64 MiB; the shipped ones hold a few KB).
pub const MAX_BKS_BYTES: u64 = 64 << 20;

/// [`best_known`], with an error naming `bks.csv` and the line when the instance's row holds
/// a value that is not a finite number ≥ 0 (`NaN`, `inf`, `-3`, `x`): such a value would
/// print as a gap of NaN %. No file, no readable header or no row for the instance: `Ok(None)`.
pub fn best_known_checked(path: &Path) -> Result<Option<(f64, bool)>> {
    let Some(dir) = path.parent() else {
        return Ok(None);
    };
    let bks = dir.join("bks.csv");
    let Ok(meta) = std::fs::metadata(&bks) else {
        return Ok(None);
    };
    if !meta.is_file() || meta.len() > MAX_BKS_BYTES {
        return Err(Error::invalid(
            bks.display().to_string(),
            format!("not a regular file of at most {MAX_BKS_BYTES} bytes"),
        ));
    }
    let Ok(mut rdr) = csv::Reader::from_path(&bks) else {
        return Ok(None);
    };
    let Ok(headers) = rdr.headers().cloned() else {
        return Ok(None);
    };
    let col = |n: &str| headers.iter().position(|h| h == n);
    let (Some(name_c), Some(best_c)) = (col("name"), col("best_known")) else {
        return Ok(None);
    };
    let proven_c = col("proven_optimal");
    let stem = stem_name(path);
    for rec in rdr.records().flatten() {
        if rec.get(name_c) != Some(stem.as_str()) {
            continue;
        }
        let text = rec.get(best_c).unwrap_or("").trim();
        let v = text
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v >= 0.0);
        let Some(v) = v else {
            let line = rec.position().map_or(0, |p| p.line() as usize);
            return Err(Error::parse(
                bks.display().to_string(),
                line,
                format!("best_known of '{stem}' is '{text}', not a finite number >= 0"),
            ));
        };
        let proven = proven_c
            .and_then(|c| rec.get(c))
            .is_some_and(|p| p.trim() == "true");
        return Ok(Some((v, proven)));
    }
    Ok(None)
}

impl Instance {
    /// An instance given by an `n × n` cost matrix (row-major: `costs[a * n + b]` is the cost
    /// of cutting cell `b` right after cell `a`) and precedence pairs `(before, after)` of
    /// 0-based cell indices: one mode per cell, an open path with no fixed first or last cell
    /// (TSPLIB's SOP fixes both: give them as precedence). Cells are named `1`…`n`. Validated
    /// like a file: costs finite, in 0..=10¹², precedence acyclic and in range.
    pub fn from_matrix(
        name: &str,
        n: usize,
        costs: Vec<f64>,
        precedence: &[(usize, usize)],
    ) -> Result<Instance> {
        Instance::from_mode_matrix(name, &vec![1; n], costs, precedence)
    }

    /// The generalized form of [`Instance::from_matrix`]: cell `i` has `modes[i]` modes (the
    /// ways to cut it: a direction, a start point), the matrix's nodes are the modes of every
    /// cell, cell by cell (`modes.iter().sum()` nodes in all), and a sequence visits each cell
    /// once in one of its modes.
    pub fn from_mode_matrix(
        name: &str,
        modes: &[usize],
        costs: Vec<f64>,
        precedence: &[(usize, usize)],
    ) -> Result<Instance> {
        let size: usize = modes.iter().sum();
        if modes.is_empty() || modes.contains(&0) {
            return Err(Error::invalid(name, "every cell needs at least one mode"));
        }
        if size.checked_mul(size) != Some(costs.len()) {
            return Err(Error::invalid(
                name,
                format!(
                    "the cost matrix has {} entries; {size} modes need {size} x {size}",
                    costs.len()
                ),
            ));
        }
        let cells = modes
            .iter()
            .enumerate()
            .map(|(i, &k)| Cell::new((i + 1).to_string(), "", vec![Mode::default(); k]))
            .collect();
        let inst = Instance {
            name: name.to_string(),
            meta: Metadata {
                generator: Some("matrix".into()),
                ..Default::default()
            },
            cells,
            precedence: precedence.to_vec(),
            matrix: Some(CostMatrix { size, costs }),
            ..Instance::default()
        };
        crate::validate::validate(&inst, name)?;
        Ok(inst)
    }
}

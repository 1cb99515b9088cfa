//! TSPLIB-style text split into its parts — header `KEY: VALUE` pairs and named sections of
//! numbered lines — and the header checks the SOP, PCGLNS and PCGTSP readers share.

use super::tsplib::{MAX_NODES_ENV, max_nodes_checked};
use crate::error::{Error, Result};

/// Numbered lines (1-based line number, trimmed text).
pub(crate) type Lines<'a> = Vec<(usize, &'a str)>;

/// A file's header and sections.
pub(crate) struct Parts<'a> {
    /// `(line, KEY upper-cased, value)` in file order.
    header: Vec<(usize, String, &'a str)>,
    /// The sections in file order, each with its lines.
    sections: Vec<(&'static str, Lines<'a>)>,
    /// The last line read (the `EOF` line, or the file's last line).
    pub(crate) last_line: usize,
}

impl Parts<'_> {
    /// A header field's line and value.
    pub(crate) fn get(&self, key: &str) -> Option<(usize, &str)> {
        self.header
            .iter()
            .find(|(_, k, _)| k == key)
            .map(|(l, _, v)| (*l, *v))
    }
    /// The lines of the first section called `name`.
    pub(crate) fn section(&self, name: &str) -> Option<&Lines<'_>> {
        self.sections
            .iter()
            .find(|(k, _)| *k == name)
            .map(|(_, l)| l)
    }
}

/// Splits a text into header pairs and the sections `names` (a line starting with one of them
/// opens it), up to an `EOF` line. With `unique`, a section that appears twice is an error;
/// without, the first one counts.
pub(crate) fn split<'a>(
    file: &str,
    text: &'a str,
    names: &[&'static str],
    unique: bool,
) -> Result<Parts<'a>> {
    let mut parts = Parts {
        header: Vec::new(),
        sections: Vec::new(),
        last_line: 1,
    };
    for (i, raw) in text.lines().enumerate() {
        let ln = i + 1;
        parts.last_line = ln;
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        if line == "EOF" {
            break;
        }
        let key = line.split([':', ' ', '\t']).next().unwrap_or("");
        if let Some(&name) = names.iter().find(|s| **s == key) {
            if unique && parts.sections.iter().any(|(k, _)| *k == name) {
                return Err(Error::parse(file, ln, format!("{name} appears twice")));
            }
            parts.sections.push((name, Vec::new()));
            continue;
        }
        if let Some((_, lines)) = parts.sections.last_mut() {
            lines.push((ln, line));
        } else if let Some((k, v)) = line.split_once(':') {
            parts
                .header
                .push((ln, k.trim().to_ascii_uppercase(), v.trim()));
        } else {
            return Err(Error::parse(
                file,
                ln,
                format!("expected 'KEY: VALUE' or a section name, found '{line}'"),
            ));
        }
    }
    Ok(parts)
}

/// A finite number `t` on line `ln` (`what` names it in the error).
pub(crate) fn number(file: &str, ln: usize, t: &str, what: &dyn Fn() -> String) -> Result<f64> {
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(Error::parse(
            file,
            ln,
            format!("expected a number for {}, found '{t}'", what()),
        )),
    }
}

/// A header field that must be a positive integer: its line and value.
pub(crate) fn positive(file: &str, p: &Parts, key: &str) -> Result<(usize, usize)> {
    let (ln, v) = p
        .get(key)
        .ok_or_else(|| Error::parse(file, 1, format!("missing header field {key}")))?;
    let n = v.parse::<usize>().ok().filter(|&d| d > 0).ok_or_else(|| {
        Error::parse(
            file,
            ln,
            format!("{key} must be a positive integer, found '{v}'"),
        )
    })?;
    Ok((ln, n))
}

/// Refuses a `TYPE` other than the `accepted` ones (the first is named in the error).
pub(crate) fn check_type(file: &str, p: &Parts, accepted: &[&str]) -> Result<()> {
    if let Some((ln, t)) = p.get("TYPE")
        && !accepted.contains(&t)
    {
        return Err(Error::parse(
            file,
            ln,
            format!("TYPE is '{t}', expected {}", accepted[0]),
        ));
    }
    Ok(())
}

/// Refuses edge weights other than an explicit full matrix.
pub(crate) fn check_explicit(file: &str, p: &Parts) -> Result<()> {
    if let Some((ln, v)) = p.get("EDGE_WEIGHT_TYPE")
        && v != "EXPLICIT"
    {
        return Err(Error::parse(
            file,
            ln,
            format!("EDGE_WEIGHT_TYPE {v} is not supported (EXPLICIT only)"),
        ));
    }
    if let Some((ln, v)) = p.get("EDGE_WEIGHT_FORMAT")
        && v != "FULL_MATRIX"
    {
        return Err(Error::parse(
            file,
            ln,
            format!("EDGE_WEIGHT_FORMAT {v} is not supported (FULL_MATRIX only)"),
        ));
    }
    Ok(())
}

/// Refuses a matrix dimension above [`max_nodes`], naming the memory it would take.
pub(crate) fn check_dimension(file: &str, ln: usize, dim: usize) -> Result<()> {
    let limit = max_nodes_checked()?;
    if dim > limit {
        return Err(Error::parse(
            file,
            ln,
            format!(
                "DIMENSION {dim} is above the limit of {limit} nodes (the matrix would take \
                 {:.1} GB); set {MAX_NODES_ENV} to raise it",
                8.0 * (dim as f64) * (dim as f64) / 1e9
            ),
        ));
    }
    Ok(())
}

/// The instance name: the file name without the first of `suffixes` it ends with, or the
/// `NAME` field when that leaves nothing.
pub(crate) fn instance_name(p: &Parts, file: &str, suffixes: &[&str]) -> String {
    let stem = std::path::Path::new(file)
        .file_name()
        .and_then(|s| s.to_str())
        .unwrap_or(file);
    let stem = suffixes
        .iter()
        .find_map(|s| stem.strip_suffix(s))
        .unwrap_or(stem);
    if stem.is_empty() {
        p.get("NAME")
            .map(|(_, v)| v.to_string())
            .unwrap_or_default()
    } else {
        stem.to_string()
    }
}

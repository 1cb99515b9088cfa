//! Native JSON formats: `cellseq-instance/1` and `cellseq-solution/1` (see `docs/format.md`).

use crate::checker::Report;
use crate::error::{Error, Result};
use crate::model::{Cell, CostMatrix, Instance, Machine, Metadata, Sequence, Tool, Visit};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Format tag of instance files.
pub const INSTANCE_FORMAT: &str = "cellseq-instance/1";
/// Format tag of solution files.
pub const SOLUTION_FORMAT: &str = "cellseq-solution/1";

/// A visit as written in files: the cell's id and the 0-based mode index.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VisitRef {
    /// Cell id.
    pub cell: String,
    /// 0-based mode index.
    pub mode: usize,
}

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct InstanceFile {
    format: String,
    name: String,
    #[serde(default)]
    meta: Metadata,
    #[serde(default)]
    machine: Machine,
    #[serde(default)]
    tools: Vec<Tool>,
    cells: Vec<Cell>,
    #[serde(default)]
    precedence: Vec<(String, String)>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    as_given: Option<Vec<VisitRef>>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "matrix_rows::deserialize"
    )]
    matrix: Option<Vec<Vec<f64>>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    first: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    last: Option<String>,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    closed: bool,
}

/// Reads the `matrix` field row by row and refuses an entry outside
/// 0..=[`crate::validate::MAX_MATRIX_COST`] as it is read, so the error carries its line and
/// column (negative entries are not TSPLIB's −1 precedence marks here: JSON instances state
/// precedence in `precedence`).
mod matrix_rows {
    use serde::Deserializer;
    use serde::de::{DeserializeSeed, Error, SeqAccess, Visitor};
    use std::fmt;

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Vec<Vec<f64>>>, D::Error> {
        d.deserialize_option(Opt)
    }

    struct Opt;
    impl<'de> Visitor<'de> for Opt {
        type Value = Option<Vec<Vec<f64>>>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("a matrix (an array of rows of numbers) or null")
        }
        fn visit_none<E: Error>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_unit<E: Error>(self) -> Result<Self::Value, E> {
            Ok(None)
        }
        fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            d.deserialize_seq(Rows).map(Some)
        }
    }

    struct Rows;
    impl<'de> Visitor<'de> for Rows {
        type Value = Vec<Vec<f64>>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str("an array of matrix rows")
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Self::Value, A::Error> {
            let mut rows = Vec::new();
            while let Some(row) = a.next_element_seed(Row(rows.len()))? {
                rows.push(row);
            }
            Ok(rows)
        }
    }

    /// Row `.0` (0-based).
    struct Row(usize);
    impl<'de> DeserializeSeed<'de> for Row {
        type Value = Vec<f64>;
        fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
            d.deserialize_seq(self)
        }
    }
    impl<'de> Visitor<'de> for Row {
        type Value = Vec<f64>;
        fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
            write!(f, "matrix row {} as an array of numbers", self.0 + 1)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> Result<Self::Value, A::Error> {
            let max = crate::validate::MAX_MATRIX_COST;
            let mut row = Vec::new();
            while let Some(v) = a.next_element::<f64>()? {
                if !(0.0..=max).contains(&v) {
                    return Err(A::Error::custom(format!(
                        "matrix entry ({}, {}) is {}: entries must lie in 0..={max:e} \
                         (precedence goes in \"precedence\", not as -1 entries)",
                        self.0 + 1,
                        row.len() + 1,
                        crate::validate::show(v)
                    )));
                }
                row.push(v);
            }
            Ok(row)
        }
    }
}

/// A solution file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolutionFile {
    /// `cellseq-solution/1`.
    pub format: String,
    /// Instance name.
    pub instance: String,
    /// Solver that produced it.
    #[serde(default)]
    pub solver: String,
    /// Seed used.
    #[serde(default)]
    pub seed: u64,
    /// Objective name.
    #[serde(default)]
    pub objective: String,
    /// The order of cells with their modes.
    pub sequence: Vec<VisitRef>,
    /// The checker's report, when written by cellseq.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub report: Option<Report>,
}

fn json_error(file: &str, text: &str, e: serde_json::Error) -> Error {
    let line = e.line().max(1);
    let at = text
        .lines()
        .nth(line - 1)
        .and_then(|l| l.get(e.column().saturating_sub(1)..))
        .unwrap_or("");
    let non_finite = ["NaN", "nan", "Infinity", "-Infinity", "inf", "-inf"]
        .iter()
        .any(|w| at.starts_with(w));
    let msg = if non_finite {
        format!("non-finite number (NaN or infinity) is not allowed: {e}")
    } else {
        e.to_string()
    };
    Error::parse(file, line, msg)
}

/// Parses an instance from JSON text.
pub fn parse_instance(file: &str, text: &str) -> Result<Instance> {
    let f: InstanceFile = serde_json::from_str(text).map_err(|e| json_error(file, text, e))?;
    if f.format != INSTANCE_FORMAT {
        return Err(Error::invalid(
            file,
            format!("format is '{}', expected '{INSTANCE_FORMAT}'", f.format),
        ));
    }
    let mut index: HashMap<&str, usize> = HashMap::new();
    for (i, c) in f.cells.iter().enumerate() {
        if index.insert(c.id.as_str(), i).is_some() {
            return Err(Error::invalid(
                file,
                format!("duplicate cell id '{}'", c.id),
            ));
        }
    }
    let look = |id: &str, what: &str| -> Result<usize> {
        index
            .get(id)
            .copied()
            .ok_or_else(|| Error::invalid(file, format!("{what} refers to unknown cell '{id}'")))
    };
    let mut precedence = Vec::with_capacity(f.precedence.len());
    for (a, b) in &f.precedence {
        precedence.push((look(a, "precedence edge")?, look(b, "precedence edge")?));
    }
    let as_given = match &f.as_given {
        Some(v) => Some(
            v.iter()
                .map(|r| Ok(Visit::new(look(&r.cell, "as_given")?, r.mode)))
                .collect::<Result<Sequence>>()?,
        ),
        None => None,
    };
    let first = f.first.as_deref().map(|id| look(id, "first")).transpose()?;
    let last = f.last.as_deref().map(|id| look(id, "last")).transpose()?;
    let matrix = match &f.matrix {
        Some(rows) => {
            let size = rows.len();
            if let Some(r) = rows.iter().position(|r| r.len() != size) {
                return Err(Error::invalid(
                    file,
                    format!(
                        "matrix row {} has {} entries, expected {size}",
                        r + 1,
                        rows[r].len()
                    ),
                ));
            }
            Some(CostMatrix {
                size,
                costs: rows.iter().flatten().copied().collect(),
            })
        }
        None => None,
    };
    Ok(Instance {
        name: f.name,
        meta: f.meta,
        machine: f.machine,
        tools: f.tools,
        cells: f.cells,
        precedence,
        as_given,
        matrix,
        first,
        last,
        closed: f.closed,
    })
}

/// Writes an instance as pretty JSON text.
pub fn instance_to_json(inst: &Instance) -> String {
    let id = |i: usize| inst.cells[i].id.clone();
    let f = InstanceFile {
        format: INSTANCE_FORMAT.into(),
        name: inst.name.clone(),
        meta: inst.meta.clone(),
        machine: inst.machine.clone(),
        tools: inst.tools.clone(),
        cells: inst.cells.clone(),
        precedence: inst
            .precedence
            .iter()
            .map(|&(a, b)| (id(a), id(b)))
            .collect(),
        as_given: inst.as_given.as_ref().map(|s| to_refs(inst, s)),
        matrix: inst
            .matrix
            .as_ref()
            .map(|m| m.costs.chunks(m.size).map(|r| r.to_vec()).collect()),
        first: inst.first.map(id),
        last: inst.last.map(id),
        closed: inst.closed,
    };
    let mut s = serde_json::to_string_pretty(&f).expect("instance serializes");
    s.push('\n');
    s
}

/// Converts a sequence to id-based visits.
pub fn to_refs(inst: &Instance, seq: &Sequence) -> Vec<VisitRef> {
    seq.iter()
        .map(|v| VisitRef {
            cell: inst.cells[v.cell].id.clone(),
            mode: v.mode,
        })
        .collect()
}

/// Resolves id-based visits against an instance.
pub fn from_refs(inst: &Instance, refs: &[VisitRef], file: &str) -> Result<Sequence> {
    let index = inst.cell_index();
    refs.iter()
        .map(|r| {
            index
                .get(r.cell.as_str())
                .map(|&c| Visit::new(c, r.mode))
                .ok_or_else(|| {
                    Error::invalid(file, format!("solution names unknown cell '{}'", r.cell))
                })
        })
        .collect()
}

/// Parses a solution file's text.
pub fn parse_solution(file: &str, text: &str) -> Result<SolutionFile> {
    let s: SolutionFile = serde_json::from_str(text).map_err(|e| json_error(file, text, e))?;
    if s.format != SOLUTION_FORMAT {
        return Err(Error::invalid(
            file,
            format!("format is '{}', expected '{SOLUTION_FORMAT}'", s.format),
        ));
    }
    Ok(s)
}

/// Writes a solution as pretty JSON text.
pub fn solution_to_json(s: &SolutionFile) -> String {
    let mut t = serde_json::to_string_pretty(s).expect("solution serializes");
    t.push('\n');
    t
}

//! The tidy results and trace tables: row types, crash-safe appending, reading with repair of
//! a torn last line, and merging of shards.
//!
//! Only columns whose names start with `wall_` hold wall-clock measurements; every other column
//! is a function of the plan alone when the budget counts evaluations.

use cellseq::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::fs::File;
use std::io::Write;
use std::path::{Path, PathBuf};

/// One trial, one row of `results.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Row {
    /// Idempotency key of the trial.
    pub run_key: String,
    /// Position of the trial in plan order.
    pub trial: usize,
    /// Instance id.
    pub instance: String,
    /// Generator (or source format) of the instance.
    pub generator: String,
    /// Generator parameters, `k=v;k=v` (all values, defaults included).
    pub gen_params: String,
    /// Number of cells.
    pub n: usize,
    /// Number of distinct tools the cells use.
    pub tools: usize,
    /// Precedence density (transitive closure / n(n-1)/2).
    pub precedence_density: f64,
    /// Solver registry name.
    pub solver: String,
    /// Solver configuration id.
    pub solver_id: String,
    /// Solver parameters, `k=v;k=v` (defaults included).
    pub params: String,
    /// Replicate number.
    pub replicate: u32,
    /// Trial seed.
    pub seed: u64,
    /// Budget label.
    pub budget: String,
    /// Objective name.
    pub objective: String,
    /// True when the solver returned a sequence the checker accepted.
    pub feasible: bool,
    /// Error message of a failed or refused trial.
    pub error: String,
    /// Objective value (checker).
    pub cost: Option<f64>,
    /// Air length, mm.
    pub air_length: Option<f64>,
    /// Total path length (cut + air), mm.
    pub path_length: Option<f64>,
    /// Lifts.
    pub lifts: Option<u64>,
    /// Tool changes.
    pub tool_changes: Option<u64>,
    /// Machining time, s.
    pub machining_time: Option<f64>,
    /// Objective value of the as-given order.
    pub as_given_cost: Option<f64>,
    /// Objective reduction against as-given, %.
    pub reduction_pct: Option<f64>,
    /// Air-length reduction against as-given, %.
    pub air_reduction_pct: Option<f64>,
    /// Total-path-length reduction against as-given, %.
    pub path_reduction_pct: Option<f64>,
    /// Machining-time reduction against as-given, %.
    pub time_reduction_pct: Option<f64>,
    /// Best-known value (bks.csv beside the instance file).
    pub best_known: Option<f64>,
    /// Gap to the best-known value, %.
    pub gap_bks_pct: Option<f64>,
    /// A lower bound (the solver's own, or a proven-optimal best-known value).
    pub lower_bound: Option<f64>,
    /// Gap to the lower bound, %.
    pub gap_lb_pct: Option<f64>,
    /// The solver proved optimality.
    pub proven_optimal: bool,
    /// Counted evaluations.
    pub evaluations: u64,
    /// Wall-clock seconds of the trial.
    pub wall_elapsed_s: f64,
}

/// One point of an anytime trace, a row of `traces.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TraceRow {
    /// Trial key.
    pub run_key: String,
    /// Trial position.
    pub trial: usize,
    /// Instance id.
    pub instance: String,
    /// Solver configuration id.
    pub solver_id: String,
    /// Replicate.
    pub replicate: u32,
    /// Evaluations when the improvement was found.
    pub evaluations: u64,
    /// Wall-clock seconds since the trial started.
    pub wall_elapsed_s: f64,
    /// Best cost so far.
    pub best: f64,
}

/// One layer of one trial, a row of `layers.csv` (see [`super::layers`]): what the moves into the
/// layer's cells and their cutting cost, beside the same figures of the as-given order.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct LayerRow {
    /// Trial key.
    pub run_key: String,
    /// Trial position.
    pub trial: usize,
    /// Instance id.
    pub instance: String,
    /// Solver configuration id.
    pub solver_id: String,
    /// Replicate.
    pub replicate: u32,
    /// Layer index (0 = top).
    pub layer: u32,
    /// Cells of the layer.
    pub cells: usize,
    /// Length cut in the layer's cells (mm).
    pub cut_length: f64,
    /// Air length of the moves into the layer's cells (mm).
    pub air_length: f64,
    /// Cut + air (mm).
    pub path_length: f64,
    /// Lifts into the layer's cells.
    pub lifts: u64,
    /// Tool changes into the layer's cells.
    pub tool_changes: u64,
    /// Machining time of the layer (s).
    pub machining_time: f64,
    /// The as-given order's path length in this layer (mm).
    pub as_given_path_length: Option<f64>,
    /// The as-given order's lifts into this layer.
    pub as_given_lifts: Option<u64>,
    /// The as-given order's machining time of this layer (s).
    pub as_given_machining_time: Option<f64>,
}

/// One instance of a campaign, a row of `instances.csv`: its tools and how the cells are
/// spread over them (paper 002: tool groups chosen, cells per tool).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct InstanceRow {
    /// Instance id.
    pub instance: String,
    /// Generator or source format.
    pub generator: String,
    /// Number of cells.
    pub n: usize,
    /// Tools used.
    pub tools: usize,
    /// Cells per tool, `TOOL:count` separated by spaces, in the instance's tool order.
    pub cells_per_tool: String,
    /// Layers present.
    pub layers: usize,
    /// The instance's comment (e.g. the panel generator's tool-group choice).
    pub comment: String,
}

/// Serialises rows to CSV bytes (no header).
pub fn to_csv_bytes<T: Serialize>(rows: &[T]) -> Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(false)
        .from_writer(Vec::new());
    for r in rows {
        w.serialize(r)
            .map_err(|e| Error::invalid("<csv>", e.to_string()))?;
    }
    w.into_inner()
        .map_err(|e| Error::invalid("<csv>", e.to_string()))
}

/// The header line of a row type.
pub fn header<T: Serialize + Default>() -> Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(true)
        .from_writer(Vec::new());
    w.serialize(T::default())
        .map_err(|e| Error::invalid("<csv>", e.to_string()))?;
    let bytes = w
        .into_inner()
        .map_err(|e| Error::invalid("<csv>", e.to_string()))?;
    let end = bytes
        .iter()
        .position(|&b| b == b'\n')
        .map(|p| p + 1)
        .unwrap_or(bytes.len());
    Ok(bytes[..end].to_vec())
}

impl Default for Row {
    fn default() -> Self {
        Row {
            run_key: String::new(),
            trial: 0,
            instance: String::new(),
            generator: String::new(),
            gen_params: String::new(),
            n: 0,
            tools: 0,
            precedence_density: 0.0,
            solver: String::new(),
            solver_id: String::new(),
            params: String::new(),
            replicate: 0,
            seed: 0,
            budget: String::new(),
            objective: String::new(),
            feasible: false,
            error: String::new(),
            cost: None,
            air_length: None,
            path_length: None,
            lifts: None,
            tool_changes: None,
            machining_time: None,
            as_given_cost: None,
            reduction_pct: None,
            air_reduction_pct: None,
            path_reduction_pct: None,
            time_reduction_pct: None,
            best_known: None,
            gap_bks_pct: None,
            lower_bound: None,
            gap_lb_pct: None,
            proven_optimal: false,
            evaluations: 0,
            wall_elapsed_s: 0.0,
        }
    }
}

impl Default for TraceRow {
    fn default() -> Self {
        TraceRow {
            run_key: String::new(),
            trial: 0,
            instance: String::new(),
            solver_id: String::new(),
            replicate: 0,
            evaluations: 0,
            wall_elapsed_s: 0.0,
            best: 0.0,
        }
    }
}

/// Reads a table, keeping only complete, well-formed records (a torn last line from a killed
/// process is dropped). Returns the rows and whether anything was dropped.
pub fn read_lenient<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<(Vec<T>, bool)> {
    let file = path.display().to_string();
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok((Vec::new(), false)),
        Err(e) => return Err(Error::io(&file, e)),
    };
    // only whole lines count: anything after the last newline was never completed
    let end = bytes
        .iter()
        .rposition(|&b| b == b'\n')
        .map(|p| p + 1)
        .unwrap_or(0);
    let mut dropped = end != bytes.len();
    let mut rdr = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(&bytes[..end]);
    let mut out = Vec::new();
    for rec in rdr.deserialize::<T>() {
        match rec {
            Ok(r) => out.push(r),
            Err(_) => dropped = true,
        }
    }
    Ok((out, dropped))
}

/// Reads a table strictly: any malformed record is an error naming the file and line.
pub fn read_strict<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<Vec<T>> {
    let file = path.display().to_string();
    let mut rdr = csv::Reader::from_path(path).map_err(|e| Error::invalid(&file, e.to_string()))?;
    let mut out = Vec::new();
    for rec in rdr.deserialize::<T>() {
        match rec {
            Ok(r) => out.push(r),
            Err(e) => {
                let line = e.position().map(|p| p.line() as usize).unwrap_or(0);
                return Err(Error::parse(&file, line, e.to_string()));
            }
        }
    }
    Ok(out)
}

/// Writes a whole table atomically (header + rows).
pub fn write_table<T: Serialize + Default>(path: &Path, rows: &[T]) -> Result<()> {
    let mut bytes = header::<T>()?;
    bytes.extend(to_csv_bytes(rows)?);
    cellseq::files::write_atomic(path, &bytes)
}

/// An append-only table file: each call writes whole records and flushes.
pub struct Appender {
    file: File,
    name: String,
}

impl Appender {
    /// Opens (creating with a header when new or empty) for appending. A symbolic link or any
    /// other non-regular file at `path` is refused, never followed.
    pub fn open<T: Serialize + Default>(path: &Path) -> Result<Appender> {
        let name = path.display().to_string();
        let (mut file, fresh) = cellseq::files::open_append(path)?;
        if fresh {
            file.write_all(&header::<T>()?)
                .map_err(|e| Error::io(&name, e))?;
            file.flush().map_err(|e| Error::io(&name, e))?;
        }
        Ok(Appender { file, name })
    }
    /// Appends rows in one write and flushes.
    pub fn append<T: Serialize>(&mut self, rows: &[T]) -> Result<()> {
        let bytes = to_csv_bytes(rows)?;
        self.file
            .write_all(&bytes)
            .map_err(|e| Error::io(&self.name, e))?;
        self.file.flush().map_err(|e| Error::io(&self.name, e))?;
        Ok(())
    }
}

/// File names of a run, for a whole campaign or one shard.
#[derive(Debug, Clone)]
pub struct OutFiles {
    /// Results table.
    pub results: PathBuf,
    /// Trace table.
    pub traces: PathBuf,
    /// Per-layer table.
    pub layers: PathBuf,
    /// Instance table.
    pub instances: PathBuf,
    /// Manifest.
    pub manifest: PathBuf,
}

impl OutFiles {
    /// `results.csv`… or `results.shard-I-of-N.csv`….
    pub fn new(dir: &Path, shard: Option<(usize, usize)>) -> OutFiles {
        let suffix = match shard {
            None => String::new(),
            Some((i, n)) => format!(".shard-{i}-of-{n}"),
        };
        OutFiles {
            results: dir.join(format!("results{suffix}.csv")),
            traces: dir.join(format!("traces{suffix}.csv")),
            layers: dir.join(format!("layers{suffix}.csv")),
            instances: dir.join(format!("instances{suffix}.csv")),
            manifest: dir.join(format!("manifest{suffix}.json")),
        }
    }
}

impl OutFiles {
    /// Refuses a run directory where any of the files is a symbolic link or not a regular
    /// file: a link planted there would otherwise be read as this run's results (and its
    /// target's content copied into them).
    pub fn refuse_links(&self) -> Result<()> {
        for p in [
            &self.results,
            &self.traces,
            &self.layers,
            &self.instances,
            &self.manifest,
        ] {
            if let Ok(m) = std::fs::symlink_metadata(p) {
                let why = if m.file_type().is_symlink() {
                    "is a symbolic link; a run never reads or writes its tables through links \
                     (remove it or choose another --out directory)"
                } else if !m.is_file() {
                    "is not a regular file"
                } else {
                    continue;
                };
                return Err(Error::invalid(p.display().to_string(), why));
            }
        }
        Ok(())
    }
}

fn files_matching(dir: &Path, prefix: &str, ext: &str) -> Result<Vec<PathBuf>> {
    let name = dir.display().to_string();
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map_err(|e| Error::io(&name, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| {
            p.file_name()
                .and_then(|s| s.to_str())
                .is_some_and(|s| s.starts_with(prefix) && s.ends_with(ext) && !s.starts_with('.'))
        })
        .collect();
    out.sort();
    Ok(out)
}

/// Merges `results*.csv` and `traces*.csv` of the directories into `out`, dropping duplicate
/// run keys (the first occurrence wins) and sorting by trial. Returns (rows, duplicates dropped).
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(usize, usize)> {
    let mut rows: Vec<Row> = Vec::new();
    let mut traces: Vec<TraceRow> = Vec::new();
    let mut layers: Vec<LayerRow> = Vec::new();
    let mut insts: Vec<InstanceRow> = Vec::new();
    let mut manifests = Vec::new();
    for d in dirs {
        for f in files_matching(d, "results", ".csv")? {
            rows.extend(read_lenient::<Row>(&f)?.0);
        }
        for f in files_matching(d, "traces", ".csv")? {
            traces.extend(read_lenient::<TraceRow>(&f)?.0);
        }
        for f in files_matching(d, "layers", ".csv")? {
            layers.extend(read_lenient::<LayerRow>(&f)?.0);
        }
        for f in files_matching(d, "instances", ".csv")? {
            insts.extend(read_lenient::<InstanceRow>(&f)?.0);
        }
        for f in files_matching(d, "manifest", ".json")? {
            let text = cellseq::files::read_text(&f)?;
            let v: serde_json::Value = serde_json::from_str(&text)
                .map_err(|e| Error::invalid(f.display().to_string(), e.to_string()))?;
            manifests.push(v);
        }
    }
    let total = rows.len();
    let mut seen = BTreeSet::new();
    rows.retain(|r| seen.insert(r.run_key.clone()));
    let dups = total - rows.len();
    rows.sort_by_key(|r| r.trial);
    // traces: keep each key's points once (from the first file that had the key)
    let mut owner: std::collections::BTreeMap<String, usize> = Default::default();
    let mut keep = Vec::new();
    let mut file_of_point = 0usize;
    let mut last_key = String::new();
    for t in traces {
        if t.run_key != last_key {
            file_of_point += 1;
            last_key = t.run_key.clone();
        }
        let o = *owner.entry(t.run_key.clone()).or_insert(file_of_point);
        if o == file_of_point && seen.contains(&t.run_key) {
            keep.push(t);
        }
    }
    keep.sort_by_key(|t| t.trial);
    // layers: one row per (key, layer)
    let mut seen_layer = BTreeSet::new();
    layers.retain(|l| seen.contains(&l.run_key) && seen_layer.insert((l.run_key.clone(), l.layer)));
    layers.sort_by_key(|l| (l.trial, l.layer));
    std::fs::create_dir_all(out).map_err(|e| Error::io(out.display().to_string(), e))?;
    write_table(&out.join("results.csv"), &rows)?;
    write_table(&out.join("traces.csv"), &keep)?;
    if !layers.is_empty() {
        write_table(&out.join("layers.csv"), &layers)?;
    }
    let mut seen_inst = BTreeSet::new();
    insts.retain(|i| seen_inst.insert(i.instance.clone()));
    if !insts.is_empty() {
        write_table(&out.join("instances.csv"), &insts)?;
    }
    if let Some(first) = manifests.first() {
        let mut m = first.clone();
        m["merged_from"] = serde_json::Value::Array(manifests.clone());
        cellseq::files::write_atomic(
            &out.join("manifest.json"),
            serde_json::to_string_pretty(&m)
                .unwrap_or_default()
                .as_bytes(),
        )?;
    }
    Ok((rows.len(), dups))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn torn_line_is_dropped() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("r.csv");
        let mut a = Appender::open::<Row>(&p).unwrap();
        let r = Row {
            run_key: "k1".into(),
            cost: Some(1.5),
            ..Row::default()
        };
        a.append(std::slice::from_ref(&r)).unwrap();
        drop(a);
        let mut bytes = std::fs::read(&p).unwrap();
        bytes.extend_from_slice(b"k2,1,inst,gen");
        std::fs::write(&p, bytes).unwrap();
        let (rows, dropped) = read_lenient::<Row>(&p).unwrap();
        assert!(dropped);
        assert_eq!(rows, vec![r]);
    }
}

//! The cell-sequencing model: cells, modes, tools, machine, precedence and instances.
//!
//! A geometric instance (cells with entry/exit points cut on a machine) and a matrix instance
//! (TSPLIB SOP, PCGTSP: explicit costs between (cell, mode) pairs) are the same [`Instance`]
//! type; only [`Instance::matrix`] tells them apart. Solvers never look at that difference
//! directly: they go through `crate::cost::CostModel`.

use crate::geom::Point3;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::collections::HashMap;

/// The kind of machining step a cell belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[derive(Default)]
pub enum StepKind {
    /// Facing the top surface.
    Face,
    /// Outer contour of the part.
    OuterContour,
    /// Pocket roughing layer.
    PocketRough,
    /// Pocket floor or wall finishing.
    PocketFinish,
    /// Rib top.
    Rib,
    /// Wall groove.
    WallGroove,
    /// Flange or edge finishing.
    Flange,
    /// Hole or hole group.
    Hole,
    /// Engraving, marking, plotting.
    Engrave,
    /// Anything else.
    #[default]
    Other,
}

impl StepKind {
    /// All kinds, in declaration order.
    pub const ALL: [StepKind; 10] = [
        StepKind::Face,
        StepKind::OuterContour,
        StepKind::PocketRough,
        StepKind::PocketFinish,
        StepKind::Rib,
        StepKind::WallGroove,
        StepKind::Flange,
        StepKind::Hole,
        StepKind::Engrave,
        StepKind::Other,
    ];
    /// The kebab-case name used in files.
    pub fn name(self) -> &'static str {
        match self {
            StepKind::Face => "face",
            StepKind::OuterContour => "outer-contour",
            StepKind::PocketRough => "pocket-rough",
            StepKind::PocketFinish => "pocket-finish",
            StepKind::Rib => "rib",
            StepKind::WallGroove => "wall-groove",
            StepKind::Flange => "flange",
            StepKind::Hole => "hole",
            StepKind::Engrave => "engrave",
            StepKind::Other => "other",
        }
    }
    /// Parses a kebab-case name.
    pub fn parse(s: &str) -> Option<StepKind> {
        StepKind::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// One way to cut a cell: where the cutter enters and where it leaves.
///
/// Matrix instances carry modes without geometry (both points at the origin).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Mode {
    /// Entry (plunge) point.
    pub entry: Point3,
    /// Exit (retract) point.
    pub exit: Point3,
}

impl Mode {
    /// An open feature cut from `entry` to `exit`.
    pub fn new(entry: Point3, exit: Point3) -> Self {
        Self { entry, exit }
    }
    /// A closed contour started and ended at `p`.
    pub fn closed(p: Point3) -> Self {
        Self { entry: p, exit: p }
    }
    /// The same cut in the other direction.
    pub fn reversed(&self) -> Self {
        Self {
            entry: self.exit,
            exit: self.entry,
        }
    }
}

/// A machining cell: one tool, one depth, fixed entry/exit points per mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Cell {
    /// Unique id.
    pub id: String,
    /// Tool id (must name an entry of [`Instance::tools`] for geometric instances).
    #[serde(default)]
    pub tool: String,
    /// Step kind.
    #[serde(default)]
    pub step: StepKind,
    /// Layer index (0 = top).
    #[serde(default)]
    pub layer: u32,
    /// Depth z of the cell (mm).
    #[serde(default)]
    pub z: f64,
    /// Feature the cell belongs to (pocket, rib, contour, hole group).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feature: Option<String>,
    /// Setup / fixture id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setup: Option<String>,
    /// Length cut inside the cell (mm).
    #[serde(default)]
    pub cut_length: f64,
    /// Cutting feed override for this cell (mm/min).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feed: Option<f64>,
    /// Whether the cell may be cut in the opposite direction.
    #[serde(default)]
    pub reversible: bool,
    /// Candidate modes (at least one).
    pub modes: Vec<Mode>,
}

impl Cell {
    /// A cell with defaults for everything but id, tool and modes.
    pub fn new(id: impl Into<String>, tool: impl Into<String>, modes: Vec<Mode>) -> Self {
        Cell {
            id: id.into(),
            tool: tool.into(),
            step: StepKind::Other,
            layer: 0,
            z: 0.0,
            feature: None,
            setup: None,
            cut_length: 0.0,
            feed: None,
            reversible: false,
            modes,
        }
    }
}

/// A cutting tool.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tool {
    /// Unique id.
    pub id: String,
    /// Diameter (mm).
    pub diameter: f64,
    /// Optional human name.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Cutting feed of this tool (mm/min); the machine's default when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feed: Option<f64>,
}

/// The machine the cells are cut on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Machine {
    /// Home position; the path starts here.
    pub home: Point3,
    /// Tool-change position.
    pub tool_change: Point3,
    /// Clearance (safe) height for rapid moves.
    pub clearance: f64,
    /// Rapid feed (mm/min).
    pub rapid_feed: f64,
    /// Default cutting feed (mm/min).
    pub cut_feed: f64,
    /// Time of one tool change (s).
    pub tool_change_time: f64,
    /// Time per lift (retract + plunge overhead, s).
    pub lift_time: f64,
    /// Whether the path returns home at the end.
    pub return_home: bool,
    /// Same-tool moves between points at the same depth no farther apart than this (mm) are
    /// linked at cutting feed without a lift. 0 links only coincident points.
    pub link_distance: f64,
    /// Tool in the spindle at the start; loading a different first tool counts as a change.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub initial_tool: Option<String>,
    /// Material that stands in the way of at-depth links (islands, bosses): a same-depth move
    /// whose straight path crosses the inside of one of these areas, below its top, lifts
    /// whatever its length. Empty: links depend on depth and `link_distance` alone.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub keep_out: Vec<KeepOut>,
}

/// An axis-aligned area the tool centre cannot cross at depths below `top` (a boss or island
/// grown by the tool radius). Its boundary is free: a move may touch or follow it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct KeepOut {
    /// Lowest x of the area (mm).
    pub x0: f64,
    /// Lowest y of the area (mm).
    pub y0: f64,
    /// Highest x of the area (mm).
    pub x1: f64,
    /// Highest y of the area (mm).
    pub y1: f64,
    /// Height of the material's top: moves at z below it are blocked (mm).
    pub top: f64,
}

impl Default for Machine {
    fn default() -> Self {
        Machine {
            home: Point3::new(0.0, 0.0, 50.0),
            tool_change: Point3::new(0.0, 0.0, 50.0),
            clearance: 10.0,
            rapid_feed: 2000.0,
            cut_feed: 500.0,
            tool_change_time: 10.0,
            lift_time: 1.0,
            return_home: false,
            link_distance: 0.0,
            initial_tool: None,
            keep_out: Vec::new(),
        }
    }
}

/// Explicit asymmetric costs between (cell, mode) pairs.
///
/// Nodes are the modes of all cells, cell by cell in cell order, mode by mode within a cell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CostMatrix {
    /// Number of nodes.
    pub size: usize,
    /// Row-major `size × size` costs: `costs[a * size + b]` is the cost of going from node a to b.
    pub costs: Vec<f64>,
}

impl CostMatrix {
    /// Cost stored for arcs that precedence forbids (TSPLIB files mark them −1). Any cost at
    /// or above it is an arc no feasible sequence uses.
    pub const FORBIDDEN: f64 = 1.0e9;

    /// Cost from node `a` to node `b`.
    #[inline]
    pub fn get(&self, a: usize, b: usize) -> f64 {
        self.costs[a * self.size + b]
    }
}

/// Where an instance came from; generators record their parameters and seed here.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Metadata {
    /// Generator name (`panel`, `casing`, …) or source format (`tsplib-sop`, `pcglns`, `gcode`, …).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub generator: Option<String>,
    /// Generator parameters.
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, String>,
    /// Generator seed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Free-form comment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub comment: Option<String>,
}

/// A visit of a cell in a given mode (indices into the instance).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub struct Visit {
    /// Cell index.
    pub cell: usize,
    /// Mode index into the cell's modes.
    pub mode: usize,
}

impl Visit {
    /// Builds a visit.
    pub const fn new(cell: usize, mode: usize) -> Self {
        Visit { cell, mode }
    }
}

/// An order of cells, each with its mode.
pub type Sequence = Vec<Visit>;

/// What a sequence is scored by.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// Machining time in seconds (default for geometric instances).
    #[default]
    Time,
    /// Air (non-cutting) path length in mm.
    Air,
    /// The explicit matrix cost (matrix instances).
    Matrix,
}

impl Objective {
    /// Parses `time`, `air`, or `matrix`/`cost`.
    pub fn parse(s: &str) -> Option<Objective> {
        match s {
            "time" => Some(Objective::Time),
            "air" => Some(Objective::Air),
            "matrix" | "cost" => Some(Objective::Matrix),
            _ => None,
        }
    }
    /// Its name.
    pub fn name(self) -> &'static str {
        match self {
            Objective::Time => "time",
            Objective::Air => "air",
            Objective::Matrix => "matrix",
        }
    }
}

/// A complete problem instance.
///
/// `Instance::default()` is an empty geometric instance (default machine, no precedence, no
/// as-programmed order, no matrix, open path): builders fill in what they have with
/// `Instance { name, cells, .., ..Instance::default() }`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Instance {
    /// Instance name.
    pub name: String,
    /// Provenance.
    pub meta: Metadata,
    /// Machine parameters (ignored by matrix instances).
    pub machine: Machine,
    /// Tool library.
    pub tools: Vec<Tool>,
    /// Cells.
    pub cells: Vec<Cell>,
    /// Precedence edges `(a, b)`: cell a before cell b (cell indices).
    pub precedence: Vec<(usize, usize)>,
    /// The as-programmed order, when the instance has one.
    pub as_given: Option<Sequence>,
    /// Explicit costs (TSPLIB SOP, PCGTSP); `None` for geometric instances.
    pub matrix: Option<CostMatrix>,
    /// Cell that must come first, if any.
    pub first: Option<usize>,
    /// Cell that must come last, if any.
    pub last: Option<usize>,
    /// Matrix instances scored as a closed tour: the cost of returning from the last cell to
    /// the (fixed, single-mode) first cell is added (PCGLNS/PCGTSP convention).
    pub closed: bool,
}

impl Instance {
    /// Number of cells.
    pub fn n(&self) -> usize {
        self.cells.len()
    }
    /// True for explicit-matrix instances.
    pub fn is_matrix(&self) -> bool {
        self.matrix.is_some()
    }
    /// The objective used when none is asked for.
    pub fn default_objective(&self) -> Objective {
        if self.is_matrix() {
            Objective::Matrix
        } else {
            Objective::Time
        }
    }
    /// The same matrix instance travelled backwards: the cost matrix transposed, every
    /// precedence edge turned round, and the first and last cells swapped (a closed tour keeps
    /// its fixed first cell, and its edges out of that cell). A sequence of one maps to a
    /// sequence of the other of the same cost by [`Instance::reverse_sequence`]. An ant
    /// colony run on the twin builds its sequences from the other end, which draws it into
    /// other basins. `None` for geometric instances and for a closed tour with a last cell.
    pub fn reversed_matrix(&self) -> Option<Instance> {
        let m = self.matrix.as_ref()?;
        let keep_first = self.closed && self.first.is_some();
        if keep_first && self.last.is_some() {
            return None;
        }
        let k = m.size;
        let mut costs = vec![0.0; k * k];
        for a in 0..k {
            for b in 0..k {
                costs[b * k + a] = m.costs[a * k + b];
            }
        }
        let precedence = self
            .precedence
            .iter()
            .map(|&(a, b)| {
                if keep_first && Some(a) == self.first {
                    (a, b)
                } else {
                    (b, a)
                }
            })
            .collect();
        let (first, last) = if keep_first {
            (self.first, None)
        } else {
            (self.last, self.first)
        };
        Some(Instance {
            name: self.name.clone(),
            meta: self.meta.clone(),
            machine: self.machine.clone(),
            tools: self.tools.clone(),
            cells: self.cells.clone(),
            precedence,
            as_given: None,
            matrix: Some(CostMatrix { size: k, costs }),
            first,
            last,
            closed: self.closed,
        })
    }
    /// Maps a sequence of this instance to one of [`Instance::reversed_matrix`] and back (the
    /// map is its own inverse): the order reversed, with a closed tour's fixed first cell
    /// left in front.
    pub fn reverse_sequence(&self, seq: &[Visit]) -> Sequence {
        let keep_first =
            self.closed && self.first.is_some() && seq.first().map(|v| v.cell) == self.first;
        let mut out = seq.to_vec();
        if keep_first {
            out[1..].reverse();
        } else {
            out.reverse();
        }
        out
    }
    /// Total number of (cell, mode) pairs.
    pub fn total_modes(&self) -> usize {
        self.cells.iter().map(|c| c.modes.len()).sum()
    }
    /// Index of a cell by id.
    pub fn cell_index(&self) -> HashMap<&str, usize> {
        self.cells
            .iter()
            .enumerate()
            .map(|(i, c)| (c.id.as_str(), i))
            .collect()
    }
    /// Index of a tool by id.
    pub fn tool(&self, id: &str) -> Option<&Tool> {
        self.tools.iter().find(|t| t.id == id)
    }
    /// Precedence density: edges of the transitive closure over n(n−1)/2.
    pub fn precedence_density(&self) -> f64 {
        crate::precedence::closure_density(&crate::precedence::Dag::new(self.n(), &self.precedence))
    }
    /// Distinct tool ids used by the cells, in first-use order.
    pub fn used_tools(&self) -> Vec<&str> {
        let mut seen = Vec::new();
        for c in &self.cells {
            if !seen.contains(&c.tool.as_str()) {
                seen.push(c.tool.as_str());
            }
        }
        seen
    }
}

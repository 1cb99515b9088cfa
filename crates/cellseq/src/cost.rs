//! The solvers' view of an instance: O(1) arc costs between (cell, mode) pairs.
//!
//! [`CostModel`] flattens the modes of all cells into *nodes* and answers `start`, `arc` and
//! `finish` costs for the chosen [`Objective`], for geometric and matrix instances alike.
//! It is the solvers' incremental evaluator; the independent checker in [`crate::check()`]
//! recomputes everything from the raw instance without using this module.

use crate::geom::Point3;
use crate::model::{CostMatrix, Instance, Objective, Sequence};
use crate::precedence::Closure;
use crate::precedence::{Dag, topological_order};
use std::sync::OnceLock;

/// Up to this many cells (with precedence) [`CostModel::closure`] builds the transitive
/// closure as bitsets: 2·n²/8 bytes, 4 MiB at the limit.
pub const CLOSURE_MAX_CELLS: usize = 4096;

/// Geometry and machine data flattened for fast arc evaluation.
#[derive(Debug, Clone)]
struct Geo {
    entry: Vec<Point3>,
    exit: Vec<Point3>,
    clearance: f64,
    /// seconds per mm at rapid feed
    rapid_rate: f64,
    lift_time: f64,
    change_time: f64,
    link_distance: f64,
    tool_change: Point3,
    home: Point3,
    return_home: bool,
    initial_tool: Option<u32>,
    /// highest entry point of any node
    max_entry_z: f64,
    /// keep-out areas of at-depth links: x0, y0, x1, y1, top
    keep_out: Vec<[f64; 5]>,
}

/// Most nodes for which [`CostModel::least_arcs`] is computed on a matrix instance.
pub const LEAST_ARCS_MAX_NODES: usize = 2000;

/// The cheapest arc out of and into every node ([`CostModel::least_arcs`]).
#[derive(Debug, Clone)]
pub struct LeastArcs {
    /// Per node: the cheapest arc to a node of another cell (infinite with one cell).
    pub out: Vec<f64>,
    /// Per node: the cheapest arc from a node of another cell.
    pub inn: Vec<f64>,
}

impl LeastArcs {
    fn new(m: &CostModel) -> Self {
        let mut out = vec![f64::INFINITY; m.nodes()];
        let mut inn = vec![f64::INFINITY; m.nodes()];
        for a in 0..m.n() {
            for ma in 0..m.modes(a) {
                let na = m.node(a, ma);
                for b in (0..m.n()).filter(|&b| b != a) {
                    for mb in 0..m.modes(b) {
                        let nb = m.node(b, mb);
                        let v = m.arc(a, ma, b, mb);
                        out[na] = out[na].min(v);
                        inn[nb] = inn[nb].min(v);
                    }
                }
            }
        }
        LeastArcs { out, inn }
    }
}

/// Arc costs, mode layout, tools and precedence of an instance, ready for search.
#[derive(Debug, Clone)]
pub struct CostModel {
    objective: Objective,
    /// node offset of each cell; `offsets[n]` = number of nodes
    offsets: Vec<u32>,
    /// every cell has exactly one mode: node = cell, read without `offsets` in the hot paths
    one_mode: bool,
    /// cell of each node
    node_cell: Vec<u32>,
    /// tool index of each cell
    tools: Vec<u32>,
    /// seconds per mm of cutting, per cell
    cut_rate: Vec<f64>,
    /// the mode that cuts the same cell in the opposite direction, per node (itself if none)
    flip: Vec<u32>,
    /// Per node: the node that cuts the cell the other way in a reversed segment (see
    /// [`CostModel::turned`]), `u32::MAX` if none.
    turn: Vec<u32>,
    /// Per cell: x such that the reversed-segment mode of every mode m is `m ^ x` (the mode
    /// itself where [`CostModel::turned`] is `None`), or `u8::MAX` when no such x exists.
    turn_xor: Vec<u8>,
    reversible: Vec<bool>,
    constant: f64,
    matrix: Option<CostMatrix>,
    /// closed matrix tours return to this node
    return_node: Option<usize>,
    geo: Option<Geo>,
    /// precedence (transitive reduction where affordable)
    pub dag: Dag,
    /// the closure of `dag`, built on first use (see [`CostModel::closure`])
    closure: OnceLock<Option<Closure>>,
    /// the cheapest arcs out of and into every node, built on first use (see
    /// [`CostModel::least_arcs`])
    least_arcs: OnceLock<Option<LeastArcs>>,
    /// whether `dag` has a topological order (see [`CostModel::acyclic`])
    acyclic: bool,
}

impl CostModel {
    /// Builds the model of a validated instance for the given objective. A geometric
    /// objective on a matrix instance falls back to the matrix cost.
    pub fn new(inst: &Instance, objective: Objective) -> CostModel {
        let n = inst.n();
        let mut offsets = Vec::with_capacity(n + 1);
        let mut node_cell = Vec::with_capacity(inst.total_modes());
        let mut acc = 0u32;
        for (i, c) in inst.cells.iter().enumerate() {
            offsets.push(acc);
            acc += c.modes.len() as u32;
            node_cell.extend(std::iter::repeat_n(i as u32, c.modes.len()));
        }
        offsets.push(acc);
        let tool_ids = inst.used_tools();
        let tools: Vec<u32> = inst
            .cells
            .iter()
            .map(|c| tool_ids.iter().position(|t| *t == c.tool).unwrap_or(0) as u32)
            .collect();
        let m = &inst.machine;
        let cut_rate: Vec<f64> = inst
            .cells
            .iter()
            .map(|c| {
                let feed = c
                    .feed
                    .or_else(|| inst.tool(&c.tool).and_then(|t| t.feed))
                    .unwrap_or(m.cut_feed);
                60.0 / feed
            })
            .collect();
        let reversible: Vec<bool> = inst.cells.iter().map(|c| c.reversible).collect();
        let mut flip: Vec<u32> = (0..acc).collect();
        let objective = if inst.is_matrix() {
            Objective::Matrix
        } else if objective == Objective::Matrix {
            Objective::Time
        } else {
            objective
        };
        let (matrix, geo, constant) = if let Some(mx) = &inst.matrix {
            (Some(mx.clone()), None, 0.0)
        } else {
            let mut entry = Vec::with_capacity(acc as usize);
            let mut exit = Vec::with_capacity(acc as usize);
            for (i, c) in inst.cells.iter().enumerate() {
                for (k, md) in c.modes.iter().enumerate() {
                    entry.push(md.entry);
                    exit.push(md.exit);
                    if c.reversible
                        && let Some(j) = c.modes.iter().position(|o| *o == md.reversed())
                    {
                        flip[offsets[i] as usize + k] = offsets[i] + j as u32;
                    }
                }
            }
            let constant = if objective == Objective::Time {
                inst.cells
                    .iter()
                    .zip(&cut_rate)
                    .map(|(c, r)| c.cut_length * r)
                    .sum()
            } else {
                0.0
            };
            let max_entry_z = entry.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max);
            let geo = Geo {
                max_entry_z,
                keep_out: m
                    .keep_out
                    .iter()
                    .map(|k| [k.x0, k.y0, k.x1, k.y1, k.top])
                    .collect(),
                entry,
                exit,
                clearance: m.clearance,
                rapid_rate: 60.0 / m.rapid_feed,
                lift_time: m.lift_time,
                change_time: m.tool_change_time,
                link_distance: m.link_distance,
                tool_change: m.tool_change,
                home: m.home,
                return_home: m.return_home,
                initial_tool: m.initial_tool.as_ref().map(|t| {
                    tool_ids
                        .iter()
                        .position(|x| x == t)
                        .unwrap_or(u32::MAX as usize) as u32
                }),
            };
            (None, Some(geo), constant)
        };
        let mut edges = inst.precedence.clone();
        if let Some(f) = inst.first {
            edges.extend((0..n).filter(|&c| c != f).map(|c| (f, c)));
        }
        if let Some(l) = inst.last {
            edges.extend((0..n).filter(|&c| c != l).map(|c| (c, l)));
        }
        let dag = Dag::new(n, &edges).reduced(20_000);
        let acyclic = topological_order(&dag).is_ok();
        let return_node = if inst.closed && inst.is_matrix() {
            inst.first.map(|f| offsets[f] as usize)
        } else {
            None
        };
        let mut cm = CostModel {
            objective,
            return_node,
            one_mode: offsets.iter().enumerate().all(|(i, &o)| o as usize == i),
            offsets,
            node_cell,
            tools,
            cut_rate,
            flip,
            turn: Vec::new(),
            turn_xor: Vec::new(),
            reversible,
            constant,
            matrix,
            geo,
            dag,
            closure: OnceLock::new(),
            least_arcs: OnceLock::new(),
            acyclic,
        };
        cm.turn = (0..cm.nodes())
            .map(|nd| {
                let (cell, mode) = cm.cell_mode(nd);
                let t = if cm.reversible(cell)
                    && let Some(f) = cm.flipped(cell, mode)
                {
                    Some(f)
                } else if !cm.is_geometric() || cm.entry(nd) == cm.exit(nd) {
                    Some(mode)
                } else {
                    None
                };
                t.map_or(u32::MAX, |md| cm.node(cell, md) as u32)
            })
            .collect();
        cm.turn_xor = (0..cm.n())
            .map(|cell| {
                let k = cm.modes(cell);
                let x = cm.turned(cell, 0).unwrap_or(0);
                let fits =
                    x < u8::MAX as usize && (0..k).all(|md| cm.turned_or_same(cell, md) == md ^ x);
                if fits { x as u8 } else { u8::MAX }
            })
            .collect();
        cm
    }

    /// The mode of `cell` in a reversed segment as `mode ^ x` for every mode (`Some(x)`):
    /// x = 1 for a reversible stroke with two modes, 0 when no mode has a direction or none
    /// can be reversed; `None` when the modes do not pair up that way (use
    /// [`CostModel::turned`]).
    #[inline]
    pub fn turn_xor(&self, cell: usize) -> Option<u32> {
        let x = self.turn_xor[cell];
        (x != u8::MAX).then_some(x as u32)
    }

    /// The mode that cuts `cell` in the opposite direction when the cell sits in a reversed
    /// segment: its flipped mode when it is reversible, the same mode when the mode has no
    /// direction (entry = exit, or a matrix instance whose nodes carry no geometry), else
    /// `None`. A table lookup.
    #[inline]
    pub fn turned(&self, cell: usize, mode: usize) -> Option<usize> {
        let t = self.turn[self.node(cell, mode)];
        (t != u32::MAX).then(|| t as usize - self.offsets[cell] as usize)
    }

    /// [`CostModel::turned`], or `mode` itself where the cell cannot be cut the other way (what
    /// a reversal does to a cell).
    #[inline]
    pub fn turned_or_same(&self, cell: usize, mode: usize) -> usize {
        self.turned(cell, mode).unwrap_or(mode)
    }

    /// Whether the precedence, with the fixed first and last cells, admits an order at all.
    /// Always true for a validated instance ([`crate::validate::validate`] refuses cycles and
    /// first or last cells that contradict the precedence); solvers that would otherwise
    /// index past the end of a partial topological order check it first.
    pub fn acyclic(&self) -> bool {
        self.acyclic
    }

    /// The objective costs are expressed in.
    pub fn objective(&self) -> Objective {
        self.objective
    }
    /// Number of cells.
    #[inline]
    pub fn n(&self) -> usize {
        self.offsets.len() - 1
    }
    /// Number of nodes ((cell, mode) pairs).
    #[inline]
    pub fn nodes(&self) -> usize {
        *self.offsets.last().unwrap_or(&0) as usize
    }
    /// Adds `add` to the matrix arc from node `na` to node `nb` (nothing on geometric models):
    /// the penalised costs of `gls`, in a copy of the model. The closure and the cheapest arcs
    /// already cached stay as they were, so with `add >= 0` they are lower bounds of the new
    /// costs, not the costs themselves.
    pub fn add_to_arc(&mut self, na: usize, nb: usize, add: f64) {
        if let Some(m) = self.matrix.as_mut() {
            m.costs[na * m.size + nb] += add;
        }
    }
    /// The transitive closure of the precedence (ancestor and descendant bitsets), built on
    /// first use and shared by every search on this model; `None` without precedence or
    /// above [`CLOSURE_MAX_CELLS`] cells.
    pub fn closure(&self) -> Option<&Closure> {
        self.closure
            .get_or_init(|| {
                (self.n() <= CLOSURE_MAX_CELLS && !self.dag.is_empty())
                    .then(|| Closure::new(&self.dag))
                    .flatten()
            })
            .as_ref()
    }
    /// The cheapest arc out of and into every node, from and to the nodes of other cells
    /// (start and finish costs not included), built on first use and shared by every search
    /// on this model; `None` above [`LEAST_ARCS_MAX_NODES`] nodes (a quarter of that on
    /// geometric instances, whose arcs cost more to compute). O(nodes²) arc costs.
    pub fn least_arcs(&self) -> Option<&LeastArcs> {
        self.least_arcs
            .get_or_init(|| {
                let cap = if self.is_geometric() {
                    LEAST_ARCS_MAX_NODES / 4
                } else {
                    LEAST_ARCS_MAX_NODES
                };
                (self.nodes() <= cap).then(|| LeastArcs::new(self))
            })
            .as_ref()
    }
    /// Some cell has more than one mode (every cell has at least one: validation refuses
    /// a cell without modes, so this is "more nodes than cells", O(1)).
    #[inline]
    pub fn multimode(&self) -> bool {
        self.nodes() > self.n()
    }
    /// True when every cell has exactly one mode (node = cell; every SOP instance).
    #[inline]
    pub fn one_mode(&self) -> bool {
        self.one_mode
    }
    /// Number of modes of a cell.
    #[inline]
    pub fn modes(&self, cell: usize) -> usize {
        if self.one_mode {
            return 1;
        }
        (self.offsets[cell + 1] - self.offsets[cell]) as usize
    }
    /// Node index of (cell, mode).
    #[inline]
    pub fn node(&self, cell: usize, mode: usize) -> usize {
        if self.one_mode {
            return cell + mode;
        }
        self.offsets[cell] as usize + mode
    }
    /// Cell and mode of a node.
    #[inline]
    pub fn cell_mode(&self, node: usize) -> (usize, usize) {
        let c = self.node_cell[node] as usize;
        (c, node - self.offsets[c] as usize)
    }
    /// Tool index (into the instance's used tools) of a cell.
    #[inline]
    pub fn tool(&self, cell: usize) -> u32 {
        self.tools[cell]
    }
    /// Whether the cell may be reversed.
    #[inline]
    pub fn reversible(&self, cell: usize) -> bool {
        self.reversible[cell]
    }
    /// The mode that cuts `cell` the other way round, if the cell is reversible and has one.
    #[inline]
    pub fn flipped(&self, cell: usize, mode: usize) -> Option<usize> {
        let nd = self.node(cell, mode);
        let f = self.flip[nd] as usize;
        (f != nd).then(|| f - self.offsets[cell] as usize)
    }
    /// True for geometric instances.
    pub fn is_geometric(&self) -> bool {
        self.geo.is_some()
    }
    /// Entry point of a node (geometric instances; origin otherwise).
    #[inline]
    pub fn entry(&self, node: usize) -> Point3 {
        self.geo.as_ref().map(|g| g.entry[node]).unwrap_or_default()
    }
    /// Exit point of a node (geometric instances; origin otherwise).
    #[inline]
    pub fn exit(&self, node: usize) -> Point3 {
        self.geo.as_ref().map(|g| g.exit[node]).unwrap_or_default()
    }
    /// Cost independent of the order (cutting time for the time objective).
    pub fn constant(&self) -> f64 {
        self.constant
    }
    /// Seconds per mm of cutting in a cell.
    #[inline]
    pub fn cut_rate(&self, cell: usize) -> f64 {
        self.cut_rate[cell]
    }
    /// The tool-change point (geometric; origin otherwise).
    pub fn tool_change_point(&self) -> Point3 {
        self.geo.as_ref().map(|g| g.tool_change).unwrap_or_default()
    }
    /// The home point (geometric; origin otherwise).
    pub fn home_point(&self) -> Point3 {
        self.geo.as_ref().map(|g| g.home).unwrap_or_default()
    }
    /// Planar distance within which same-depth, same-tool moves are linked without a lift.
    pub fn link_distance(&self) -> f64 {
        self.geo.as_ref().map(|g| g.link_distance).unwrap_or(0.0)
    }
    /// A lower bound on the part of any lifting same-tool move out of (cell, mode) that does
    /// not depend on the planar distance: retract, plunge to the highest entry, lift time.
    pub fn lift_floor(&self, cell: usize, mode: usize) -> f64 {
        match &self.geo {
            None => 0.0,
            Some(g) => {
                let ex = g.exit[self.node(cell, mode)];
                let air = (g.clearance - ex.z) + (g.clearance - g.max_entry_z);
                self.scale(g, air, 1, 0, 0.0)
            }
        }
    }
    /// The part of any tool-changing move out of (cell, mode) that does not depend on the
    /// target: retract, travel to the tool-change point, change and lift time.
    pub fn change_offset(&self, cell: usize, mode: usize) -> f64 {
        match &self.geo {
            None => 0.0,
            Some(g) => {
                let ex = g.exit[self.node(cell, mode)];
                let air = (g.clearance - ex.z) + ex.at_z(g.clearance).dist(&g.tool_change);
                self.scale(g, air, 1, 1, 0.0)
            }
        }
    }
    /// The part of any tool-changing move into `node` that depends on the target: from the
    /// tool-change point over to above its entry at clearance, and down (0 on matrix
    /// instances). A tool change out of (cell, mode) into `node` costs
    /// [`CostModel::change_offset`] plus this.
    pub fn change_tail(&self, node: usize) -> f64 {
        match &self.geo {
            None => 0.0,
            Some(g) => {
                let en = g.entry[node];
                let air = g.tool_change.dist(&en.at_z(g.clearance)) + (g.clearance - en.z);
                self.scale(g, air, 0, 0, 0.0)
            }
        }
    }
    /// Seconds per mm at rapid (geometric), used by lower bounds on moves.
    pub fn rapid_rate(&self) -> f64 {
        self.geo.as_ref().map(|g| g.rapid_rate).unwrap_or(1.0)
    }

    /// Cost of starting the path with (cell, mode).
    #[inline]
    pub fn start(&self, cell: usize, mode: usize) -> f64 {
        let b = self.node(cell, mode);
        match &self.geo {
            None => 0.0,
            Some(g) => {
                let en = g.entry[b];
                let above = en.at_z(g.clearance);
                let down = g.clearance - en.z;
                let change = matches!(g.initial_tool, Some(t) if t != self.tools[cell]);
                let air = if change {
                    g.home.dist(&g.tool_change) + g.tool_change.dist(&above) + down
                } else {
                    g.home.dist(&above) + down
                };
                self.scale(g, air, 0, change as u32, 0.0)
            }
        }
    }

    /// The cheapest arc from cell `a` to cell `b` over every pair of their modes.
    pub fn cheapest_arc(&self, a: usize, b: usize) -> f64 {
        let mut best = f64::INFINITY;
        for ma in 0..self.modes(a) {
            for mb in 0..self.modes(b) {
                best = best.min(self.arc(a, ma, b, mb));
            }
        }
        best
    }

    /// Cost of going from (a, ma) to (b, mb).
    #[inline(always)]
    pub fn arc(&self, a: usize, ma: usize, b: usize, mb: usize) -> f64 {
        let na = self.node(a, ma);
        let nb = self.node(b, mb);
        match &self.geo {
            // the matrix case stays small enough to inline into every move's delta
            None => match &self.matrix {
                Some(m) => m.get(na, nb),
                None => 0.0,
            },
            Some(g) => self.geo_arc(g, a, na, b, nb),
        }
    }

    /// [`CostModel::arc`] on a geometric instance, between nodes `na` (of cell `a`) and `nb`
    /// (of cell `b`).
    #[inline]
    fn geo_arc(&self, g: &Geo, a: usize, na: usize, b: usize, nb: usize) -> f64 {
        let ex = g.exit[na];
        let en = g.entry[nb];
        if self.tools[a] == self.tools[b] {
            let dxy = ex.dist_xy(&en);
            if (ex.z - en.z).abs() <= 1e-9 && dxy <= g.link_distance + 1e-9 {
                let d = if g.keep_out.is_empty() {
                    Some(dxy)
                } else {
                    link_path(&g.keep_out, ex, en, dxy)
                };
                if let Some(d) = d.filter(|&d| d <= g.link_distance + 1e-9) {
                    // linked at cutting feed, no lift
                    return match self.objective {
                        Objective::Time => d * self.cut_rate[b],
                        _ => d,
                    };
                }
            }
            let air = (g.clearance - ex.z) + dxy + (g.clearance - en.z);
            self.scale(g, air, 1, 0, 0.0)
        } else {
            let air = (g.clearance - ex.z)
                + ex.at_z(g.clearance).dist(&g.tool_change)
                + g.tool_change.dist(&en.at_z(g.clearance))
                + (g.clearance - en.z);
            self.scale(g, air, 1, 1, 0.0)
        }
    }

    /// Cost of ending the path with (cell, mode).
    #[inline]
    pub fn finish(&self, cell: usize, mode: usize) -> f64 {
        match &self.geo {
            Some(g) if g.return_home => {
                let ex = g.exit[self.node(cell, mode)];
                let air = (g.clearance - ex.z) + ex.at_z(g.clearance).dist(&g.home);
                self.scale(g, air, 0, 0, 0.0)
            }
            Some(_) => 0.0,
            None => match (&self.matrix, self.return_node) {
                (Some(m), Some(r)) => m.get(self.node(cell, mode), r),
                _ => 0.0,
            },
        }
    }

    #[inline]
    fn scale(&self, g: &Geo, air: f64, lifts: u32, changes: u32, extra: f64) -> f64 {
        match self.objective {
            Objective::Time => {
                air * g.rapid_rate
                    + lifts as f64 * g.lift_time
                    + changes as f64 * g.change_time
                    + extra
            }
            _ => air,
        }
    }

    /// Full cost of a sequence (solver-side evaluation; no feasibility check).
    pub fn evaluate(&self, seq: &Sequence) -> f64 {
        let Some(first) = seq.first() else {
            return self.constant;
        };
        let mut total = self.constant + self.start(first.cell, first.mode);
        for w in seq.windows(2) {
            total += self.arc(w[0].cell, w[0].mode, w[1].cell, w[1].mode);
        }
        let last = seq[seq.len() - 1];
        total + self.finish(last.cell, last.mode)
    }

    /// The cheapest arc cost from (a, ma) into any mode of b, and that mode.
    #[inline]
    pub fn best_arc_into(&self, a: usize, ma: usize, b: usize) -> (f64, usize) {
        let mut best = (f64::INFINITY, 0);
        for mb in 0..self.modes(b) {
            let c = self.arc(a, ma, b, mb);
            if c < best.0 {
                best = (c, mb);
            }
        }
        best
    }
}

/// The length of the at-depth move from `a` to `b` (planar distance `dxy`) past the keep-out
/// areas: the straight move when it is clear, else the shorter clear dog-leg of an axial and
/// a circumferential leg (either order, `|dx| + |dy|`), else `None` (the cutter lifts).
fn link_path(keep_out: &[[f64; 5]], a: Point3, b: Point3, dxy: f64) -> Option<f64> {
    if !link_blocked(keep_out, a, b) {
        return Some(dxy);
    }
    let corners = [Point3::new(b.x, a.y, a.z), Point3::new(a.x, b.y, a.z)];
    corners
        .iter()
        .any(|&c| !link_blocked(keep_out, a, c) && !link_blocked(keep_out, c, b))
        .then(|| (b.x - a.x).abs() + (b.y - a.y).abs())
}

/// Whether the straight at-depth move from `a` to `b` crosses the inside of a keep-out area
/// (`[x0, y0, x1, y1, top]`) whose top stands above `a.z`: Liang–Barsky clipping of the
/// segment against the area shrunk by 1 µm, so a move that touches or follows the boundary
/// is free.
fn link_blocked(keep_out: &[[f64; 5]], a: Point3, b: Point3) -> bool {
    const EPS: f64 = 1e-6;
    keep_out.iter().any(|k| {
        if k[4] <= a.z + 1e-9 {
            return false;
        }
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        for (p, d, lo, hi) in [
            (a.x, b.x - a.x, k[0] + EPS, k[2] - EPS),
            (a.y, b.y - a.y, k[1] + EPS, k[3] - EPS),
        ] {
            if lo >= hi {
                return false;
            }
            if d.abs() < 1e-12 {
                if p <= lo || p >= hi {
                    return false;
                }
            } else {
                let (u, v) = ((lo - p) / d, (hi - p) / d);
                t0 = t0.max(u.min(v));
                t1 = t1.min(u.max(v));
            }
        }
        t0 < t1
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `node` and `modes` (read without the offsets when every cell has one mode) agree with
    /// `cell_mode` on one-mode and several-mode instances.
    #[test]
    fn nodes_and_modes_agree_with_the_offsets() {
        for (kind, params) in [
            ("random-sop", vec![("n", "30")]),
            ("generalized", vec![("n", "30"), ("modes", "4")]),
        ] {
            let kv = params
                .iter()
                .map(|(k, v)| (k.to_string(), v.to_string()))
                .collect();
            let inst = crate::generate::generate(kind, &kv, 3).expect("generated");
            let m = CostModel::new(&inst, Objective::Matrix);
            assert_eq!(m.one_mode, !m.multimode(), "{kind}");
            let mut next = 0;
            for cell in 0..m.n() {
                for md in 0..m.modes(cell) {
                    assert_eq!(m.node(cell, md), next, "{kind}");
                    assert_eq!(m.cell_mode(next), (cell, md), "{kind}");
                    next += 1;
                }
            }
            assert_eq!(next, m.nodes(), "{kind}");
        }
    }
}

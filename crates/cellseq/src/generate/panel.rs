//! `panel`: an aircraft integral panel (paper 002, generalized-pocket model).
//!
//! A plate with `rows × cols` pockets on a grid (skewed by `skew`, made irregular by `jitter`),
//! separated by ribs of width `rib`, inside a flange of width `flange`. Pockets have random
//! floor depths and corner radii; some carry an island (boss), some are open (through the
//! plate), some have a wall groove. Cells:
//!
//! - per pocket: roughing layers (N from [`toolsel::layer_count`]), floor finishing (closed
//!   pockets), wall finishing (4 start points), island finishing, wall groove;
//! - rib tops (one open, reversible stroke per interior grid edge);
//! - flange/edge finishing (one stroke per border grid edge);
//! - outer contour roughing layers and finishing;
//! - holes in the flange.
//!
//! Tools come from a TOML library ([`toolsel`]): finishing = largest radius ≤ the pocket's
//! corner radius; roughing = largest with η ≥ `eta_min`, then groups merged when μ > `mu`.
//!
//! Precedence (paper rules): roughing layers top-down (rule 3: the pocket's layers overlap);
//! rough before finish of the same pocket; outer-contour roughing before pocket roughing
//! (rule 2, `outer_first`); outer-contour finishing before flange finishing; rule 4 step-type
//! order between the wall groove, pocket finishing, adjacent flange segments and adjacent ribs
//! of each pocket (`rule4`); face before hole (the flange segment before its holes).
//! Rule 5 (symmetry) is left to the solvers.
//!
//! As-programmed order: by procedure (tool, larger first), then feature numbering (outer
//! contour, pockets 1…, ribs, flange, holes), layer by layer.

use super::common::{closed_modes, programmed_order, pt, r3, stroke_modes, tools_larger_first};
use super::toolsel::{self, RoughJob, ToolLibrary, ToolSpec};
use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{Cell, Instance, Machine, Metadata, StepKind, Tool};
use crate::params::{ParamKind, ParamSpec, Params};
use geo::{Area, BooleanOps, Buffer, Centroid, LineString, MultiPolygon, Polygon, coord};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Parameters.
pub static SPECS: &[ParamSpec] = &[
    ParamSpec {
        name: "rows",
        default: "2",
        kind: ParamKind::int(1, 100_000),
        help: "pocket rows",
    },
    ParamSpec {
        name: "cols",
        default: "3",
        kind: ParamKind::int(1, 100_000),
        help: "pocket columns",
    },
    ParamSpec {
        name: "pitch",
        default: "150",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "grid spacing (mm)",
    },
    ParamSpec {
        name: "pitch_var",
        default: "0.3",
        kind: ParamKind::float_below(0.0, 0.5),
        help: "column widths and row heights vary by ± this fraction of the pitch (< 0.5)",
    },
    ParamSpec {
        name: "skew",
        default: "0",
        kind: ParamKind::float(-1.0, 1.0),
        help: "x shift per row, as a fraction of the pitch",
    },
    ParamSpec {
        name: "jitter",
        default: "0",
        kind: ParamKind::float_below(0.0, 0.2),
        help: "random shift of inner grid nodes, fraction of the pitch (< 0.2)",
    },
    ParamSpec {
        name: "rib",
        default: "6",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "rib width (mm)",
    },
    ParamSpec {
        name: "flange",
        default: "25",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "flange width around the pockets (mm)",
    },
    ParamSpec {
        name: "thickness",
        default: "45",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "plate thickness (mm)",
    },
    ParamSpec {
        name: "depth_min",
        default: "15",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "smallest pocket depth H (mm)",
    },
    ParamSpec {
        name: "depth_max",
        default: "40",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "largest pocket depth H (mm)",
    },
    ParamSpec {
        name: "radius_min",
        default: "4",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "smallest pocket corner radius (mm)",
    },
    ParamSpec {
        name: "radius_max",
        default: "16",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "largest pocket corner radius (mm)",
    },
    ParamSpec {
        name: "ap",
        default: "6",
        kind: ParamKind::float(0.01, 1e4),
        help: "roughing step-down a_p (mm)",
    },
    ParamSpec {
        name: "delta",
        default: "1",
        kind: ParamKind::float(0.0, 1e4),
        help: "finishing allowance δ (mm)",
    },
    ParamSpec {
        name: "islands",
        default: "0.2",
        kind: ParamKind::float(0.0, 1.0),
        help: "probability that a pocket has an island",
    },
    ParamSpec {
        name: "open",
        default: "0.1",
        kind: ParamKind::float(0.0, 1.0),
        help: "probability that a pocket is open (through)",
    },
    ParamSpec {
        name: "grooves",
        default: "0.2",
        kind: ParamKind::float(0.0, 1.0),
        help: "probability that a pocket has a wall groove",
    },
    ParamSpec {
        name: "holes",
        default: "4",
        kind: ParamKind::int(0, 100_000),
        help: "holes in the flange",
    },
    ParamSpec {
        name: "hole_diameter",
        default: "6.8",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "hole diameter (mm); the largest drill not above it",
    },
    ParamSpec {
        name: "eta_min",
        default: "0.9",
        kind: ParamKind::float(0.0, 1.0),
        help: "minimum machinable ratio of the roughing tool",
    },
    ParamSpec {
        name: "mu",
        default: "0.7",
        kind: ParamKind::float(0.0, 100.0),
        help: "merge two roughing tool groups when μ exceeds this",
    },
    ParamSpec {
        name: "outer_first",
        default: "true",
        kind: ParamKind::Bool,
        help: "rule 2: outer-contour roughing before pocket roughing",
    },
    ParamSpec {
        name: "rule4",
        default: "wall-groove,pocket,flange,rib",
        kind: ParamKind::Text,
        help: "rule 4 step-type order (a permutation of wall-groove,pocket,flange,rib)",
    },
    ParamSpec {
        name: "tools",
        default: "default",
        kind: ParamKind::Text,
        help: "tool library TOML file ('default': crates/cellseq/src/generate/default-tools.toml)",
    },
];

const RULE4_TYPES: [&str; 4] = ["wall-groove", "pocket", "flange", "rib"];

fn parse_rule4(s: &str) -> Result<Vec<usize>> {
    let parts: Vec<&str> = s.split(',').map(|x| x.trim()).collect();
    let mut order = Vec::new();
    for p in &parts {
        match RULE4_TYPES.iter().position(|t| t == p) {
            Some(i) if !order.contains(&i) => order.push(i),
            _ => {
                return Err(Error::Param(format!(
                    "panel: rule4 must be a permutation of {}, got '{s}'",
                    RULE4_TYPES.join(",")
                )));
            }
        }
    }
    if order.len() != 4 {
        return Err(Error::Param(format!(
            "panel: rule4 must name all of {}, got '{s}'",
            RULE4_TYPES.join(",")
        )));
    }
    Ok(order)
}

/// The part being built: cells with their programming keys.
struct Builder {
    cells: Vec<Cell>,
    keys: Vec<(u64, u64)>,
    prec: Vec<(usize, usize)>,
}

impl Builder {
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        id: String,
        tool: &ToolSpec,
        step: StepKind,
        layer: u32,
        z: f64,
        feature: &str,
        cut: f64,
        modes: Vec<crate::model::Mode>,
        key: (u64, u64),
    ) -> usize {
        let mut c = Cell::new(id, tool.id.clone(), modes);
        c.step = step;
        c.layer = layer;
        c.z = r3(z);
        c.feature = Some(feature.to_string());
        c.cut_length = r3(cut);
        c.reversible = c.modes.len() == 2
            && c.modes[0] == c.modes[1].reversed()
            && c.modes[0].entry != c.modes[0].exit;
        self.cells.push(c);
        self.keys.push(key);
        self.cells.len() - 1
    }
}

fn poly_of(mp: MultiPolygon<f64>) -> Option<Polygon<f64>> {
    mp.0.into_iter()
        .max_by(|a, b| a.unsigned_area().total_cmp(&b.unsigned_area()))
}

fn perimeter(p: &Polygon<f64>) -> f64 {
    let ring = |ls: &LineString<f64>| {
        ls.lines()
            .map(|l| (l.end.x - l.start.x).hypot(l.end.y - l.start.y))
            .sum::<f64>()
    };
    ring(p.exterior()) + p.interiors().iter().map(ring).sum::<f64>()
}

/// A flange segment: its cell and its two ends.
type FlangeSeg = (usize, (f64, f64), (f64, f64));

/// The panel's parameters, read and checked.
struct Settings {
    rows: usize,
    cols: usize,
    pitch: f64,
    pitch_var: f64,
    skew: f64,
    jitter: f64,
    rib: f64,
    flange: f64,
    thickness: f64,
    dmin: f64,
    dmax: f64,
    rmin: f64,
    rmax: f64,
    ap: f64,
    delta: f64,
    islands: f64,
    open: f64,
    grooves: f64,
    outer_first: bool,
    holes: usize,
    hole_diameter: f64,
    rule4: Vec<usize>,
    eta_min: f64,
    mu: f64,
    /// The smallest column width or row height the pitch variation allows.
    min_pitch: f64,
}

/// Most roughing layers of one pocket (depth_max / ap): each layer is a cell.
const MAX_LAYERS: f64 = 1000.0;

/// A refused parameter combination.
fn bad<T>(m: String) -> Result<T> {
    Err(Error::Param(format!("panel: {m}")))
}

impl Settings {
    fn read(p: &Params) -> Result<Settings> {
        let s = Settings {
            rows: p.int("rows") as usize,
            cols: p.int("cols") as usize,
            pitch: p.float("pitch"),
            pitch_var: p.float("pitch_var"),
            skew: p.float("skew"),
            jitter: p.float("jitter"),
            rib: p.float("rib"),
            flange: p.float("flange"),
            thickness: p.float("thickness"),
            dmin: p.float("depth_min"),
            dmax: p.float("depth_max"),
            rmin: p.float("radius_min"),
            rmax: p.float("radius_max"),
            ap: p.float("ap"),
            delta: p.float("delta"),
            islands: p.float("islands"),
            open: p.float("open"),
            grooves: p.float("grooves"),
            outer_first: p.bool("outer_first"),
            holes: p.int("holes") as usize,
            hole_diameter: p.float("hole_diameter"),
            rule4: Vec::new(),
            eta_min: p.float("eta_min"),
            mu: p.float("mu"),
            min_pitch: p.float("pitch") * (1.0 - p.float("pitch_var")),
        };
        s.check()?;
        Ok(Settings {
            rule4: parse_rule4(p.word("rule4"))?,
            ..s
        })
    }

    fn check(&self) -> Result<()> {
        let (rows, cols, rib, ap) = (self.rows, self.cols, self.rib, self.ap);
        // each parameter lies in its declared range (checked by `Params`); what is left are
        // limits on their combination
        if rows.saturating_mul(cols) > 100_000 {
            return bad("rows x cols must be at most 100000 pockets".into());
        }
        if !(self.dmin <= self.dmax && self.dmax < self.thickness) {
            return bad("need depth_min <= depth_max < thickness".into());
        }
        if self.dmax / ap > MAX_LAYERS {
            return bad(format!(
                "depth_max / ap = {:.0} roughing layers per pocket, more than {MAX_LAYERS}: raise ap",
                self.dmax / ap
            ));
        }
        if !(0.0 < self.rmin
            && self.rmin <= self.rmax
            && 2.0 * self.rmax + rib < 0.6 * self.min_pitch)
        {
            return bad(
                "need 0 < radius_min <= radius_max and 2 radius_max + rib < 0.6 pitch (1 - pitch_var)"
                    .into(),
            );
        }
        Ok(())
    }
}

/// The plate's grid: `nodes[i][j]` for column line `i` and row line `j`, and the centre of the
/// grid's outline.
struct Grid {
    nodes: Vec<Vec<(f64, f64)>>,
    centre: (f64, f64),
    /// The grid's outline (the ribs' outer edges), counter-clockwise from node (0, 0).
    outline: Polygon<f64>,
}

impl Grid {
    /// Irregular column widths and row heights, skew, inner-node jitter.
    fn new(s: &Settings, rng: &mut ChaCha8Rng) -> Grid {
        let (rows, cols, pitch, pitch_var) = (s.rows, s.cols, s.pitch, s.pitch_var);
        let mut col_x = vec![s.flange];
        for _ in 0..cols {
            let w = pitch * (1.0 + rng.random_range(-pitch_var..=pitch_var));
            col_x.push(col_x.last().copied().unwrap_or(0.0) + w);
        }
        let mut row_y = vec![s.flange];
        for _ in 0..rows {
            let h = pitch * (1.0 + rng.random_range(-pitch_var..=pitch_var));
            row_y.push(row_y.last().copied().unwrap_or(0.0) + h);
        }
        let node = |i: usize, j: usize, d: (f64, f64)| -> (f64, f64) {
            (
                col_x[i] + (row_y[j] - s.flange) * s.skew + d.0,
                row_y[j] + d.1,
            )
        };
        let jitter = s.jitter;
        let mut nodes = vec![vec![(0.0, 0.0); rows + 1]; cols + 1];
        for (i, col) in nodes.iter_mut().enumerate() {
            for (j, nd) in col.iter_mut().enumerate() {
                let inner = i > 0 && i < cols && j > 0 && j < rows;
                let d = if inner && jitter > 0.0 {
                    (
                        rng.random_range(-jitter..jitter) * s.min_pitch,
                        rng.random_range(-jitter..jitter) * s.min_pitch,
                    )
                } else {
                    (0.0, 0.0)
                };
                *nd = node(i, j, d);
            }
        }
        let mut border: Vec<(f64, f64)> = Vec::new();
        border.extend((0..cols).map(|i| nodes[i][0]));
        border.extend((0..rows).map(|j| nodes[cols][j]));
        border.extend((0..cols).map(|i| nodes[cols - i][rows]));
        border.extend((0..rows).map(|j| nodes[0][rows - j]));
        let mut ring: Vec<_> = border.iter().map(|&(x, y)| coord! {x: x, y: y}).collect();
        ring.push(ring[0]);
        let outline = Polygon::new(LineString::from(ring), vec![]);
        let centre = outline
            .centroid()
            .map(|c| (c.x(), c.y()))
            .unwrap_or((0.0, 0.0));
        Grid {
            nodes,
            centre,
            outline,
        }
    }

    /// `q` moved `off` away from the centre.
    fn outside(&self, (x, y): (f64, f64), off: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.centre.0, y - self.centre.1);
        let l = dx.hypot(dy).max(1e-9);
        (x + dx / l * off, y + dy / l * off)
    }

    /// The four corners of grid cell (`i`, `j`), counter-clockwise.
    fn quad(&self, i: usize, j: usize) -> [(f64, f64); 4] {
        let n = &self.nodes;
        [n[i][j], n[i + 1][j], n[i + 1][j + 1], n[i][j + 1]]
    }
}

/// The outer contour's cells: its roughing layers, top-down, and its finishing pass.
struct OuterContour {
    rough: Vec<usize>,
    finish: usize,
}

/// Roughing layers around the plate, then finishing.
fn outer_contour(
    b: &mut Builder,
    s: &Settings,
    g: &Grid,
    lib: &ToolLibrary,
    big: &ToolSpec,
) -> OuterContour {
    let (rows, cols, flange, thickness) = (s.rows, s.cols, s.flange, s.thickness);
    let plate = poly_of(g.outline.buffer(flange)).expect("plate outline");
    let plate_perim = perimeter(&plate);
    let n = &g.nodes;
    let corners = [n[0][0], n[cols][0], n[cols][rows], n[0][rows]];
    let n_outer = toolsel::layer_count(thickness, s.ap, s.delta).max(1);
    let finish_tool = lib.finishing_tool(flange).clone();
    let mut rough = Vec::new();
    for k in 1..=n_outer {
        let z = -(k as f64 * s.ap).min(thickness);
        let pts: Vec<Point3> = corners
            .iter()
            .map(|&c| {
                let (x, y) = g.outside(c, flange * std::f64::consts::SQRT_2 + big.radius());
                pt(x, y, z)
            })
            .collect();
        let c = b.add(
            format!("OC-R{k}"),
            big,
            StepKind::OuterContour,
            k - 1,
            z,
            "outer",
            plate_perim,
            closed_modes(&pts[..1]),
            (0, k as u64),
        );
        if let Some(&prev) = rough.last() {
            b.prec.push((prev, c));
        }
        rough.push(c);
    }
    let z_of = -thickness;
    let pts: Vec<Point3> = corners
        .iter()
        .map(|&c| {
            let (x, y) = g.outside(c, flange * std::f64::consts::SQRT_2 + finish_tool.radius());
            pt(x, y, z_of)
        })
        .collect();
    let finish = b.add(
        "OC-F".into(),
        &finish_tool,
        StepKind::OuterContour,
        n_outer,
        z_of,
        "outer",
        plate_perim,
        closed_modes(&pts),
        (0, n_outer as u64 + 1),
    );
    b.prec
        .push((*rough.last().expect("at least one layer"), finish));
    OuterContour { rough, finish }
}

/// A pocket's cells and what tool selection needs of it.
struct Pocket {
    rough: Vec<usize>,
    finish: Vec<usize>,
    groove: Vec<usize>,
    area: f64,
    layers: u32,
    /// The roughing tool chosen for it alone (before groups are merged).
    rough_tool: String,
}

/// The cells of pocket `pno` in grid cell (`i`, `j`): roughing layers (with a placeholder tool,
/// set by [`rough_tools`]), floor, wall and island finishing, wall groove.
#[allow(clippy::too_many_arguments)]
fn pocket(
    b: &mut Builder,
    s: &Settings,
    g: &Grid,
    lib: &ToolLibrary,
    big: &ToolSpec,
    (i, j, pno): (usize, usize, usize),
    rng: &mut ChaCha8Rng,
) -> Result<Pocket> {
    let (rib, ap, delta, thickness) = (s.rib, s.ap, s.delta, s.thickness);
    let fid = format!("P{pno:03}");
    let quad = g.quad(i, j);
    let mut ring: Vec<_> = quad.iter().map(|&(x, y)| coord! {x: x, y: y}).collect();
    ring.push(ring[0]);
    let q = Polygon::new(LineString::from(ring), vec![]);
    let r = r3(rng.random_range(s.rmin..=s.rmax));
    let core = poly_of(q.buffer(-(rib / 2.0 + r)));
    let Some(core) = core else {
        return bad(format!(
            "pocket {pno} vanishes: reduce jitter/skew or rib/radius"
        ));
    };
    let mut poly = poly_of(core.buffer(r)).expect("rounded pocket");
    let c = poly.centroid().map(|c| (c.x(), c.y())).unwrap_or(quad[0]);
    let island = rng.random_bool(s.islands);
    let island_r = 0.12 * s.pitch;
    if island {
        let boss = geo::Point::new(c.0, c.1).buffer(island_r);
        if let Some(pp) = poly_of(poly.difference(&boss)) {
            poly = pp;
        }
    }
    let open = rng.random_bool(s.open);
    let h = if open {
        thickness
    } else {
        r3(rng.random_range(s.dmin..=s.dmax))
    };
    let groove = rng.random_bool(s.grooves);
    let groove_side = rng.random_range(0..4usize);
    let area = poly.unsigned_area();
    let n = toolsel::layer_count(h, ap, delta).max(1);
    let fin = lib.finishing_tool(r).clone();
    // entry of the roughing helix: between centroid and the first corner (or centroid)
    let e = if island {
        ((c.0 + quad[0].0) / 2.0, (c.1 + quad[0].1) / 2.0)
    } else {
        c
    };
    let shape = Shape {
        fid,
        key: pno as u64,
        quad,
        centre: c,
        entry: e,
        corner: r,
        depth: h,
        layers: n,
        open,
        island: island.then_some(island_r),
        wall: perimeter(&poly),
    };
    let mut pk = Pocket {
        rough: rough_cells(b, s, big, &shape),
        finish: Vec::new(),
        groove: Vec::new(),
        area,
        layers: n,
        rough_tool: lib.roughing_tool(&poly, s.eta_min).id.clone(),
    };
    let last = *pk.rough.last().expect("layers");
    pk.finish = finish_cells(b, s, &fin, &shape, area);
    for &f in &pk.finish {
        b.prec.push((last, f));
    }
    if groove {
        let cell = groove_cell(b, s, &fin, &shape, groove_side);
        b.prec.push((last, cell));
        pk.groove.push(cell);
    }
    Ok(pk)
}

/// What the cells of one pocket are placed by.
struct Shape {
    fid: String,
    key: u64,
    quad: [(f64, f64); 4],
    centre: (f64, f64),
    /// Entry of the roughing helix.
    entry: (f64, f64),
    /// Corner radius.
    corner: f64,
    /// Floor depth (the plate's thickness when open).
    depth: f64,
    /// Roughing layers.
    layers: u32,
    open: bool,
    /// Radius of the island, if any.
    island: Option<f64>,
    /// Length of the wall.
    wall: f64,
}

/// Roughing layers, top-down, each after the one above (placeholder tool; set after merging).
fn rough_cells(b: &mut Builder, s: &Settings, big: &ToolSpec, p: &Shape) -> Vec<usize> {
    let (e, h) = (p.entry, p.depth);
    let mut rough: Vec<usize> = Vec::new();
    for k in 1..=p.layers {
        let z = if p.open {
            -(k as f64 * s.ap).min(h)
        } else {
            -(k as f64 * s.ap).min(h - s.delta)
        };
        let cell = b.add(
            format!("{}-R{k}", p.fid),
            big,
            StepKind::PocketRough,
            k - 1,
            z,
            &p.fid,
            0.0,
            closed_modes(&[pt(e.0, e.1, z)]),
            (p.key, k as u64),
        );
        if let Some(&prev) = rough.last() {
            b.prec.push((prev, cell));
        }
        rough.push(cell);
    }
    rough
}

/// Floor finishing (closed pockets), wall finishing (start points at the edge midpoints, one
/// tool radius inside), island finishing.
fn finish_cells(b: &mut Builder, s: &Settings, fin: &ToolSpec, p: &Shape, area: f64) -> Vec<usize> {
    let (fid, n, h, e, c, quad) = (&p.fid, p.layers, p.depth, p.entry, p.centre, p.quad);
    let mut finish = Vec::new();
    if !p.open {
        let cell = b.add(
            format!("{fid}-FF"),
            fin,
            StepKind::PocketFinish,
            n,
            -h,
            fid,
            area / fin.cutting_width,
            closed_modes(&[pt(e.0, e.1, -h)]),
            (p.key, n as u64 + 1),
        );
        finish.push(cell);
    }
    let off = s.rib / 2.0 + fin.radius();
    let starts: Vec<Point3> = (0..4)
        .map(|s| {
            let (a, bb) = (quad[s], quad[(s + 1) % 4]);
            let m = ((a.0 + bb.0) / 2.0, (a.1 + bb.1) / 2.0);
            let (dx, dy) = (c.0 - m.0, c.1 - m.1);
            let l = dx.hypot(dy).max(1e-9);
            pt(m.0 + dx / l * off, m.1 + dy / l * off, -h)
        })
        .collect();
    let wf = b.add(
        format!("{fid}-WF"),
        fin,
        StepKind::PocketFinish,
        n,
        -h,
        fid,
        p.wall,
        closed_modes(&starts),
        (p.key, n as u64 + 2),
    );
    finish.push(wf);
    if let Some(island_r) = p.island {
        let rr = island_r + fin.radius();
        let starts: Vec<Point3> = (0..4)
            .map(|s| {
                let a = std::f64::consts::FRAC_PI_2 * s as f64;
                pt(c.0 + rr * a.cos(), c.1 + rr * a.sin(), -h)
            })
            .collect();
        let cell = b.add(
            format!("{fid}-IF"),
            fin,
            StepKind::PocketFinish,
            n,
            -h,
            fid,
            std::f64::consts::TAU * island_r,
            closed_modes(&starts),
            (p.key, n as u64 + 3),
        );
        finish.push(cell);
    }
    finish
}

/// The wall groove along side `side` of the pocket, at half depth.
fn groove_cell(b: &mut Builder, s: &Settings, fin: &ToolSpec, p: &Shape, side: usize) -> usize {
    let (c, quad, r) = (p.centre, p.quad, p.corner);
    let (a, bb) = (quad[side], quad[(side + 1) % 4]);
    let inset = |q: (f64, f64)| {
        let (dx, dy) = (c.0 - q.0, c.1 - q.1);
        let l = dx.hypot(dy).max(1e-9);
        let o = (s.rib / 2.0 + r) * std::f64::consts::SQRT_2 + fin.radius();
        (q.0 + dx / l * o, q.1 + dy / l * o)
    };
    let (a, bb) = (inset(a), inset(bb));
    let z = -p.depth / 2.0;
    let len = (bb.0 - a.0).hypot(bb.1 - a.1);
    b.add(
        format!("{}-G", p.fid),
        fin,
        StepKind::WallGroove,
        p.layers,
        z,
        &p.fid,
        len,
        stroke_modes(pt(a.0, a.1, z), pt(bb.0, bb.1, z), true),
        (p.key, p.layers as u64 + 4),
    )
}

/// Tool selection of pocket roughing: each pocket's own tool, then groups merged when μ >
/// `mu`; sets the roughing cells' tool and cutting length and returns the census for the
/// instance's comment.
fn rough_tools(b: &mut Builder, s: &Settings, lib: &ToolLibrary, pockets: &[Pocket]) -> String {
    let census = |assign: &[String]| -> String {
        let mut parts: Vec<String> = Vec::new();
        for t in &lib.tools {
            let k = assign.iter().filter(|a| **a == t.id).count();
            if k > 0 {
                parts.push(format!("{}x{k}", t.id));
            }
        }
        parts.join(" ")
    };
    let mut rough_assign: Vec<String> = pockets.iter().map(|p| p.rough_tool.clone()).collect();
    let jobs: Vec<RoughJob> = pockets
        .iter()
        .map(|p| RoughJob {
            area: p.area,
            layers: p.layers,
        })
        .collect();
    let before = census(&rough_assign);
    let merges = toolsel::merge_groups(&jobs, &mut rough_assign, lib, s.mu);
    let comment = format!(
        "pocket roughing tools (eta_min {}): {before}; after {merges} merge(s) at mu > {}: {}",
        s.eta_min,
        s.mu,
        census(&rough_assign)
    );
    for (pk, tid) in pockets.iter().zip(&rough_assign) {
        let t = lib.get(tid).expect("library tool");
        for &c in &pk.rough {
            b.cells[c].tool = t.id.clone();
            b.cells[c].cut_length = r3(pk.area / t.cutting_width);
        }
        debug_assert_eq!(pk.rough.len() as u32, pk.layers);
    }
    comment
}

/// The rib and flange cells next to each pocket, and the flange segments.
struct Edges {
    ribs_of: Vec<Vec<usize>>,
    flange_of: Vec<Vec<usize>>,
    flange_cells: Vec<FlangeSeg>,
}

/// Ribs (interior grid edges) and flange segments (border grid edges, after the outer
/// contour's finishing).
fn ribs_and_flange(
    b: &mut Builder,
    s: &Settings,
    g: &Grid,
    lib: &ToolLibrary,
    outer_finish: usize,
) -> Edges {
    let (rows, cols, flange) = (s.rows, s.cols, s.flange);
    let np = rows * cols;
    let rib_tool = lib.finishing_tool(2.0 * s.rib).clone();
    let pocket_of = |i: usize, j: usize| j * cols + i;
    let mut e = Edges {
        ribs_of: vec![Vec::new(); np],
        flange_of: vec![Vec::new(); np],
        flange_cells: Vec::new(),
    };
    let base = np as u64 + 1;
    let mut seg = 0u64;
    let mut edge = |b: &mut Builder,
                    e: &mut Edges,
                    p: (f64, f64),
                    q: (f64, f64),
                    sides: &[usize],
                    border: bool| {
        seg += 1;
        let (a2, e2) = if border {
            let sh = |x: (f64, f64)| g.outside(x, flange / 2.0);
            (sh(p), sh(q))
        } else {
            (p, q)
        };
        let len = (e2.0 - a2.0).hypot(e2.1 - a2.1);
        let (id, feat, step, key) = if border {
            (
                format!("FL{seg:04}"),
                "flange".to_string(),
                StepKind::Flange,
                (base + 1, seg),
            )
        } else {
            (
                format!("RIB{seg:04}"),
                format!("rib{seg:04}"),
                StepKind::Rib,
                (base, seg),
            )
        };
        let c = b.add(
            id,
            &rib_tool,
            step,
            0,
            0.0,
            &feat,
            len,
            stroke_modes(pt(a2.0, a2.1, 0.0), pt(e2.0, e2.1, 0.0), true),
            key,
        );
        for &side in sides {
            if border {
                e.flange_of[side].push(c);
            } else {
                e.ribs_of[side].push(c);
            }
        }
        if border {
            e.flange_cells.push((c, a2, e2));
        }
    };
    let n = &g.nodes;
    for j in 0..=rows {
        for i in 0..cols {
            let mut sides = Vec::new();
            if j > 0 {
                sides.push(pocket_of(i, j - 1));
            }
            if j < rows {
                sides.push(pocket_of(i, j));
            }
            edge(b, &mut e, n[i][j], n[i + 1][j], &sides, j == 0 || j == rows);
        }
    }
    for i in 0..=cols {
        for j in 0..rows {
            let mut sides = Vec::new();
            if i > 0 {
                sides.push(pocket_of(i - 1, j));
            }
            if i < cols {
                sides.push(pocket_of(i, j));
            }
            edge(b, &mut e, n[i][j], n[i][j + 1], &sides, i == 0 || i == cols);
        }
    }
    for &(c, _, _) in &e.flange_cells {
        b.prec.push((outer_finish, c));
    }
    e
}

/// Rule 4 between the related features of each pocket, in the order `rule4` names them.
fn rule4_links(b: &mut Builder, rule4: &[usize], pockets: &[Pocket], e: &Edges) {
    for (k, pk) in pockets.iter().enumerate() {
        let sets: [&[usize]; 4] = [&pk.groove, &pk.finish, &e.flange_of[k], &e.ribs_of[k]];
        let present: Vec<&[usize]> = rule4
            .iter()
            .map(|&t| sets[t])
            .filter(|s| !s.is_empty())
            .collect();
        for w in present.windows(2) {
            for &x in w[0] {
                for &y in w[1] {
                    b.prec.push((x, y));
                }
            }
        }
    }
}

/// Holes in the flange, spread over its segments: face (flange segment) before hole.
fn holes(
    b: &mut Builder,
    s: &Settings,
    lib: &ToolLibrary,
    flange_cells: &[FlangeSeg],
    rng: &mut ChaCha8Rng,
) -> Result<()> {
    let nholes = s.holes;
    if nholes == 0 {
        return Ok(());
    }
    let Some(drill) = lib.drill_for(s.hole_diameter).cloned() else {
        return bad("holes need a drill in the tool library".into());
    };
    let base = (s.rows * s.cols) as u64 + 1;
    for h in 0..nholes {
        let (fc, a, e) = flange_cells[(h * flange_cells.len()) / nholes];
        let t = rng.random_range(0.2..0.8);
        let (x, y) = (a.0 + (e.0 - a.0) * t, a.1 + (e.1 - a.1) * t);
        let c = b.add(
            format!("H{:03}", h + 1),
            &drill,
            StepKind::Hole,
            0,
            -s.thickness,
            "holes",
            s.thickness,
            closed_modes(&[pt(x, y, 0.0)]),
            (base + 2, h as u64),
        );
        b.prec.push((fc, c));
    }
    Ok(())
}

/// The instance: the tools used (largest first), the as-programmed order, the machine.
fn assemble(mut b: Builder, lib: &ToolLibrary, name: String, comment: String) -> Instance {
    let (used, rank) = tools_larger_first(lib, &b.cells);
    b.prec.sort_unstable();
    b.prec.dedup();
    let order = programmed_order(b.cells.len(), &b.prec, &rank, &b.keys);
    let tools: Vec<Tool> = used.iter().map(|t| t.to_tool()).collect();
    let machine = Machine {
        home: Point3::new(0.0, 0.0, 100.0),
        tool_change: Point3::new(0.0, 0.0, 100.0),
        clearance: 10.0,
        rapid_feed: 15000.0,
        cut_feed: 2000.0,
        tool_change_time: 8.0,
        lift_time: 1.0,
        ..Machine::default()
    };
    Instance {
        name,
        meta: Metadata {
            comment: Some(comment),
            ..Metadata::default()
        },
        machine,
        tools,
        cells: b.cells,
        precedence: b.prec,
        as_given: Some(order),
        ..Instance::default()
    }
}

/// Generates a panel: geometry (grid, outer contour, pockets, ribs and flange, holes), tool
/// selection of pocket roughing, precedence, assembly.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    check(p)?;
    let s = Settings::read(p)?;
    let lib = ToolLibrary::load(p.word("tools"))?;
    build(s, lib, seed)
}

/// Checks what the declared ranges cannot (limits on the parameters' combination, the tool
/// library); about how many cells the panel will have, at most.
pub fn check(p: &Params) -> Result<u64> {
    let s = Settings::read(p)?;
    let lib = ToolLibrary::load(p.word("tools"))?;
    if s.holes > 0 && lib.drill_for(s.hole_diameter).is_none() {
        return bad(format!(
            "holes need a drill of at most hole_diameter = {} mm in the tool library '{}'",
            s.hole_diameter,
            p.word("tools")
        ));
    }
    let pockets = (s.rows * s.cols) as f64;
    let layers = s.dmax / s.ap + 6.0;
    let grid = 2.0 * ((s.rows + 1) * (s.cols + 1)) as f64;
    Ok((pockets * layers + grid + s.holes as f64 + s.thickness / s.ap + 2.0) as u64)
}

/// The panel of checked settings `s` with tools from `lib`.
fn build(s: Settings, lib: ToolLibrary, seed: u64) -> Result<Instance> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let g = Grid::new(&s, &mut rng);
    let mut b = Builder {
        cells: Vec::new(),
        keys: Vec::new(),
        prec: Vec::new(),
    };
    let big = lib
        .end_mills()
        .next()
        .expect("library has an end mill")
        .clone();
    let outer = outer_contour(&mut b, &s, &g, &lib, &big);
    let mut pockets: Vec<Pocket> = Vec::with_capacity(s.rows * s.cols);
    for j in 0..s.rows {
        for i in 0..s.cols {
            let pno = pockets.len() + 1;
            let pk = pocket(&mut b, &s, &g, &lib, &big, (i, j, pno), &mut rng)?;
            if s.outer_first {
                b.prec
                    .push((*outer.rough.last().expect("layers"), pk.rough[0]));
            }
            pockets.push(pk);
        }
    }
    let comment = rough_tools(&mut b, &s, &lib, &pockets);
    let edges = ribs_and_flange(&mut b, &s, &g, &lib, outer.finish);
    rule4_links(&mut b, &s.rule4, &pockets, &edges);
    holes(&mut b, &s, &lib, &edges.flange_cells, &mut rng)?;
    Ok(assemble(
        b,
        &lib,
        format!("panel-{}x{}-s{seed}", s.rows, s.cols),
        comment,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rule4_parsing() {
        assert_eq!(
            parse_rule4("wall-groove,pocket,flange,rib").unwrap(),
            vec![0, 1, 2, 3]
        );
        assert_eq!(
            parse_rule4("rib, flange,pocket,wall-groove").unwrap(),
            vec![3, 2, 1, 0]
        );
        assert!(parse_rule4("rib,rib,pocket,flange").is_err());
        assert!(parse_rule4("rib,pocket").is_err());
    }
}

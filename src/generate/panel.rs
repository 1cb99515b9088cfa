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
        kind: ParamKind::Int,
        help: "pocket rows",
    },
    ParamSpec {
        name: "cols",
        default: "3",
        kind: ParamKind::Int,
        help: "pocket columns",
    },
    ParamSpec {
        name: "pitch",
        default: "150",
        kind: ParamKind::Float,
        help: "grid spacing (mm)",
    },
    ParamSpec {
        name: "pitch_var",
        default: "0.3",
        kind: ParamKind::Float,
        help: "column widths and row heights vary by ± this fraction of the pitch (< 0.5)",
    },
    ParamSpec {
        name: "skew",
        default: "0",
        kind: ParamKind::Float,
        help: "x shift per row, as a fraction of the pitch",
    },
    ParamSpec {
        name: "jitter",
        default: "0",
        kind: ParamKind::Float,
        help: "random shift of inner grid nodes, fraction of the pitch (< 0.2)",
    },
    ParamSpec {
        name: "rib",
        default: "6",
        kind: ParamKind::Float,
        help: "rib width (mm)",
    },
    ParamSpec {
        name: "flange",
        default: "25",
        kind: ParamKind::Float,
        help: "flange width around the pockets (mm)",
    },
    ParamSpec {
        name: "thickness",
        default: "45",
        kind: ParamKind::Float,
        help: "plate thickness (mm)",
    },
    ParamSpec {
        name: "depth_min",
        default: "15",
        kind: ParamKind::Float,
        help: "smallest pocket depth H (mm)",
    },
    ParamSpec {
        name: "depth_max",
        default: "40",
        kind: ParamKind::Float,
        help: "largest pocket depth H (mm)",
    },
    ParamSpec {
        name: "radius_min",
        default: "4",
        kind: ParamKind::Float,
        help: "smallest pocket corner radius (mm)",
    },
    ParamSpec {
        name: "radius_max",
        default: "16",
        kind: ParamKind::Float,
        help: "largest pocket corner radius (mm)",
    },
    ParamSpec {
        name: "ap",
        default: "6",
        kind: ParamKind::Float,
        help: "roughing step-down a_p (mm)",
    },
    ParamSpec {
        name: "delta",
        default: "1",
        kind: ParamKind::Float,
        help: "finishing allowance δ (mm)",
    },
    ParamSpec {
        name: "islands",
        default: "0.2",
        kind: ParamKind::Float,
        help: "probability that a pocket has an island",
    },
    ParamSpec {
        name: "open",
        default: "0.1",
        kind: ParamKind::Float,
        help: "probability that a pocket is open (through)",
    },
    ParamSpec {
        name: "grooves",
        default: "0.2",
        kind: ParamKind::Float,
        help: "probability that a pocket has a wall groove",
    },
    ParamSpec {
        name: "holes",
        default: "4",
        kind: ParamKind::Int,
        help: "holes in the flange",
    },
    ParamSpec {
        name: "hole_diameter",
        default: "6.8",
        kind: ParamKind::Float,
        help: "hole diameter (mm); the largest drill not above it",
    },
    ParamSpec {
        name: "eta_min",
        default: "0.9",
        kind: ParamKind::Float,
        help: "minimum machinable ratio of the roughing tool",
    },
    ParamSpec {
        name: "mu",
        default: "0.7",
        kind: ParamKind::Float,
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
        help: "tool library TOML file ('default': instances/tools/default.toml)",
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

/// Generates a panel.
#[allow(clippy::needless_range_loop)]
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    let rows = p.int("rows") as usize;
    let cols = p.int("cols") as usize;
    let pitch = p.float("pitch");
    let pitch_var = p.float("pitch_var");
    let skew = p.float("skew");
    let jitter = p.float("jitter");
    let rib = p.float("rib");
    let flange = p.float("flange");
    let thickness = p.float("thickness");
    let (dmin, dmax) = (p.float("depth_min"), p.float("depth_max"));
    let (rmin, rmax) = (p.float("radius_min"), p.float("radius_max"));
    let ap = p.float("ap");
    let delta = p.float("delta");
    let bad = |m: String| Err(Error::Param(format!("panel: {m}")));
    if rows == 0 || cols == 0 || rows.saturating_mul(cols) > 100_000 {
        return bad("rows and cols must be at least 1 (at most 100000 pockets)".into());
    }
    if !(pitch > 0.0 && rib > 0.0 && flange > 0.0 && thickness > 0.0 && ap > 0.0 && delta >= 0.0) {
        return bad(
            "pitch, rib, flange, thickness and ap must be positive, delta non-negative".into(),
        );
    }
    if !(0.0 < dmin && dmin <= dmax && dmax < thickness) {
        return bad("need 0 < depth_min <= depth_max < thickness".into());
    }
    if !(0.0..0.5).contains(&pitch_var) {
        return bad("pitch_var must lie in [0, 0.5)".into());
    }
    let min_pitch = pitch * (1.0 - pitch_var);
    if !(0.0 < rmin && rmin <= rmax && 2.0 * rmax + rib < 0.6 * min_pitch) {
        return bad(
            "need 0 < radius_min <= radius_max and 2 radius_max + rib < 0.6 pitch (1 - pitch_var)"
                .into(),
        );
    }
    if !(0.0..0.2).contains(&jitter) || !(-1.0..=1.0).contains(&skew) {
        return bad("jitter must lie in [0, 0.2) and skew in [-1, 1]".into());
    }
    for k in ["islands", "open", "grooves"] {
        if !(0.0..=1.0).contains(&p.float(k)) {
            return bad(format!("{k} must lie in [0, 1]"));
        }
    }
    let rule4 = parse_rule4(p.word("rule4"))?;
    let lib = ToolLibrary::load(p.word("tools"))?;
    let eta_min = p.float("eta_min");
    let mu = p.float("mu");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);

    // grid nodes: irregular column widths and row heights, skew, inner-node jitter
    let mut col_x = vec![flange];
    for _ in 0..cols {
        let w = pitch * (1.0 + rng.random_range(-pitch_var..=pitch_var));
        col_x.push(col_x.last().copied().unwrap_or(0.0) + w);
    }
    let mut row_y = vec![flange];
    for _ in 0..rows {
        let h = pitch * (1.0 + rng.random_range(-pitch_var..=pitch_var));
        row_y.push(row_y.last().copied().unwrap_or(0.0) + h);
    }
    let node = |i: usize, j: usize, d: (f64, f64)| -> (f64, f64) {
        (col_x[i] + (row_y[j] - flange) * skew + d.0, row_y[j] + d.1)
    };
    let mut nodes = vec![vec![(0.0, 0.0); rows + 1]; cols + 1];
    for (i, col) in nodes.iter_mut().enumerate() {
        for (j, nd) in col.iter_mut().enumerate() {
            let inner = i > 0 && i < cols && j > 0 && j < rows;
            let d = if inner && jitter > 0.0 {
                (
                    rng.random_range(-jitter..jitter) * min_pitch,
                    rng.random_range(-jitter..jitter) * min_pitch,
                )
            } else {
                (0.0, 0.0)
            };
            *nd = node(i, j, d);
        }
    }

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

    // outer contour: roughing layers around the plate, then finishing
    let mut border: Vec<(f64, f64)> = Vec::new();
    border.extend((0..cols).map(|i| nodes[i][0]));
    border.extend((0..rows).map(|j| nodes[cols][j]));
    border.extend((0..cols).map(|i| nodes[cols - i][rows]));
    border.extend((0..rows).map(|j| nodes[0][rows - j]));
    let mut ring: Vec<_> = border.iter().map(|&(x, y)| coord! {x: x, y: y}).collect();
    ring.push(ring[0]);
    let inner_outline = Polygon::new(LineString::from(ring), vec![]);
    let plate = poly_of(inner_outline.buffer(flange)).expect("plate outline");
    let plate_perim = perimeter(&plate);
    let corners = [
        nodes[0][0],
        nodes[cols][0],
        nodes[cols][rows],
        nodes[0][rows],
    ];
    let centre = inner_outline
        .centroid()
        .map(|c| (c.x(), c.y()))
        .unwrap_or((0.0, 0.0));
    let outside = |(x, y): (f64, f64), off: f64| -> (f64, f64) {
        let (dx, dy) = (x - centre.0, y - centre.1);
        let l = dx.hypot(dy).max(1e-9);
        (x + dx / l * off, y + dy / l * off)
    };
    let n_outer = toolsel::layer_count(thickness, ap, delta).max(1);
    let outer_finish_tool = lib.finishing_tool(flange).clone();
    let mut outer_rough = Vec::new();
    for k in 1..=n_outer {
        let z = -(k as f64 * ap).min(thickness);
        let pts: Vec<Point3> = corners
            .iter()
            .map(|&c| {
                let (x, y) = outside(c, flange * std::f64::consts::SQRT_2 + big.radius());
                pt(x, y, z)
            })
            .collect();
        let c = b.add(
            format!("OC-R{k}"),
            &big,
            StepKind::OuterContour,
            k - 1,
            z,
            "outer",
            plate_perim,
            closed_modes(&pts[..1]),
            (0, k as u64),
        );
        if let Some(&prev) = outer_rough.last() {
            b.prec.push((prev, c));
        }
        outer_rough.push(c);
    }
    let z_of = -thickness;
    let pts: Vec<Point3> = corners
        .iter()
        .map(|&c| {
            let (x, y) = outside(
                c,
                flange * std::f64::consts::SQRT_2 + outer_finish_tool.radius(),
            );
            pt(x, y, z_of)
        })
        .collect();
    let outer_finish = b.add(
        "OC-F".into(),
        &outer_finish_tool,
        StepKind::OuterContour,
        n_outer,
        z_of,
        "outer",
        plate_perim,
        closed_modes(&pts),
        (0, n_outer as u64 + 1),
    );
    b.prec.push((
        *outer_rough.last().expect("at least one layer"),
        outer_finish,
    ));

    // pockets
    struct Pocket {
        rough: Vec<usize>,
        finish: Vec<usize>,
        groove: Vec<usize>,
        area: f64,
        layers: u32,
    }
    let np = rows * cols;
    let mut pockets: Vec<Pocket> = Vec::with_capacity(np);
    let mut rough_assign: Vec<String> = Vec::with_capacity(np);
    let mut jobs: Vec<RoughJob> = Vec::with_capacity(np);
    for j in 0..rows {
        for i in 0..cols {
            let pno = pockets.len() + 1;
            let fid = format!("P{pno:03}");
            let quad = [
                nodes[i][j],
                nodes[i + 1][j],
                nodes[i + 1][j + 1],
                nodes[i][j + 1],
            ];
            let mut ring: Vec<_> = quad.iter().map(|&(x, y)| coord! {x: x, y: y}).collect();
            ring.push(ring[0]);
            let q = Polygon::new(LineString::from(ring), vec![]);
            let r = r3(rng.random_range(rmin..=rmax));
            let core = poly_of(q.buffer(-(rib / 2.0 + r)));
            let Some(core) = core else {
                return bad(format!(
                    "pocket {pno} vanishes: reduce jitter/skew or rib/radius"
                ));
            };
            let mut poly = poly_of(core.buffer(r)).expect("rounded pocket");
            let c = poly.centroid().map(|c| (c.x(), c.y())).unwrap_or(quad[0]);
            let island = rng.random_bool(p.float("islands"));
            let island_r = 0.12 * pitch;
            if island {
                let boss = geo::Point::new(c.0, c.1).buffer(island_r);
                if let Some(pp) = poly_of(poly.difference(&boss)) {
                    poly = pp;
                }
            }
            let open = rng.random_bool(p.float("open"));
            let h = if open {
                thickness
            } else {
                r3(rng.random_range(dmin..=dmax))
            };
            let groove = rng.random_bool(p.float("grooves"));
            let groove_side = rng.random_range(0..4usize);
            let area = poly.unsigned_area();
            let n = toolsel::layer_count(h, ap, delta).max(1);
            rough_assign.push(lib.roughing_tool(&poly, eta_min).id.clone());
            jobs.push(RoughJob { area, layers: n });
            let fin = lib.finishing_tool(r).clone();
            // entry of the roughing helix: between centroid and the first corner (or centroid)
            let e = if island {
                ((c.0 + quad[0].0) / 2.0, (c.1 + quad[0].1) / 2.0)
            } else {
                c
            };
            let mut pk = Pocket {
                rough: Vec::new(),
                finish: Vec::new(),
                groove: Vec::new(),
                area,
                layers: n,
            };
            let key = pno as u64;
            for k in 1..=n {
                let z = if open {
                    -(k as f64 * ap).min(h)
                } else {
                    -(k as f64 * ap).min(h - delta)
                };
                // placeholder tool; set after merging
                let cell = b.add(
                    format!("{fid}-R{k}"),
                    &big,
                    StepKind::PocketRough,
                    k - 1,
                    z,
                    &fid,
                    0.0,
                    closed_modes(&[pt(e.0, e.1, z)]),
                    (key, k as u64),
                );
                if let Some(&prev) = pk.rough.last() {
                    b.prec.push((prev, cell));
                }
                pk.rough.push(cell);
            }
            let last = *pk.rough.last().expect("layers");
            if !open {
                let cell = b.add(
                    format!("{fid}-FF"),
                    &fin,
                    StepKind::PocketFinish,
                    n,
                    -h,
                    &fid,
                    area / fin.cutting_width,
                    closed_modes(&[pt(e.0, e.1, -h)]),
                    (key, n as u64 + 1),
                );
                pk.finish.push(cell);
            }
            // wall finishing: start points at the edge midpoints, one tool radius inside
            let off = rib / 2.0 + fin.radius();
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
                &fin,
                StepKind::PocketFinish,
                n,
                -h,
                &fid,
                perimeter(&poly),
                closed_modes(&starts),
                (key, n as u64 + 2),
            );
            pk.finish.push(wf);
            if island {
                let rr = island_r + fin.radius();
                let starts: Vec<Point3> = (0..4)
                    .map(|s| {
                        let a = std::f64::consts::FRAC_PI_2 * s as f64;
                        pt(c.0 + rr * a.cos(), c.1 + rr * a.sin(), -h)
                    })
                    .collect();
                let cell = b.add(
                    format!("{fid}-IF"),
                    &fin,
                    StepKind::PocketFinish,
                    n,
                    -h,
                    &fid,
                    std::f64::consts::TAU * island_r,
                    closed_modes(&starts),
                    (key, n as u64 + 3),
                );
                pk.finish.push(cell);
            }
            for &f in &pk.finish {
                b.prec.push((last, f));
            }
            if groove {
                let (a, bb) = (quad[groove_side], quad[(groove_side + 1) % 4]);
                let inset = |q: (f64, f64)| {
                    let (dx, dy) = (c.0 - q.0, c.1 - q.1);
                    let l = dx.hypot(dy).max(1e-9);
                    let o = (rib / 2.0 + r) * std::f64::consts::SQRT_2 + fin.radius();
                    (q.0 + dx / l * o, q.1 + dy / l * o)
                };
                let (a, bb) = (inset(a), inset(bb));
                let z = -h / 2.0;
                let len = (bb.0 - a.0).hypot(bb.1 - a.1);
                let cell = b.add(
                    format!("{fid}-G"),
                    &fin,
                    StepKind::WallGroove,
                    n,
                    z,
                    &fid,
                    len,
                    stroke_modes(pt(a.0, a.1, z), pt(bb.0, bb.1, z), true),
                    (key, n as u64 + 4),
                );
                b.prec.push((last, cell));
                pk.groove.push(cell);
            }
            if p.bool("outer_first") {
                b.prec
                    .push((*outer_rough.last().expect("layers"), pk.rough[0]));
            }
            pockets.push(pk);
        }
    }
    // roughing tool groups, merged by mu
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
    let before = census(&rough_assign);
    let merges = toolsel::merge_groups(&jobs, &mut rough_assign, &lib, mu);
    let comment = format!(
        "pocket roughing tools (eta_min {eta_min}): {before}; after {merges} merge(s) at mu > {mu}: {}",
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

    // ribs (interior grid edges) and flange segments (border grid edges)
    let rib_tool = lib.finishing_tool(2.0 * rib).clone();
    let pocket_of = |i: usize, j: usize| j * cols + i;
    let mut ribs_of: Vec<Vec<usize>> = vec![Vec::new(); np];
    let mut flange_of: Vec<Vec<usize>> = vec![Vec::new(); np];
    let mut flange_cells: Vec<FlangeSeg> = Vec::new();
    let base = np as u64 + 1;
    let mut seg = 0u64;
    let mut edge =
        |b: &mut Builder, a: (f64, f64), e: (f64, f64), sides: &[usize], border: bool| {
            seg += 1;
            let (a2, e2) = if border {
                let sh = |q: (f64, f64)| outside(q, flange / 2.0);
                (sh(a), sh(e))
            } else {
                (a, e)
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
            for &s in sides {
                if border {
                    flange_of[s].push(c);
                } else {
                    ribs_of[s].push(c);
                }
            }
            if border {
                flange_cells.push((c, a2, e2));
            }
        };
    for j in 0..=rows {
        for i in 0..cols {
            let mut sides = Vec::new();
            if j > 0 {
                sides.push(pocket_of(i, j - 1));
            }
            if j < rows {
                sides.push(pocket_of(i, j));
            }
            edge(
                &mut b,
                nodes[i][j],
                nodes[i + 1][j],
                &sides,
                j == 0 || j == rows,
            );
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
            edge(
                &mut b,
                nodes[i][j],
                nodes[i][j + 1],
                &sides,
                i == 0 || i == cols,
            );
        }
    }
    for &(c, _, _) in &flange_cells {
        b.prec.push((outer_finish, c));
    }
    // rule 4 between the related features of each pocket
    for (k, pk) in pockets.iter().enumerate() {
        let sets: [&[usize]; 4] = [&pk.groove, &pk.finish, &flange_of[k], &ribs_of[k]];
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
    // holes in the flange: face (flange segment) before hole
    let nholes = p.int("holes") as usize;
    if nholes > 0 {
        let Some(drill) = lib.drill_for(p.float("hole_diameter")).cloned() else {
            return bad("holes need a drill in the tool library".into());
        };
        for h in 0..nholes {
            let (fc, a, e) = flange_cells[(h * flange_cells.len()) / nholes];
            let t = rng.random_range(0.2..0.8);
            let (x, y) = (a.0 + (e.0 - a.0) * t, a.1 + (e.1 - a.1) * t);
            let c = b.add(
                format!("H{:03}", h + 1),
                &drill,
                StepKind::Hole,
                0,
                -thickness,
                "holes",
                thickness,
                closed_modes(&[pt(x, y, 0.0)]),
                (base + 2, h as u64),
            );
            b.prec.push((fc, c));
        }
    }

    // tools actually used, largest first
    let (used, rank) = tools_larger_first(&lib, &b.cells);
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
    Ok(Instance {
        name: format!("panel-{rows}x{cols}-s{seed}"),
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
    })
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

//! Geometric and generalized families: `geometric-sparse` (a CNC part of pockets and holes
//! with sparse precedence, 10³–10⁵ cells) and `generalized` (a matrix instance whose cells
//! have several modes).

use super::{check_matrix_n, dag::random_dag, n_spec, p_spec, sop_shaped};
use crate::error::Result;
use crate::generate::common::{programmed_order, pt};
use crate::model::{Cell, Instance, Machine, Mode, StepKind, Tool};
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::TAU;

/// `geometric-sparse` parameters.
pub static GEOMETRIC_SPECS: &[ParamSpec] = &[
    n_spec("1000", 1_000_000),
    ParamSpec {
        name: "size",
        default: "1000",
        kind: ParamKind::float(100.0, 1e8),
        help: "side of the square part (mm)",
    },
    ParamSpec {
        name: "layers",
        default: "3",
        kind: ParamKind::int(1, 20),
        help: "most roughing layers of a pocket (each pocket has 1..=layers)",
    },
    ParamSpec {
        name: "modes",
        default: "4",
        kind: ParamKind::int(1, 16),
        help: "start points per closed contour",
    },
    ParamSpec {
        name: "holes",
        default: "0.3",
        kind: ParamKind::float(0.0, 1.0),
        help: "share of features that are holes (spot drill, then drill)",
    },
];

/// `generalized` parameters.
pub static GENERALIZED_SPECS: &[ParamSpec] = &[
    n_spec("100", super::MAX_N),
    ParamSpec {
        name: "c",
        default: "1000",
        kind: ParamKind::int(1, 1_000_000),
        help: "side of the square the nodes lie in; costs are rounded distances",
    },
    p_spec("15"),
    ParamSpec {
        name: "modes",
        default: "4",
        kind: ParamKind::int(1, 64),
        help: "most modes (nodes) per cell; each cell has 1..=modes",
    },
    ParamSpec {
        name: "spread",
        default: "5",
        kind: ParamKind::float(0.0, 100.0),
        help: "a cell's nodes lie within spread % of c of its centre",
    },
    ParamSpec {
        name: "open",
        default: "0",
        kind: ParamKind::float(0.0, 1.0),
        help: "share of cells that are open features: two modes, entered at one end and left at the other (asymmetric costs)",
    },
];

const STEP: f64 = 2.0;

fn tools() -> Vec<Tool> {
    [
        ("T1", 16.0, 800.0),
        ("T2", 8.0, 600.0),
        ("T3", 6.0, 300.0),
        ("T4", 5.0, 200.0),
    ]
    .iter()
    .map(|&(id, d, f)| Tool {
        id: id.into(),
        diameter: d,
        name: None,
        feed: Some(f),
    })
    .collect()
}

/// `geometric-sparse`: pockets roughed in layers (layer l before l + 1) then finished (after
/// the last layer), and holes spot-drilled then drilled; features at random in a square.
pub fn geometric_sparse(p: &Params, seed: u64) -> Result<Instance> {
    let n = p.int("n") as usize;
    let size = p.float("size");
    let layers = p.int("layers");
    let modes = p.int("modes") as usize;
    let holes = p.float("holes");
    // every parameter lies in its declared range (checked by `Params`)
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut cells: Vec<Cell> = Vec::with_capacity(n);
    let mut precedence = Vec::new();
    let mut rank = Vec::with_capacity(n);
    let mut key = Vec::with_capacity(n);
    let mut feature = 0u64;
    while cells.len() < n {
        let left = n - cells.len();
        let (x, y) = (rng.random_range(0.0..size), rng.random_range(0.0..size));
        let fid = format!("f{feature}");
        let push = |cells: &mut Vec<Cell>, mut c: Cell, r: u32, k: (u64, u64)| {
            c.feature = Some(fid.clone());
            cells.push(c);
            (r, k)
        };
        if rng.random_bool(holes) {
            let depth = rng.random_range(5.0..25.0);
            let specs = [("T3", -1.0, 1.0), ("T4", -depth, depth)];
            let first = cells.len();
            for (t, (tool, z, cut)) in specs.into_iter().enumerate().take(left) {
                let mut c = Cell::new(
                    format!("h{feature}-{t}"),
                    tool,
                    vec![Mode::closed(pt(x, y, z))],
                );
                c.step = StepKind::Hole;
                c.z = z;
                c.cut_length = cut;
                let (r, k) = push(&mut cells, c, 2 + t as u32, (feature, 0));
                rank.push(r);
                key.push(k);
            }
            if cells.len() == first + 2 {
                precedence.push((first, first + 1));
            }
        } else {
            let radius: f64 = rng.random_range(5.0..25.0);
            let k = (rng.random_range(1..=layers) as usize).min(left.saturating_sub(1).max(1));
            let phase = rng.random_range(0.0..TAU);
            let ring = |r: f64, z: f64| -> Vec<Mode> {
                (0..modes)
                    .map(|m| {
                        let a = phase + TAU * m as f64 / modes as f64;
                        Mode::closed(pt(x + r * a.cos(), y + r * a.sin(), z))
                    })
                    .collect()
            };
            let first = cells.len();
            for l in 0..k {
                let z = -STEP * (l as f64 + 1.0);
                let rr = (radius - 8.0).max(1.0);
                let mut c = Cell::new(format!("p{feature}-r{l}"), "T1", ring(rr, z));
                c.step = StepKind::PocketRough;
                c.layer = l as u32;
                c.z = z;
                c.cut_length = TAU * rr;
                let (r, kk) = push(&mut cells, c, 0, (feature, l as u64));
                rank.push(r);
                key.push(kk);
                if l > 0 {
                    precedence.push((first + l - 1, first + l));
                }
            }
            if cells.len() < n {
                let z = -STEP * k as f64;
                let mut c = Cell::new(format!("p{feature}-f"), "T2", ring(radius - 4.0, z));
                c.step = StepKind::PocketFinish;
                c.layer = (k - 1) as u32;
                c.z = z;
                c.cut_length = TAU * (radius - 4.0);
                let (r, kk) = push(&mut cells, c, 1, (feature, k as u64));
                rank.push(r);
                key.push(kk);
                precedence.push((first + k - 1, cells.len() - 1));
            }
        }
        feature += 1;
    }
    let order = programmed_order(n, &precedence, &rank, &key);
    let machine = Machine {
        home: pt(0.0, 0.0, 50.0),
        tool_change: pt(0.0, 0.0, 50.0),
        clearance: 5.0,
        ..Machine::default()
    };
    Ok(Instance {
        name: format!("geometric-sparse-n{n}-s{seed}"),
        machine,
        tools: tools(),
        cells,
        precedence,
        as_given: Some(order),
        ..Instance::default()
    })
}

/// Checks `generalized`'s parameters together (the matrix's size depends on n and modes);
/// the number of cells.
pub fn generalized_check(p: &Params) -> Result<u64> {
    let (n, modes) = (p.int("n") as usize, p.int("modes") as usize);
    let most = if p.float("open") > 0.0 {
        modes.max(2)
    } else {
        modes
    };
    check_matrix_n("generalized", n, most)?;
    Ok(n as u64 + 2)
}

/// `generalized`: cells of 1..=modes nodes each, the nodes of a cell near its centre in a
/// square of side c; costs are rounded distances between nodes; precedence of closure
/// density p %. SOP-shaped (dummy start and end cells). With `open` > 0 that share of the
/// cells are open features instead (a slot, a line, an open contour): two modes, the same
/// stroke cut one way or the other, so a mode is entered at one end and left at the other
/// and the cost of u then v is the distance from u's exit to v's entry (asymmetric).
pub fn generalized(p: &Params, seed: u64) -> Result<Instance> {
    generalized_check(p)?;
    let n = p.int("n") as usize;
    let modes = p.int("modes") as usize;
    let open = p.float("open");
    let c = p.int("c");
    let density = p.float("p") / 100.0;
    let spread = p.float("spread");
    let side = c as f64;
    let radius = spread / 100.0 * side;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut counts: Vec<usize> = (0..n).map(|_| rng.random_range(1..=modes)).collect();
    // the start points of every cell, near its centre
    let mut points: Vec<Vec<(f64, f64)>> = Vec::with_capacity(n);
    for &k in &counts {
        let (cx, cy) = (rng.random_range(0.0..side), rng.random_range(0.0..side));
        let pts: Vec<(f64, f64)> = (0..k)
            .map(|_| {
                let a = rng.random_range(0.0..TAU);
                let r = radius * rng.random_range(0.0f64..1.0).sqrt();
                (cx + r * a.cos(), cy + r * a.sin())
            })
            .collect();
        points.push(pts);
    }
    let edges = random_dag(n, density, &mut rng);
    // Open features come from a stream of their own, so `open = 0` writes the same bytes
    // as before the parameter existed.
    // (entry, exit) of every node, cell by cell
    let mut nodes: Vec<((f64, f64), (f64, f64))> = Vec::new();
    let mut side_rng = ChaCha8Rng::seed_from_u64(seed);
    side_rng.set_stream(1);
    for (cell, pts) in points.iter().enumerate() {
        if open > 0.0 && side_rng.random_bool(open) {
            // a stroke from the cell's first point, up to twice the spread radius long
            let a = pts[0];
            let t = side_rng.random_range(0.0..TAU);
            let len = 2.0 * radius * side_rng.random_range(0.0f64..1.0);
            let b = (a.0 + len * t.cos(), a.1 + len * t.sin());
            nodes.push((a, b));
            nodes.push((b, a));
            counts[cell] = 2;
        } else {
            nodes.extend(pts.iter().map(|&q| (q, q)));
        }
    }
    let name = format!("generalized-n{n}-c{c}-p{}-s{seed}", p.float("p"));
    let name = if open > 0.0 {
        format!("{name}-open{open}")
    } else {
        name
    };
    Ok(sop_shaped(
        name,
        &counts,
        |u, v| {
            let (a, b) = (nodes[u].1, nodes[v].0);
            ((a.0 - b.0).hypot(a.1 - b.1)).round()
        },
        &edges,
    ))
}

//! `uniform`: cells at random in a box, for scaling studies (up to millions of cells).
//!
//! Each cell is an open stroke (entry → exit) or, with probability `closed`, a closed contour
//! with `modes` candidate start points on a circle. Reversible open cells get a second,
//! reversed mode. Precedence is drawn over a random hidden order: either every pair with
//! probability `density` (O(n²), for n ≤ 5000) or `preds` random predecessors per cell (sparse).

use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{Cell, Instance, Machine, Mode, StepKind, Tool, Visit};
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Parameters.
pub static SPECS: &[ParamSpec] = &[
    ParamSpec {
        name: "n",
        default: "100",
        kind: ParamKind::int(1, crate::params::MAX_CELLS),
        help: "number of cells (about 1.5 KB of memory each once generated and saved)",
    },
    ParamSpec {
        name: "size",
        default: "1000",
        kind: ParamKind::float_above(0.0, 1e8),
        help: "side of the square box (mm)",
    },
    ParamSpec {
        name: "modes",
        default: "1",
        kind: ParamKind::int(1, 1000),
        help: "start points per closed cell",
    },
    ParamSpec {
        name: "closed",
        default: "0",
        kind: ParamKind::float(0.0, 1.0),
        help: "fraction of closed contours",
    },
    ParamSpec {
        name: "reversible",
        default: "true",
        kind: ParamKind::Bool,
        help: "open cells may be cut either way",
    },
    ParamSpec {
        name: "length",
        default: "20",
        kind: ParamKind::float(0.0, 1e6),
        help: "mean stroke length / contour radius (mm)",
    },
    ParamSpec {
        name: "tools",
        default: "1",
        kind: ParamKind::int(1, 10_000),
        help: "number of tools",
    },
    ParamSpec {
        name: "layers",
        default: "1",
        kind: ParamKind::int(1, 1_000_000),
        help: "number of depth layers",
    },
    ParamSpec {
        name: "density",
        default: "0",
        kind: ParamKind::float(0.0, 1.0),
        help: "probability of a precedence pair (n <= 5000)",
    },
    ParamSpec {
        name: "lift",
        default: "7",
        kind: ParamKind::float(0.0, 1e6),
        help: "height of the retract plane above the top layer (mm); 0 = plotter/laser-like travel with no vertical moves on the top layer",
    },
    ParamSpec {
        name: "preds",
        default: "0",
        kind: ParamKind::int(0, 1000),
        help: "random predecessors per cell (sparse precedence)",
    },
];

/// Most modes a uniform instance may have in all (n × modes, open cells have 2): 10⁸.
const MAX_MODES: u64 = 100_000_000;

/// Most precedence pairs `preds` may draw in all (n × preds): 10⁸, 1.6 GB of pairs.
const MAX_PAIRS: u64 = 100_000_000;

/// Checks what the declared ranges cannot (limits on the parameters' combination); the
/// number of cells the instance will have.
pub fn check(p: &Params) -> Result<u64> {
    let n = p.int("n");
    let (modes, preds) = (p.int("modes"), p.int("preds"));
    let bad = |m: String| Err(Error::Param(format!("uniform: {m}")));
    if n.saturating_mul(modes.max(2)) > MAX_MODES {
        return bad(format!(
            "n x modes = {} modes, more than {MAX_MODES}: lower n or modes",
            n.saturating_mul(modes.max(2))
        ));
    }
    if n.saturating_mul(preds) > MAX_PAIRS {
        return bad(format!(
            "n x preds = {} precedence pairs, more than {MAX_PAIRS}: lower n or preds",
            n.saturating_mul(preds)
        ));
    }
    if p.float("density") > 0.0 && n > 5000 {
        return bad("density is O(n^2): use preds=K for more than 5000 cells".into());
    }
    Ok(n)
}

/// Generates a uniform instance.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    check(p)?;
    let n = p.int("n") as usize;
    let size = p.float("size");
    let modes = p.int("modes") as usize;
    let closed = p.float("closed");
    let reversible = p.bool("reversible");
    let len = p.float("length");
    let ntools = p.int("tools") as usize;
    let layers = p.int("layers") as u32;
    let density = p.float("density");
    let preds = p.int("preds") as usize;
    let lift = p.float("lift");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let step = 2.0;
    let tools: Vec<Tool> = (0..ntools)
        .map(|t| Tool {
            id: format!("T{}", t + 1),
            diameter: 20.0 / (t as f64 + 1.0),
            name: None,
            feed: Some(600.0 - 50.0 * (t.min(8) as f64)),
        })
        .collect();
    let mut cells = Vec::with_capacity(n);
    for i in 0..n {
        let layer = rng.random_range(0..layers);
        let z = -(layer as f64 + 1.0) * step;
        let x = rng.random_range(0.0..size);
        let y = rng.random_range(0.0..size);
        let tool = rng.random_range(0..ntools);
        let is_closed = closed > 0.0 && rng.random_bool(closed);
        let (ms, cut, rev) = if is_closed {
            let r = len * rng.random_range(0.5..1.5);
            let phase = rng.random_range(0.0..std::f64::consts::TAU);
            let ms: Vec<Mode> = (0..modes)
                .map(|k| {
                    let a = phase + std::f64::consts::TAU * k as f64 / modes as f64;
                    Mode::closed(Point3::new(x + r * a.cos(), y + r * a.sin(), z))
                })
                .collect();
            (ms, std::f64::consts::TAU * r, false)
        } else {
            let l = len * rng.random_range(0.5..1.5);
            let a = rng.random_range(0.0..std::f64::consts::TAU);
            let e = Point3::new(x, y, z);
            let f = Point3::new(x + l * a.cos(), y + l * a.sin(), z);
            let m = Mode::new(e, f);
            let ms = if reversible {
                vec![m, m.reversed()]
            } else {
                vec![m]
            };
            (ms, l, reversible)
        };
        let mut c = Cell::new(format!("c{i}"), format!("T{}", tool + 1), ms);
        c.step = if is_closed {
            StepKind::PocketRough
        } else {
            StepKind::Other
        };
        c.layer = layer;
        c.z = z;
        c.cut_length = cut;
        c.reversible = rev;
        cells.push(c);
    }
    // precedence over a hidden random order
    let hidden = super::common::random_permutation(n, &mut rng);
    let mut precedence = Vec::new();
    if density > 0.0 {
        for a in 0..n {
            for b in a + 1..n {
                if rng.random_bool(density) {
                    precedence.push((hidden[a], hidden[b]));
                }
            }
        }
    }
    if preds > 0 {
        for b in 1..n {
            for _ in 0..preds.min(b) {
                let a = rng.random_range(0..b);
                precedence.push((hidden[a], hidden[b]));
            }
        }
        precedence.sort_unstable();
        precedence.dedup();
    }
    // as programmed: by tool, then layer, then cell number (a typical unoptimized CAM order)
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by_key(|&c| (cells[c].tool.clone(), cells[c].layer, c));
    let machine = Machine {
        home: Point3::new(0.0, 0.0, 50.0),
        tool_change: Point3::new(0.0, 0.0, 50.0),
        clearance: lift - step,
        ..Machine::default()
    };
    Ok(Instance {
        name: format!("uniform-n{n}-s{seed}"),
        machine,
        tools,
        cells,
        precedence,
        as_given: Some(order.into_iter().map(|c| Visit::new(c, 0)).collect()),
        ..Instance::default()
    })
}

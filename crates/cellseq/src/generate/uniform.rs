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
        kind: ParamKind::Int,
        help: "number of cells",
    },
    ParamSpec {
        name: "size",
        default: "1000",
        kind: ParamKind::Float,
        help: "side of the square box (mm)",
    },
    ParamSpec {
        name: "modes",
        default: "1",
        kind: ParamKind::Int,
        help: "start points per closed cell",
    },
    ParamSpec {
        name: "closed",
        default: "0",
        kind: ParamKind::Float,
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
        kind: ParamKind::Float,
        help: "mean stroke length / contour radius (mm)",
    },
    ParamSpec {
        name: "tools",
        default: "1",
        kind: ParamKind::Int,
        help: "number of tools",
    },
    ParamSpec {
        name: "layers",
        default: "1",
        kind: ParamKind::Int,
        help: "number of depth layers",
    },
    ParamSpec {
        name: "density",
        default: "0",
        kind: ParamKind::Float,
        help: "probability of a precedence pair (n <= 5000)",
    },
    ParamSpec {
        name: "lift",
        default: "7",
        kind: ParamKind::Float,
        help: "height of the retract plane above the top layer (mm); 0 = plotter/laser-like travel with no vertical moves on the top layer",
    },
    ParamSpec {
        name: "preds",
        default: "0",
        kind: ParamKind::Int,
        help: "random predecessors per cell (sparse precedence)",
    },
];

/// Generates a uniform instance.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    let n = p.int("n") as usize;
    let size = p.float("size");
    let modes = p.int("modes").max(1) as usize;
    let closed = p.float("closed");
    let reversible = p.bool("reversible");
    let len = p.float("length");
    let ntools = p.int("tools").max(1) as usize;
    let layers = p.int("layers").max(1) as u32;
    let density = p.float("density");
    let preds = p.int("preds") as usize;
    let lift = p.float("lift");
    let bad = |m: String| Err(Error::Param(format!("uniform: {m}")));
    if n == 0 {
        return bad("n must be at least 1".into());
    }
    if size.is_nan() || size <= 0.0 || len.is_nan() || len < 0.0 {
        return bad("size must be positive and length non-negative".into());
    }
    if lift.is_nan() || lift < 0.0 {
        return bad("lift must be non-negative".into());
    }
    if !(0.0..=1.0).contains(&closed) || !(0.0..=1.0).contains(&density) {
        return bad("closed and density must lie in [0, 1]".into());
    }
    if density > 0.0 && n > 5000 {
        return bad("density is O(n^2): use preds=K for more than 5000 cells".into());
    }
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
    let mut hidden: Vec<usize> = (0..n).collect();
    for i in (1..n).rev() {
        let j = rng.random_range(0..=i);
        hidden.swap(i, j);
    }
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

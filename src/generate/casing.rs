//! `casing`: rough machining of a layered casing (paper 004).
//!
//! The cylindrical casing (diameter `diameter`) is unrolled to the plane: x = arc length in
//! [0, π·D], y = axial position. `regions` annular regions of axial width `width` lie along
//! the axis. Each region carries features (triangular, round and keyway blocks) that appear
//! as the relative cutting depth w grows over the 5 layers w = 0.15, 0.35, 0.55, 0.75, 0.95
//! (none at the first layer, as in the paper); the features present at a layer split the
//! region into fan-shaped sub-regions (arc intervals; the seam at x = 0 also splits). Each
//! sub-region at each layer is a cell cut by axial zig-zag passes, with an advance point and a
//! retract point; reversible cells have the reversed mode as well.
//!
//! One flat end mill (`tool_diameter`, default 12 mm), cutting feed 500 mm/min and rapid
//! 2000 mm/min by default. `machine.link_distance` (`link_distance`, default 60 mm: most blocks
//! plus the tool on both sides) lets the tool go from one sub-region to the next one around a
//! block, or into the neighbouring annular region, at the same depth and cutting feed without
//! a lift, as in the paper (where only 26 lifts remain after optimization). A lift costs
//! `lift_time` (default 5 s: retract, approach and plunge at reduced feed) plus its rapid
//! moves, so with the default feeds a link is the faster move up to about 60 mm.
//!
//! Precedence: a sub-region at layer k+1 after every sub-region of layer k of the same region
//! whose arc interval overlaps it; with `region_first=true` (the paper's practice) all
//! sub-regions of region r at a layer come before those of region r+1 at that layer.
//! As-programmed order: layer by layer, sub-regions in numbering order (region, then arc).

use super::common::{programmed_order, pt, r3, stroke_modes};
use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{Cell, Instance, Machine, StepKind, Tool};
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Relative cutting depths of the 5 layers (paper 004).
pub const LAYERS_W: [f64; 5] = [0.15, 0.35, 0.55, 0.75, 0.95];

/// Parameters.
pub static SPECS: &[ParamSpec] = &[
    ParamSpec {
        name: "regions",
        default: "3",
        kind: ParamKind::Int,
        help: "annular regions along the axis",
    },
    ParamSpec {
        name: "features",
        default: "6",
        kind: ParamKind::Int,
        help: "mean number of features per region",
    },
    ParamSpec {
        name: "diameter",
        default: "300",
        kind: ParamKind::Float,
        help: "casing diameter (mm); unrolled length π·D",
    },
    ParamSpec {
        name: "width",
        default: "60",
        kind: ParamKind::Float,
        help: "axial width of an annular region (mm)",
    },
    ParamSpec {
        name: "gap",
        default: "0",
        kind: ParamKind::Float,
        help: "axial gap between regions (mm)",
    },
    ParamSpec {
        name: "depth",
        default: "20",
        kind: ParamKind::Float,
        help: "radial allowance removed at w = 1 (mm)",
    },
    ParamSpec {
        name: "tool_diameter",
        default: "12",
        kind: ParamKind::Float,
        help: "flat end mill diameter (mm)",
    },
    ParamSpec {
        name: "cut_feed",
        default: "500",
        kind: ParamKind::Float,
        help: "cutting feed (mm/min)",
    },
    ParamSpec {
        name: "rapid_feed",
        default: "2000",
        kind: ParamKind::Float,
        help: "rapid feed (mm/min)",
    },
    ParamSpec {
        name: "stepover",
        default: "0.6",
        kind: ParamKind::Float,
        help: "zig-zag step-over, fraction of the tool diameter",
    },
    ParamSpec {
        name: "link_distance",
        default: "60",
        kind: ParamKind::Float,
        help: "same-depth moves up to this long go around a block without a lift (mm)",
    },
    ParamSpec {
        name: "lift_time",
        default: "5",
        kind: ParamKind::Float,
        help: "overhead of one lift: retract, approach and plunge at reduced feed (s)",
    },
    ParamSpec {
        name: "reversible",
        default: "true",
        kind: ParamKind::Bool,
        help: "sub-regions may be cut either way (two modes)",
    },
    ParamSpec {
        name: "region_first",
        default: "true",
        kind: ParamKind::Bool,
        help: "finish a region's sub-regions (per layer) before the next region (hard constraint)",
    },
];

/// Feature block shapes; only their arc width matters for the split.
const SHAPES: [(&str, f64, f64); 3] = [
    ("triangular", 25.0, 35.0),
    ("round", 20.0, 30.0),
    ("keyway", 35.0, 50.0),
];

/// Generates a casing.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    let regions = p.int("regions") as usize;
    let mean = p.int("features") as usize;
    let d = p.float("diameter");
    let width = p.float("width");
    let gap = p.float("gap");
    let depth = p.float("depth");
    let td = p.float("tool_diameter");
    let stepover = p.float("stepover") * td;
    let bad = |m: String| Err(Error::Param(format!("casing: {m}")));
    if regions == 0 || regions > 10_000 {
        return bad("regions must lie in 1..=10000".into());
    }
    if !(d > 0.0 && depth > 0.0 && td > 0.0 && width > 2.0 * td && gap >= 0.0 && stepover > 0.0) {
        return bad(
            "diameter, depth, tool_diameter, stepover must be positive, width > 2 tool diameters"
                .into(),
        );
    }
    if !(p.float("cut_feed") > 0.0 && p.float("rapid_feed") > 0.0) {
        return bad("feeds must be positive".into());
    }
    let circ = std::f64::consts::PI * d;
    let max_feats = mean.saturating_add(mean / 2);
    if max_feats > 0 && circ / max_feats as f64 <= 50.0 + 3.0 * td {
        return bad(format!(
            "{mean} features per region do not fit on a circumference of {circ:.0} mm: raise diameter"
        ));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // features per region: (start, end, appearing layer)
    let mut feats: Vec<Vec<(f64, f64, usize)>> = Vec::with_capacity(regions);
    for _ in 0..regions {
        let k = if mean == 0 {
            0
        } else {
            rng.random_range(mean.div_ceil(2)..=max_feats)
        };
        let slot = if k > 0 { circ / k as f64 } else { circ };
        let mut fs = Vec::with_capacity(k);
        for s in 0..k {
            let (_, lo, hi) = SHAPES[rng.random_range(0..SHAPES.len())];
            let w = rng.random_range(lo..=hi);
            let room = (slot - w) / 2.0 - td;
            let centre = (s as f64 + 0.5) * slot + rng.random_range(-0.5..=0.5) * room.max(0.0);
            let appear = rng.random_range(1..LAYERS_W.len());
            fs.push((r3(centre - w / 2.0), r3(centre + w / 2.0), appear));
        }
        feats.push(fs);
    }
    let r = td / 2.0;
    let tool = Tool {
        id: format!("EM{}", td),
        diameter: td,
        name: Some(format!("flat end mill D{td}")),
        feed: None,
    };
    let mut cells: Vec<Cell> = Vec::new();
    let mut keys: Vec<(u64, u64)> = Vec::new();
    let mut prec: Vec<(usize, usize)> = Vec::new();
    // cells of the previous layer per region: (start, end, cell)
    let mut prev: Vec<Vec<(f64, f64, usize)>> = vec![Vec::new(); regions];
    for (l, &w) in LAYERS_W.iter().enumerate() {
        let z = -w * depth;
        let mut number = 0u64;
        let mut layer_regions: Vec<Vec<usize>> = Vec::with_capacity(regions);
        for (ri, fs) in feats.iter().enumerate() {
            let y0 = ri as f64 * (width + gap);
            let y1 = y0 + width;
            let mut active: Vec<(f64, f64)> =
                fs.iter().filter(|f| f.2 <= l).map(|f| (f.0, f.1)).collect();
            active.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut cuts = vec![0.0];
            for &(a, b) in &active {
                cuts.push(a);
                cuts.push(b);
            }
            cuts.push(circ);
            let mut here = Vec::new();
            let mut mine = Vec::new();
            for iv in cuts.chunks(2) {
                let (a0, a1) = (iv[0], iv[1]);
                if a1 - a0 < 2.0 * td {
                    continue; // too narrow for the tool: left to finishing
                }
                number += 1;
                let ex0 = a0 + r;
                let ex1 = a1 - r;
                let passes = ((ex1 - ex0) / stepover).ceil() as usize + 1;
                let yl = y0 + r;
                let yh = y1 - r;
                let exit_y = if passes % 2 == 1 { yh } else { yl };
                let cut = passes as f64 * (yh - yl) + (ex1 - ex0);
                let modes = stroke_modes(pt(ex0, yl, z), pt(ex1, exit_y, z), p.bool("reversible"));
                let mut c = Cell::new(
                    format!("L{}-R{}-S{}", l + 1, ri + 1, number),
                    tool.id.clone(),
                    modes,
                );
                c.step = StepKind::PocketRough;
                c.layer = l as u32;
                c.z = r3(z);
                c.feature = Some(format!("R{}", ri + 1));
                c.cut_length = r3(cut);
                c.reversible = p.bool("reversible");
                let idx = cells.len();
                cells.push(c);
                keys.push((l as u64, number));
                for &(b0, b1, pc) in &prev[ri] {
                    if b0.max(a0) < b1.min(a1) {
                        prec.push((pc, idx));
                    }
                }
                here.push((a0, a1, idx));
                mine.push(idx);
            }
            prev[ri] = here;
            layer_regions.push(mine);
        }
        if p.bool("region_first") {
            for wdw in layer_regions.windows(2) {
                for &a in &wdw[0] {
                    for &b in &wdw[1] {
                        prec.push((a, b));
                    }
                }
            }
        }
    }
    prec.sort_unstable();
    prec.dedup();
    let order = programmed_order(cells.len(), &prec, &vec![0; cells.len()], &keys);
    let machine = Machine {
        home: Point3::new(0.0, -50.0, 50.0),
        tool_change: Point3::new(0.0, -50.0, 50.0),
        clearance: 5.0,
        rapid_feed: p.float("rapid_feed"),
        cut_feed: p.float("cut_feed"),
        tool_change_time: 10.0,
        lift_time: p.float("lift_time"),
        link_distance: p.float("link_distance"),
        initial_tool: Some(tool.id.clone()),
        ..Machine::default()
    };
    Ok(Instance {
        name: format!("casing-r{regions}-f{mean}-s{seed}"),
        machine,
        tools: vec![tool],
        cells,
        precedence: prec,
        as_given: Some(order),
        ..Instance::default()
    })
}

//! `casing`: rough machining of a layered casing (paper 004).
//!
//! The cylindrical casing (diameter `diameter`) is unrolled to the plane: x = arc length in
//! [0, π·D], y = axial position. `regions` annular regions of axial width `width` lie along
//! the axis. Each region carries features (triangular, round and keyway blocks: islands and
//! bosses) that appear as the relative cutting depth w grows over the 5 layers w = 0.15, 0.35,
//! 0.55, 0.75, 0.95 (none at the first layer, as in the paper); a block spans its region's
//! axial width, so the blocks present at a layer split the region into fan-shaped sub-regions
//! (arc intervals; the seam at x = 0 also splits). Each sub-region at each layer is a cell cut
//! by axial zig-zag passes, entered at an advance point and left at a retract point;
//! reversible cells have the reversed mode as well (the paper's swappable point pair).
//!
//! One flat end mill (`tool_diameter`, default 12 mm), cutting feed 500 mm/min and rapid
//! 2000 mm/min by default. At depth the cutter may move from one sub-region to another without
//! a lift (at cutting feed) when the straight move is at most `link_distance` long (default
//! 60 mm) and crosses no block standing above that depth: every block is a keep-out area of
//! the machine ([`crate::model::KeepOut`], the block grown by the tool radius, its top between
//! the layer before it appears and the layer where it does). So a move between neighbouring
//! sub-regions of one region (a block between them) lifts, and a move into the neighbouring
//! annular region past the block's end can stay at depth. A lift costs `lift_time` (default
//! 5 s: retract, approach and plunge at reduced feed) plus its rapid moves.
//!
//! Precedence: a sub-region at layer k+1 after every sub-region of layer k of the same region
//! whose arc interval overlaps it; with `region_first=true` all sub-regions of region r at a
//! layer come before those of region r+1 at that layer (off by default: the paper's own
//! optimized order of its w = 0.35 example, 1-2-7-8-6-5-4-3, leaves the numbering's region
//! order).
//! As-programmed order: layer by layer, sub-regions in numbering order (region, then arc),
//! each from its advance point (the paper's 1-2-3-…). [`paper_example`] builds the paper's
//! w = 0.35 example (4 sub-regions, 8 advance/retract points). Assumptions where the paper is
//! silent: `notes/paper004.md`.

use super::common::{programmed_order, pt, r3, stroke_modes};
use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{Cell, Instance, KeepOut, Machine, StepKind, Tool, Visit};
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
        kind: ParamKind::int(1, 10_000),
        help: "annular regions along the axis",
    },
    ParamSpec {
        name: "features",
        default: "6",
        kind: ParamKind::int(0, 10_000),
        help: "mean number of features per region",
    },
    ParamSpec {
        name: "diameter",
        default: "300",
        kind: ParamKind::float_above(0.0, 1e6),
        help: "casing diameter (mm); unrolled length π·D",
    },
    ParamSpec {
        name: "width",
        default: "60",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "axial width of an annular region (mm)",
    },
    ParamSpec {
        name: "gap",
        default: "0",
        kind: ParamKind::float(0.0, 1e4),
        help: "axial gap between regions (mm)",
    },
    ParamSpec {
        name: "depth",
        default: "20",
        kind: ParamKind::float_above(0.0, 1e4),
        help: "radial allowance removed at w = 1 (mm)",
    },
    ParamSpec {
        name: "tool_diameter",
        default: "12",
        kind: ParamKind::float_above(0.0, 1000.0),
        help: "flat end mill diameter (mm)",
    },
    ParamSpec {
        name: "cut_feed",
        default: "500",
        kind: ParamKind::float(0.001, 1e6),
        help: "cutting feed (mm/min)",
    },
    ParamSpec {
        name: "rapid_feed",
        default: "2000",
        kind: ParamKind::float(0.001, 1e6),
        help: "rapid feed (mm/min)",
    },
    ParamSpec {
        name: "stepover",
        default: "0.6",
        kind: ParamKind::float_above(0.0, 1.0),
        help: "zig-zag step-over, fraction of the tool diameter",
    },
    ParamSpec {
        name: "link_distance",
        default: "60",
        kind: ParamKind::float(0.0, 1e9),
        help: "same-depth moves up to this long go around a block without a lift (mm)",
    },
    ParamSpec {
        name: "lift_time",
        default: "5",
        kind: ParamKind::float(0.0, 1e6),
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
        default: "false",
        kind: ParamKind::Bool,
        help: "all sub-regions of region r (per layer) before those of region r+1 (hard constraint)",
    },
];

/// Feature block shapes; only their arc width matters for the split.
const SHAPES: [(&str, f64, f64); 3] = [
    ("triangular", 25.0, 35.0),
    ("round", 20.0, 30.0),
    ("keyway", 35.0, 50.0),
];

/// Features per region: (start, end, appearing layer), `mean` / 2 to `max_feats` of them, one
/// per equal slot of the circumference, each placed at random inside its slot.
fn features(
    regions: usize,
    (mean, max_feats): (usize, usize),
    circ: f64,
    td: f64,
    rng: &mut ChaCha8Rng,
) -> Vec<Vec<(f64, f64, usize)>> {
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
    feats
}

/// The cells built so far, their programming keys and precedence.
#[derive(Default)]
struct Cells {
    cells: Vec<Cell>,
    keys: Vec<(u64, u64)>,
    prec: Vec<(usize, usize)>,
}

/// The casing's size: circumference, region width and gap.
struct Geometry {
    circ: f64,
    width: f64,
    gap: f64,
}

/// The sub-regions of layer `l` in every region: the arcs between the features present at this
/// layer, each after the overlapping sub-regions of the layer above (`prev`, updated). Returns
/// the layer's cells per region.
fn layer(
    out: &mut Cells,
    g: &Geometry,
    cut: &Cut,
    l: usize,
    feats: &[Vec<(f64, f64, usize)>],
    prev: &mut [Vec<(f64, f64, usize)>],
) -> Vec<Vec<usize>> {
    let td = 2.0 * cut.radius;
    let mut number = 0u64;
    let mut layer_regions: Vec<Vec<usize>> = Vec::with_capacity(feats.len());
    for (ri, fs) in feats.iter().enumerate() {
        let y0 = ri as f64 * (g.width + g.gap);
        let y1 = y0 + g.width;
        let mut active: Vec<(f64, f64)> =
            fs.iter().filter(|f| f.2 <= l).map(|f| (f.0, f.1)).collect();
        active.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut cuts = vec![0.0];
        for &(a, b) in &active {
            cuts.push(a);
            cuts.push(b);
        }
        cuts.push(g.circ);
        let mut here = Vec::new();
        let mut mine = Vec::new();
        for iv in cuts.chunks(2) {
            let (a0, a1) = (iv[0], iv[1]);
            if a1 - a0 < 2.0 * td {
                continue; // too narrow for the tool: left to finishing
            }
            number += 1;
            let c = sub_region(
                cut,
                (a0, a1),
                (y0, y1),
                format!("L{}-R{}-S{}", l + 1, ri + 1, number),
                l,
                ri,
            );
            let idx = out.cells.len();
            out.cells.push(c);
            out.keys.push((l as u64, number));
            for &(b0, b1, pc) in &prev[ri] {
                if b0.max(a0) < b1.min(a1) {
                    out.prec.push((pc, idx));
                }
            }
            here.push((a0, a1, idx));
            mine.push(idx);
        }
        prev[ri] = here;
        layer_regions.push(mine);
    }
    layer_regions
}

/// Checks what the declared ranges cannot (limits on the parameters' combination); about how
/// many cells the casing will have, at most.
pub fn check(p: &Params) -> Result<u64> {
    let regions = p.int("regions");
    let mean = p.int("features");
    let td = p.float("tool_diameter");
    let bad = |m: String| Err(Error::Param(format!("casing: {m}")));
    if p.float("width") <= 2.0 * td {
        return bad("width must be more than 2 tool diameters".into());
    }
    if regions.saturating_mul(mean) > 1_000_000 {
        return bad(format!(
            "regions x features = {} features, more than 1000000 (each makes about 5 cells)",
            regions.saturating_mul(mean)
        ));
    }
    let circ = std::f64::consts::PI * p.float("diameter");
    let max_feats = mean.saturating_add(mean / 2);
    if max_feats > 0 && circ / max_feats as f64 <= 50.0 + 3.0 * td {
        return bad(format!(
            "{mean} features per region do not fit on a circumference of {circ:.0} mm: raise diameter"
        ));
    }
    // five layers of a region's features and the blocks between them
    Ok(regions * (max_feats + 1) * 2 * LAYERS_W.len() as u64)
}

/// Generates a casing.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    check(p)?;
    let regions = p.int("regions") as usize;
    let mean = p.int("features") as usize;
    let d = p.float("diameter");
    let width = p.float("width");
    let gap = p.float("gap");
    let depth = p.float("depth");
    let td = p.float("tool_diameter");
    let stepover = p.float("stepover") * td;
    let circ = std::f64::consts::PI * d;
    let max_feats = mean.saturating_add(mean / 2);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let feats = features(regions, (mean, max_feats), circ, td, &mut rng);
    let r = td / 2.0;
    let tool = Tool {
        id: format!("EM{}", td),
        diameter: td,
        name: Some(format!("flat end mill D{td}")),
        feed: None,
    };
    let mut cells = Cells::default();
    // cells of the previous layer per region: (start, end, cell)
    let mut prev: Vec<Vec<(f64, f64, usize)>> = vec![Vec::new(); regions];
    let geometry = Geometry { circ, width, gap };
    for (l, &w) in LAYERS_W.iter().enumerate() {
        let cut = Cut {
            tool: &tool.id,
            radius: r,
            z: -w * depth,
            stepover,
            reversible: p.bool("reversible"),
        };
        let layer_regions = layer(&mut cells, &geometry, &cut, l, &feats, &mut prev);
        if p.bool("region_first") {
            for wdw in layer_regions.windows(2) {
                for &a in &wdw[0] {
                    for &b in &wdw[1] {
                        cells.prec.push((a, b));
                    }
                }
            }
        }
    }
    let Cells {
        cells,
        keys,
        mut prec,
    } = cells;
    prec.sort_unstable();
    prec.dedup();
    let order = programmed_order(cells.len(), &prec, &vec![0; cells.len()], &keys);
    // every block, grown by the tool radius, stops at-depth moves below its top
    let mut keep_out = Vec::new();
    for (ri, fs) in feats.iter().enumerate() {
        let y0 = ri as f64 * (width + gap);
        for &(a, b, appear) in fs {
            keep_out.push(block(a, b, (y0, y0 + width), r, appear, depth));
        }
    }
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
        keep_out,
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

/// What every sub-region of a layer shares: the tool, the depth, the step-over and whether
/// the cutter may cut it either way.
struct Cut<'a> {
    tool: &'a str,
    radius: f64,
    z: f64,
    stepover: f64,
    reversible: bool,
}

/// The cell of the sub-region over arc `xs` and axial band `ys`: axial zig-zag passes
/// `stepover` apart, tool centre one radius inside the band, entered at the advance point
/// (low arc end, low axial edge) and left at the retract point (high arc end, on the side
/// where the last pass ends).
fn sub_region(
    cut: &Cut,
    (a0, a1): (f64, f64),
    (y0, y1): (f64, f64),
    id: String,
    layer: usize,
    region: usize,
) -> Cell {
    let r = cut.radius;
    let ex0 = a0 + r;
    let ex1 = a1 - r;
    let passes = ((ex1 - ex0) / cut.stepover).ceil() as usize + 1;
    let yl = y0 + r;
    let yh = y1 - r;
    let exit_y = if passes % 2 == 1 { yh } else { yl };
    let length = passes as f64 * (yh - yl) + (ex1 - ex0);
    let modes = stroke_modes(pt(ex0, yl, cut.z), pt(ex1, exit_y, cut.z), cut.reversible);
    let mut c = Cell::new(id, cut.tool, modes);
    c.step = StepKind::PocketRough;
    c.layer = layer as u32;
    c.z = r3(cut.z);
    c.feature = Some(format!("R{}", region + 1));
    c.cut_length = r3(length);
    c.reversible = cut.reversible;
    c
}

/// The keep-out area of a block over arc `[a, b]` spanning the band `ys`, grown by the tool
/// radius `r`; its top lies halfway between the depth of the layer before `appear` (where the
/// block is still under the surface being cut) and that of `appear` (where it stands).
fn block(a: f64, b: f64, (y0, y1): (f64, f64), r: f64, appear: usize, depth: f64) -> KeepOut {
    let above = -LAYERS_W[appear.saturating_sub(1)] * depth;
    let at = -LAYERS_W[appear] * depth;
    KeepOut {
        x0: r3(a - r),
        y0: r3(y0 - r),
        x1: r3(b + r),
        y1: r3(y1 + r),
        top: r3((above + at) / 2.0),
    }
}

/// Paper 004's worked example at w = 0.35: three fan-shaped machining regions (one sector of
/// the three annular regions, a third of the default circumference, 314.159 mm) in which one
/// keyway block (40 mm, centred) has appeared in the middle region, so four sub-regions with
/// eight advance/retract points: 1-2 in region I, 3-4 and 5-6 either side of the block in
/// region II, 7-8 in region III. Default casing geometry and machine otherwise (D 12 mm end
/// mill, step-over 0.6 D, 60 mm regions, 20 mm allowance so z = −7 mm, link distance 60 mm,
/// no region-first precedence: the paper's search only pairs each region's two points).
/// The as-programmed order is 1-2-3-4-5-6-7-8. Where the paper gives no geometry (its
/// Figure 3 and Table 2 are not in the text) the sizes are the generator's defaults, not
/// fitted to the paper's lengths: `notes/paper004.md`.
pub fn paper_example() -> Instance {
    let sector = std::f64::consts::PI * 300.0 / 3.0;
    let (width, depth, td) = (60.0, 20.0, 12.0);
    let tool = Tool {
        id: format!("EM{td}"),
        diameter: td,
        name: Some(format!("flat end mill D{td}")),
        feed: None,
    };
    let cut = Cut {
        tool: &tool.id,
        radius: td / 2.0,
        z: -LAYERS_W[1] * depth,
        stepover: 0.6 * td,
        reversible: true,
    };
    let (k0, k1) = (sector / 2.0 - 20.0, sector / 2.0 + 20.0);
    let parts = [
        ((0.0, sector), 0usize),
        ((0.0, k0), 1),
        ((k1, sector), 1),
        ((0.0, sector), 2),
    ];
    let cells: Vec<Cell> = parts
        .iter()
        .enumerate()
        .map(|(i, &(xs, ri))| {
            let ys = (ri as f64 * width, (ri as f64 + 1.0) * width);
            sub_region(&cut, xs, ys, format!("S{}", i + 1), 1, ri)
        })
        .collect();
    let machine = Machine {
        home: Point3::new(0.0, -50.0, 50.0),
        tool_change: Point3::new(0.0, -50.0, 50.0),
        clearance: 5.0,
        rapid_feed: 2000.0,
        cut_feed: 500.0,
        tool_change_time: 10.0,
        lift_time: 5.0,
        link_distance: 60.0,
        initial_tool: Some(tool.id.clone()),
        keep_out: vec![block(k0, k1, (width, 2.0 * width), td / 2.0, 1, depth)],
        ..Machine::default()
    };
    let as_given = (0..cells.len())
        .map(|c| Visit { cell: c, mode: 0 })
        .collect();
    Instance {
        name: "casing-paper004-w035".into(),
        machine,
        tools: vec![tool],
        cells,
        as_given: Some(as_given),
        ..Instance::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checker::check;
    use crate::cost::CostModel;
    use crate::model::{Objective, Sequence};
    use std::collections::BTreeMap;

    fn seq(order: &[(usize, usize)]) -> Sequence {
        order
            .iter()
            .map(|&(cell, mode)| Visit { cell, mode })
            .collect()
    }

    /// The w = 0.35 example: the path lengths of the paper's two orders as the model computes
    /// them, against a hand derivation from the geometry in `paper_example`'s doc.
    #[test]
    fn paper_example_orders() {
        let inst = paper_example();
        crate::validate::validate(&inst, "example").unwrap();
        let s = std::f64::consts::PI * 100.0; // the sector
        let (k0, k1) = (s / 2.0 - 20.0, s / 2.0 + 20.0);
        // passes of 48 mm (60 mm band less the tool) 7.2 mm apart, plus the step-overs
        let wide = 43.0 * 48.0 + (s - 12.0); // regions I and III: 43 passes, ends on the high edge
        let half = 19.0 * 48.0 + (k0 - 12.0); // either side of the block: 19 passes, high edge
        let cut = 2.0 * wide + 2.0 * half;
        let dz = 12.0; // clearance 5 mm above z = -7 mm
        let lift = |dx: f64, dy: f64| 2.0 * dz + dx.hypot(dy);
        let approach = (6.0f64 * 6.0 + 56.0 * 56.0 + 45.0 * 45.0).sqrt() + dz; // home to point 1
        // 1-2-3-4-5-6-7-8: every move between sub-regions lifts (the block, or > 60 mm)
        let given = approach
            + lift(s - 12.0, 12.0) // 2 -> 3
            + lift(k1 - k0 + 12.0, 48.0) // 4 -> 5, across the block
            + lift(s - 12.0, 12.0); // 6 -> 7
        // 1-2-7-8-6-5-4-3: 2 -> 7 lifts, 8 -> 6 stays at depth (60 mm axially, past the
        // block's end), 5 -> 4 lifts across the block
        let paper = approach + lift(s - 12.0, 72.0) + 60.0 + lift(k1 - k0 + 12.0, 48.0);
        let as_given = inst.as_given.clone().unwrap();
        let order = seq(&[(0, 0), (3, 0), (2, 1), (1, 1)]);
        for (sq, expect, lifts) in [(&as_given, given, 3), (&order, paper, 2)] {
            let r = check(&inst, sq, Objective::Air).unwrap();
            assert!(
                (r.cut_length - cut).abs() < 0.01,
                "{} vs {cut}",
                r.cut_length
            );
            assert!(
                (r.path_length - (cut + expect)).abs() < 0.01,
                "{} vs {}",
                r.path_length,
                cut + expect
            );
            assert_eq!(r.lifts, lifts);
            let m = CostModel::new(&inst, Objective::Air);
            assert!((m.evaluate(sq) - r.cost).abs() < 1e-6);
        }
    }

    /// The model's own optimum of the example (Held-Karp over all orders and directions):
    /// 1-2-6-5-4-3-7-8, one lift, 7105.3 mm; tabu reaches it.
    #[test]
    fn paper_example_optimum() {
        let inst = paper_example();
        let solve = |name: &str| {
            crate::solvers::run(
                name,
                &inst,
                Objective::Air,
                &BTreeMap::new(),
                1,
                crate::solvers::Budget {
                    time_limit: None,
                    max_evals: Some(200_000),
                },
                &mut crate::solvers::NoObserver,
            )
            .unwrap()
        };
        let exact = solve("exact");
        assert!(exact.outcome.proven_optimal);
        let best = seq(&[(0, 0), (2, 1), (1, 1), (3, 0)]);
        let r = check(&inst, &best, Objective::Air).unwrap();
        assert!((r.path_length - 7105.3).abs() < 0.05, "{}", r.path_length);
        assert_eq!(r.lifts, 1);
        assert!((exact.outcome.cost - r.cost).abs() < 1e-6);
        let tabu = check(&inst, &solve("tabu").outcome.sequence, Objective::Air).unwrap();
        assert!((tabu.cost - r.cost).abs() < 1e-6);
    }

    #[test]
    fn blocks_stop_links_across_them_but_not_past_their_ends() {
        let inst = paper_example();
        let m = CostModel::new(&inst, Objective::Air);
        // 4 -> 5 (B's retract to C's advance) is 70.8 mm: no link at 60 mm, lifts
        // with link distance 100 mm it would link, but the block stands in the way
        let mut wide = inst.clone();
        wide.machine.link_distance = 100.0;
        let w = CostModel::new(&wide, Objective::Air);
        assert!(w.arc(1, 0, 2, 0) > 70.0 + 24.0 - 1e-6);
        let r = check(
            &wide,
            &seq(&[(0, 0), (1, 0), (2, 0), (3, 0)]),
            Objective::Air,
        )
        .unwrap();
        assert_eq!(r.lifts, 3);
        // without the block the same move is a link
        let mut open = wide.clone();
        open.machine.keep_out.clear();
        let o = CostModel::new(&open, Objective::Air);
        assert!((o.arc(1, 0, 2, 0) - 48.0f64.hypot(52.0)).abs() < 1e-3);
        // D's retract to C's retract (reversed C) passes the block's end: a 60 mm link
        assert!((m.arc(3, 0, 2, 1) - 60.0).abs() < 1e-9);
    }

    #[test]
    fn generated_casings_carry_their_blocks() {
        let inst = crate::generate::generate("casing", &BTreeMap::new(), 1).unwrap();
        assert!(!inst.machine.keep_out.is_empty());
        // no cell's advance or retract point lies inside a block that stands at its depth
        for c in &inst.cells {
            for md in &c.modes {
                for p in [md.entry, md.exit] {
                    let inside = inst.machine.keep_out.iter().any(|k| {
                        k.top > p.z && p.x > k.x0 && p.x < k.x1 && p.y > k.y0 && p.y < k.y1
                    });
                    assert!(!inside, "{} has a point inside a block", c.id);
                }
            }
        }
        // the as-programmed order of a casing lifts between neighbouring sub-regions
        let r = check(&inst, inst.as_given.as_ref().unwrap(), Objective::Air).unwrap();
        assert!(r.lifts as usize >= inst.n() / 2);
    }
}

//! `cabin`: a large cabin structural part (patent 003).
//!
//! A part of `length × width` with top surfaces at several heights. Cells:
//! - face milling of `faces` strips of the top (open strokes, reversible);
//! - open features (slots, steps) with two critical contact points: rough and finish cells,
//!   each an open stroke between the two contact points (reversible: both directions);
//! - closed features (pockets, bosses) with one contact point at the rotation centre: rough
//!   and finish cells, entered and left at the centre;
//! - hole groups (bolt circles): one cell per hole, drilled from the top.
//!
//! Tools from the TOML library (`tools`): face = largest end mill, roughing = largest end mill
//! with radius ≤ 16 mm, finishing = largest end mill with radius ≤ the feature's corner radius,
//! drills for the holes. Precedence (the patent's matrix M): rough before finish of each
//! feature; face before hole (the face strip under a hole group before its holes); face before
//! the features cut into it. As-programmed order: tool by tool (larger first), then feature
//! numbering.

use super::common::{closed_modes, programmed_order, pt, r3, stroke_modes, tools_larger_first};
use super::toolsel::{ToolLibrary, ToolSpec};
use crate::error::{Error, Result};
use crate::geom::Point3;
use crate::model::{Cell, Instance, Machine, Mode, StepKind, Tool};
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Parameters.
pub static SPECS: &[ParamSpec] = &[
    ParamSpec {
        name: "features",
        default: "6",
        kind: ParamKind::int(0, 1_000_000),
        help: "open + closed features (each gives a rough and a finish cell)",
    },
    ParamSpec {
        name: "open_fraction",
        default: "0.5",
        kind: ParamKind::float(0.0, 1.0),
        help: "fraction of open features (two contact points)",
    },
    ParamSpec {
        name: "faces",
        default: "2",
        kind: ParamKind::int(1, 10_000),
        help: "face-milling strips",
    },
    ParamSpec {
        name: "hole_groups",
        default: "2",
        kind: ParamKind::int(0, 10_000),
        help: "hole groups (bolt circles)",
    },
    ParamSpec {
        name: "holes",
        default: "3",
        kind: ParamKind::int(0, 10_000),
        help: "holes per group",
    },
    ParamSpec {
        name: "length",
        default: "2000",
        kind: ParamKind::float(200.0, 1e6),
        help: "part length (mm)",
    },
    ParamSpec {
        name: "width",
        default: "800",
        kind: ParamKind::float(200.0, 1e6),
        help: "part width (mm)",
    },
    ParamSpec {
        name: "levels",
        default: "3",
        kind: ParamKind::int(1, 1000),
        help: "distinct top-surface heights (50 mm apart)",
    },
    ParamSpec {
        name: "tools",
        default: "default",
        kind: ParamKind::Text,
        help: "tool library TOML file ('default': crates/cellseq/src/generate/default-tools.toml)",
    },
];

struct B {
    cells: Vec<Cell>,
    keys: Vec<(u64, u64)>,
}

impl B {
    #[allow(clippy::too_many_arguments)]
    fn add(
        &mut self,
        id: String,
        tool: &ToolSpec,
        step: StepKind,
        z: f64,
        feat: String,
        cut: f64,
        modes: Vec<Mode>,
        key: (u64, u64),
    ) -> usize {
        let mut c = Cell::new(id, tool.id.clone(), modes);
        c.step = step;
        c.z = r3(z);
        c.reversible = c.modes.len() == 2 && c.modes[0].entry != c.modes[0].exit;
        c.feature = Some(feat);
        c.cut_length = r3(cut);
        self.cells.push(c);
        self.keys.push(key);
        self.cells.len() - 1
    }
}

/// The part's plan view: faces in strips along x, each at its level.
struct Part {
    len: f64,
    wid: f64,
    nfaces: usize,
    levels: usize,
    strip: f64,
}

impl Part {
    /// Top height at `x`.
    fn level_of(&self, x: f64) -> f64 {
        -50.0 * (((x / self.strip) as usize).min(self.nfaces - 1) % self.levels) as f64
    }

    /// The face under `x`.
    fn face_of(&self, x: f64) -> usize {
        ((x / self.strip) as usize).min(self.nfaces - 1)
    }
}

/// Margin of features and hole groups from the part's edges, mm.
const MARGIN: f64 = 60.0;

/// One face-milling cell per face strip.
fn faces(b: &mut B, part: &Part, face_tool: &ToolSpec) -> Vec<usize> {
    let (strip, wid) = (part.strip, part.wid);
    let mut faces = Vec::with_capacity(part.nfaces);
    for f in 0..part.nfaces {
        let x0 = f as f64 * strip;
        let z = part.level_of(x0 + strip / 2.0);
        let r = face_tool.radius();
        let passes = ((wid - 2.0 * r) / face_tool.cutting_width).ceil().max(1.0);
        let cut = passes * (strip - 2.0 * r) + (wid - 2.0 * r);
        let c = b.add(
            format!("F{:02}", f + 1),
            face_tool,
            StepKind::Face,
            z,
            format!("face{}", f + 1),
            cut,
            stroke_modes(pt(x0 + r, r, z), pt(x0 + strip - r, wid - r, z), true),
            (f as u64, 0),
        );
        faces.push(c);
    }
    faces
}

/// Feature `k` (open: a slot or step with two contact points; closed: one at its rotation
/// centre): roughing then finishing, after the face it lies in. Returns the roughing cell and
/// the feature's x.
#[allow(clippy::too_many_arguments)]
fn feature(
    b: &mut B,
    part: &Part,
    lib: &ToolLibrary,
    rough_tool: &ToolSpec,
    open_fraction: f64,
    (k, fno): (usize, u64),
    rng: &mut ChaCha8Rng,
) -> (usize, usize, f64) {
    let (len, wid) = (part.len, part.wid);
    let x = rng.random_range(MARGIN..len - MARGIN);
    let y = rng.random_range(MARGIN..wid - MARGIN);
    let top = part.level_of(x);
    let d = r3(rng.random_range(5.0..40.0));
    let z = top - d;
    let cr = rng.random_range(3.0..12.0);
    let fin = lib.finishing_tool(cr).clone();
    let fid = format!("E{:03}", k + 1);
    let open = rng.random_bool(open_fraction);
    let (rm, fm, cut) = if open {
        // two critical contact points: ends of a slot / step
        let l = rng.random_range(60.0..250.0);
        let a = if rng.random_bool(0.5) {
            0.0
        } else {
            std::f64::consts::FRAC_PI_2
        };
        let (dx, dy) = (l / 2.0 * f64::cos(a), l / 2.0 * f64::sin(a));
        let (p1x, p1y) = ((x - dx).clamp(0.0, len), (y - dy).clamp(0.0, wid));
        let (p2x, p2y) = ((x + dx).clamp(0.0, len), (y + dy).clamp(0.0, wid));
        (
            stroke_modes(pt(p1x, p1y, z), pt(p2x, p2y, z), true),
            stroke_modes(pt(p1x, p1y, z), pt(p2x, p2y, z), true),
            l,
        )
    } else {
        // closed: one contact point at the rotation centre
        let rad = rng.random_range(20.0..80.0);
        (
            closed_modes(&[pt(x, y, z)]),
            closed_modes(&[pt(x, y, z)]),
            std::f64::consts::TAU * rad,
        )
    };
    let kind = if open { "open" } else { "closed" };
    let rc = b.add(
        format!("{fid}-R"),
        rough_tool,
        StepKind::PocketRough,
        z,
        format!("{fid}-{kind}"),
        cut * 2.0,
        rm,
        (fno, 0),
    );
    let fc = b.add(
        format!("{fid}-F"),
        &fin,
        StepKind::PocketFinish,
        z,
        format!("{fid}-{kind}"),
        cut,
        fm,
        (fno, 1),
    );
    b.cells[fc].layer = 1;
    (rc, fc, x)
}

/// Hole group `g`: `nholes` holes on a circle, each after the face it lies in.
fn hole_group(
    b: &mut B,
    part: &Part,
    drill: &ToolSpec,
    (g, fno, nholes): (usize, u64, usize),
    faces: &[usize],
    prec: &mut Vec<(usize, usize)>,
    rng: &mut ChaCha8Rng,
) {
    let cx = rng.random_range(MARGIN..part.len - MARGIN);
    let cy = rng.random_range(MARGIN..part.wid - MARGIN);
    let rad = rng.random_range(20.0..(MARGIN - 5.0));
    let top = part.level_of(cx);
    let depth = r3(rng.random_range(10.0..30.0));
    let phase = rng.random_range(0.0..std::f64::consts::TAU);
    for h in 0..nholes {
        let a = phase + std::f64::consts::TAU * h as f64 / nholes as f64;
        let (hx, hy) = (cx + rad * a.cos(), cy + rad * a.sin());
        let c = b.add(
            format!("HG{:02}-{:02}", g + 1, h + 1),
            drill,
            StepKind::Hole,
            top - depth,
            format!("HG{:02}", g + 1),
            depth,
            closed_modes(&[pt(hx, hy, top)]),
            (fno, h as u64),
        );
        prec.push((faces[part.face_of(cx)], c));
    }
}

/// Checks what the declared ranges cannot (limits on the parameters' combination, the tool
/// library); about how many cells the part will have, at most.
pub fn check(p: &Params) -> Result<u64> {
    let (nf, nfaces) = (p.int("features"), p.int("faces"));
    let (ngroups, nholes) = (p.int("hole_groups"), p.int("holes"));
    let bad = |m: String| Err(Error::Param(format!("cabin: {m}")));
    let cells = nf
        .saturating_mul(2)
        .saturating_add(ngroups.saturating_mul(nholes))
        .saturating_add(nfaces);
    if cells > 2_000_000 {
        return bad(format!(
            "2 x features + hole_groups x holes + faces = {cells} cells, more than 2000000"
        ));
    }
    let lib = ToolLibrary::load(p.word("tools"))?;
    if ngroups * nholes > 0 && lib.drills().next().is_none() {
        return bad(format!(
            "hole groups need drills in the tool library '{}'",
            p.word("tools")
        ));
    }
    Ok(cells)
}

/// Generates a cabin part.
pub fn generate(p: &Params, seed: u64) -> Result<Instance> {
    let nf = p.int("features") as usize;
    let nfaces = p.int("faces") as usize;
    let ngroups = p.int("hole_groups") as usize;
    let nholes = p.int("holes") as usize;
    let len = p.float("length");
    let wid = p.float("width");
    let levels = p.int("levels") as usize;
    let of = p.float("open_fraction");
    check(p)?;
    let lib = ToolLibrary::load(p.word("tools"))?;
    let face_tool = lib.end_mills().next().expect("end mill").clone();
    let rough_tool = lib.finishing_tool(16.0).clone();
    let drills: Vec<ToolSpec> = lib.drills().cloned().collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut b = B {
        cells: Vec::new(),
        keys: Vec::new(),
    };
    let mut prec = Vec::new();
    let part = Part {
        len,
        wid,
        nfaces,
        levels,
        strip: len / nfaces as f64,
    };
    let faces = faces(&mut b, &part, &face_tool);
    for k in 0..nf {
        let fno = (nfaces + k) as u64;
        let (rc, fc, x) = feature(&mut b, &part, &lib, &rough_tool, of, (k, fno), &mut rng);
        prec.push((faces[part.face_of(x)], rc));
        prec.push((rc, fc));
    }
    for g in 0..ngroups {
        let fno = (nfaces + nf + g) as u64;
        let drill = drills[g % drills.len()].clone();
        hole_group(
            &mut b,
            &part,
            &drill,
            (g, fno, nholes),
            &faces,
            &mut prec,
            &mut rng,
        );
    }
    let (used, rank) = tools_larger_first(&lib, &b.cells);
    prec.sort_unstable();
    prec.dedup();
    let order = programmed_order(b.cells.len(), &prec, &rank, &b.keys);
    let tools: Vec<Tool> = used.iter().map(|t| t.to_tool()).collect();
    let machine = Machine {
        home: Point3::new(0.0, 0.0, 300.0),
        tool_change: Point3::new(0.0, 0.0, 300.0),
        clearance: 30.0,
        rapid_feed: 10000.0,
        cut_feed: 1000.0,
        tool_change_time: 10.0,
        lift_time: 1.0,
        ..Machine::default()
    };
    Ok(Instance {
        name: format!("cabin-f{nf}-g{ngroups}x{nholes}-s{seed}"),
        machine,
        tools,
        cells: b.cells,
        precedence: prec,
        as_given: Some(order),
        ..Instance::default()
    })
}

//! The drawing pipeline, the same steps as the G-code one: a drawing's strokes, grouped in
//! scopes (layer and stroke colour) in their required order, become one instance per scope; a
//! registry solver sequences it with the scope's share of the command's [`Allowance`]
//! ([`solve_group`]: the file's own order kept where the solver's is not shorter); [`render`]
//! writes the result (SVG, or G-code from a DXF) and verifies it, keeping the file's order if
//! the new one fails the check; the caller writes the text atomically. Cut mode adds
//! inner-before-outer precedence.

use super::{Allowance, solve_group};
use crate::drawing::{Drawing, PenUp, Stroke, dist, pen_up};
use crate::dxf::{self, Post};
use crate::svg;
use cellseq::SolverKind;
use cellseq::error::{Error, Result};
use cellseq::geom::Point3;
use cellseq::geom::polygon::PolygonIndex;
use cellseq::model::{Cell, Instance, Machine, Metadata, Mode, Objective, StepKind, Tool, Visit};
use rstar::RTree;
use rstar::primitives::{GeomWithData, Rectangle};

pub mod blocks;
pub mod semantics;

pub use semantics::{Blocks, Pens, Reading};
use std::collections::HashMap;
use std::time::{Duration, Instant};

/// The registry solver drawings get by default (`drawing`: 2-opt and Or-opt with reversal,
/// then iterated local search).
pub const DRAWING_SOLVER: SolverKind = SolverKind::Drawing;

/// Evaluations per stroke of the default budget (deterministic, linear in the drawing's size);
/// see `notes/svg.md` for the measurements behind it.
pub const EVALS_PER_STROKE: u64 = 4000;

/// The smallest default budget of a scope, in evaluations.
pub const MIN_EVALS: u64 = 1_000_000;

/// Options of [`optimize`].
#[derive(Debug, Clone)]
pub struct Options {
    /// The solver.
    pub solver: SolverKind,
    /// Total time limit (s), shared among scopes by size.
    pub time_limit: Option<f64>,
    /// Total evaluation budget, shared among scopes by size. Without this and without a time
    /// limit each scope gets [`EVALS_PER_STROKE`] evaluations per stroke (at least
    /// [`MIN_EVALS`]).
    pub max_evals: Option<u64>,
    /// Solver parameters (`--param`).
    pub params: std::collections::BTreeMap<String, String>,
    /// Seed.
    pub seed: u64,
    /// Allow drawing strokes backwards / closed strokes from another vertex.
    pub reversible: bool,
    /// Layers and stroke colours are ordering scopes (false: one scope, as [`Pens::None`]).
    pub scopes: bool,
    /// What a pen is ([`semantics`]); default: read from the file.
    pub pens: Pens,
    /// What a plain top-level group is ([`semantics`]); default: read from the file.
    pub blocks: Blocks,
    /// Cut mode: strokes inside a closed stroke come before it.
    pub cut: bool,
    /// Plain groups that are children of the root (not Inkscape layers) are blocks whose
    /// order between one another is free: each is still drawn as one contiguous run with its
    /// own colour order, and runs of them are put in the order of least travel. Off: every
    /// layer in the file's order. No effect with cut mode or without scopes.
    pub free_groups: bool,
    /// Containment tolerance (user units).
    pub contain_tol: f64,
    /// Maximum start-vertex candidates of a closed stroke.
    pub max_starts: usize,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            solver: DRAWING_SOLVER,
            time_limit: None,
            max_evals: None,
            params: Default::default(),
            seed: 1,
            reversible: true,
            scopes: true,
            pens: Pens::Auto,
            blocks: Blocks::Auto,
            cut: false,
            free_groups: true,
            contain_tol: 0.01,
            max_starts: 8,
        }
    }
}

/// Scopes in drawing order: each a list of stroke indices. With `by_scope`, one per layer
/// and stroke colour ([`Reading::STRICT`]); without, one.
pub fn scopes(d: &Drawing, by_scope: bool) -> Vec<Vec<usize>> {
    let r = if by_scope {
        Reading::STRICT
    } else {
        Reading::new(Pens::None, Blocks::None)
    };
    scopes_of(d, r)
}

/// Scopes in drawing order under a reading: one per unit ([`semantics::units`]) and pen
/// (the stroke colour with [`Pens::Colour`]), units in the file's order, a unit's pens in the
/// order they first appear; one scope with [`Pens::None`].
pub fn scopes_of(d: &Drawing, r: Reading) -> Vec<Vec<usize>> {
    if r.pens == Pens::None || r.pens == Pens::Auto {
        return vec![(0..d.strokes.len()).collect()];
    }
    let units = semantics::units(d, r.blocks);
    let mut index: HashMap<(usize, &str), usize> = HashMap::new();
    let mut keys: Vec<usize> = Vec::new();
    let mut out: Vec<Vec<usize>> = Vec::new();
    for (i, s) in d.strokes.iter().enumerate() {
        let pen = match r.pens {
            Pens::Colour => d.styles[s.style].stroke.as_str(),
            _ => "",
        };
        let unit = units[s.layer];
        let g = *index.entry((unit, pen)).or_insert_with(|| {
            keys.push(unit);
            out.push(Vec::new());
            out.len() - 1
        });
        out[g].push(i);
    }
    let mut idx: Vec<usize> = (0..out.len()).collect();
    idx.sort_by_key(|&g| (keys[g], out[g][0]));
    idx.into_iter()
        .map(|g| std::mem::take(&mut out[g]))
        .collect()
}

/// Start-vertex candidates of a closed stroke (all when few, else evenly spaced).
fn starts_of(s: &Stroke, max: usize) -> Vec<usize> {
    let n = s.points.len();
    if !s.closed {
        return vec![0];
    }
    let k = n.min(max.max(1));
    (0..k).map(|i| i * n / k).collect()
}

fn bbox(s: &Stroke) -> [f64; 4] {
    let mut b = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    for p in &s.points {
        b[0] = b[0].min(p[0]);
        b[1] = b[1].min(p[1]);
        b[2] = b[2].max(p[0]);
        b[3] = b[3].max(p[1]);
    }
    b
}

/// Cut-mode precedence within a scope (local indices): a stroke whose points all lie inside a
/// closed stroke with a larger bounding box (with tolerance) comes before it. Candidate pairs
/// come from an R-tree of the closed strokes' boxes (those holding the inner stroke's first
/// point), and each closed stroke is indexed once for its point tests
/// ([`PolygonIndex`]), so neither many strokes nor long ones cost a product of sizes.
pub fn containment(d: &Drawing, scope: &[usize], tol: f64) -> Vec<(usize, usize)> {
    let boxes: Vec<[f64; 4]> = scope.iter().map(|&i| bbox(&d.strokes[i])).collect();
    let area = |b: &[f64; 4]| (b[2] - b[0]).max(0.0) * (b[3] - b[1]).max(0.0);
    let mut outers: Vec<usize> = (0..scope.len())
        .filter(|&k| d.strokes[scope[k]].closed && d.strokes[scope[k]].points.len() >= 3)
        .collect();
    outers.sort_by(|&a, &b| area(&boxes[a]).total_cmp(&area(&boxes[b])));
    // rank[b]: position of b in `outers`, the order its edges are listed in
    let mut rank = vec![usize::MAX; scope.len()];
    for (r, &b) in outers.iter().enumerate() {
        rank[b] = r;
    }
    let tree = RTree::bulk_load(
        outers
            .iter()
            .map(|&b| {
                let bb = boxes[b];
                GeomWithData::new(
                    Rectangle::from_corners([bb[0] - tol, bb[1] - tol], [bb[2] + tol, bb[3] + tol]),
                    b,
                )
            })
            .collect(),
    );
    let mut index: Vec<Option<PolygonIndex>> = vec![None; scope.len()];
    let mut edges = Vec::new();
    let mut candidates = Vec::new();
    for a in 0..scope.len() {
        let ba = boxes[a];
        let aa = area(&ba);
        let sa = &d.strokes[scope[a]];
        let Some(&first) = sa.points.first() else {
            continue;
        };
        candidates.clear();
        candidates.extend(
            tree.locate_all_at_point(first)
                .map(|r| r.data)
                .filter(|&b| b != a),
        );
        candidates.sort_unstable_by_key(|&b| rank[b]);
        for &b in &candidates {
            let bb = boxes[b];
            if area(&bb) <= aa + tol * tol {
                continue;
            }
            if ba[0] < bb[0] - tol
                || ba[1] < bb[1] - tol
                || ba[2] > bb[2] + tol
                || ba[3] > bb[3] + tol
            {
                continue;
            }
            let poly =
                index[b].get_or_insert_with(|| PolygonIndex::new(&d.strokes[scope[b]].points, tol));
            if sa.points.iter().all(|&p| poly.contains(p)) {
                edges.push((a, b));
            }
        }
    }
    edges
}

/// Cut mode: reorders scopes so that a scope whose closed strokes enclose strokes of another
/// scope comes after it (stable topological order: the first scope in file order whose
/// predecessors are all placed; on a cycle, the first unplaced one). Linear in the scopes and
/// their containment edges (a heap of ready scopes), not in the square of the scopes.
pub fn inner_scopes_first(d: &Drawing, sc: Vec<Vec<usize>>, tol: f64) -> Vec<Vec<usize>> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let all: Vec<usize> = sc.iter().flatten().copied().collect();
    let mut scope_of = vec![0usize; d.strokes.len()];
    for (k, s) in sc.iter().enumerate() {
        for &i in s {
            scope_of[i] = k;
        }
    }
    let m = sc.len();
    // before: a must precede b
    let mut pairs: Vec<(usize, usize)> = containment(d, &all, tol)
        .into_iter()
        .map(|(a, b)| (scope_of[all[a]], scope_of[all[b]]))
        .filter(|(a, b)| a != b)
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    let mut succs: Vec<Vec<usize>> = vec![Vec::new(); m];
    let mut missing = vec![0usize; m];
    for &(a, b) in &pairs {
        succs[a].push(b);
        missing[b] += 1;
    }
    let mut ready: BinaryHeap<Reverse<usize>> =
        (0..m).filter(|&b| missing[b] == 0).map(Reverse).collect();
    let mut placed = vec![false; m];
    let mut first_unplaced = 0;
    let mut order = Vec::with_capacity(m);
    while order.len() < m {
        let next = loop {
            match ready.pop() {
                Some(Reverse(b)) if placed[b] => continue,
                Some(Reverse(b)) => break b,
                None => {
                    // a cycle: the first unplaced scope in file order
                    while placed[first_unplaced] {
                        first_unplaced += 1;
                    }
                    break first_unplaced;
                }
            }
        };
        placed[next] = true;
        order.push(next);
        for &b in &succs[next] {
            missing[b] -= 1;
            if missing[b] == 0 && !placed[b] {
                ready.push(Reverse(b));
            }
        }
    }
    let mut sc = sc;
    order
        .into_iter()
        .map(|k| std::mem::take(&mut sc[k]))
        .collect()
}

/// The instance of one scope, starting at `home`; also the (reverse, start vertex) of each
/// mode of each cell.
pub fn scope_instance(
    d: &Drawing,
    scope: &[usize],
    home: [f64; 2],
    opts: &Options,
) -> (Instance, Vec<Vec<(bool, usize)>>) {
    let mut orient = Vec::with_capacity(scope.len());
    let cells: Vec<Cell> = scope
        .iter()
        .map(|&i| {
            let s = &d.strokes[i];
            let p = |q: [f64; 2]| Point3::new(q[0], q[1], 0.0);
            let mut modes = Vec::new();
            let mut or = Vec::new();
            if s.closed {
                let ks = if opts.reversible {
                    starts_of(s, opts.max_starts)
                } else {
                    vec![0]
                };
                for k in ks {
                    modes.push(Mode::closed(p(s.points[k])));
                    or.push((false, k));
                }
            } else {
                modes.push(Mode::new(p(s.start()), p(s.end())));
                or.push((false, 0));
                if opts.reversible && !s.is_dot() {
                    modes.push(Mode::new(p(s.end()), p(s.start())));
                    or.push((true, 0));
                }
            }
            orient.push(or);
            let mut c = Cell::new(format!("s{}", i + 1), "pen", modes);
            c.reversible = opts.reversible && !s.closed && !s.is_dot();
            c.step = StepKind::Engrave;
            c.cut_length = s.length();
            c.layer = s.layer as u32;
            c.feature = Some(format!("line {}", s.line));
            c
        })
        .collect();
    let precedence = if opts.cut {
        containment(d, scope, opts.contain_tol)
    } else {
        Vec::new()
    };
    let n = cells.len();
    let inst = Instance {
        name: d.file.clone(),
        meta: Metadata {
            generator: Some("svg".into()),
            ..Metadata::default()
        },
        machine: Machine {
            home: Point3::new(home[0], home[1], 0.0),
            tool_change: Point3::new(home[0], home[1], 0.0),
            clearance: 0.0,
            initial_tool: Some("pen".into()),
            ..Machine::default()
        },
        tools: vec![Tool {
            id: "pen".into(),
            diameter: 1.0,
            name: None,
            feed: None,
        }],
        cells,
        precedence,
        as_given: Some((0..n).map(|i| Visit::new(i, 0)).collect()),
        ..Instance::default()
    };
    (inst, orient)
}

/// The whole drawing as one instance (scopes chained by precedence), for `cellseq import`.
/// The reading is the one the file's conventions give ([`semantics::readings`]).
pub fn import(d: &Drawing, opts: &Options) -> Result<Instance> {
    let (pens, blocks) = given(opts);
    let reading = semantics::readings(d, pens, blocks).0[0];
    let sc = reading_scopes(d, opts, reading);
    let all: Vec<usize> = sc.iter().flatten().copied().collect();
    let (mut inst, _) = scope_instance(
        d,
        &all,
        [0.0, 0.0],
        &Options {
            cut: false,
            ..opts.clone()
        },
    );
    let mut edges = Vec::new();
    let mut start = 0;
    for (k, s) in sc.iter().enumerate() {
        if opts.cut {
            edges.extend(
                containment(d, s, opts.contain_tol)
                    .into_iter()
                    .map(|(a, b)| (a + start, b + start)),
            );
        }
        if k + 1 < sc.len() {
            if edges.len() + s.len() * sc[k + 1].len() > 20_000_000 {
                return Err(Error::invalid(
                    &d.file,
                    "too many scope precedence edges to export",
                ));
            }
            let next = start + s.len();
            for a in 0..s.len() {
                for b in 0..sc[k + 1].len() {
                    edges.push((start + a, next + b));
                }
            }
        }
        start += s.len();
    }
    inst.precedence = edges;
    Ok(inst)
}

/// The result of [`optimize`].
#[derive(Debug, Clone)]
pub struct Optimized {
    /// The strokes in the new order and orientation.
    pub strokes: Vec<Stroke>,
    /// Figures of the file's order.
    pub before: PenUp,
    /// Figures of the new order.
    pub after: PenUp,
    /// Solver seconds.
    pub solve_s: f64,
    /// Number of scopes.
    pub scopes: usize,
    /// Precedence edges (cut mode).
    pub edges: usize,
    /// Scopes where the solver's order was not shorter than the file's: they kept the file's
    /// order.
    pub kept_original: usize,
    /// Plain top-level groups were drawn in another order than the file's
    /// ([`Options::free_groups`]).
    pub groups_reordered: bool,
    /// Why the whole drawing was kept in the file's order, when it was (the new order failed
    /// the built-in check; see [`render`]).
    pub note: Option<String>,
    /// The reading of pens and blocks kept ([`semantics`]).
    pub reading: Reading,
    /// Why that reading was considered (the file's conventions, or "as given").
    pub semantics: String,
    /// Every reading solved, in the order tried, with its pen-up travel in all (mm); the
    /// kept one has the least (the first on a tie).
    pub tried: Vec<(Reading, f64)>,
}

/// The pens and blocks the options ask for: `scopes` off is one pen; `free_groups` off
/// keeps plain groups as parts in the file's order.
fn given(opts: &Options) -> (Pens, Blocks) {
    if !opts.scopes {
        return (Pens::None, Blocks::None);
    }
    let blocks = match opts.blocks {
        Blocks::Auto if !opts.free_groups => Blocks::Group,
        b => b,
    };
    (opts.pens, blocks)
}

/// The scopes of a reading, in the order they are drawn (cut mode: inner scopes first).
fn reading_scopes(d: &Drawing, opts: &Options, r: Reading) -> Vec<Vec<usize>> {
    let sc = scopes_of(d, r);
    if opts.cut && sc.len() > 1 {
        inner_scopes_first(d, sc, opts.contain_tol)
    } else {
        sc
    }
}

fn layer_label(d: &Drawing) -> impl Fn(&Stroke) -> String + '_ {
    move |s: &Stroke| d.layers[s.layer].label.clone()
}

/// The default evaluation budget of a scope of `size` strokes (no time limit, no evaluation
/// budget given): [`EVALS_PER_STROKE`] per stroke, at least [`MIN_EVALS`].
pub fn default_evals(size: usize) -> u64 {
    (EVALS_PER_STROKE * size as u64).max(MIN_EVALS)
}

/// [`optimize_within`] with an allowance starting now, from the options' budget.
pub fn optimize(d: &Drawing, opts: &Options) -> Result<Optimized> {
    optimize_within(d, opts, &Allowance::new(opts.time_limit, opts.max_evals)?)
}

/// The scopes solved in one order: the strokes, the figures of the report, and each scope's
/// entry (first stroke's start) and exit (last stroke's end).
struct Pass {
    strokes: Vec<Stroke>,
    solve_s: f64,
    edges: usize,
    kept: usize,
    ends: Vec<([f64; 2], [f64; 2])>,
}

/// How much of the budget is still to be shared ([`Allowance::share_or`]): strokes left and
/// strokes in all passes.
struct Shares {
    left: usize,
    total: usize,
    reserve_s: f64,
}

/// Solves the scopes `sc` in this order, each from the previous one's exit (the first from the
/// origin) with its share of `allowance` ([`solve_group`]: the scope's file order kept unless
/// the solver's is shorter). A scope whose share of time is nothing keeps the file's order
/// without running the solver.
fn solve_pass(
    d: &Drawing,
    sc: &[Vec<usize>],
    opts: &Options,
    allowance: &Allowance,
    shares: &mut Shares,
) -> Result<Pass> {
    let mut home = [0.0, 0.0];
    let mut p = Pass {
        strokes: Vec::with_capacity(d.strokes.len()),
        solve_s: 0.0,
        edges: 0,
        kept: 0,
        ends: Vec::with_capacity(sc.len()),
    };
    for s in sc {
        let budget = allowance.share_or(
            s.len(),
            shares.left,
            shares.total,
            shares.reserve_s,
            default_evals(s.len()),
        );
        shares.left = shares.left.saturating_sub(s.len());
        if budget.time_limit.is_some_and(|t| t.is_zero()) {
            // no time left: the file's order, without building the scope's instance
            let first = p.strokes.len();
            p.strokes.extend(s.iter().map(|&i| d.strokes[i].clone()));
            p.kept += usize::from(opts.solver != SolverKind::AsGiven);
            let entry = p.strokes.get(first).map_or(home, |x| x.start());
            if let Some(l) = p.strokes.last() {
                home = l.end();
            }
            p.ends.push((entry, home));
            continue;
        }
        let (inst, orient) = scope_instance(d, s, home, opts);
        p.edges += inst.precedence.len();
        let r = solve_group(
            &inst,
            Objective::Air,
            opts.solver,
            &opts.params,
            opts.seed,
            budget,
        )?;
        p.solve_s += r.elapsed_s;
        p.kept += usize::from(r.kept_original && opts.solver != SolverKind::AsGiven);
        let first = p.strokes.len();
        for v in &r.sequence {
            let (rev, k) = orient[v.cell][v.mode];
            p.strokes.push(d.strokes[s[v.cell]].oriented(rev, k));
        }
        let entry = p.strokes.get(first).map_or(home, |x| x.start());
        if let Some(l) = p.strokes.last() {
            home = l.end();
        }
        p.ends.push((entry, home));
    }
    Ok(p)
}

/// Starts every closed stroke of the drawn sequence at the vertex that makes the pen's way
/// from the previous stroke's end and on to the next stroke's start shortest (the sequence,
/// and so the drawing, is unchanged; a closed stroke ends where it starts, so its start is
/// also its exit, which a scope's solve chooses without knowing what comes after the scope:
/// a boxes.py part drawn inner first ends on its outline, wherever the next part is). Two
/// sweeps, each linear in the points; a vertex is taken only when strictly shorter, so the
/// travel never grows.
fn start_vertices(strokes: &mut [Stroke], origin: [f64; 2]) {
    for _ in 0..2 {
        let mut prev = origin;
        for i in 0..strokes.len() {
            if strokes[i].closed && strokes[i].points.len() > 2 {
                let next = strokes.get(i + 1).map(Stroke::start);
                let cost = |q: [f64; 2]| dist(prev, q) + next.map_or(0.0, |n| dist(q, n));
                let s = &strokes[i];
                let mut best = (0, cost(s.points[0]));
                for (k, &q) in s.points.iter().enumerate().skip(1) {
                    let c = cost(q);
                    if c < best.1 - 1e-9 {
                        best = (k, c);
                    }
                }
                if best.0 != 0 {
                    strokes[i].points.rotate_left(best.0);
                }
            }
            prev = strokes[i].end();
        }
    }
}

/// The blocks of scopes `sc` (file order, one layer's scopes contiguous): `(first scope, end
/// scope, free)` per layer. A block is free when its layer is a plain group that is a child of
/// the root (not an Inkscape layer, not the root's own strokes).
fn blocks_of(d: &Drawing, sc: &[Vec<usize>]) -> Vec<(usize, usize, bool)> {
    let layer = |k: usize| d.strokes[sc[k][0]].layer;
    let mut out: Vec<(usize, usize, bool)> = Vec::new();
    for k in 0..sc.len() {
        match out.last_mut() {
            Some(b) if layer(b.0) == layer(k) => b.1 = k + 1,
            _ => {
                let l = layer(k);
                out.push((k, k + 1, semantics::is_plain_group(d, l)));
            }
        }
    }
    out
}

/// The scopes in a new order in which every run of consecutive free blocks is put in the order
/// of least travel between them ([`blocks::order_until`], on the entries and exits the blocks
/// had in `pass`), from the exit of the block before the run (or the origin) to the entry of
/// the block after it; `None` when no order changes.
fn free_block_order(
    d: &Drawing,
    sc: &[Vec<usize>],
    pass: &Pass,
    deadline: Option<Instant>,
) -> Option<Vec<usize>> {
    let bl = blocks_of(d, sc);
    let mut order: Vec<usize> = Vec::with_capacity(sc.len());
    let mut changed = false;
    let mut i = 0;
    while i < bl.len() {
        let mut j = i + 1;
        if bl[i].2 {
            while j < bl.len() && bl[j].2 {
                j += 1;
            }
        }
        let run = &bl[i..j];
        let start = if i == 0 {
            [0.0, 0.0]
        } else {
            pass.ends[bl[i - 1].1 - 1].1
        };
        let finish = bl.get(j).map(|b| pass.ends[b.0].0);
        let ends: Vec<_> = run
            .iter()
            .map(|b| (pass.ends[b.0].0, pass.ends[b.1 - 1].1))
            .collect();
        let o = blocks::order_until(start, &ends, finish, deadline);
        changed |= o.iter().enumerate().any(|(k, &b)| k != b);
        for b in o {
            order.extend(run[b].0..run[b].1);
        }
        i = j;
    }
    changed.then_some(order)
}

/// Plain top-level groups of reading `r` are blocks in a free order ([`Options::free_groups`];
/// only with scopes in layers, not in cut mode, whose containment order crosses layers).
fn reorders(opts: &Options, r: Reading, sc: &[Vec<usize>]) -> bool {
    opts.free_groups
        && r.blocks == Blocks::Group
        && r.pens != Pens::None
        && !opts.cut
        && sc.len() > 1
}

/// The strokes of the free blocks of `sc` (they are solved twice).
fn free_strokes(d: &Drawing, sc: &[Vec<usize>]) -> usize {
    blocks_of(d, sc)
        .iter()
        .filter(|b| b.2)
        .map(|b| sc[b.0..b.1].iter().map(Vec::len).sum::<usize>())
        .sum()
}

/// Seconds of the time limit kept for writing and verifying: 2 % of the limit plus the larger
/// of twice the time already spent (reading: the check reads the output again) and 6 µs per
/// stroke and 0.5 µs per point (the output has one element per stroke, so it can take longer
/// to read back than the input: one path of 300 000 sub-paths is 300 000 paths written).
fn reserve_s(d: &Drawing, allowance: &Allowance) -> f64 {
    let Some(t) = allowance.time_limit else {
        return 0.0;
    };
    let spent = allowance.started.elapsed().as_secs_f64();
    let points: usize = d.strokes.iter().map(|s| s.points.len()).sum();
    let size = 6e-6 * d.strokes.len() as f64 + 0.5e-6 * points as f64;
    0.02 * t + size.max(2.0 * spent)
}

/// One reading solved: its scopes in their order; with free blocks, again in the order of
/// least travel between blocks, kept when shorter in all. Returns the pass and whether the
/// blocks were reordered.
fn solve_reading(
    d: &Drawing,
    opts: &Options,
    r: Reading,
    sc: &[Vec<usize>],
    allowance: &Allowance,
    shares: &mut Shares,
    deadline: Option<Instant>,
) -> Result<(Pass, bool)> {
    let key = layer_label(d);
    let figures = |s: &[Stroke]| pen_up(s, d.mm_per_unit, &key);
    // inner first: the containment order inside each scope, as cut mode has it
    let inner = Options {
        cut: opts.cut || r.inner_first,
        ..opts.clone()
    };
    let opts_in = &inner;
    // closed strokes' start vertices are set once the order is known (start_vertices), after
    // the block order is chosen from each scope's own entry and exit
    let polish = |mut p: Pass| {
        if opts.reversible {
            start_vertices(&mut p.strokes, [0.0, 0.0]);
        }
        p
    };
    let best = solve_pass(d, sc, opts_in, allowance, shares)?;
    if !reorders(opts, r, sc) {
        return Ok((polish(best), false));
    }
    let Some(order) = free_block_order(d, sc, &best, deadline) else {
        return Ok((polish(best), false));
    };
    let best = polish(best);
    let sc2: Vec<Vec<usize>> = order.iter().map(|&k| sc[k].clone()).collect();
    let p = polish(solve_pass(d, &sc2, opts_in, allowance, shares)?);
    let (a, b) = (figures(&best.strokes), figures(&p.strokes));
    Ok(if b.pen_up_total_mm < a.pen_up_total_mm {
        let solve_s = best.solve_s + p.solve_s;
        (Pass { solve_s, ..p }, true)
    } else {
        let solve_s = best.solve_s + p.solve_s;
        (Pass { solve_s, ..best }, false)
    })
}

/// Sequences each scope with a registry solver through the steps the G-code pipeline uses:
/// the scope's share of the command's [`Allowance`], [`solve_group`] (air-travel objective,
/// start at the previous scope's exit, the first at the origin; the file's order kept unless
/// the solver's is shorter). With [`Options::free_groups`], plain top-level groups are then
/// put in the order of least travel between them and solved again in that order; that result
/// is kept only when its pen-up travel in all is shorter. Each reading of the pens and blocks
/// ([`semantics::readings`]) is solved so, and the one with the least pen-up travel is kept.
/// [`render`] then writes and verifies the result.
///
/// The allowance's time limit covers the whole command from `allowance.started`: a reserve
/// (`reserve_s`) is kept for writing and verifying, the solver and block ordering stop at
/// it, and a scope left without time keeps the file's order.
pub fn optimize_within(d: &Drawing, opts: &Options, allowance: &Allowance) -> Result<Optimized> {
    let (pens, blocks) = given(opts);
    let (readings, why) = semantics::readings(d, pens, blocks);
    // readings with the same scopes as an earlier one are not solved again
    let mut plans: Vec<(Reading, Vec<Vec<usize>>)> = Vec::new();
    for r in readings {
        let sc = reading_scopes(d, opts, r);
        if r.inner_first {
            let all: Vec<usize> = sc.iter().flatten().copied().collect();
            let inside = containment(d, &all, opts.contain_tol);
            if !semantics::parts_apart(&sc, &inside, d.strokes.len()) {
                continue;
            }
        }
        if !plans.iter().any(|p| p.1 == sc && !r.inner_first) {
            plans.push((r, sc));
        }
    }
    let total: usize = plans
        .iter()
        .map(|(r, sc)| {
            let free = if reorders(opts, *r, sc) {
                free_strokes(d, sc)
            } else {
                0
            };
            d.strokes.len().max(1) + free
        })
        .sum();
    let reserve_s = reserve_s(d, allowance);
    let deadline = allowance.time_limit.map(|t| {
        let left = (t - reserve_s).max(0.0);
        allowance.started + Duration::try_from_secs_f64(left).unwrap_or(Duration::MAX / 4)
    });
    let mut shares = Shares {
        left: total,
        total,
        reserve_s,
    };
    let key = layer_label(d);
    let figures = |s: &[Stroke]| pen_up(s, d.mm_per_unit, &key);
    // (reading, its scopes, its pass, blocks reordered, pen-up in all)
    type Solved = (Reading, Vec<Vec<usize>>, Pass, bool, f64);
    let mut best: Option<Solved> = None;
    let mut tried = Vec::new();
    let mut solve_s = 0.0;
    for (r, sc) in plans {
        let (pass, reordered) = solve_reading(d, opts, r, &sc, allowance, &mut shares, deadline)?;
        solve_s += pass.solve_s;
        let up = figures(&pass.strokes).pen_up_total_mm;
        tried.push((r, up));
        if best.as_ref().is_none_or(|b| up < b.4) {
            best = Some((r, sc, pass, reordered, up));
        }
    }
    let (reading, sc, best, groups_reordered, _) = best.expect("at least one reading");
    Ok(Optimized {
        before: figures(&d.strokes),
        after: figures(&best.strokes),
        strokes: best.strokes,
        solve_s,
        scopes: sc.len(),
        edges: best.edges,
        kept_original: best.kept,
        groups_reordered,
        note: None,
        reading,
        semantics: why,
        tried,
    })
}

/// What [`render`] writes.
#[derive(Debug, Clone, Copy)]
pub enum Output<'a> {
    /// The drawing as SVG (also the preview of a DXF).
    Svg,
    /// A DXF's G-code, by its post.
    Gcode(&'a Post),
}

/// Writes the optimized drawing as `output` and verifies the text against the input (the same
/// segments, the kept elements; for G-code, the post's own check). When the new order fails
/// the check, the file's order is written instead (and verified), `opt` is updated to say so
/// and why; when that fails too, the error is returned. Returns the text and the number of
/// segments verified; the caller writes it atomically.
pub fn render(d: &Drawing, opt: &mut Optimized, output: Output) -> Result<(String, usize)> {
    let emit = |strokes: &[Stroke]| -> Result<(String, usize)> {
        match output {
            Output::Svg => {
                let t = svg::write(d, strokes);
                let n = svg::verify(d, "<optimized>", &t)?;
                Ok((t, n))
            }
            Output::Gcode(post) => {
                let t = dxf::write_gcode(d, strokes, post);
                let n = dxf::verify_gcode(d, "<optimized>", &t, post)?;
                Ok((t, n))
            }
        }
    };
    match emit(&opt.strokes) {
        Ok(r) => Ok(r),
        // when in doubt, keep the original: the file's order, checked the same way
        Err(e) => {
            let r = emit(&d.strokes)?;
            opt.strokes = d.strokes.clone();
            opt.after = opt.before;
            opt.groups_reordered = false;
            opt.note = Some(format!("the new order failed the built-in check: {e}"));
            Ok(r)
        }
    }
}

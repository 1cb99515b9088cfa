//! K-nearest candidate lists per cell: good successors (`out`) and good predecessors (`inn`).
//!
//! Geometric instances use kiddo k-d trees over entry and exit points (no n × n matrix);
//! matrix instances rank the cheapest arcs of the matrix.

use crate::clock::Deadline;
use crate::cost::CostModel;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::collections::HashMap;
use std::num::NonZero;

/// Candidate lists of at most K cells per cell.
#[derive(Debug, Clone)]
pub struct Neighbours {
    /// `out[c]`: cells that are cheap to go to from c, best first.
    pub out: Vec<Vec<u32>>,
    /// `inn[c]`: cells that are cheap to come from into c, best first.
    pub inn: Vec<Vec<u32>>,
}

impl Neighbours {
    /// Per cell, its out-neighbours, then the in-neighbours not among them: the cells worth
    /// linking to it in either direction, each once.
    pub fn merged(&self) -> Vec<Vec<u32>> {
        self.out
            .iter()
            .zip(&self.inn)
            .map(|(out, inn)| {
                let mut v = out.clone();
                for &x in inn {
                    if !v.contains(&x) {
                        v.push(x);
                    }
                }
                v
            })
            .collect()
    }

    /// Builds lists of `k` neighbours per cell.
    pub fn new(m: &CostModel, k: usize) -> Self {
        Self::new_until(m, k, Deadline::NONE)
    }

    /// Like [`Neighbours::new`]; the cells whose turn comes after `deadline` get empty lists
    /// (a search over them finds fewer moves, none wrong): on 10⁵ geometric cells the lists
    /// take about a second.
    pub fn new_until(m: &CostModel, k: usize, deadline: Deadline) -> Self {
        let k = k.min(m.n().saturating_sub(1));
        if k == 0 {
            return Neighbours {
                out: vec![Vec::new(); m.n()],
                inn: vec![Vec::new(); m.n()],
            };
        }
        if m.is_geometric() {
            geometric(m, k, deadline)
        } else {
            matrix(m, k, deadline)
        }
    }
}

fn matrix(m: &CostModel, k: usize, deadline: Deadline) -> Neighbours {
    let n = m.n();
    // one row or column of cheapest arcs at a time: O(n) memory besides the lists (an n × n
    // table doubled the memory of the largest matrix instances)
    let mut line = vec![0.0f64; n];
    let pick = |line: &[f64]| -> Vec<u32> {
        let by = |x: &u32, y: &u32| {
            line[*x as usize]
                .total_cmp(&line[*y as usize])
                .then(x.cmp(y))
        };
        let mut v: Vec<u32> = (0..n as u32).collect();
        if k < n {
            v.select_nth_unstable_by(k, by);
            v.truncate(k);
            // a list keeps k entries, not the n it was chosen from (n² memory in all)
            v.shrink_to_fit();
        }
        v.sort_by(by);
        v
    };
    let cost = |a: usize, b: usize| {
        if a == b {
            f64::INFINITY
        } else {
            m.cheapest_arc(a, b)
        }
    };
    let mut out = Vec::with_capacity(n);
    for a in 0..n {
        if deadline.passed() {
            out.push(Vec::new());
            continue;
        }
        for (b, x) in line.iter_mut().enumerate() {
            *x = cost(a, b);
        }
        out.push(pick(&line));
    }
    let mut inn = Vec::with_capacity(n);
    for b in 0..n {
        if deadline.passed() {
            inn.push(Vec::new());
            continue;
        }
        for (a, x) in line.iter_mut().enumerate() {
            *x = cost(a, b);
        }
        inn.push(pick(&line));
    }
    Neighbours { out, inn }
}

/// Most modes of one cell its neighbours are searched from (see [`geometric`]).
const MAX_QUERY_MODES: usize = 64;

/// A k-d tree over the distinct points of one side (entries or exits), each point ("site")
/// with its nodes grouped by tool, lowest first. Coincident points are one site, so a query
/// among thousands of them costs no more than among distinct ones.
struct Sites {
    tree: ImmutableKdTree<f64, 2>,
    /// per site: (tool, its nodes at the site in increasing order)
    nodes: Vec<Vec<(u32, Vec<u32>)>>,
}

impl Sites {
    fn new(m: &CostModel, exit: bool) -> Sites {
        let mut index: HashMap<[u64; 2], u32> = HashMap::new();
        let mut pts: Vec<(u32, [f64; 2])> = Vec::new();
        let mut nodes: Vec<Vec<(u32, Vec<u32>)>> = Vec::new();
        for nd in 0..m.nodes() {
            let p = if exit { m.exit(nd) } else { m.entry(nd) };
            let id = *index
                .entry([p.x.to_bits(), p.y.to_bits()])
                .or_insert_with(|| {
                    pts.push((pts.len() as u32, [p.x, p.y]));
                    nodes.push(Vec::new());
                    pts.len() as u32 - 1
                }) as usize;
            let tool = m.tool(m.cell_mode(nd).0);
            match nodes[id].iter_mut().find(|g| g.0 == tool) {
                Some(g) => g.1.push(nd as u32),
                None => nodes[id].push((tool, vec![nd as u32])),
            }
        }
        let tree = ImmutableKdTree::new_from_entries(&pts).expect("k-d tree build");
        Sites { tree, nodes }
    }
}

/// The largest number of nodes at one point.
fn most_at_one_point(m: &CostModel) -> usize {
    let mut count: HashMap<[u64; 3], usize> = HashMap::new();
    let mut most = 0;
    for nd in 0..m.nodes() {
        for (side, p) in [(0, m.entry(nd)), (1, m.exit(nd))] {
            let c = count
                .entry([side, p.x.to_bits(), p.y.to_bits()])
                .or_insert(0);
            *c += 1;
            most = most.max(*c);
        }
    }
    most
}

fn geometric(m: &CostModel, k: usize, deadline: Deadline) -> Neighbours {
    // a query for the 2k + 1 nearest nodes among many more at one point walks all of them:
    // then the trees hold distinct points
    if most_at_one_point(m) > 2 * k + 1 {
        return geometric_sites(m, k, deadline);
    }
    geometric_nodes(m, k, deadline)
}

/// `f` of every cell `0..n`, in parallel chunks, the clock read between chunks; empty lists
/// for the cells left once `deadline` passes. Each cell's list depends on nothing else: identical whatever the
/// number of threads or chunks.
fn lists(n: usize, deadline: Deadline, f: impl Fn(usize) -> Vec<u32> + Sync + Send) -> Vec<Vec<u32>> {
    const CHUNK: usize = 4096;
    let mut v = Vec::with_capacity(n);
    let mut c = 0;
    while c < n {
        if deadline.passed() {
            // the cells whose turn comes after the deadline get empty lists
            v.resize(n, Vec::new());
            return v;
        }
        let e = (c + CHUNK).min(n);
        v.extend((c..e).into_par_iter().map(&f).collect::<Vec<_>>());
        c = e;
    }
    v
}

/// Neighbour lists from k-d trees over every node's point.
fn geometric_nodes(m: &CostModel, k: usize, deadline: Deadline) -> Neighbours {
    let n = m.n();
    let build = |exit: bool| {
        crate::geom::xy_tree((0..m.nodes()).map(|nd| {
            let p = if exit { m.exit(nd) } else { m.entry(nd) };
            [p.x, p.y]
        }))
    };
    let entries = build(false);
    let exits = build(true);
    let query = |tree: &ImmutableKdTree<f64, 2>, c: usize, use_exit: bool| -> Vec<u32> {
        let mut want = k * 2 + 1;
        // a cell of many modes (a contour with thousands of start points) is queried from an
        // evenly spaced share of them: its own points fill every query around it, and
        // querying from each one with a growing count is O(modes · nodes)
        let modes = m.modes(c);
        let step = modes.div_ceil(MAX_QUERY_MODES);
        loop {
            let mut best: Vec<(f64, u32)> = Vec::new();
            for md in (0..modes).step_by(step) {
                let nd = m.node(c, md);
                let p = if use_exit { m.exit(nd) } else { m.entry(nd) };
                let kk = want.min(m.nodes());
                let res = tree
                    .query(&[p.x, p.y])
                    .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(kk).expect("k > 0"))
                    .execute();
                for r in res {
                    let (o, _) = m.cell_mode(r.item as usize);
                    // same-tool neighbours first: a tool change costs more than any short hop
                    let pen = if m.tool(o) == m.tool(c) { 0.0 } else { 1e12 };
                    if o != c {
                        best.push((r.distance + pen, o as u32));
                    }
                }
            }
            best.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut cells: Vec<u32> = Vec::with_capacity(k);
            for (_, o) in best {
                if !cells.contains(&o) {
                    cells.push(o);
                    if cells.len() == k {
                        break;
                    }
                }
            }
            if cells.len() == k || want >= m.nodes() {
                return cells;
            }
            want *= 4;
        }
    };
    // independent per cell: built in parallel, identical whatever the number of threads
    let out = lists(n, deadline, |c| query(&entries, c, true));
    let inn = lists(n, deadline, |c| query(&exits, c, false));
    Neighbours { out, inn }
}

/// Neighbour lists from k-d trees over the distinct points ([`Sites`]): many nodes at one
/// point cost one tree point, and each site offers its k + 1 lowest cells per tool.
fn geometric_sites(m: &CostModel, k: usize, deadline: Deadline) -> Neighbours {
    let n = m.n();
    let entries = Sites::new(m, false);
    let exits = Sites::new(m, true);
    let query = |sites: &Sites, c: usize, use_exit: bool| -> Vec<u32> {
        let nsites = sites.nodes.len();
        let mut want = k * 2 + 1;
        loop {
            let mut best: Vec<(f64, u32)> = Vec::new();
            for md in 0..m.modes(c) {
                let nd = m.node(c, md);
                let p = if use_exit { m.exit(nd) } else { m.entry(nd) };
                let kk = want.min(nsites);
                let res = sites
                    .tree
                    .query(&[p.x, p.y])
                    .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(kk).expect("k > 0"))
                    .execute();
                for r in res {
                    for (tool, list) in &sites.nodes[r.item as usize] {
                        // same-tool neighbours first: a tool change costs more than any short
                        // hop
                        let pen = if *tool == m.tool(c) { 0.0 } else { 1e12 };
                        // a site's nodes cost the same: its k + 1 lowest cells are enough
                        let mut taken = 0;
                        let mut last = u32::MAX;
                        for &x in list {
                            let o = m.cell_mode(x as usize).0 as u32;
                            if o as usize == c || o == last {
                                continue;
                            }
                            if taken > k {
                                break;
                            }
                            best.push((r.distance + pen, o));
                            last = o;
                            taken += 1;
                        }
                    }
                }
            }
            best.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut cells: Vec<u32> = Vec::with_capacity(k);
            for (_, o) in best {
                if !cells.contains(&o) {
                    cells.push(o);
                    if cells.len() == k {
                        break;
                    }
                }
            }
            if cells.len() == k || want >= nsites {
                return cells;
            }
            want *= 4;
        }
    };
    // independent per cell: built in parallel, identical whatever the number of threads
    let out = lists(n, deadline, |c| query(&entries, c, true));
    let inn = lists(n, deadline, |c| query(&exits, c, false));
    Neighbours { out, inn }
}

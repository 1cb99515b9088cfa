//! Readers for TSPLIB-style text: TSPLIB SOP (`TYPE: SOP`) and PCGLNS/PCGTSP (`TYPE: PCGLNS`).

use super::sections::{
    Lines, check_dimension, check_explicit, check_type, instance_name, number, positive, split,
};
use crate::error::{Error, Result};
use crate::model::{Cell, CostMatrix, Instance, Metadata, Mode};
use std::collections::BTreeSet;

/// Cost stored for arcs that precedence forbids (the files mark them −1).
pub const FORBIDDEN_ARC: f64 = CostMatrix::FORBIDDEN;

/// Largest matrix dimension read by default: a matrix of n nodes takes 8·n² bytes, 3.2 GB at
/// this limit. The environment variable [`MAX_NODES_ENV`] raises (or lowers) it.
pub const MAX_NODES: usize = 20_000;
/// Environment variable that overrides [`MAX_NODES`].
pub const MAX_NODES_ENV: &str = "CELLSEQ_MAX_MATRIX_NODES";

/// What [`MAX_NODES_ENV`] may be set to: a matrix of 10⁵ nodes takes 80 GB.
pub const MAX_NODES_RANGE: crate::params::IntRange = crate::params::IntRange::new(1, 100_000);

/// The matrix dimension limit in force: [`MAX_NODES_ENV`] when set to a whole number in
/// [`MAX_NODES_RANGE`], else [`MAX_NODES`] ([`max_nodes_checked`] refuses a bad setting).
pub fn max_nodes() -> usize {
    max_nodes_checked().unwrap_or(MAX_NODES)
}

/// The matrix dimension limit in force; an error naming [`MAX_NODES_ENV`] when it is set to
/// anything but a whole number in [`MAX_NODES_RANGE`].
pub fn max_nodes_checked() -> Result<usize> {
    let Some(v) = std::env::var_os(MAX_NODES_ENV) else {
        return Ok(MAX_NODES);
    };
    let text = v.to_string_lossy();
    let n = text
        .trim()
        .parse::<u64>()
        .map_err(|_| {
            format!("{MAX_NODES_ENV} must be a whole number in {MAX_NODES_RANGE}, got '{text}'")
        })
        .and_then(|n| MAX_NODES_RANGE.check(MAX_NODES_ENV, n))
        .map_err(Error::Param)?;
    Ok(n as usize)
}

/// Whitespace tokens of numbered lines, read lazily, each with its 1-based line number.
#[derive(Clone)]
struct Tokens<'a> {
    file: &'a str,
    lines: &'a [(usize, &'a str)],
    /// the next line to split
    next_line: usize,
    current: Option<(usize, std::str::SplitWhitespace<'a>)>,
    peeked: Option<(usize, &'a str)>,
    last_line: usize,
}

impl<'a> Tokens<'a> {
    fn new(file: &'a str, lines: &'a [(usize, &'a str)]) -> Self {
        let last_line = lines.last().map(|l| l.0).unwrap_or(1);
        Tokens {
            file,
            lines,
            next_line: 0,
            current: None,
            peeked: None,
            last_line,
        }
    }
    fn advance(&mut self) -> Option<(usize, &'a str)> {
        if let Some(t) = self.peeked.take() {
            return Some(t);
        }
        loop {
            if let Some((ln, it)) = &mut self.current
                && let Some(t) = it.next()
            {
                return Some((*ln, t));
            }
            let &(ln, l) = self.lines.get(self.next_line)?;
            self.next_line += 1;
            self.current = Some((ln, l.split_whitespace()));
        }
    }
    fn peek(&mut self) -> Option<(usize, &'a str)> {
        if self.peeked.is_none() {
            self.peeked = self.advance();
        }
        self.peeked
    }
    /// How many tokens are left (counted without allocating).
    fn remaining(&self) -> usize {
        let mut t = self.clone();
        let mut k = 0;
        while t.advance().is_some() {
            k += 1;
        }
        k
    }
    fn next_num(&mut self, what: &dyn Fn() -> String) -> Result<(usize, f64)> {
        let Some((ln, t)) = self.advance() else {
            return Err(Error::parse(
                self.file,
                self.last_line,
                format!("file ends early: expected {}", what()),
            ));
        };
        Ok((ln, number(self.file, ln, t, what)?))
    }
    fn next_int(&mut self, what: &str) -> Result<(usize, i64)> {
        let (ln, v) = self.next_num(&|| what.to_string())?;
        if v.fract() != 0.0 || v.abs() > 9.0e15 {
            return Err(Error::parse(
                self.file,
                ln,
                format!("expected an integer for {what}, found {v}"),
            ));
        }
        Ok((ln, v as i64))
    }
}

/// Checks a declared matrix dimension against the limit and against the numbers the
/// section holds, before anything of that size is allocated.
fn check_matrix_size(file: &str, ln: usize, dim: usize, tok: &Tokens) -> Result<()> {
    check_dimension(file, ln, dim)?;
    let have = tok.remaining();
    let need = dim.saturating_mul(dim);
    if have < need {
        return Err(Error::parse(
            file,
            tok.last_line,
            format!(
                "file ends early: EDGE_WEIGHT_SECTION holds {have} numbers, but a {dim}x{dim} \
                 matrix needs {need}"
            ),
        ));
    }
    Ok(())
}

/// A matrix entry: -1 marks precedence (`Ok(None)`), other numbers must lie in
/// 0..=[`crate::validate::MAX_MATRIX_COST`].
fn entry(file: &str, ln: usize, i: usize, j: usize, v: f64) -> Result<Option<f64>> {
    if v == -1.0 {
        return Ok(None);
    }
    if v < 0.0 {
        return Err(Error::parse(
            file,
            ln,
            format!(
                "matrix entry ({}, {}) is negative ({}); only -1 marks precedence",
                i + 1,
                j + 1,
                crate::validate::show(v)
            ),
        ));
    }
    let max = crate::validate::MAX_MATRIX_COST;
    if v > max {
        return Err(Error::parse(
            file,
            ln,
            format!(
                "matrix entry ({}, {}) is {}, above the limit {max:e}",
                i + 1,
                j + 1,
                crate::validate::show(v)
            ),
        ));
    }
    Ok(Some(v))
}

/// Parses a TSPLIB SOP file. Node i (1-based) becomes cell `"i"` with one mode.
pub fn parse_sop(file: &str, text: &str) -> Result<Instance> {
    let h = split(file, text, &["EDGE_WEIGHT_SECTION"], false)?;
    check_type(file, &h, &["SOP"])?;
    check_explicit(file, &h)?;
    let (_, dim) = positive(file, &h, "DIMENSION")?;
    let Some(lines) = h.section("EDGE_WEIGHT_SECTION") else {
        return Err(Error::parse(
            file,
            text.lines().count().max(1),
            "missing EDGE_WEIGHT_SECTION",
        ));
    };
    let mut tok = Tokens::new(file, lines);
    let (ln, d2) = tok.next_int("the dimension after EDGE_WEIGHT_SECTION")?;
    if d2 != dim as i64 {
        return Err(Error::parse(
            file,
            ln,
            format!("dimension after EDGE_WEIGHT_SECTION is {d2}, header says DIMENSION {dim}"),
        ));
    }
    check_matrix_size(file, ln, dim, &tok)?;
    let mut costs = vec![0.0; dim * dim];
    let mut edges = Vec::new();
    for i in 0..dim {
        for j in 0..dim {
            let (ln, v) = tok.next_num(&|| format!("matrix entry ({}, {})", i + 1, j + 1))?;
            match entry(file, ln, i, j, v)? {
                None => {
                    if i == j {
                        return Err(Error::parse(
                            file,
                            ln,
                            format!("node {} must precede itself", i + 1),
                        ));
                    }
                    edges.push((j, i));
                    costs[i * dim + j] = FORBIDDEN_ARC;
                }
                Some(v) => costs[i * dim + j] = v,
            }
        }
    }
    if let Some((ln, t)) = tok.peek() {
        return Err(Error::parse(
            file,
            ln,
            format!("unexpected token '{t}' after the {dim}x{dim} matrix (wrong DIMENSION?)"),
        ));
    }
    let cells = (0..dim)
        .map(|i| Cell::new((i + 1).to_string(), "", vec![Mode::default()]))
        .collect();
    Ok(Instance {
        name: instance_name(&h, file, &[".sop", ".pcglns"]),
        meta: Metadata {
            generator: Some("tsplib-sop".into()),
            comment: h.get("COMMENT").map(|(_, v)| v.to_string()),
            ..Default::default()
        },
        cells,
        precedence: edges,
        matrix: Some(CostMatrix { size: dim, costs }),
        first: Some(0),
        last: Some(dim - 1),
        ..Instance::default()
    })
}

/// Parses a PCGLNS (PCGTSP) file. Group g becomes cell `"g"` whose modes are the group's
/// nodes in file order.
pub fn parse_pcglns(file: &str, text: &str) -> Result<Instance> {
    let h = split(
        file,
        text,
        &[
            "EDGE_WEIGHT_SECTION",
            "GTSP_SET_SECTION",
            "GTSP_SET_ORDERING",
            "START_GROUP_SECTION",
        ],
        false,
    )?;
    check_type(file, &h, &["PCGLNS", "PCGTSP"])?;
    check_explicit(file, &h)?;
    let (dim_line, dim) = positive(file, &h, "DIMENSION")?;
    let (sets_line, ngroups) = positive(file, &h, "GTSP_SETS")?;
    // sizes from the header, checked before the per-node and per-group tables are allocated
    check_dimension(file, dim_line, dim)?;
    if ngroups > dim {
        return Err(Error::parse(
            file,
            sets_line,
            format!("GTSP_SETS {ngroups} is more than the {dim} nodes (every group needs a node)"),
        ));
    }
    let section = |name: &str| -> Result<Lines> {
        h.section(name).cloned().ok_or_else(|| {
            Error::parse(file, text.lines().count().max(1), format!("missing {name}"))
        })
    };
    let (group_of, groups) = pcglns_groups(file, section("GTSP_SET_SECTION")?, dim, ngroups)?;
    let lines = section("EDGE_WEIGHT_SECTION")?;
    let mut edges: BTreeSet<(usize, usize)> = BTreeSet::new();
    let costs = pcglns_matrix(file, (&lines, dim_line), &group_of, &groups, &mut edges)?;
    if let Ok(order) = section("GTSP_SET_ORDERING") {
        pcglns_ordering(file, order, ngroups, &mut edges)?;
    }
    let start = pcglns_start(file, section("START_GROUP_SECTION")?, &groups)?;
    Ok(generalized_instance(
        instance_name(&h, file, &[".sop", ".pcglns"]),
        "pcglns",
        h.get("COMMENT").map(|(_, v)| v.to_string()),
        &groups,
        start,
        edges,
        CostMatrix { size: dim, costs },
    ))
}

/// The instance of a generalized file (PCGLNS, PCGTSP): one cell per group with one mode per
/// node, the start group ordered before every other group, the node matrix, a closed tour.
pub(crate) fn generalized_instance(
    name: String,
    generator: &str,
    comment: Option<String>,
    groups: &[Vec<usize>],
    start: usize,
    mut edges: BTreeSet<(usize, usize)>,
    matrix: CostMatrix,
) -> Instance {
    for g in 0..groups.len() {
        if g != start {
            edges.insert((start, g));
        }
    }
    let cells = groups
        .iter()
        .enumerate()
        .map(|(g, nodes)| Cell::new((g + 1).to_string(), "", vec![Mode::default(); nodes.len()]))
        .collect();
    Instance {
        name,
        meta: Metadata {
            generator: Some(generator.into()),
            comment,
            ..Default::default()
        },
        cells,
        precedence: edges.into_iter().collect(),
        matrix: Some(matrix),
        first: Some(start),
        closed: true,
        ..Instance::default()
    }
}

/// The groups of a PCGLNS file (`GTSP_SET_SECTION`): the group of every node and the nodes
/// of every group, in file order; every node in exactly one group, no group empty.
fn pcglns_groups(
    file: &str,
    lines: Vec<(usize, &str)>,
    dim: usize,
    ngroups: usize,
) -> Result<(Vec<usize>, Vec<Vec<usize>>)> {
    let mut group_of = vec![usize::MAX; dim];
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); ngroups];
    let mut seen_group = vec![false; ngroups];
    for (ln, line) in lines {
        let nums = parse_list(file, ln, line)?;
        let g = group_number(file, ln, nums[0], ngroups)?;
        if seen_group[g] {
            return Err(Error::parse(
                file,
                ln,
                format!("group {} listed twice", g + 1),
            ));
        }
        seen_group[g] = true;
        add_to_group(file, ln, g, &nums[1..], &mut group_of, &mut groups)?;
    }
    groups_complete(file, &groups, &group_of)?;
    Ok((group_of, groups))
}

/// The cost matrix of a PCGLNS file (`EDGE_WEIGHT_SECTION`, `DIMENSION` on line `dim_line`) in
/// our node numbering (group by group, file order within); a forbidden arc (-1) from node i to
/// node j says that j's group precedes i's, which goes into `edges`.
fn pcglns_matrix(
    file: &str,
    (lines, dim_line): (&[(usize, &str)], usize),
    group_of: &[usize],
    groups: &[Vec<usize>],
    edges: &mut BTreeSet<(usize, usize)>,
) -> Result<Vec<f64>> {
    let dim = group_of.len();
    let mut new_index = vec![0usize; dim];
    let mut k = 0;
    for g in groups {
        for &v in g {
            new_index[v] = k;
            k += 1;
        }
    }
    let mut tok = Tokens::new(file, lines);
    check_matrix_size(file, dim_line, dim, &tok)?;
    let mut costs = vec![0.0; dim * dim];
    for i in 0..dim {
        for j in 0..dim {
            let (ln, v) = tok.next_num(&|| format!("matrix entry ({}, {})", i + 1, j + 1))?;
            let (gi, gj) = (group_of[i], group_of[j]);
            let slot = new_index[i] * dim + new_index[j];
            match entry(file, ln, i, j, v)? {
                None => costs[slot] = forbidden_arc(file, ln, (gi, gj), edges)?,
                Some(v) => costs[slot] = v,
            }
        }
    }
    if let Some((ln, t)) = tok.peek() {
        return Err(Error::parse(
            file,
            ln,
            format!("unexpected token '{t}' after the {dim}x{dim} matrix (wrong DIMENSION?)"),
        ));
    }
    Ok(costs)
}

/// A -1 entry from a node of group `gi` to a node of group `gj` of a generalized file: group
/// `gj` precedes `gi` (added to `edges`), and the arc costs [`FORBIDDEN_ARC`].
pub(crate) fn forbidden_arc(
    file: &str,
    ln: usize,
    (gi, gj): (usize, usize),
    edges: &mut BTreeSet<(usize, usize)>,
) -> Result<f64> {
    if gi == gj {
        return Err(Error::parse(
            file,
            ln,
            format!("group {} must precede itself", gi + 1),
        ));
    }
    edges.insert((gj, gi));
    Ok(FORBIDDEN_ARC)
}

/// The precedence of `GTSP_SET_ORDERING`: each line's first group before the others.
fn pcglns_ordering(
    file: &str,
    lines: Vec<(usize, &str)>,
    ngroups: usize,
    edges: &mut BTreeSet<(usize, usize)>,
) -> Result<()> {
    for (ln, line) in lines {
        let nums = parse_list(file, ln, line)?;
        let g = group_number(file, ln, nums[0], ngroups)?;
        for &x in &nums[1..] {
            let hgrp = group_number(file, ln, x, ngroups)?;
            if hgrp == g {
                return Err(Error::parse(
                    file,
                    ln,
                    format!("group {} must precede itself", g + 1),
                ));
            }
            edges.insert((g, hgrp));
        }
    }
    Ok(())
}

/// The start group (`START_GROUP_SECTION`), which must hold a single node.
fn pcglns_start(file: &str, lines: Vec<(usize, &str)>, groups: &[Vec<usize>]) -> Result<usize> {
    let mut tok = Tokens::new(file, &lines);
    let (ln, s) = tok.next_int("the start group")?;
    let start = group_number(file, ln, s, groups.len())?;
    if groups[start].len() != 1 {
        return Err(Error::parse(
            file,
            ln,
            format!(
                "start group {} has {} nodes; closed PCGLNS tours need a single-node start group",
                start + 1,
                groups[start].len()
            ),
        ));
    }
    Ok(start)
}

/// Puts the 1-based `nodes` of one NODE_GROUP_SECTION line into group `g` (0-based), refusing
/// a node out of range or already in a group.
pub(crate) fn add_to_group(
    file: &str,
    ln: usize,
    g: usize,
    nodes: &[i64],
    group_of: &mut [usize],
    groups: &mut [Vec<usize>],
) -> Result<()> {
    let dim = group_of.len();
    for &v in nodes {
        if v < 1 || v as usize > dim {
            return Err(Error::parse(
                file,
                ln,
                format!("node {v} out of range 1..{dim}"),
            ));
        }
        let v = v as usize - 1;
        if group_of[v] != usize::MAX {
            return Err(Error::parse(
                file,
                ln,
                format!("node {} is in two groups", v + 1),
            ));
        }
        group_of[v] = g;
        groups[g].push(v);
    }
    Ok(())
}

/// Refuses a group without nodes and a node in no group (`usize::MAX` in `group_of`).
pub(crate) fn groups_complete(file: &str, groups: &[Vec<usize>], group_of: &[usize]) -> Result<()> {
    if let Some(g) = groups.iter().position(|g| g.is_empty()) {
        return Err(Error::invalid(
            file,
            format!("group {} has no nodes", g + 1),
        ));
    }
    if let Some(v) = group_of.iter().position(|&g| g == usize::MAX) {
        return Err(Error::invalid(
            file,
            format!("node {} belongs to no group", v + 1),
        ));
    }
    Ok(())
}

/// Parses "a b c ... -1" into the numbers before the terminating -1.
pub(crate) fn parse_list(file: &str, ln: usize, line: &str) -> Result<Vec<i64>> {
    let mut out = Vec::new();
    let mut ended = false;
    for t in line.split_whitespace() {
        if ended {
            return Err(Error::parse(
                file,
                ln,
                format!("token '{t}' after the terminating -1"),
            ));
        }
        let v: i64 = t
            .parse()
            .map_err(|_| Error::parse(file, ln, format!("expected an integer, found '{t}'")))?;
        if v == -1 {
            ended = true;
        } else {
            out.push(v);
        }
    }
    if !ended {
        return Err(Error::parse(file, ln, "list is not terminated by -1"));
    }
    if out.is_empty() {
        return Err(Error::parse(file, ln, "empty list"));
    }
    Ok(out)
}

/// Group number `g` (1-based) of `ngroups` as an index.
pub(crate) fn group_number(file: &str, ln: usize, g: i64, ngroups: usize) -> Result<usize> {
    if g < 1 || g as usize > ngroups {
        return Err(Error::parse(
            file,
            ln,
            format!("group {g} out of range 1..{ngroups}"),
        ));
    }
    Ok(g as usize - 1)
}

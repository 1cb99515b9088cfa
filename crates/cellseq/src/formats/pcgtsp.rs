//! Reader for the original PCGTSPLIB format, `TYPE: PCGTSP` (Salman, Ekstedt et al.):
//! float costs, node weights, groups of nodes and a start group.
//!
//! ```text
//! NAME: ESC07.pcgtsp
//! TYPE: PCGTSP
//! DIMENSION: 39                 nodes
//! GROUPS: 8                     groups (clusters)
//! EDGE_WEIGHT_TYPE: EXPLICIT
//! EDGE_WEIGHT_FORMAT: FULL_MATRIX
//! NODE_WEIGHT_SECTION           DIMENSION numbers: the cost of visiting each node
//! EDGE_WEIGHT_SECTION           DIMENSION x DIMENSION numbers (no repeated dimension);
//!                               -1 at (i, j): the group of node j precedes the group of node i
//! NODE_GROUP_SECTION            lines "g v1 v2 ... -1": the nodes (1-based) of group g
//! START_GROUP_SECTION           the start group (a single node)
//! EOF
//! ```
//!
//! A solution visits one node per group as a closed tour from the start group. Group g
//! becomes cell `"g"` whose modes are its nodes in file order (like the PCGLNS reader), a −1
//! entry a precedence edge and a forbidden arc, and a node's weight is added to every
//! allowed arc into it: a closed tour enters each node it visits exactly once, so the tour's
//! cost is its arcs plus its nodes' weights. A file in the integer PCGLNS layout
//! (`GTSP_SETS`, `GTSP_SET_SECTION`) is handed to [`super::tsplib::parse_pcglns`].
//!
//! Sizes are checked before anything of that size is allocated (DIMENSION against
//! [`super::tsplib::max_nodes`], and the number of matrix entries the file really holds);
//! every error names the file and the line.

use super::sections::{
    Parts, check_dimension, check_explicit, check_type, instance_name, number, positive,
};
use super::tsplib::{
    add_to_group, forbidden_arc, generalized_instance, group_number, groups_complete,
    parse_list as list,
};
use crate::error::{Error, Result};
use crate::model::{CostMatrix, Instance};
use std::collections::BTreeSet;

const SECTIONS: [&str; 4] = [
    "NODE_WEIGHT_SECTION",
    "EDGE_WEIGHT_SECTION",
    "NODE_GROUP_SECTION",
    "START_GROUP_SECTION",
];

/// Whitespace tokens of numbered lines.
fn tokens<'a>(lines: &'a [(usize, &'a str)]) -> impl Iterator<Item = (usize, &'a str)> + 'a {
    lines
        .iter()
        .flat_map(|&(ln, l)| l.split_whitespace().map(move |t| (ln, t)))
}

/// Parses a `TYPE: PCGTSP` file (see the module documentation); no validation.
pub fn parse_pcgtsp(file: &str, text: &str) -> Result<Instance> {
    let p = super::sections::split(file, text, &SECTIONS, true)?;
    if p.get("GTSP_SETS").is_some() {
        return super::tsplib::parse_pcglns(file, text);
    }
    let (dim, ngroups) = header(file, &p)?;
    let weight = node_weights(file, &p, dim)?;
    let (group_of, groups) = node_groups(file, &p, dim, ngroups)?;
    let mut new_index = vec![0usize; dim];
    for (k, &v) in groups.iter().flatten().enumerate() {
        new_index[v] = k;
    }
    let (costs, edges) = matrix(file, &p, &weight, &group_of, &new_index)?;
    let start = start_group(file, &p, &groups)?;
    Ok(generalized_instance(
        instance_name(&p, file, &[".pcgtsp"]),
        "pcgtsp",
        p.get("COMMENT").map(|(_, v)| v.to_string()),
        &groups,
        start,
        edges,
        CostMatrix { size: dim, costs },
    ))
}

/// The error for a missing section `name` (at the file's last line).
fn missing(file: &str, p: &Parts, name: &str) -> Error {
    Error::parse(file, p.last_line, format!("missing {name}"))
}

/// The header's checks: the type and the matrix format, `DIMENSION` (within the node
/// limit) and `GROUPS` (at most one per node); returns both.
fn header(file: &str, p: &Parts) -> Result<(usize, usize)> {
    check_type(file, p, &["PCGTSP"])?;
    check_explicit(file, p)?;
    let (dim_line, dim) = positive(file, p, "DIMENSION")?;
    let (groups_line, ngroups) = positive(file, p, "GROUPS")?;
    check_dimension(file, dim_line, dim)?;
    if ngroups > dim {
        return Err(Error::parse(
            file,
            groups_line,
            format!("GROUPS {ngroups} is more than the {dim} nodes (every group needs a node)"),
        ));
    }
    Ok((dim, ngroups))
}

/// The node weights of `NODE_WEIGHT_SECTION` (0 when the section is absent).
fn node_weights(file: &str, p: &Parts, dim: usize) -> Result<Vec<f64>> {
    let max = crate::validate::MAX_MATRIX_COST;
    let mut weight = vec![0.0; dim];
    if let Some(lines) = p.section("NODE_WEIGHT_SECTION") {
        let mut k = 0;
        for (ln, t) in tokens(lines) {
            if k == dim {
                return Err(Error::parse(
                    file,
                    ln,
                    format!("NODE_WEIGHT_SECTION holds more than the {dim} node weights"),
                ));
            }
            let v = number(file, ln, t, &|| format!("the weight of node {}", k + 1))?;
            if !(0.0..=max).contains(&v) {
                return Err(Error::parse(
                    file,
                    ln,
                    format!(
                        "weight of node {} is {}: weights must lie in 0..={max:e}",
                        k + 1,
                        crate::validate::show(v)
                    ),
                ));
            }
            weight[k] = v;
            k += 1;
        }
        if k < dim {
            return Err(Error::parse(
                file,
                lines.last().map_or(p.last_line, |l| l.0),
                format!("NODE_WEIGHT_SECTION holds {k} weights, DIMENSION says {dim}"),
            ));
        }
    }
    Ok(weight)
}

/// `NODE_GROUP_SECTION`: each node's group and each group's nodes.
fn node_groups(
    file: &str,
    p: &Parts,
    dim: usize,
    ngroups: usize,
) -> Result<(Vec<usize>, Vec<Vec<usize>>)> {
    let mut group_of = vec![usize::MAX; dim];
    let mut groups: Vec<Vec<usize>> = vec![Vec::new(); ngroups];
    for &(ln, line) in p
        .section("NODE_GROUP_SECTION")
        .ok_or_else(|| missing(file, p, "NODE_GROUP_SECTION"))?
    {
        let nums = list(file, ln, line)?;
        let g = group_number(file, ln, nums[0], ngroups)?;
        if !groups[g].is_empty() {
            return Err(Error::parse(
                file,
                ln,
                format!("group {} listed twice", g + 1),
            ));
        }
        if nums.len() < 2 {
            return Err(Error::parse(
                file,
                ln,
                format!("group {} has no nodes", g + 1),
            ));
        }
        add_to_group(file, ln, g, &nums[1..], &mut group_of, &mut groups)?;
    }
    groups_complete(file, &groups, &group_of)?;
    Ok((group_of, groups))
}

/// `EDGE_WEIGHT_SECTION`: the costs, node weights added, rows and columns in group order
/// (`new_index`), and the precedence pairs of groups its -1 entries give.
#[allow(clippy::type_complexity)]
fn matrix(
    file: &str,
    p: &Parts,
    weight: &[f64],
    group_of: &[usize],
    new_index: &[usize],
) -> Result<(Vec<f64>, BTreeSet<(usize, usize)>)> {
    let dim = weight.len();
    let max = crate::validate::MAX_MATRIX_COST;
    // the matrix: count what the section holds before allocating dim x dim
    let lines = p
        .section("EDGE_WEIGHT_SECTION")
        .ok_or_else(|| missing(file, p, "EDGE_WEIGHT_SECTION"))?;
    let need = dim * dim;
    let have = tokens(lines).take(need + 1).count();
    if have != need {
        let ln = lines.last().map_or(p.last_line, |l| l.0);
        return Err(Error::parse(
            file,
            ln,
            format!(
                "EDGE_WEIGHT_SECTION holds {}{have} numbers, but a {dim}x{dim} matrix needs {need}",
                if have > need { "more than " } else { "" },
            ),
        ));
    }
    let mut costs = vec![0.0; need];
    let mut edges: BTreeSet<(usize, usize)> = BTreeSet::new();
    for (k, (ln, t)) in tokens(lines).enumerate() {
        let (i, j) = (k / dim, k % dim);
        let v = number(file, ln, t, &|| {
            format!("matrix entry ({}, {})", i + 1, j + 1)
        })?;
        let slot = new_index[i] * dim + new_index[j];
        if v == -1.0 {
            costs[slot] = forbidden_arc(file, ln, (group_of[i], group_of[j]), &mut edges)?;
            continue;
        }
        if !(0.0..=max).contains(&v) {
            return Err(Error::parse(
                file,
                ln,
                format!(
                    "matrix entry ({}, {}) is {}: entries must lie in 0..={max:e}, or be -1 \
                     for precedence",
                    i + 1,
                    j + 1,
                    crate::validate::show(v)
                ),
            ));
        }
        let with_weight = v + weight[j];
        if with_weight > max {
            return Err(Error::parse(
                file,
                ln,
                format!(
                    "matrix entry ({}, {}) plus the weight of node {} is above {max:e}",
                    i + 1,
                    j + 1,
                    j + 1
                ),
            ));
        }
        costs[slot] = if i == j { 0.0 } else { with_weight };
    }
    Ok((costs, edges))
}

/// `START_GROUP_SECTION`: the start group, which must hold a single node.
fn start_group(file: &str, p: &Parts, groups: &[Vec<usize>]) -> Result<usize> {
    let ngroups = groups.len();
    let start_lines = p
        .section("START_GROUP_SECTION")
        .ok_or_else(|| missing(file, p, "START_GROUP_SECTION"))?;
    let mut it = tokens(start_lines);
    let Some((ln, t)) = it.next() else {
        return Err(Error::parse(
            file,
            p.last_line,
            "START_GROUP_SECTION holds no group",
        ));
    };
    let s: i64 = t
        .parse()
        .map_err(|_| Error::parse(file, ln, format!("expected a group number, found '{t}'")))?;
    let start = group_number(file, ln, s, ngroups)?;
    if let Some((ln, t)) = it.find(|&(_, t)| t != "-1") {
        return Err(Error::parse(
            file,
            ln,
            format!("unexpected token '{t}' after the start group"),
        ));
    }
    if groups[start].len() != 1 {
        return Err(Error::parse(
            file,
            ln,
            format!(
                "start group {} has {} nodes; a closed PCGTSP tour needs a single-node start group",
                start + 1,
                groups[start].len()
            ),
        ));
    }
    Ok(start)
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = "NAME: t.pcgtsp\nTYPE: PCGTSP \nDIMENSION: 4\nGROUPS: 3\n\
        EDGE_WEIGHT_TYPE: EXPLICIT \nEDGE_WEIGHT_FORMAT : FULL_MATRIX \n\
        NODE_WEIGHT_SECTION \n0 0 0.5 1\nEDGE_WEIGHT_SECTION \n\
        0 1.5 2 3\n0 0 -1 4\n0 5 0 6\n0 7 8.25 0\n\
        NODE_GROUP_SECTION \n1 1 -1\n2 2 -1\n3 3 4 -1\nSTART_GROUP_SECTION \n1\nEOF\n";

    #[test]
    fn reads_floats_weights_groups_and_precedence() {
        let inst = parse_pcgtsp("t.pcgtsp", SMALL).unwrap();
        crate::validate::validate(&inst, "t.pcgtsp").unwrap();
        assert_eq!(inst.n(), 3);
        assert_eq!(inst.cells[2].modes.len(), 2);
        assert!(inst.closed);
        assert_eq!(inst.first, Some(0));
        // -1 at (2, 3): group 3 precedes group 2
        assert!(inst.precedence.contains(&(2, 1)));
        let m = inst.matrix.as_ref().unwrap();
        assert_eq!(m.get(0, 1), 1.5); // no weight on node 2
        assert_eq!(m.get(0, 2), 2.5); // node 3 weighs 0.5
        assert_eq!(m.get(3, 2), 8.75);
        assert_eq!(m.get(1, 2), super::super::tsplib::FORBIDDEN_ARC);
        assert_eq!(m.get(2, 3), 7.0); // node 3 -> node 4 (weight 1)
    }

    #[test]
    fn errors_name_the_line() {
        let cases = [
            (SMALL.replace("0 0 -1 4", "0 0 -2 4"), "t.pcgtsp:11:"),
            (SMALL.replace("0 7 8.25 0\n", ""), "needs 16"),
            (SMALL.replace("GROUPS: 3", "GROUPS: 9"), "t.pcgtsp:4:"),
            (
                SMALL.replace("DIMENSION: 4", "DIMENSION: 99999999"),
                "limit",
            ),
            (SMALL.replace("3 3 4 -1", "3 3 4"), "t.pcgtsp:17:"),
            (SMALL.replace("0 0 0.5 1", "0 0 x 1"), "t.pcgtsp:8:"),
            (SMALL.replace("\n1\nEOF", "\n3\nEOF"), "single-node"),
            (SMALL.replace("2 2 -1", "2 1 -1"), "two groups"),
        ];
        for (text, want) in cases {
            let e = parse_pcgtsp("t.pcgtsp", &text).unwrap_err().to_string();
            assert!(e.contains("t.pcgtsp") && e.contains(want), "{want}: {e}");
        }
    }
}

//! Cluster choice: disjoint sets of cells that any path must enter and leave, taken from the
//! subtours of the assignment relaxation where they raise the root bound most.

use crate::bound::assignment;
use crate::bound::cells::CellGraph;
use crate::clock::Deadline;

/// Disjoint clusters of cells for the bound: subtours of the assignment relaxation, found
/// hierarchically (contract every subtour that avoids home into one group, solve the
/// assignment on the groups again, repeat), then the laminar family is cut so that the root
/// surcharge (Σ of entering + leaving surcharges, reduced costs `r`) is largest: each cluster
/// is kept whole or replaced by its best sub-family.
/// The hierarchy stops at `deadline` with the rounds done.
pub(super) fn choose_clusters(
    g: &CellGraph,
    r: &dyn Fn(usize, usize) -> f64,
    deadline: Deadline,
) -> Vec<Vec<u32>> {
    let (tree, groups) = cluster_tree(g, deadline);
    best_cut(g, r, &tree, &groups)
}

/// A tree of clusters: each node's cells and children, children before parents.
type Tree = Vec<(Vec<u32>, Vec<usize>)>;

/// Groups of cells (home = n), each with its node in the [`Tree`] when it was merged.
type Groups = Vec<(Vec<u32>, Option<usize>)>;

/// The hierarchy of assignment subtours: contract every subtour that avoids home into one
/// group, solve the assignment on the groups again, repeat (at most 16 rounds). Returns the
/// tree of clusters and the last groups (cells, with their tree node when merged).
fn cluster_tree(g: &CellGraph, deadline: Deadline) -> (Tree, Groups) {
    let n = g.n;
    // tree of clusters: cells and children
    let mut tree: Tree = Vec::new();
    // current groups: cells (home = n) and tree node
    let mut groups: Groups = (0..=n).map(|c| (vec![c as u32], None)).collect();
    for _round in 0..16 {
        let k = groups.len();
        if k <= 2 {
            break;
        }
        let mut cost = vec![f64::INFINITY; k * k];
        for a in 0..k {
            for b in 0..k {
                if a == b {
                    continue;
                }
                let mut best = f64::INFINITY;
                for &x in &groups[a].0 {
                    for &y in &groups[b].0 {
                        best = best.min(g.c(x as usize, y as usize));
                    }
                }
                cost[a * k + b] = best;
            }
        }
        let Some(asg) = assignment::hungarian_duals_until(k, |a, b| cost[a * k + b], deadline)
        else {
            break;
        };
        let asg = (asg.value, asg.col);
        let home = groups.iter().position(|gr| gr.0.contains(&(n as u32)));
        let mut seen = vec![false; k];
        let mut next: Groups = Vec::new();
        let mut merged = false;
        for s0 in 0..k {
            if seen[s0] {
                continue;
            }
            let mut cyc = Vec::new();
            let mut x = s0;
            while !seen[x] {
                seen[x] = true;
                cyc.push(x);
                x = asg.1[x];
            }
            if cyc.len() >= 2 && !cyc.iter().any(|&x| Some(x) == home) {
                let cells: Vec<u32> = cyc.iter().flat_map(|&x| groups[x].0.clone()).collect();
                let children: Vec<usize> = cyc.iter().filter_map(|&x| groups[x].1).collect();
                tree.push((cells.clone(), children));
                next.push((cells, Some(tree.len() - 1)));
                merged = true;
            } else {
                next.extend(cyc.iter().map(|&x| groups[x].clone()));
            }
        }
        groups = next;
        if !merged {
            break;
        }
    }
    (tree, groups)
}

/// The laminar family cut so that the root surcharge (Σ of entering + leaving surcharges in
/// reduced costs `r`) is largest: each cluster of `tree` is kept whole or replaced by its best
/// sub-family, from the roots among `groups`.
fn best_cut(
    g: &CellGraph,
    r: &dyn Fn(usize, usize) -> f64,
    tree: &Tree,
    groups: &Groups,
) -> Vec<Vec<u32>> {
    let n = g.n;
    // root surcharge of each cluster
    let d = n + 1;
    let mut min_in = vec![f64::INFINITY; n];
    let mut min_out = vec![f64::INFINITY; n];
    for i in 0..d {
        for j in 0..d {
            let c = r(i, j);
            if g.c(i, j).is_finite() {
                if j < n {
                    min_in[j] = min_in[j].min(c);
                }
                if i < n {
                    min_out[i] = min_out[i].min(c);
                }
            }
        }
    }
    let mut inside = vec![false; d];
    let surcharge = |cells: &[u32], inside: &mut Vec<bool>| {
        for &c in cells {
            inside[c as usize] = true;
        }
        let mut d_in = f64::INFINITY;
        let mut d_out = f64::INFINITY;
        for &j in cells {
            let j = j as usize;
            for i in 0..d {
                if !inside[i] && g.c(i, j).is_finite() {
                    d_in = d_in.min(r(i, j) - min_in[j]);
                }
                if !inside[i] && g.c(j, i).is_finite() {
                    d_out = d_out.min(r(j, i) - min_out[j]);
                }
            }
        }
        for &c in cells {
            inside[c as usize] = false;
        }
        let f = |x: f64| if x.is_finite() { x.max(0.0) } else { 0.0 };
        f(d_in) + f(d_out)
    };
    // children come before parents in `tree`
    let mut val = vec![0.0; tree.len()];
    let mut whole = vec![false; tree.len()];
    for t in 0..tree.len() {
        let own = surcharge(&tree[t].0, &mut inside);
        let sub: f64 = tree[t].1.iter().map(|&c| val[c]).sum();
        whole[t] = own >= sub && own > 0.0;
        val[t] = own.max(sub);
    }
    let mut out = Vec::new();
    let mut stack: Vec<usize> = groups.iter().filter_map(|gr| gr.1).collect();
    while let Some(t) = stack.pop() {
        if whole[t] {
            out.push(tree[t].0.clone());
        } else {
            stack.extend(tree[t].1.iter().copied());
        }
    }
    out.sort();
    out
}

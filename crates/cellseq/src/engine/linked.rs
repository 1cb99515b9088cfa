//! Or-opt on a doubly linked list, for large instances.
//!
//! In the array form of [`Solution`] an Or-opt move shifts every cell between the old and the
//! new place of the segment, O(distance). From a greedy start on 10^6 cells most useful moves
//! go to a spatial neighbour that sits far away in the order, so a pass costs O(n²) in the
//! worst case and does not finish in a minute. On a linked list every Or-opt move (a segment
//! of 1–3 cells moved between a candidate neighbour and its successor, kept or cut the other
//! way) and every in-place mode change is O(1). Precedence is checked with the list's order
//! labels ([`OrderList`]): a segment may go between v and w when each of its cells' outside
//! predecessors is at or before v and each outside successor at or after w (and, reversed,
//! when no precedence pair lies inside it), O(degree) per candidate. [`or_opt`] runs that pass
//! to a local optimum (don't-look bits, best move per looked-at cell) and writes the result
//! back into the array form.

use super::order::OrderList;
use super::{Costs, Neighbours, Solution};
use crate::context::Context;
use crate::cost::CostModel;
use std::collections::VecDeque;

/// The path as a cyclic linked list with order labels, and the cells' modes.
struct List {
    ord: OrderList,
    mode: Vec<u32>,
}

impl List {
    fn slot(&self, x: u32) -> Option<(usize, usize)> {
        let n = self.mode.len() as u32;
        (x != n).then(|| (x as usize, self.mode[x as usize] as usize))
    }
    /// Cost of the link x → y (either may be the sentinel), with the given modes for cells.
    #[inline]
    fn link(&self, c: &Costs, x: u32, mx: u32, y: u32, my: u32) -> f64 {
        let n = self.mode.len() as u32;
        let a = (x != n).then_some((x as usize, mx as usize));
        let b = (y != n).then_some((y as usize, my as usize));
        c.link(a, b)
    }
    #[inline]
    fn cur(&self, c: &Costs, x: u32, y: u32) -> f64 {
        c.link(self.slot(x), self.slot(y))
    }
    #[inline]
    fn md(&self, x: u32) -> u32 {
        self.mode.get(x as usize).copied().unwrap_or(0)
    }
}

/// Cells v after which a segment entered at `head` and left at `tail` may be inserted
/// (between v and its successor): candidate predecessors of `head`, the predecessors of
/// candidate successors of `tail`, and the sentinel (insertion at the start).
fn insertion_points<'a>(
    nb: &'a Neighbours,
    l: &'a List,
    head: u32,
    tail: u32,
) -> impl Iterator<Item = u32> + 'a {
    nb.inn[head as usize]
        .iter()
        .copied()
        .chain(
            nb.out[tail as usize]
                .iter()
                .map(|&w| l.ord.prev[w as usize]),
        )
        .chain([l.mode.len() as u32])
}

/// A move found for a looked-at cell.
#[derive(Clone, Copy)]
struct Found {
    delta: f64,
    /// Segment: first, last (in current order), length.
    f: u32,
    l: u32,
    /// Insert between v and w = next[v]; reversed or not. `v == u32::MAX`: in-place mode
    /// change of f to mode `w`.
    v: u32,
    w: u32,
    rev: bool,
}

/// Or-opt (segments of 1–3 cells, kept or reversed, next to candidate neighbours) and
/// single-cell mode changes on a linked list, to a local optimum or until the budget ends.
/// Returns true on any improvement; `s` is rewritten, its cost updated by the move deltas.
pub fn or_opt(c: &Costs, nb: &Neighbours, s: &mut Solution, ctx: &mut Context) -> bool {
    let m = c.m;
    let n = s.n();
    if n < 2 {
        return false;
    }
    let d = n as u32;
    let mut l = List {
        ord: OrderList::from_order(n, &s.order),
        mode: s.mode.clone(),
    };
    let prec = !m.dag.is_empty();

    let mut on = vec![true; n];
    let mut queue: VecDeque<u32> = s.order.iter().copied().collect();
    let mut improved = false;
    while let Some(x) = queue.pop_front() {
        on[x as usize] = false;
        if ctx.exhausted() {
            break;
        }
        let mut evals = 0u64;
        let mut best = Found {
            delta: 0.0,
            f: x,
            l: x,
            v: 0,
            w: 0,
            rev: false,
        };
        mode_change(c, &l, x, &mut best, &mut evals);
        segment_moves(c, nb, &l, x, prec, &mut best, &mut evals);
        ctx.count(evals);
        if !super::vnd::improves(best.delta, s.cost) {
            continue;
        }
        improved = true;
        s.cost += best.delta;
        for z in apply(m, &mut l, &best, x) {
            if z != d && !on[z as usize] {
                on[z as usize] = true;
                queue.push_back(z);
            }
        }
    }
    // back to the array form
    for (p, z) in l.ord.cells().enumerate() {
        s.order[p] = z;
        s.pos[z as usize] = p as u32;
    }
    s.mode = l.mode;
    improved
}

/// The best in-place mode change of cell `x`, if better than `best`.
fn mode_change(c: &Costs, l: &List, x: u32, best: &mut Found, evals: &mut u64) {
    let m = c.m;
    // in-place mode change
    let (p, q) = (l.ord.prev[x as usize], l.ord.next[x as usize]);
    let here = l.cur(c, p, x) + l.cur(c, x, q);
    for mx in 0..m.modes(x as usize) as u32 {
        if mx == l.mode[x as usize] {
            continue;
        }
        *evals += 1;
        let dl = l.link(c, p, l.md(p), x, mx) + l.link(c, x, mx, q, l.md(q)) - here;
        if dl < best.delta {
            *best = Found {
                delta: dl,
                f: x,
                l: x,
                v: u32::MAX,
                w: mx,
                rev: false,
            };
        }
    }
}

/// The best Or-opt move of the segments x, x+1, x+2 (following the order), kept or reversed,
/// to an insertion point next to a candidate neighbour, if better than `best` (`prec`: the
/// instance has precedence).
fn segment_moves(
    c: &Costs,
    nb: &Neighbours,
    l: &List,
    x: u32,
    prec: bool,
    best: &mut Found,
    evals: &mut u64,
) {
    let m = c.m;
    let d = l.mode.len() as u32;
    let mut seg_modes = [0u32; 3];
    let mut seg = [0u32; 3];
    // segments x, x+1, x+2 following the order
    let mut len = 0usize;
    let mut y = x;
    let mut can_rev = true;
    while len < 3 && y != d {
        seg[len] = y;
        match m.turned(y as usize, l.mode[y as usize] as usize) {
            Some(t) => seg_modes[len] = t as u32,
            None => can_rev = false,
        }
        len += 1;
        let (f, lst) = (seg[0], seg[len - 1]);
        let (p, q) = (l.ord.prev[f as usize], l.ord.next[lst as usize]);
        let gain = l.cur(c, p, f) + l.cur(c, lst, q) - l.cur(c, p, q);
        let inside = |z: u32| seg[..len].contains(&z);
        // labels the new place must lie between: after every outside predecessor, before
        // every outside successor (read once per segment, O(1) per candidate)
        let (lo, hi) = if prec {
            bounds(m, &l.ord, &seg[..len])
        } else {
            (0, u64::MAX)
        };
        let fits = |v: u32, w: u32| l.ord.after(v) >= lo && l.ord.before(w) <= hi;
        let rev_ok = !prec || reversible(m, &seg[..len]);
        let (mf, ml) = (l.mode[f as usize], l.mode[lst as usize]);
        let (rf, rl) = (seg_modes[0], seg_modes[len - 1]);
        // candidate insertion edges (v, w = next v), forward: v → f … lst → w;
        // reversed: v → lst' … f' → w
        for v in insertion_points(nb, l, f, lst) {
            let w = l.ord.next[v as usize];
            if inside(v) || inside(w) || v == p {
                continue;
            }
            if !fits(v, w) {
                continue;
            }
            *evals += 1;
            let dl = l.link(c, v, l.md(v), f, mf) + l.link(c, lst, ml, w, l.md(w))
                - l.cur(c, v, w)
                - gain;
            if dl < best.delta {
                *best = Found {
                    delta: dl,
                    f,
                    l: lst,
                    v,
                    w,
                    rev: false,
                };
            }
        }
        if can_rev && (len > 1 || rf != mf) {
            for v in insertion_points(nb, l, lst, f) {
                let w = l.ord.next[v as usize];
                // v == p (then w == f) reverses the segment in place
                if inside(v) || (v != p && inside(w)) {
                    continue;
                }
                let (vv, ww) = if v == p { (p, q) } else { (v, w) };
                if !rev_ok || !fits(vv, ww) {
                    continue;
                }
                let removed = if v == p {
                    l.cur(c, p, f) + l.cur(c, lst, q)
                } else {
                    l.cur(c, v, w) + gain
                };
                *evals += 1;
                let mut dl =
                    l.link(c, vv, l.md(vv), lst, rl) + l.link(c, f, rf, ww, l.md(ww)) - removed;
                // inner links of the reversed segment
                for k in 0..len - 1 {
                    let (a, b) = (seg[k], seg[k + 1]);
                    dl += l.link(c, b, seg_modes[k + 1], a, seg_modes[k]) - l.cur(c, a, b);
                }
                if dl < best.delta {
                    *best = Found {
                        delta: dl,
                        f,
                        l: lst,
                        v,
                        w,
                        rev: true,
                    };
                }
            }
        }
        y = l.ord.next[y as usize];
    }
}

/// Applies the move `best` found for the looked-at cell `x` to the list; returns the cells
/// whose links changed (the sentinel where fewer).
fn apply(m: &CostModel, l: &mut List, best: &Found, x: u32) -> [u32; 7] {
    let d = l.mode.len() as u32;
    let mut touched = [d; 7];
    if best.v == u32::MAX {
        l.mode[x as usize] = best.w;
        touched[..3].copy_from_slice(&[l.ord.prev[x as usize], x, l.ord.next[x as usize]]);
    } else {
        let (f, lst) = (best.f, best.l);
        let (p, q) = (l.ord.prev[f as usize], l.ord.next[lst as usize]);
        // the segment's cells, first to last
        let mut cells = [d; 3];
        let mut k = 0;
        let mut z = f;
        loop {
            cells[k] = z;
            k += 1;
            if z == lst {
                break;
            }
            z = l.ord.next[z as usize];
        }
        // insertion edge (v, w) once the segment is unlinked
        let (v, w) = if best.v == p {
            (p, q)
        } else {
            (best.v, best.w)
        };
        for &z in &cells[..k] {
            l.ord.unlink(z);
        }
        let mut order = cells;
        if best.rev {
            order[..k].reverse();
        }
        let mut a = v;
        for &z in &order[..k] {
            if best.rev {
                let md = l.mode[z as usize] as usize;
                l.mode[z as usize] = m.turned_or_same(z as usize, md) as u32;
            }
            l.ord.insert_after(a, z);
            a = z;
        }
        touched[..k].copy_from_slice(&cells[..k]);
        touched[3..7].copy_from_slice(&[p, q, v, w]);
    }
    touched
}

/// The highest label among the outside predecessors of the segment `seg` (0 if none) and the
/// lowest among its outside successors (u64::MAX if none): the segment may go between v and w
/// when v's label is at least the first and w's at most the second.
fn bounds(m: &CostModel, ord: &OrderList, seg: &[u32]) -> (u64, u64) {
    let (mut lo, mut hi) = (0, u64::MAX);
    for &z in seg {
        for &p in &m.dag.preds[z as usize] {
            if !seg.contains(&p) {
                lo = lo.max(ord.after(p));
            }
        }
        for &q in &m.dag.succs[z as usize] {
            if !seg.contains(&q) {
                hi = hi.min(ord.after(q));
            }
        }
    }
    (lo, hi)
}

/// True when no precedence pair lies inside the segment, so it may be cut backwards.
fn reversible(m: &CostModel, seg: &[u32]) -> bool {
    seg.iter()
        .all(|&z| m.dag.succs[z as usize].iter().all(|q| !seg.contains(q)))
}

//! Twin detection: cells that are copies of each other apart from the precedence, ordered by
//! index (symmetry breaking that keeps an optimum).

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::precedence::Closure;

/// Largest instance searched for interchangeable cells (O(n² · n · modes²)).
pub(super) const TWIN_MAX_CELLS: usize = 300;

/// Whether cells `a` and `b` are *cost twins*: neither precedes the other, same modes, same
/// start and finish costs, `arc(a, i, b, j) = arc(b, i, a, j)`, and the same arc costs to and
/// from every other cell (mode by mode) wherever the precedence closure allows both arcs.
/// Exchanging `a` and `b` (with their modes) in a feasible sequence whose exchanged version is
/// feasible too keeps its cost: every arc of a feasible sequence is allowed by the closure, so
/// every arc that changes is one compared here.
fn cost_twins(m: &CostModel, cl: &Closure, a: usize, b: usize) -> bool {
    let k = m.modes(a);
    if k != m.modes(b) || cl.before(a, b) || cl.before(b, a) {
        return false;
    }
    for i in 0..k {
        if m.start(a, i) != m.start(b, i) || m.finish(a, i) != m.finish(b, i) {
            return false;
        }
        for j in 0..k {
            if m.arc(a, i, b, j) != m.arc(b, i, a, j) {
                return false;
            }
        }
    }
    for c in 0..m.n() {
        if c == a || c == b {
            continue;
        }
        let out = cl.arc_allowed(a, c) && cl.arc_allowed(b, c);
        let inn = cl.arc_allowed(c, a) && cl.arc_allowed(c, b);
        for i in 0..k {
            for j in 0..m.modes(c) {
                if (out && m.arc(a, i, c, j) != m.arc(b, i, c, j))
                    || (inn && m.arc(c, j, a, i) != m.arc(c, j, b, i))
                {
                    return false;
                }
            }
        }
    }
    true
}

/// Whether `a` may lead `b`: every ancestor of `a` is an ancestor of `b`, and every
/// descendant of `b` is a descendant of `a` (neither precedes the other). Then in a feasible
/// sequence with `b` before `a`, exchanging them keeps it feasible: `a` moves earlier but
/// still after all of its ancestors, `b` moves later but still before all of its descendants.
fn may_lead(cl: &Closure, a: usize, b: usize) -> bool {
    (0..cl.n()).all(|c| {
        c == a
            || c == b
            || ((!cl.before(c, a) || cl.before(c, b)) && (!cl.before(b, c) || cl.before(a, c)))
    })
}

/// Symmetry breaking: pairs `(a, b)` of cost twins (`cost_twins`: copies of each other apart
/// from the precedence) where `a` may lead `b` (`may_lead`; when each may lead the other,
/// the smaller index leads). Any optimum can be turned into one where `a` comes before `b`
/// for every pair: exchange an inverted pair while there is one; each exchange keeps
/// feasibility and cost and lowers the number of inversions against a linear extension of
/// the strict order "leads, then index", so the exchanges end. Cells with the same precedence
/// (e.g. 1–3 of p43.1) are ordered by index; p43.2's cells 5 and 6 too (6 has one more
/// predecessor). Empty when the precedence has a cycle.
#[cfg(any(test, feature = "internals"))]
pub fn interchangeable_order(m: &CostModel) -> Vec<(usize, usize)> {
    Closure::new(&m.dag)
        .map(|cl| twin_order(m, &cl, Deadline::NONE))
        .unwrap_or_default()
}

/// The pairs of [`interchangeable_order`] found before `deadline` (any subset of the pairs
/// keeps an optimum too).
pub(super) fn twin_order(m: &CostModel, cl: &Closure, deadline: Deadline) -> Vec<(usize, usize)> {
    let n = m.n();
    let mut out = Vec::new();
    for a in 0..n {
        if deadline.passed() {
            break;
        }
        for b in a + 1..n {
            if !cost_twins(m, cl, a, b) {
                continue;
            }
            if may_lead(cl, a, b) {
                out.push((a, b));
            } else if may_lead(cl, b, a) {
                out.push((b, a));
            }
        }
    }
    out
}

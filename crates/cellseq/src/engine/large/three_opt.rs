//! Sequential 3-opt moves for [`Large`]: three links of the path removed and three added so
//! that the two middle stretches come back in another order or turned (segment insertion of
//! any length, with or without reversal, and the double reversal), found as in Lin and
//! Kernighan's scheme: t1 = the looked-at cell, t2 one of its path neighbours, t3 a candidate
//! of t2 with a positive partial gain, t4 a path neighbour of t3, t5 a candidate of t4 with a
//! positive partial gain, t6 a path neighbour of t5; removed {t1 t2, t3 t4, t5 t6}, added
//! {t2 t3, t4 t5, t6 t1}.
//!
//! The path is read as a cycle through a dummy node (`None`: the start before the first cell
//! and the end after the last), and the stretch holding the dummy keeps its place and its
//! direction, so every new link has a known direction and the start and end links are
//! costed as they are. A reconnection is recognised generically: the six link ends are the
//! ends of the three stretches, and walking the added links from the fixed stretch must pass
//! both others once and come back. Reconnections that add back a removed link are 2-opt moves
//! ([`Large`]'s own) and are skipped. As for 2-opt, a turned stretch is costed by its end
//! links only ([`super::applies`]).

use super::{Large, Move};

/// Candidates per list tried for t3 and for t5 ([`Large::three_k`]).
pub const THREE_K: usize = 5;

/// A node of the cycle: a cell, or `None` for the dummy (the path's start and end).
type Node = Option<u32>;

/// A 3-opt reconnection: cuts after positions `p[0] < p[1] < p[2]` (−1: before the first
/// cell) split the path into A₁ B C A₂; the new path is A₁ C B A₂ (`c_first`) or A₁ B' C' A₂,
/// with B and C turned where flagged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Three {
    /// The cut positions, sorted.
    pub p: [isize; 3],
    /// C comes before B.
    pub c_first: bool,
    /// B is turned.
    pub rev_b: bool,
    /// C is turned.
    pub rev_c: bool,
}

impl Three {
    /// First and last positions of B and of C.
    fn ends(&self) -> [usize; 4] {
        let [p1, p2, p3] = self.p;
        [
            (p1 + 1) as usize,
            p2 as usize,
            (p2 + 1) as usize,
            p3 as usize,
        ]
    }
}

/// Ports: 0 = A's end, 1 / 2 = B's start / end, 3 / 4 = C's start / end, 5 = A's start.
const A_END: usize = 0;
const A_START: usize = 5;

impl<'a> Large<'a> {
    #[inline]
    fn succ(&self, u: Node) -> Node {
        match u {
            None => self.t.first(),
            Some(c) => self.t.next(c),
        }
    }

    #[inline]
    fn pred(&self, u: Node) -> Node {
        match u {
            None => self.t.last(),
            Some(c) => self.t.prev(c),
        }
    }

    /// Cost of the path's link between neighbours `u` and `v` (`v` after `u` where `fwd`).
    #[inline]
    fn current(&self, u: Node, fwd: bool, v: Node) -> f64 {
        if fwd {
            self.link(self.sl(u), self.sl(v))
        } else {
            self.link(self.sl(v), self.sl(u))
        }
    }

    /// Estimate of a new link between cells `u` and `v` for the partial gains (in the
    /// direction of their current order).
    #[inline]
    fn estimate(&self, u: u32, v: u32) -> f64 {
        let (a, b) = (Some(u), Some(v));
        if self.t.pos(u) < self.t.pos(v) {
            self.link(self.sl(a), self.sl(b))
        } else {
            self.link(self.sl(b), self.sl(a))
        }
    }

    /// The best improving 3-opt move from cell `x`, where better than `best`.
    pub(super) fn three_opt_moves(&self, x: u32, best: &mut (f64, Move), evals: &mut u64) {
        let n = self.t.n();
        if n < 5 {
            return;
        }
        let t1 = Some(x);
        for fwd1 in [true, false] {
            let t2 = self.step(t1, fwd1);
            let Some(c2) = t2 else { continue };
            let g0 = self.current(t1, fwd1, t2);
            *evals += self.tried(c2);
            for (t3, g1) in self.added(c2, t1, g0) {
                for fwd3 in [true, false] {
                    let t4 = self.step(t3, fwd3);
                    let Some(c4) = t4 else { continue };
                    let l34 = self.current(t3, fwd3, t4);
                    *evals += self.tried(c4);
                    for (t5, _) in self.added(c4, None, g1 + l34) {
                        for fwd5 in [true, false] {
                            let t6 = self.step(t5, fwd5);
                            let ts = [t1, t2, t3, t4, t5, t6];
                            let l56 = self.current(t5, fwd5, t6);
                            let fwd = [fwd1, fwd3, fwd5];
                            if let Some((d, mv)) = self.reconnect(&ts, fwd, g0 + l34 + l56) {
                                *evals += 3;
                                if d < best.0 && self.allowed(&mv) {
                                    *best = (d, Move::Three(mv));
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    /// The path neighbour of `u` after it (`fwd`) or before it.
    #[inline]
    fn step(&self, u: Node, fwd: bool) -> Node {
        if fwd { self.succ(u) } else { self.pred(u) }
    }

    /// Number of candidates of cell `c` that [`Large::added`] looks at.
    #[inline]
    fn tried(&self, c: u32) -> u64 {
        self.three_k.min(self.nb.out[c as usize].len()) as u64
    }

    /// The next added link's far ends: candidates `v` of cell `c` among its
    /// [`Large::three_k`] nearest (the lists never hold `c` itself), neither `skip` (t1 for
    /// t3; `None` for t5) nor a path neighbour of `c`, whose partial gain `g` − estimate(c, v)
    /// stays positive, each with that gain.
    fn added(&self, c: u32, skip: Node, g: f64) -> impl Iterator<Item = (Node, f64)> {
        let u = Some(c);
        let (s, p) = (self.succ(u), self.pred(u));
        let list = &self.nb.out[c as usize];
        list[..self.three_k.min(list.len())]
            .iter()
            .filter_map(move |&v| {
                let t = Some(v);
                if t == skip || t == s || t == p {
                    return None;
                }
                let g1 = g - self.estimate(c, v);
                (g1 > 0.0).then_some((t, g1))
            })
    }

    /// The reconnection removing {t1 t2, t3 t4, t5 t6} (t2 after t1 on the path where
    /// `fwd[0]`, before it otherwise; the same for t4 and t6) and adding {t2 t3, t4 t5,
    /// t6 t1}, with its exact delta (`removed`: the three removed links' cost), or `None` when
    /// it is not a 3-opt move of the path (a link removed twice, two pieces, a removed link
    /// added back).
    fn reconnect(&self, ts: &[Node; 6], fwd: [bool; 3], removed: f64) -> Option<(f64, Three)> {
        // each removed link as (cut position, index in ts of its end that comes first)
        let mut cuts = [(0isize, 0usize); 3];
        for (e, cut) in cuts.iter_mut().enumerate() {
            let tail = if fwd[e] { 2 * e } else { 2 * e + 1 };
            let p = ts[tail].map_or(-1, |c| self.t.pos(c) as isize);
            *cut = (p, tail);
        }
        cuts.sort_unstable();
        if cuts[0].0 == cuts[1].0 || cuts[1].0 == cuts[2].0 {
            return None;
        }
        // port of each t: the tail of cut r is port 2r, its head port 2r+1
        let mut port = [0usize; 6];
        for (r, &(_, tail)) in cuts.iter().enumerate() {
            port[tail] = 2 * r;
            port[tail ^ 1] = 2 * r + 1;
        }
        let mut node = [None; 6];
        for i in 0..6 {
            node[port[i]] = ts[i];
        }
        let mut partner = [0usize; 6];
        for (a, b) in [(1, 2), (3, 4), (5, 0)] {
            let (pa, pb) = (port[a], port[b]);
            // a removed link added back: a 2-opt move, or no move
            if pa / 2 == pb / 2 {
                return None;
            }
            partner[pa] = pb;
            partner[pb] = pa;
        }
        let mut cur = A_END;
        let mut exit = self.sl(node[A_END]);
        let mut added = 0.0;
        let mut order = [(0usize, false); 2];
        for step in &mut order {
            let q = partner[cur];
            if q == A_START || q == A_END {
                return None;
            }
            // ports 1, 2 are B's (segment 1), ports 3, 4 C's (segment 2)
            let seg = q.div_ceil(2);
            let rev = q % 2 == 0;
            let entry = if rev {
                self.fl(node[q])
            } else {
                self.sl(node[q])
            };
            added += self.link(exit, entry);
            let out = if rev { q - 1 } else { q + 1 };
            exit = if rev {
                self.fl(node[out])
            } else {
                self.sl(node[out])
            };
            *step = (seg, rev);
            cur = out;
        }
        if partner[cur] != A_START || order[0].0 == order[1].0 {
            return None;
        }
        added += self.link(exit, self.sl(node[A_START]));
        let p = [cuts[0].0, cuts[1].0, cuts[2].0];
        let c_first = order[0].0 == 2;
        let (rb, rc) = if c_first {
            (order[1].1, order[0].1)
        } else {
            (order[0].1, order[1].1)
        };
        Some((
            added - removed,
            Three {
                p,
                c_first,
                rev_b: rb,
                rev_c: rc,
            },
        ))
    }

    /// True when the move keeps the precedence (always, without any).
    fn allowed(&self, mv: &Three) -> bool {
        if self.free {
            return true;
        }
        let (p1, [b0, b1, c0, c1]) = (mv.p[0], mv.ends());
        (!mv.c_first || self.swappable(p1, b1, c1))
            && (!mv.rev_b || self.reversible(b0, b1))
            && (!mv.rev_c || self.reversible(c0, c1))
    }

    /// Applies a 3-opt move (`d`: its delta).
    pub(super) fn apply_three(&mut self, mv: Three, d: f64) {
        let (p1, [b0, b1, c0, c1]) = (mv.p[0], mv.ends());
        if mv.c_first {
            self.apply_swap(p1, b1, c1, d);
            let lc = c1 - c0 + 1;
            if mv.rev_c {
                self.apply_reverse(b0, b0 + lc - 1, 0.0);
            }
            if mv.rev_b {
                self.apply_reverse(b0 + lc, c1, 0.0);
            }
        } else {
            debug_assert!(mv.rev_b && mv.rev_c);
            self.apply_reverse(b0, b1, d);
            self.apply_reverse(c0, c1, 0.0);
        }
    }
}

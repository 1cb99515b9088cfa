//! Assignment bound with Lagrangian subtour-elimination multipliers (Balas–Christofides
//! style restricted Lagrangian).
//!
//! Every feasible sequence closed through home is one cycle, so for every set `S` of cells
//! (home not in `S`) it leaves `S` at least once: `x(δ⁺(S)) ≥ 1`. Relaxing these constraints
//! with multipliers `μ_S ≥ 0` gives
//! `L(μ) = min over assignments x of Σ (c(i, j) − μ(i, j)) x(i, j) + Σ μ_S`, where
//! `μ(i, j) = Σ {μ_S : i ∈ S, j ∉ S}`: a lower bound for every `μ ≥ 0`. The family of sets
//! grows with the subtours of the assignments found (those avoiding home), and subgradient
//! steps (Polyak steps towards a known solution cost when given) raise `L`.
//!
//! With precedence, the constraint is sharpened to the π-inequality of Balas, Fischetti and
//! Pulleyblank: the *last* arc leaving `S` cannot end in a predecessor `π(S)` of a cell of
//! `S` (that predecessor would come after it), so `x(S → V ∖ (S ∪ π(S))) ≥ 1`; arcs from `S`
//! into `π(S)` get no multiplier.
//!
//! The result also splits every arc cost as `c(i, j) = u_i + v_j + μ(i, j) + r(i, j)` with
//! the final assignment duals `u`, `v` and `r ≥ 0`: a path that must still leave the sets
//! `S` pays `Σ μ_S` over them on top of its potentials, which the tree search uses per prefix
//! ([`crate::solvers::beam`]). On p43.1 (cells 38–42 cheap inside, ~25 000 to leave) the plain
//! assignment gives 900; with the multipliers, about the optimum minus a few percent of the
//! part outside that cluster.

use super::assignment::{self, Assignment};
use super::cells::CellGraph;
use crate::clock::Deadline;
use crate::precedence::Closure;
use rustc_hash::FxHashMap;

/// Multipliers, sets and duals of the subtour-elimination Lagrangian.
#[derive(Debug, Clone)]
pub struct SecBound {
    /// The bound `L(μ)` of the best multipliers (cycle through home, no constant).
    pub value: f64,
    /// Row potentials of the final assignment (cells, then home).
    pub u: Vec<f64>,
    /// Column potentials of the final assignment (cells, then home).
    pub v: Vec<f64>,
    /// The sets with a positive multiplier (cells only, sorted).
    pub sets: Vec<Vec<u32>>,
    /// Per set, its predecessors outside it `π(S)` (arcs into them are not charged).
    pub pi: Vec<Vec<u32>>,
    /// Their multipliers (positive).
    pub mu: Vec<f64>,
    /// Subgradient iterations run.
    pub iterations: usize,
}

impl SecBound {
    /// The dense matrix `μ(i, j)` over cells and home (index n), row-major with `n + 1`
    /// columns.
    pub fn arc_multipliers(&self, n: usize) -> Vec<f64> {
        arc_multipliers(n, &self.sets, &self.pi, &self.mu)
    }
}

fn arc_multipliers(n: usize, sets: &[Vec<u32>], pi: &[Vec<u32>], mu: &[f64]) -> Vec<f64> {
    let d = n + 1;
    let mut out = vec![0.0; d * d];
    let mut inside = vec![false; d];
    for ((s, p), &m) in sets.iter().zip(pi).zip(mu) {
        if m <= 0.0 {
            continue;
        }
        for &c in s.iter().chain(p) {
            inside[c as usize] = true;
        }
        for &i in s {
            let row = &mut out[i as usize * d..(i as usize + 1) * d];
            for (j, x) in row.iter_mut().enumerate() {
                if !inside[j] {
                    *x += m;
                }
            }
        }
        for &c in s.iter().chain(p) {
            inside[c as usize] = false;
        }
    }
    out
}

/// Runs up to `iterations` assignment solves (at most `max_sets` sets) from `μ = 0`, where
/// `upper` is the cost of a known cycle through home (without the constant); `closure` (the
/// precedence closure) turns the subtour constraints into π-inequalities. `None` when no
/// finite assignment exists.
///
/// First a monotone dual ascent: each subtour `S` of the current assignment gets
/// `μ_S += min reduced cost of an arc leaving S` (the subtours are disjoint, so the reduced
/// costs stay non-negative and `L` rises by at least the sum); when no subtour can be raised
/// any more, subgradient steps `μ_S += step · (1 − arcs leaving S)` follow.
pub fn sec_bound(
    g: &CellGraph,
    closure: Option<&Closure>,
    upper: Option<f64>,
    iterations: usize,
    max_sets: usize,
) -> Option<SecBound> {
    sec_bound_until(g, closure, upper, iterations, max_sets, Deadline::NONE)
}

/// Like [`sec_bound`], stopping at `deadline` with the best multipliers so far (every
/// iterate is a valid bound); `None` when not even the first assignment was done.
pub fn sec_bound_until(
    g: &CellGraph,
    closure: Option<&Closure>,
    upper: Option<f64>,
    iterations: usize,
    max_sets: usize,
    deadline: Deadline,
) -> Option<SecBound> {
    let n = g.n;
    let d = n + 1;
    let mut f = Family::default();
    let mut best: Option<SecBound> = None;
    let mut theta = 0.25;
    let mut stale = 0;
    let mut done = 0;
    let mut ascent = true;
    for it in 0..iterations.max(1) {
        done = it + 1;
        let ma = arc_multipliers(n, &f.sets, &f.pi, &f.mu);
        let Some(a) =
            assignment::hungarian_duals_until(d, |i, j| g.c(i, j) - ma[i * d + j], deadline)
        else {
            if deadline.passed() {
                break;
            }
            return None;
        };
        let value = a.value + f.mu.iter().sum::<f64>();
        if best
            .as_ref()
            .is_none_or(|b| value > b.value + 1e-9 * b.value.abs().max(1.0))
        {
            best = Some(SecBound {
                value,
                u: a.u.clone(),
                v: a.v.clone(),
                sets: f.sets.clone(),
                pi: f.pi.clone(),
                mu: f.mu.clone(),
                iterations: 0,
            });
            stale = 0;
        } else {
            stale += 1;
            if stale >= 10 {
                theta /= 2.0;
                stale = 0;
            }
        }
        let (tours, raised) = f.subtours(g, closure, &a, &ma, value, ascent, max_sets);
        if ascent {
            if raised {
                continue;
            }
            ascent = false;
        }
        let b = best.as_ref().map_or(value, |b| b.value);
        if tours == 1 {
            // one cycle through home: a feasible tour of this value, nothing to raise
            break;
        }
        if let Some(u) = upper
            && b >= u - 1e-9 * u.abs().max(1.0)
        {
            break;
        }
        if !f.subgradient_step(&a, theta, value, b, upper) {
            break;
        }
    }
    let mut b = best?;
    // keep only the sets that carry a multiplier
    let keep: Vec<usize> = (0..b.sets.len()).filter(|&k| b.mu[k] > 0.0).collect();
    b.sets = keep.iter().map(|&k| b.sets[k].clone()).collect();
    b.pi = keep.iter().map(|&k| b.pi[k].clone()).collect();
    b.mu = keep.iter().map(|&k| b.mu[k]).collect();
    b.iterations = done;
    Some(b)
}

/// The growing family of subtour-elimination sets of [`sec_bound`].
#[derive(Default)]
struct Family {
    /// the sets (cells, sorted)
    sets: Vec<Vec<u32>>,
    /// per set, its predecessors outside it `π(S)`
    pi: Vec<Vec<u32>>,
    /// each set's index in `sets`
    known: FxHashMap<Vec<u32>, usize>,
    /// per set, `S ∪ π(S)` as a mask over cells and home: the heads that do not count as
    /// leaving S
    member: Vec<Vec<bool>>,
    /// per set, its multiplier
    mu: Vec<f64>,
}

impl Family {
    /// Adds the set `cyc` (sorted cells) with its `π(S)` from `closure` and `μ = 0`; returns
    /// its index.
    fn add(&mut self, cyc: Vec<u32>, closure: Option<&Closure>, n: usize) -> usize {
        // `mem`: S ∪ π(S), the heads that do not count as leaving S
        let mut mem = vec![false; n + 1];
        for &c in &cyc {
            mem[c as usize] = true;
        }
        let mut p = Vec::new();
        if let Some(cl) = closure {
            for a in 0..n {
                if !mem[a] && cyc.iter().any(|&s| cl.before(a, s as usize)) {
                    p.push(a as u32);
                }
            }
        }
        for &a in &p {
            mem[a as usize] = true;
        }
        self.member.push(mem);
        self.pi.push(p);
        self.known.insert(cyc.clone(), self.sets.len());
        self.sets.push(cyc);
        self.mu.push(0.0);
        self.sets.len() - 1
    }

    /// Walks the cycles of the assignment `a` (on costs net of the multipliers `ma`, bound
    /// `value`): subtours avoiding home become new sets (up to `max_sets`), and during the
    /// `ascent` each subtour's multiplier rises by the cheapest reduced cost of leaving it.
    /// Returns the number of cycles and whether some multiplier rose.
    #[allow(clippy::too_many_arguments)]
    fn subtours(
        &mut self,
        g: &CellGraph,
        closure: Option<&Closure>,
        a: &Assignment,
        ma: &[f64],
        value: f64,
        ascent: bool,
        max_sets: usize,
    ) -> (usize, bool) {
        let n = g.n;
        let d = n + 1;
        let mut seen = vec![false; d];
        let mut tours = 0;
        let mut raised = false;
        for s0 in 0..d {
            if seen[s0] {
                continue;
            }
            tours += 1;
            let mut cyc = Vec::new();
            let mut x = s0;
            while !seen[x] {
                seen[x] = true;
                cyc.push(x as u32);
                x = a.col[x];
            }
            if cyc.contains(&(n as u32)) || self.sets.len() >= max_sets {
                continue;
            }
            cyc.sort_unstable();
            let k = if let Some(&k) = self.known.get(&cyc) {
                if !ascent {
                    continue;
                }
                k
            } else {
                self.add(cyc, closure, n)
            };
            if ascent {
                // cheapest reduced cost of leaving the subtour
                let mem = &self.member[k];
                let mut delta = f64::INFINITY;
                for &i in &self.sets[k] {
                    let i = i as usize;
                    for (j, inside) in mem.iter().enumerate() {
                        let c = g.c(i, j);
                        if !inside && c.is_finite() {
                            delta = delta.min(c - ma[i * d + j] - a.u[i] - a.v[j]);
                        }
                    }
                }
                if delta.is_finite() && delta > 1e-9 * value.abs().max(1.0) {
                    self.mu[k] += delta;
                    raised = true;
                }
            }
        }
        (tours, raised)
    }

    /// One subgradient step `μ_S += step · (1 − arcs of `a` leaving S)`, projected onto
    /// `μ ≥ 0`, a Polyak step towards `upper` (or 5 % above the best bound `b`) scaled by
    /// `theta`; false when there is no direction or `theta` is spent.
    fn subgradient_step(
        &mut self,
        a: &Assignment,
        theta: f64,
        value: f64,
        b: f64,
        upper: Option<f64>,
    ) -> bool {
        let sub: Vec<f64> = self
            .sets
            .iter()
            .zip(&self.member)
            .map(|(s, mem)| 1.0 - s.iter().filter(|&&i| !mem[a.col[i as usize]]).count() as f64)
            .collect();
        let norm: f64 = sub
            .iter()
            .zip(&self.mu)
            .filter(|&(&s, &m)| !(m <= 0.0 && s < 0.0))
            .map(|(s, _)| s * s)
            .sum();
        if norm == 0.0 || theta < 1e-4 {
            return false;
        }
        let target = upper.unwrap_or(b + 0.05 * b.abs().max(1.0));
        let step = theta * (target - value).max(1e-6 * b.abs().max(1.0)) / norm;
        for (m, s) in self.mu.iter_mut().zip(&sub) {
            *m = (*m + step * s).max(0.0);
        }
        true
    }
}

/// Subgradient iterations affordable within about `work` elementary steps (d³ per
/// assignment).
pub fn affordable_iterations(n: usize, work: f64, max: usize) -> usize {
    let d = (n + 1) as f64;
    ((work / (d * d * d)) as usize).min(max)
}

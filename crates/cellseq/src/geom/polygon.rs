//! Point-in-polygon queries against one closed polygon, many times: the polygon's edges are
//! bucketed into horizontal slabs, so a query looks only at the edges whose height range
//! (grown by the tolerance) holds the query point, not at every edge. A drawing's containment
//! test asks this for every point of one stroke against another stroke; two strokes of 10^5
//! points each made that 10^10 edge visits without the slabs.

/// A closed polygon (the last point joins the first) prepared for [`contains`](Self::contains).
#[derive(Debug, Clone)]
pub struct PolygonIndex<'a> {
    pts: &'a [[f64; 2]],
    tol: f64,
    y0: f64,
    inv_h: f64,
    slabs: usize,
    /// Offsets into `edges` per slab (`slabs + 1` entries).
    start: Vec<usize>,
    /// Edge indices (edge `i` joins `pts[i]` and `pts[(i + 1) % n]`), slab after slab.
    edges: Vec<u32>,
}

/// Entries per edge, on average, that the slab lists may hold: with more slabs than that
/// allows (long edges spanning many slabs), the slab count is halved.
const FILL: usize = 8;

impl<'a> PolygonIndex<'a> {
    /// Indexes `pts` for queries with boundary tolerance `tol` (a point within `tol` of an
    /// edge counts as inside). Points must be finite.
    pub fn new(pts: &'a [[f64; 2]], tol: f64) -> Self {
        let n = pts.len();
        let span = |i: usize| {
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            (a[1].min(b[1]) - tol, a[1].max(b[1]) + tol)
        };
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in 0..n {
            let (a, b) = span(i);
            lo = lo.min(a);
            hi = hi.max(b);
        }
        let height = (hi - lo).max(f64::MIN_POSITIVE);
        let mut slabs = (n / 2).clamp(1, 1 << 20);
        let slab_of = |y: f64, inv_h: f64, slabs: usize| slab(y, lo, inv_h, slabs);
        // fewer slabs while long edges would fill the lists beyond FILL entries per edge
        let inv_h = loop {
            let inv_h = slabs as f64 / height;
            let entries: usize = (0..n)
                .map(|i| {
                    let (a, b) = span(i);
                    slab_of(b, inv_h, slabs) - slab_of(a, inv_h, slabs) + 1
                })
                .sum();
            if slabs == 1 || entries <= FILL * n.max(1) {
                break inv_h;
            }
            slabs /= 2;
        };
        let mut count = vec![0usize; slabs + 1];
        for i in 0..n {
            let (a, b) = span(i);
            for k in slab_of(a, inv_h, slabs)..=slab_of(b, inv_h, slabs) {
                count[k + 1] += 1;
            }
        }
        for k in 0..slabs {
            count[k + 1] += count[k];
        }
        let start = count.clone();
        let mut edges = vec![0u32; count[slabs]];
        let mut next = count;
        for i in 0..n {
            let (a, b) = span(i);
            for k in slab_of(a, inv_h, slabs)..=slab_of(b, inv_h, slabs) {
                edges[next[k]] = i as u32;
                next[k] += 1;
            }
        }
        PolygonIndex {
            pts,
            tol,
            y0: lo,
            inv_h,
            slabs,
            start,
            edges,
        }
    }

    /// True when `p` lies inside the polygon (even-odd rule) or within the tolerance of its
    /// boundary. The same answer as testing every edge: an edge the ray from `p` crosses, or
    /// one within the tolerance, spans `p`'s height and so is in `p`'s slab.
    pub fn contains(&self, p: [f64; 2]) -> bool {
        let n = self.pts.len();
        if n == 0 {
            return false;
        }
        let k = slab(p[1], self.y0, self.inv_h, self.slabs);
        let mut c = false;
        for &e in &self.edges[self.start[k]..self.start[k + 1]] {
            let i = e as usize;
            let (a, b) = (self.pts[i], self.pts[(i + 1) % n]);
            if seg_dist(p, a, b) <= self.tol {
                return true;
            }
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    c = !c;
                }
            }
        }
        c
    }
}

/// The slab of height `y` among `slabs` slabs of height `1 / inv_h` from `y0`, clamped to the
/// first and last; monotone in `y`, so an edge listed in the slabs of its ends' heights is in
/// the slab of every height between them.
fn slab(y: f64, y0: f64, inv_h: f64, slabs: usize) -> usize {
    let k = ((y - y0) * inv_h).floor();
    if k.is_nan() || k < 0.0 {
        0
    } else {
        (k as usize).min(slabs - 1)
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a[0] + t * dx - p[0], a[1] + t * dy - p[1]);
    (qx * qx + qy * qy).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Every edge, as the index must agree with.
    fn brute(p: [f64; 2], poly: &[[f64; 2]], tol: f64) -> bool {
        let n = poly.len();
        let mut c = false;
        for i in 0..n {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            if seg_dist(p, a, b) <= tol {
                return true;
            }
            if (a[1] > p[1]) != (b[1] > p[1]) {
                let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
                if p[0] < x {
                    c = !c;
                }
            }
        }
        c
    }

    #[test]
    fn agrees_with_every_edge_on_random_polygons() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for case in 0..200 {
            let n = rng.random_range(3..60);
            // star-shaped, self-intersecting or with long spikes: all must agree
            let poly: Vec<[f64; 2]> = (0..n)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / n as f64;
                    let r = if case % 3 == 0 {
                        rng.random_range(0.0..100.0)
                    } else {
                        rng.random_range(20.0..30.0)
                    };
                    [r * a.cos(), r * a.sin()]
                })
                .collect();
            let tol = [0.0, 1e-3, 0.5][case % 3];
            let idx = PolygonIndex::new(&poly, tol);
            for _ in 0..200 {
                let p = [
                    rng.random_range(-110.0..110.0),
                    rng.random_range(-110.0..110.0),
                ];
                assert_eq!(
                    idx.contains(p),
                    brute(p, &poly, tol),
                    "case {case} at {p:?}"
                );
            }
            // the vertices themselves (on the boundary) and points at vertex heights
            for &v in &poly {
                assert_eq!(idx.contains(v), brute(v, &poly, tol));
                let q = [v[0] - 3.0, v[1]];
                assert_eq!(idx.contains(q), brute(q, &poly, tol));
            }
        }
    }

    #[test]
    fn a_square_holds_its_centre_not_a_far_point() {
        let sq = [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]];
        let idx = PolygonIndex::new(&sq, 1e-6);
        assert!(idx.contains([5.0, 5.0]));
        assert!(idx.contains([10.0, 5.0]));
        assert!(!idx.contains([15.0, 5.0]));
        assert!(!idx.contains([5.0, -1e7]));
        assert!(!PolygonIndex::new(&[], 0.0).contains([0.0, 0.0]));
    }
}

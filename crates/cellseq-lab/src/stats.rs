//! Statistics for the report: summaries, a deterministic bootstrap CI, the paired Wilcoxon
//! signed-rank test, Holm's correction, the Friedman test with average ranks, and a log-log fit.
//!
//! Distributions come from `statrs`; the tests are implemented here and checked against the
//! outputs R prints for its own documentation examples.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

/// Mean (NaN when empty).
pub fn mean(x: &[f64]) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    x.iter().sum::<f64>() / x.len() as f64
}

/// Sample standard deviation (n − 1; 0 for fewer than two values).
pub fn std_dev(x: &[f64]) -> f64 {
    if x.len() < 2 || x.iter().all(|v| *v == x[0]) {
        return 0.0;
    }
    let m = mean(x);
    (x.iter().map(|v| (v - m) * (v - m)).sum::<f64>() / (x.len() as f64 - 1.0)).sqrt()
}

/// Quantile with linear interpolation (R type 7). NaN when empty.
pub fn quantile(x: &[f64], q: f64) -> f64 {
    if x.is_empty() {
        return f64::NAN;
    }
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    let h = (s.len() as f64 - 1.0) * q.clamp(0.0, 1.0);
    let lo = h.floor() as usize;
    let hi = h.ceil() as usize;
    s[lo] + (h - lo as f64) * (s[hi] - s[lo])
}

/// Median.
pub fn median(x: &[f64]) -> f64 {
    quantile(x, 0.5)
}

/// Percentile bootstrap confidence interval of the mean, `resamples` draws from a fixed seed.
pub fn bootstrap_ci_mean(x: &[f64], level: f64, resamples: usize, seed: u64) -> (f64, f64) {
    if x.is_empty() {
        return (f64::NAN, f64::NAN);
    }
    if x.len() == 1 {
        return (x[0], x[0]);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let n = x.len();
    let means: Vec<f64> = (0..resamples)
        .map(|_| (0..n).map(|_| x[rng.random_range(0..n)]).sum::<f64>() / n as f64)
        .collect();
    let a = (1.0 - level) / 2.0;
    (quantile(&means, a), quantile(&means, 1.0 - a))
}

/// Average ranks (1-based) with ties sharing the mean of their positions.
pub fn ranks(x: &[f64]) -> Vec<f64> {
    let mut idx: Vec<usize> = (0..x.len()).collect();
    idx.sort_by(|&a, &b| x[a].total_cmp(&x[b]));
    let mut r = vec![0.0; x.len()];
    let mut i = 0;
    while i < idx.len() {
        let mut j = i;
        while j + 1 < idx.len() && x[idx[j + 1]] == x[idx[i]] {
            j += 1;
        }
        let avg = (i + j) as f64 / 2.0 + 1.0;
        for &k in &idx[i..=j] {
            r[k] = avg;
        }
        i = j + 1;
    }
    r
}

/// Result of a Wilcoxon signed-rank test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wilcoxon {
    /// V: the sum of the ranks of the positive differences x − y.
    pub v: f64,
    /// Number of non-zero differences.
    pub n: usize,
    /// Two-sided p-value (1 when there is no non-zero difference).
    pub p: f64,
    /// True when the exact null distribution was used.
    pub exact: bool,
}

/// Paired two-sided Wilcoxon signed-rank test of x against y, as R's
/// `wilcox.test(x, y, paired = TRUE)`: zero differences are dropped; the exact distribution is
/// used for fewer than 50 pairs without ties, otherwise the normal approximation with tie and
/// continuity correction.
pub fn wilcoxon_signed_rank(x: &[f64], y: &[f64]) -> Wilcoxon {
    let d: Vec<f64> = x
        .iter()
        .zip(y)
        .map(|(a, b)| a - b)
        .filter(|d| *d != 0.0)
        .collect();
    let n = d.len();
    if n == 0 {
        return Wilcoxon {
            v: 0.0,
            n: 0,
            p: 1.0,
            exact: true,
        };
    }
    let abs: Vec<f64> = d.iter().map(|v| v.abs()).collect();
    let r = ranks(&abs);
    // `+ 0.0` turns the -0.0 of an empty sum into 0.0
    let v: f64 = d
        .iter()
        .zip(&r)
        .filter(|(d, _)| **d > 0.0)
        .map(|(_, r)| r)
        .sum::<f64>()
        + 0.0;
    let ties = {
        let mut s = abs.clone();
        s.sort_by(f64::total_cmp);
        s.windows(2).any(|w| w[0] == w[1])
    };
    if n < 50 && !ties {
        // counts[k] = number of sign assignments with rank sum k
        let max = n * (n + 1) / 2;
        let mut counts = vec![0f64; max + 1];
        counts[0] = 1.0;
        for i in 1..=n {
            for k in (i..=max).rev() {
                counts[k] += counts[k - i];
            }
        }
        let total: f64 = counts.iter().sum();
        let vi = v.round() as usize;
        let le: f64 = counts[..=vi].iter().sum::<f64>() / total;
        let ge: f64 = counts[vi..].iter().sum::<f64>() / total;
        let p = (2.0 * le.min(ge)).min(1.0);
        return Wilcoxon {
            v,
            n,
            p,
            exact: true,
        };
    }
    let nf = n as f64;
    let mu = nf * (nf + 1.0) / 4.0;
    let mut tie_sum = 0.0;
    let mut s = abs.clone();
    s.sort_by(f64::total_cmp);
    let mut i = 0;
    while i < s.len() {
        let mut j = i;
        while j + 1 < s.len() && s[j + 1] == s[i] {
            j += 1;
        }
        let t = (j - i + 1) as f64;
        tie_sum += t * t * t - t;
        i = j + 1;
    }
    let sigma = (nf * (nf + 1.0) * (2.0 * nf + 1.0) / 24.0 - tie_sum / 48.0).sqrt();
    if sigma == 0.0 {
        return Wilcoxon {
            v,
            n,
            p: 1.0,
            exact: false,
        };
    }
    let z = v - mu;
    let correction = 0.5 * z.signum();
    let z = (z - correction) / sigma;
    let norm = Normal::new(0.0, 1.0).expect("standard normal");
    let p = (2.0 * norm.cdf(-z.abs())).min(1.0);
    Wilcoxon {
        v,
        n,
        p,
        exact: false,
    }
}

/// Holm's step-down adjustment of p-values (as R's `p.adjust(p, "holm")`).
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let mut idx: Vec<usize> = (0..m).collect();
    idx.sort_by(|&a, &b| p[a].total_cmp(&p[b]));
    let mut out = vec![0.0; m];
    let mut running: f64 = 0.0;
    for (k, &i) in idx.iter().enumerate() {
        let adj = ((m - k) as f64 * p[i]).min(1.0);
        running = running.max(adj);
        out[i] = running;
    }
    out
}

/// Result of a Friedman test.
#[derive(Debug, Clone, PartialEq)]
pub struct Friedman {
    /// Friedman chi-squared statistic (tie-corrected).
    pub statistic: f64,
    /// Degrees of freedom (k − 1).
    pub df: f64,
    /// p-value from the chi-squared distribution.
    pub p: f64,
    /// Average rank of each treatment (1 = smallest value).
    pub avg_ranks: Vec<f64>,
}

/// Friedman rank-sum test on `blocks[b][t]` (b blocks, t treatments), as R's `friedman.test`
/// with its tie correction. `None` with fewer than 2 blocks or 2 treatments.
pub fn friedman(blocks: &[Vec<f64>]) -> Option<Friedman> {
    let b = blocks.len();
    let k = blocks.first()?.len();
    if b < 2 || k < 2 || blocks.iter().any(|r| r.len() != k) {
        return None;
    }
    let mut sums = vec![0.0; k];
    let mut tie_total = 0.0;
    for row in blocks {
        let r = ranks(row);
        for (s, v) in sums.iter_mut().zip(&r) {
            *s += v;
        }
        let mut s = row.clone();
        s.sort_by(f64::total_cmp);
        let mut i = 0;
        while i < s.len() {
            let mut j = i;
            while j + 1 < s.len() && s[j + 1] == s[i] {
                j += 1;
            }
            let t = (j - i + 1) as f64;
            tie_total += t * t * t - t;
            i = j + 1;
        }
    }
    let (bf, kf) = (b as f64, k as f64);
    let num = 12.0
        * sums
            .iter()
            .map(|s| (s - bf * (kf + 1.0) / 2.0).powi(2))
            .sum::<f64>();
    let den = bf * kf * (kf + 1.0) - tie_total / (kf - 1.0);
    let statistic = if den > 0.0 { num / den } else { 0.0 };
    let df = kf - 1.0;
    let p = ChiSquared::new(df)
        .map(|c| 1.0 - c.cdf(statistic))
        .unwrap_or(f64::NAN);
    Some(Friedman {
        statistic,
        df,
        p,
        avg_ranks: sums.iter().map(|s| s / bf).collect(),
    })
}

/// Least-squares fit of log10(y) = a + b·log10(x) over positive pairs: `(b, a)`.
pub fn loglog_slope(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / pts.len() as f64;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / pts.len() as f64;
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx == 0.0 {
        return None;
    }
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let b = sxy / sxx;
    Some((b, my - b * mx))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    /// R `?wilcox.test` example (Hollander & Wolfe 1973, p. 29f, depression scale factor):
    /// `wilcox.test(x, y, paired = TRUE, alternative = "greater")` prints V = 40,
    /// p-value = 0.01953; the two-sided p-value is twice that, 0.0390625 (exact: 20/512).
    #[test]
    #[allow(clippy::approx_constant)] // 3.14 is data, not pi
    fn wilcoxon_matches_r_depression_example() {
        let x = [1.83, 0.50, 1.62, 2.48, 1.68, 1.88, 1.55, 3.06, 1.30];
        let y = [0.878, 0.647, 0.598, 2.05, 1.06, 1.29, 1.06, 3.14, 1.29];
        let w = wilcoxon_signed_rank(&x, &y);
        assert_eq!(w.v, 40.0);
        assert!(w.exact);
        assert!(close(w.p, 0.0390625, 1e-12), "{}", w.p);
        // symmetric: swapping the samples gives V = n(n+1)/2 − 40 and the same p
        let w2 = wilcoxon_signed_rank(&y, &x);
        assert_eq!(w2.v, 5.0);
        assert!(close(w2.p, w.p, 1e-12));
    }

    /// Normal approximation with ties, checked by hand: d = (1,1,2,2,3,3,-1); |d| has ties, so
    /// R's `wilcox.test.default` uses the normal approximation with tie and continuity
    /// correction (correct = TRUE); the expected p is that formula evaluated by hand.
    #[test]
    fn wilcoxon_normal_with_ties_follows_r_formula() {
        let x = [1.0, 1.0, 2.0, 2.0, 3.0, 3.0, -1.0];
        let y = [0.0; 7];
        let w = wilcoxon_signed_rank(&x, &y);
        assert!(!w.exact);
        // ranks of |d| = 1,1,1,2,2,3,3 -> 2,2,2,4.5,4.5,6.5,6.5 ; V = 28 - 2 = 26
        assert_eq!(w.v, 26.0);
        let n: f64 = 7.0;
        let sigma = (n * (n + 1.0) * (2.0 * n + 1.0) / 24.0 - (24.0 + 6.0 + 6.0) / 48.0).sqrt();
        let z = (26.0 - 14.0 - 0.5) / sigma;
        let p = 2.0 * Normal::new(0.0, 1.0).unwrap().cdf(-z);
        assert!(close(w.p, p, 1e-12));
        assert!(w.p > 0.02 && w.p < 0.05, "{}", w.p);
    }

    /// R `?p.adjust`-style check worked by hand: p = (0.01, 0.04, 0.03, 0.005) ->
    /// Holm = (0.03, 0.06, 0.06, 0.02).
    #[test]
    fn holm_by_hand() {
        let a = holm(&[0.01, 0.04, 0.03, 0.005]);
        let want = [0.03, 0.06, 0.06, 0.02];
        for (x, w) in a.iter().zip(want) {
            assert!(close(*x, w, 1e-12), "{a:?}");
        }
    }

    /// R `?friedman.test` example: RoundingTimes (Hollander & Wolfe 1973, p. 140ff), 22 players
    /// × 3 methods of rounding first base. R prints: Friedman chi-squared = 11.143, df = 2,
    /// p-value = 0.003805.
    #[test]
    fn friedman_matches_r_rounding_times() {
        let data = [
            [5.40, 5.50, 5.55],
            [5.85, 5.70, 5.75],
            [5.20, 5.60, 5.50],
            [5.55, 5.50, 5.40],
            [5.90, 5.85, 5.70],
            [5.45, 5.55, 5.60],
            [5.40, 5.40, 5.35],
            [5.45, 5.50, 5.35],
            [5.25, 5.15, 5.00],
            [5.85, 5.80, 5.70],
            [5.25, 5.20, 5.10],
            [5.65, 5.55, 5.45],
            [5.60, 5.35, 5.45],
            [5.05, 5.00, 4.95],
            [5.50, 5.50, 5.40],
            [5.45, 5.55, 5.50],
            [5.55, 5.55, 5.35],
            [5.45, 5.50, 5.55],
            [5.50, 5.45, 5.25],
            [5.65, 5.60, 5.40],
            [5.70, 5.65, 5.55],
            [6.30, 6.30, 6.25],
        ];
        let blocks: Vec<Vec<f64>> = data.iter().map(|r| r.to_vec()).collect();
        let f = friedman(&blocks).unwrap();
        assert_eq!(f.df, 2.0);
        assert!(close(f.statistic, 11.143, 5e-4), "{}", f.statistic);
        assert!(close(f.p, 0.003805, 5e-6), "{}", f.p);
        assert_eq!(f.avg_ranks.len(), 3);
        assert!(close(f.avg_ranks.iter().sum::<f64>(), 6.0, 1e-12));
    }

    #[test]
    fn summaries() {
        let x = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(mean(&x), 2.5);
        assert_eq!(median(&x), 2.5);
        assert!(close(std_dev(&x), 1.2909944487358056, 1e-12));
        assert_eq!(quantile(&x, 0.25), 1.75);
        let (lo, hi) = bootstrap_ci_mean(&x, 0.95, 2000, 7);
        assert!(lo >= 1.0 && hi <= 4.0 && lo < 2.5 && hi > 2.5);
        assert_eq!(bootstrap_ci_mean(&x, 0.95, 2000, 7), (lo, hi));
        let (b, a) = loglog_slope(&[(10.0, 100.0), (100.0, 10000.0), (1000.0, 1e6)]).unwrap();
        assert!(close(b, 2.0, 1e-12) && close(a, 0.0, 1e-12));
    }
}

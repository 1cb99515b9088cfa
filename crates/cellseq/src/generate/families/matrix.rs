//! Random matrix families: `random-sop`, `atsp`, `symmetric`, `near-symmetric`.

use super::{C_SPEC, dag::random_dag, n_spec, p_spec, sop_shaped};
use crate::error::{Error, Result};
use crate::model::Instance;
use crate::params::{ParamKind, ParamSpec, Params};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// `random-sop` parameters.
pub static RANDOM_SOP_SPECS: &[ParamSpec] = &[n_spec("200", super::MAX_N), C_SPEC, p_spec("15")];

/// `atsp` parameters.
pub static ATSP_SPECS: &[ParamSpec] = &[
    n_spec("200", super::MAX_N),
    C_SPEC,
    ParamSpec {
        name: "class",
        default: "amat",
        kind: ParamKind::Choice(&["amat", "tmat"]),
        help: "amat: costs uniform in [0, c]; tmat: their shortest-path closure (triangle inequality holds; n <= 2000)",
    },
];

/// `symmetric` parameters.
pub static SYMMETRIC_SPECS: &[ParamSpec] = &[
    n_spec("200", super::MAX_N),
    C_SPEC,
    p_spec("0"),
    ParamSpec {
        name: "pairs",
        default: "0",
        kind: ParamKind::int(0, super::MAX_N / 2),
        help: "precedence of this many disjoint pairs of cells (one before the other, as pickups before their deliveries) instead of p; at most n / 2, and only with p = 0",
    },
];

/// `near-symmetric` parameters.
pub static NEAR_SYMMETRIC_SPECS: &[ParamSpec] = &[
    n_spec("200", super::MAX_N),
    C_SPEC,
    p_spec("0"),
    ParamSpec {
        name: "asym",
        default: "5",
        kind: ParamKind::float(0.0, 100.0),
        help: "asymmetric part: each arc adds an integer uniform in [0, asym % of c]",
    },
    ParamSpec {
        name: "plane",
        default: "false",
        kind: ParamKind::Bool,
        help: "the symmetric part is the rounded distance between random points in a c x c square (metric costs, as TSPLIB's kro instances) instead of a random matrix",
    },
];

/// Integer costs uniform in [0, c] for every ordered pair of `n` cells (row-major, diagonal 0).
fn uniform_costs(n: usize, c: u64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            if i != j {
                m[i * n + j] = rng.random_range(0..=c) as f64;
            }
        }
    }
    m
}

/// Symmetric integer costs uniform in [0, c].
fn symmetric_costs(n: usize, c: u64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        for j in i + 1..n {
            let v = rng.random_range(0..=c) as f64;
            m[i * n + j] = v;
            m[j * n + i] = v;
        }
    }
    m
}

/// Rounded distances between `n` points uniform in a `c` x `c` square (row-major, diagonal 0).
fn plane_costs(n: usize, c: u64, rng: &mut ChaCha8Rng) -> Vec<f64> {
    let side = c as f64;
    let pts: Vec<(f64, f64)> = (0..n)
        .map(|_| (rng.random_range(0.0..=side), rng.random_range(0.0..=side)))
        .collect();
    let mut m = vec![0.0; n * n];
    for i in 0..n {
        for j in i + 1..n {
            let v = (pts[i].0 - pts[j].0).hypot(pts[i].1 - pts[j].1).round();
            m[i * n + j] = v;
            m[j * n + i] = v;
        }
    }
    m
}

/// `random-sop`: asymmetric costs uniform in [0, c], precedence of closure density p %.
pub fn random_sop(p: &Params, seed: u64) -> Result<Instance> {
    let n = p.int("n") as usize;
    let c = p.int("c");
    let density = p.float("p") / 100.0;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let m = uniform_costs(n, c, &mut rng);
    let edges = random_dag(n, density, &mut rng);
    let name = format!("random-sop-n{n}-c{c}-p{}-s{seed}", p.float("p"));
    Ok(sop_shaped(name, &vec![1; n], |u, v| m[u * n + v], &edges))
}

/// Checks `atsp`'s parameters together (`tmat` is O(n³)); the number of cells.
pub fn atsp_check(p: &Params) -> Result<u64> {
    let n = p.int("n");
    if p.word("class") == "tmat" && n > 2000 {
        return Err(Error::Param(format!(
            "atsp: class=tmat is O(n^3): n must be at most 2000, got {n}"
        )));
    }
    Ok(n + 2)
}

/// `atsp`: no precedence; `amat` costs uniform in [0, c], `tmat` their shortest-path closure.
pub fn atsp(p: &Params, seed: u64) -> Result<Instance> {
    atsp_check(p)?;
    let n = p.int("n") as usize;
    let c = p.int("c");
    let class = p.word("class").to_string();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut m = uniform_costs(n, c, &mut rng);
    if class == "tmat" {
        // Floyd–Warshall: every cost becomes the shortest path's
        for k in 0..n {
            for i in 0..n {
                let ik = m[i * n + k];
                for j in 0..n {
                    let via = ik + m[k * n + j];
                    if via < m[i * n + j] {
                        m[i * n + j] = via;
                    }
                }
            }
        }
    }
    let name = format!("atsp-{class}-n{n}-c{c}-s{seed}");
    Ok(sop_shaped(name, &vec![1; n], |u, v| m[u * n + v], &[]))
}

/// Checks `symmetric`'s parameters together (`pairs` fit in `n` and exclude `p`); the number
/// of cells.
pub fn symmetric_check(p: &Params) -> Result<u64> {
    let (n, pairs) = (p.int("n"), p.int("pairs"));
    if pairs > 0 && 2 * pairs > n {
        return Err(Error::Param(format!(
            "symmetric: pairs must be at most n / 2 = {}, got {pairs}",
            n / 2
        )));
    }
    if pairs > 0 && p.float("p") > 0.0 {
        return Err(Error::Param(
            "symmetric: give either p (a random precedence DAG) or pairs (disjoint pairs), not both"
                .to_string(),
        ));
    }
    Ok(n + 2)
}

/// `k` disjoint precedence pairs among `n` cells, each cell in at most one pair: the first
/// `2k` cells of a random permutation, taken two by two (the first of each two before the
/// second).
fn disjoint_pairs(n: usize, k: usize, rng: &mut ChaCha8Rng) -> Vec<(usize, usize)> {
    let cells = crate::generate::common::random_permutation(n, rng);
    cells[..2 * k]
        .chunks_exact(2)
        .map(|w| (w[0], w[1]))
        .collect()
}

/// `symmetric`: symmetric costs uniform in [0, c], precedence of closure density p % or, with
/// `pairs` = k > 0, k disjoint pairs (the shape of TSPLIB's pickup-and-delivery-like
/// instances: each pair one cell before another, no other precedence).
pub fn symmetric(p: &Params, seed: u64) -> Result<Instance> {
    symmetric_check(p)?;
    let n = p.int("n") as usize;
    let c = p.int("c");
    let pairs = p.int("pairs") as usize;
    let density = p.float("p") / 100.0;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let m = symmetric_costs(n, c, &mut rng);
    let (edges, name) = if pairs > 0 {
        (
            disjoint_pairs(n, pairs, &mut rng),
            format!("symmetric-n{n}-c{c}-pairs{pairs}-s{seed}"),
        )
    } else {
        (
            random_dag(n, density, &mut rng),
            format!("symmetric-n{n}-c{c}-p{}-s{seed}", p.float("p")),
        )
    };
    Ok(sop_shaped(name, &vec![1; n], |u, v| m[u * n + v], &edges))
}

/// `near-symmetric`: symmetric costs plus an asymmetric part in [0, asym % of c].
pub fn near_symmetric(p: &Params, seed: u64) -> Result<Instance> {
    let n = p.int("n") as usize;
    let c = p.int("c");
    let density = p.float("p") / 100.0;
    let asym = p.float("asym");
    let top = (asym / 100.0 * c as f64).round() as u64;
    let plane = p.bool("plane");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut m = if plane {
        plane_costs(n, c, &mut rng)
    } else {
        symmetric_costs(n, c, &mut rng)
    };
    for i in 0..n {
        for j in 0..n {
            if i != j {
                m[i * n + j] += rng.random_range(0..=top) as f64;
            }
        }
    }
    let edges = random_dag(n, density, &mut rng);
    let kind = if plane {
        "near-symmetric-plane"
    } else {
        "near-symmetric"
    };
    let name = format!("{kind}-n{n}-c{c}-p{}-s{seed}", p.float("p"));
    Ok(sop_shaped(name, &vec![1; n], |u, v| m[u * n + v], &edges))
}

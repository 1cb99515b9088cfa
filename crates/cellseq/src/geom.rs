//! Small 3-D point type used by every geometric part of the model, and planar queries
//! ([`polygon`]).

pub mod polygon;

use kiddo::ImmutableKdTree;
use serde::{Deserialize, Serialize};

/// A k-d tree over planar points whose items are their indices in `points`. Immutable trees
/// are built once and are robust to many coincident or collinear points.
pub fn xy_tree(points: impl IntoIterator<Item = [f64; 2]>) -> ImmutableKdTree<f64, 2> {
    let pts: Vec<(u32, [f64; 2])> = points
        .into_iter()
        .enumerate()
        .map(|(i, p)| (i as u32, p))
        .collect();
    ImmutableKdTree::new_from_entries(&pts).expect("k-d tree build")
}

/// A point in machine coordinates (mm). Serialized as `[x, y, z]`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(from = "[f64; 3]", into = "[f64; 3]")]
pub struct Point3 {
    /// X coordinate.
    pub x: f64,
    /// Y coordinate.
    pub y: f64,
    /// Z coordinate (depth is negative below the part's top surface by convention).
    pub z: f64,
}

impl Point3 {
    /// Builds a point.
    pub const fn new(x: f64, y: f64, z: f64) -> Self {
        Self { x, y, z }
    }
    /// True when every coordinate is finite (no NaN, no infinity).
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }
    /// Planar (XY) distance.
    pub fn dist_xy(&self, o: &Point3) -> f64 {
        // not `hypot`: libm's overflow-safe version is several times slower, and coordinates
        // in millimetres are nowhere near overflow
        let (dx, dy) = (self.x - o.x, self.y - o.y);
        (dx * dx + dy * dy).sqrt()
    }
    /// Euclidean 3-D distance.
    pub fn dist(&self, o: &Point3) -> f64 {
        let (dx, dy, dz) = (self.x - o.x, self.y - o.y, self.z - o.z);
        (dx * dx + dy * dy + dz * dz).sqrt()
    }
    /// The same XY position at height `z`.
    pub fn at_z(&self, z: f64) -> Point3 {
        Point3::new(self.x, self.y, z)
    }
}

impl From<[f64; 3]> for Point3 {
    fn from(a: [f64; 3]) -> Self {
        Point3::new(a[0], a[1], a[2])
    }
}

impl From<Point3> for [f64; 3] {
    fn from(p: Point3) -> Self {
        [p.x, p.y, p.z]
    }
}

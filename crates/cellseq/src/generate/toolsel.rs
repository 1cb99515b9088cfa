//! Tool library and tool selection of the generalized-pocket model (paper 002, §2.3).
//!
//! - finishing tool: the largest end mill whose radius ≤ the pocket's minimum corner radius;
//! - roughing tool: the largest end mill whose machinable ratio η = A_m / A ≥ η_min, where A_m
//!   is the area the tool can reach (the pocket opened by the tool disk: offset inward by the
//!   radius, then outward again, computed with `geo`'s buffer) and A the pocket area;
//! - tool-group merging: with single-layer time t = A / (w·f·n) and T = t·N per cell, two tool
//!   groups are merged onto the smaller tool when μ = ΣT(own tools) / ΣT(smaller tool) > μ_min;
//! - roughing layer count N: nn = ⌊H / a_p⌋, N = nn if H − a_p·nn < δ, else nn + 1.

use crate::error::{Error, Result};
use crate::params::FloatRange;
use geo::{Area, Buffer, MultiPolygon, Polygon};
use serde::Deserialize;
use std::path::Path;

/// The default library shipped with the project (`crates/cellseq/src/generate/default-tools.toml`).
pub const DEFAULT_LIBRARY: &str = include_str!("default-tools.toml");

/// What a tool is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum ToolKind {
    /// Flat end mill (pockets, contours, ribs).
    #[default]
    EndMill,
    /// Twist drill (holes).
    Drill,
}

/// One tool of the library.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSpec {
    /// Unique id.
    pub id: String,
    /// End mill or drill.
    #[serde(default)]
    pub kind: ToolKind,
    /// Diameter (mm).
    pub diameter: f64,
    /// Radial width of cut w (mm).
    pub cutting_width: f64,
    /// Feed per revolution f (mm/rev).
    pub feed: f64,
    /// Spindle speed n (rev/min).
    pub spindle: f64,
}

impl ToolSpec {
    /// Radius (mm).
    pub fn radius(&self) -> f64 {
        self.diameter / 2.0
    }
    /// Cutting feed f·n (mm/min).
    pub fn feed_rate(&self) -> f64 {
        self.feed * self.spindle
    }
    /// Area removal rate w·f·n (mm²/min) of one layer.
    pub fn area_rate(&self) -> f64 {
        self.cutting_width * self.feed * self.spindle
    }
    /// As a model tool.
    pub fn to_tool(&self) -> crate::model::Tool {
        crate::model::Tool {
            id: self.id.clone(),
            diameter: self.diameter,
            name: Some(match self.kind {
                ToolKind::EndMill => format!("end mill D{}", self.diameter),
                ToolKind::Drill => format!("drill D{}", self.diameter),
            }),
            feed: Some(self.feed_rate()),
        }
    }
}

/// Diameters and widths of cut a library may give (mm): (0, 10⁴].
pub const TOOL_SIZE: FloatRange = FloatRange::above(0.0, 1e4);
/// Feeds per revolution a library may give (mm/rev): (0, 10³].
pub const FEED_PER_REV: FloatRange = FloatRange::above(0.0, 1e3);
/// Spindle speeds a library may give (rev/min): (0, 10⁶].
pub const SPINDLE: FloatRange = FloatRange::above(0.0, 1e6);

/// A tool library: end mills and drills, sorted by decreasing diameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolLibrary {
    /// The tools, largest first (ties by id).
    pub tools: Vec<ToolSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LibraryFile {
    tool: Vec<ToolSpec>,
}

impl ToolLibrary {
    /// Parses TOML text (`[[tool]]` tables); `file` names the source in errors.
    pub fn parse(file: &str, text: &str) -> Result<ToolLibrary> {
        let lf: LibraryFile = toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].lines().count().max(1))
                .unwrap_or(1);
            Error::parse(file, line, e.message().to_string())
        })?;
        let mut tools = lf.tool;
        if !tools.iter().any(|t| t.kind == ToolKind::EndMill) {
            return Err(Error::invalid(file, "the tool library has no end mill"));
        }
        for (i, t) in tools.iter().enumerate() {
            for (key, v, range) in [
                ("diameter", t.diameter, TOOL_SIZE),
                ("cutting_width", t.cutting_width, TOOL_SIZE),
                ("feed", t.feed, FEED_PER_REV),
                ("spindle", t.spindle, SPINDLE),
            ] {
                range
                    .check(&format!("tool '{}': {key}", t.id), v)
                    .map_err(|m| Error::invalid(file, m))?;
            }
            if t.feed_rate() < crate::validate::MIN_FEED {
                return Err(Error::invalid(
                    file,
                    format!(
                        "tool '{}': feed x spindle = {} mm/min, below the least feed {} mm/min",
                        t.id,
                        t.feed_rate(),
                        crate::validate::MIN_FEED
                    ),
                ));
            }
            if tools[..i].iter().any(|o| o.id == t.id) {
                return Err(Error::invalid(
                    file,
                    format!("duplicate tool id '{}'", t.id),
                ));
            }
        }
        tools.sort_by(|a, b| {
            b.diameter
                .total_cmp(&a.diameter)
                .then_with(|| a.id.cmp(&b.id))
        });
        Ok(ToolLibrary { tools })
    }
    /// The library shipped with the project.
    pub fn default_library() -> ToolLibrary {
        ToolLibrary::parse(
            "crates/cellseq/src/generate/default-tools.toml",
            DEFAULT_LIBRARY,
        )
        .expect("the shipped tool library parses")
    }
    /// `default` gives the shipped library; anything else is read as a TOML file.
    pub fn load(spec: &str) -> Result<ToolLibrary> {
        if spec == "default" {
            return Ok(ToolLibrary::default_library());
        }
        let text = crate::files::read_text(Path::new(spec))?;
        ToolLibrary::parse(spec, &text)
    }
    /// End mills, largest first.
    pub fn end_mills(&self) -> impl Iterator<Item = &ToolSpec> {
        self.tools.iter().filter(|t| t.kind == ToolKind::EndMill)
    }
    /// Drills, largest first.
    pub fn drills(&self) -> impl Iterator<Item = &ToolSpec> {
        self.tools.iter().filter(|t| t.kind == ToolKind::Drill)
    }
    /// A tool by id.
    pub fn get(&self, id: &str) -> Option<&ToolSpec> {
        self.tools.iter().find(|t| t.id == id)
    }
    /// The smallest end mill.
    pub fn smallest_end_mill(&self) -> &ToolSpec {
        self.end_mills().last().expect("library has an end mill")
    }
    /// Finishing tool: the largest end mill whose radius ≤ `min_corner_radius`
    /// (the smallest end mill when none fits).
    pub fn finishing_tool(&self, min_corner_radius: f64) -> &ToolSpec {
        self.end_mills()
            .find(|t| t.radius() <= min_corner_radius + 1e-9)
            .unwrap_or_else(|| self.smallest_end_mill())
    }
    /// Roughing tool: the largest end mill with η ≥ `eta_min` on `pocket`, searched from the
    /// largest down (the smallest end mill when none reaches η_min).
    pub fn roughing_tool(&self, pocket: &Polygon<f64>, eta_min: f64) -> &ToolSpec {
        self.end_mills()
            .find(|t| machinable_ratio(pocket, t.radius()) >= eta_min)
            .unwrap_or_else(|| self.smallest_end_mill())
    }
    /// The largest drill no larger than `diameter` (the smallest drill when none is; `None`
    /// when the library has no drill).
    pub fn drill_for(&self, diameter: f64) -> Option<&ToolSpec> {
        self.drills()
            .find(|t| t.diameter <= diameter + 1e-9)
            .or_else(|| self.drills().last())
    }
}

/// Area a tool of radius `r` can reach in `pocket`: the morphological opening of the pocket by
/// the tool disk (offset inward by r, then outward by r).
pub fn machinable_area(pocket: &Polygon<f64>, r: f64) -> f64 {
    if r <= 0.0 {
        return pocket.unsigned_area();
    }
    let inner: MultiPolygon<f64> = pocket.buffer(-r);
    if inner.0.is_empty() || inner.unsigned_area() <= 0.0 {
        return 0.0;
    }
    inner.buffer(r).unsigned_area()
}

/// Machinable ratio η = A_m / A in [0, 1].
pub fn machinable_ratio(pocket: &Polygon<f64>, r: f64) -> f64 {
    let a = pocket.unsigned_area();
    if a <= 0.0 {
        return 0.0;
    }
    (machinable_area(pocket, r) / a).clamp(0.0, 1.0)
}

/// Roughing layer count: nn = ⌊H / a_p⌋; N = nn when the rest H − a_p·nn is below the
/// allowance δ (it is left to finishing), else nn + 1.
pub fn layer_count(h: f64, ap: f64, delta: f64) -> u32 {
    if !(h > 0.0 && ap > 0.0) {
        return 0;
    }
    let nn = (h / ap + 1e-9).floor();
    let rest = h - ap * nn;
    if rest < delta - 1e-12 || rest.abs() <= 1e-9 {
        nn as u32
    } else {
        nn as u32 + 1
    }
}

/// Single-layer time t = A / (w·f·n) in minutes.
pub fn layer_time(area: f64, tool: &ToolSpec) -> f64 {
    area / tool.area_rate()
}

/// One roughing cell for merging: pocket area and its layer count.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoughJob {
    /// Pocket area A (mm²).
    pub area: f64,
    /// Layer count N.
    pub layers: u32,
}

/// Total time T = t·N of a job with a tool (minutes).
pub fn job_time(job: &RoughJob, tool: &ToolSpec) -> f64 {
    layer_time(job.area, tool) * job.layers as f64
}

/// μ of merging the jobs of `a` (cut with tool `ta`) and `b` (cut with `tb`) onto the smaller
/// of the two tools: (ΣT own tools) / (ΣT all with the smaller tool).
pub fn merge_ratio(a: &[RoughJob], ta: &ToolSpec, b: &[RoughJob], tb: &ToolSpec) -> f64 {
    let small = if ta.diameter <= tb.diameter { ta } else { tb };
    let own: f64 = a.iter().map(|j| job_time(j, ta)).sum::<f64>()
        + b.iter().map(|j| job_time(j, tb)).sum::<f64>();
    let all: f64 = a.iter().chain(b).map(|j| job_time(j, small)).sum();
    if all > 0.0 { own / all } else { 0.0 }
}

/// Merges tool groups greedily: while some pair of groups has μ > `mu_min`, the pair with the
/// largest μ (ties: larger tools first) is moved onto its smaller tool. `assign[i]` is the id
/// of the tool of job i; it is updated in place. Returns the number of merges.
pub fn merge_groups(
    jobs: &[RoughJob],
    assign: &mut [String],
    lib: &ToolLibrary,
    mu_min: f64,
) -> usize {
    let mut merges = 0;
    loop {
        let mut ids: Vec<&ToolSpec> = Vec::new();
        for a in assign.iter() {
            let t = lib.get(a).expect("assigned tools come from the library");
            if !ids.iter().any(|x| x.id == t.id) {
                ids.push(t);
            }
        }
        ids.sort_by(|a, b| {
            b.diameter
                .total_cmp(&a.diameter)
                .then_with(|| a.id.cmp(&b.id))
        });
        let group = |t: &ToolSpec| -> Vec<RoughJob> {
            jobs.iter()
                .zip(assign.iter())
                .filter(|(_, a)| **a == t.id)
                .map(|(j, _)| *j)
                .collect()
        };
        let mut best: Option<(f64, usize, usize)> = None;
        for i in 0..ids.len() {
            for k in i + 1..ids.len() {
                let mu = merge_ratio(&group(ids[i]), ids[i], &group(ids[k]), ids[k]);
                if mu > mu_min && best.is_none_or(|b| mu > b.0) {
                    best = Some((mu, i, k));
                }
            }
        }
        let Some((_, i, k)) = best else { return merges };
        // ids sorted largest first: k is the smaller tool
        let (from, to) = (ids[i].id.clone(), ids[k].id.clone());
        for a in assign.iter_mut() {
            if *a == from {
                *a = to.clone();
            }
        }
        merges += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geo::{Rect, coord};

    fn rounded_square(side: f64, r: f64) -> Polygon<f64> {
        let sq = Rect::new(coord! {x: 0.0, y: 0.0}, coord! {x: side, y: side}).to_polygon();
        sq.buffer(-r).buffer(r).0.into_iter().next().unwrap()
    }

    #[test]
    fn layer_count_edge_cases() {
        // exact multiple: no rest
        assert_eq!(layer_count(20.0, 5.0, 0.5), 4);
        // rest below allowance: left to finishing
        assert_eq!(layer_count(20.3, 5.0, 0.5), 4);
        // rest exactly the allowance: one more layer
        assert_eq!(layer_count(20.5, 5.0, 0.5), 5);
        // rest above allowance
        assert_eq!(layer_count(22.0, 5.0, 0.5), 5);
        // shallower than one step
        assert_eq!(layer_count(3.0, 5.0, 0.5), 1);
        assert_eq!(layer_count(0.3, 5.0, 0.5), 0);
        // floating point: 0.3 / 0.1 must count 3 layers
        assert_eq!(layer_count(0.3, 0.1, 0.01), 3);
        assert_eq!(layer_count(0.0, 5.0, 0.5), 0);
        assert_eq!(layer_count(10.0, 0.0, 0.5), 0);
    }

    #[test]
    fn finishing_tool_fits_corner_radius() {
        let lib = ToolLibrary::default_library();
        for r in [3.0, 4.0, 5.5, 8.0, 10.0, 12.4, 20.0, 40.0] {
            let t = lib.finishing_tool(r);
            assert!(t.radius() <= r, "r={r}: {} too big", t.id);
            // and it is the largest such tool
            assert!(
                lib.end_mills()
                    .all(|o| o.radius() > r || o.diameter <= t.diameter)
            );
        }
        assert_eq!(lib.finishing_tool(8.0).id, "EM16");
        assert_eq!(lib.finishing_tool(7.9).id, "EM12");
    }

    #[test]
    fn eta_falls_as_tool_grows() {
        let r = 6.0;
        let p = rounded_square(100.0, r);
        let mut last = f64::INFINITY;
        for tr in [2.0, 4.0, 6.0, 10.0, 15.0, 20.0, 30.0, 45.0] {
            let eta = machinable_ratio(&p, tr);
            assert!(eta <= last + 1e-6, "eta({tr}) = {eta} > {last}");
            last = eta;
        }
        // a tool no larger than the corner radius reaches (almost) everything
        assert!(machinable_ratio(&p, r) > 0.995);
        // a big tool leaves the corners: area lost = 4 (1 - pi/4)(R^2 - r^2)
        let big = 20.0;
        let expect = 1.0
            - 4.0 * (1.0 - std::f64::consts::PI / 4.0) * (big * big - r * r) / p.unsigned_area();
        assert!((machinable_ratio(&p, big) - expect).abs() < 2e-3);
        // a tool wider than the pocket reaches nothing
        assert_eq!(machinable_ratio(&p, 60.0), 0.0);
    }

    #[test]
    fn roughing_tool_respects_eta_min() {
        let lib = ToolLibrary::default_library();
        let p = rounded_square(120.0, 5.0);
        let t = lib.roughing_tool(&p, 0.97);
        assert!(machinable_ratio(&p, t.radius()) >= 0.97);
        // the next larger end mill would not reach eta_min
        let bigger: Vec<_> = lib
            .end_mills()
            .filter(|o| o.diameter > t.diameter)
            .collect();
        if let Some(b) = bigger.last() {
            assert!(machinable_ratio(&p, b.radius()) < 0.97);
        }
        // a narrow slot gets a smaller roughing tool than a wide pocket
        let slot = Rect::new(coord! {x: 0.0, y: 0.0}, coord! {x: 200.0, y: 22.0}).to_polygon();
        assert!(lib.roughing_tool(&slot, 0.9).diameter < t.diameter);
    }

    fn tool(id: &str, d: f64, w: f64, f: f64, n: f64) -> ToolSpec {
        ToolSpec {
            id: id.into(),
            kind: ToolKind::EndMill,
            diameter: d,
            cutting_width: w,
            feed: f,
            spindle: n,
        }
    }

    #[test]
    fn mu_merging_two_groups_by_hand() {
        // big: w f n = 20 * 0.5 * 10 = 100 mm²/min; small: 10 * 0.5 * 10 = 50 mm²/min
        let big = tool("B", 20.0, 20.0, 0.5, 10.0);
        let small = tool("S", 10.0, 10.0, 0.5, 10.0);
        let lib = ToolLibrary {
            tools: vec![big.clone(), small.clone()],
        };
        // group B: A = 1000, N = 2 -> T = 1000/100*2 = 20 min (with S: 40)
        // group S: A = 500,  N = 1 -> T = 500/50*1  = 10 min
        // mu = (20 + 10) / (40 + 10) = 0.6
        let jobs = [
            RoughJob {
                area: 1000.0,
                layers: 2,
            },
            RoughJob {
                area: 500.0,
                layers: 1,
            },
        ];
        let mu = merge_ratio(&jobs[..1], &big, &jobs[1..], &small);
        assert!((mu - 0.6).abs() < 1e-12);
        let mut assign = vec!["B".to_string(), "S".to_string()];
        assert_eq!(merge_groups(&jobs, &mut assign, &lib, 0.7), 0);
        assert_eq!(assign, ["B", "S"]);
        assert_eq!(merge_groups(&jobs, &mut assign, &lib, 0.55), 1);
        assert_eq!(assign, ["S", "S"]);
    }

    #[test]
    fn library_errors_name_the_file() {
        let e =
            ToolLibrary::parse("lib.toml", "[[tool]]\nid = \"A\"\ndiameter = 10.0\n").unwrap_err();
        assert!(e.to_string().starts_with("lib.toml:"), "{e}");
        let e = ToolLibrary::parse(
            "lib.toml",
            "[[tool]]\nid=\"A\"\ndiameter=-1.0\ncutting_width=1.0\nfeed=1.0\nspindle=1.0\n",
        )
        .unwrap_err();
        assert!(
            e.to_string()
                .contains("tool 'A': diameter must be a finite number in (0, 10000]"),
            "{e}"
        );
        for (key, v) in [
            ("diameter", "1e300"),
            ("cutting_width", "nan"),
            ("feed", "inf"),
            ("spindle", "1e7"),
            ("spindle", "1e-9"),
        ] {
            let text =
                "[[tool]]\nid=\"A\"\ndiameter=10.0\ncutting_width=1.0\nfeed=0.1\nspindle=1000.0\n"
                    .replace(&format!("{key}="), &format!("{key}={v}\nx_"));
            let text = text.replace("x_", "# ");
            let e = ToolLibrary::parse("lib.toml", &text)
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("lib.toml") && e.contains(key),
                "{key}={v}: {e}"
            );
        }
    }
}

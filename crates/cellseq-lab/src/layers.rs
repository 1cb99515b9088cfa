//! Per-layer breakdown of a sequence (paper 004 reports its figures per casing layer).
//!
//! Recomputed from the instance and the sequence alone (not from the solver): each move is
//! charged to the layer of the cell it leads INTO — its air length, its lift and tool change,
//! and its time — and each cell's cut length and cutting time to the cell's own layer. The final
//! return home leads into no cell and is reported separately, so the layers plus the return
//! add up to the checker's totals (tested).

use cellseq::model::{Instance, Sequence};
use serde::{Deserialize, Serialize};

/// What the moves into one layer's cells and the cutting of those cells cost.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct LayerStats {
    /// Layer index (0 = top).
    pub layer: u32,
    /// Cells of the layer.
    pub cells: usize,
    /// Length cut inside the layer's cells (mm).
    pub cut_length: f64,
    /// Air length of the moves into the layer's cells (mm), at-depth links included.
    pub air_length: f64,
    /// Lifts (retract/plunge cycles) of the moves into the layer's cells.
    pub lifts: u64,
    /// Tool changes of the moves into the layer's cells.
    pub tool_changes: u64,
    /// Machining time (s) of the moves into and the cutting of the layer's cells.
    pub machining_time: f64,
}

/// A sequence's breakdown: one entry per layer present (ascending) and the return home.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Breakdown {
    /// Per layer, ascending by layer index.
    pub layers: Vec<LayerStats>,
    /// Air length of the final return home (mm; 0 when the machine does not return).
    pub return_air: f64,
    /// Time of the final return home (s).
    pub return_time: f64,
}

fn dist3(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// The per-layer breakdown of `seq` on a geometric instance (`None` for matrix instances, which
/// have no geometry). Same machine model as [`cellseq::checker::check`]; cells must be valid indices.
pub fn breakdown(inst: &Instance, seq: &Sequence) -> Option<Breakdown> {
    if inst.is_matrix() {
        return None;
    }
    let m = &inst.machine;
    let h = m.clearance;
    let home: [f64; 3] = m.home.into();
    let tc: [f64; 3] = m.tool_change.into();
    let mut by: std::collections::BTreeMap<u32, LayerStats> = Default::default();
    let mut prev: Option<([f64; 3], &str)> = None;
    for v in seq {
        let cell = inst.cells.get(v.cell)?;
        let md = *cell.modes.get(v.mode)?;
        let entry: [f64; 3] = md.entry.into();
        let exit: [f64; 3] = md.exit.into();
        let feed = cell
            .feed
            .or_else(|| {
                inst.tools
                    .iter()
                    .find(|t| t.id == cell.tool)
                    .and_then(|t| t.feed)
            })
            .unwrap_or(m.cut_feed);
        let above_entry = [entry[0], entry[1], h];
        let (mut rapid, mut link, mut lift, mut change) = (0.0, 0.0, 0u64, 0u64);
        match prev {
            None => {
                let first_change = m.initial_tool.as_ref().is_some_and(|t| *t != cell.tool);
                rapid = if first_change {
                    change = 1;
                    dist3(home, tc) + dist3(tc, above_entry)
                } else {
                    dist3(home, above_entry)
                } + (h - entry[2]);
            }
            Some((pexit, ptool)) if ptool != cell.tool => {
                change = 1;
                lift = 1;
                rapid = (h - pexit[2])
                    + dist3([pexit[0], pexit[1], h], tc)
                    + dist3(tc, above_entry)
                    + (h - entry[2]);
            }
            Some((pexit, _)) => {
                let planar = ((pexit[0] - entry[0]).powi(2) + (pexit[1] - entry[1]).powi(2)).sqrt();
                let at_depth =
                    if (pexit[2] - entry[2]).abs() <= 1e-9 && planar <= m.link_distance + 1e-9 {
                        cellseq::checker::at_depth_length(m, pexit, entry)
                            .filter(|&d| d <= m.link_distance + 1e-9)
                    } else {
                        None
                    };
                if let Some(d) = at_depth {
                    link = d;
                } else {
                    lift = 1;
                    rapid = (h - pexit[2]) + planar + (h - entry[2]);
                }
            }
        }
        let s = by.entry(cell.layer).or_insert(LayerStats {
            layer: cell.layer,
            ..LayerStats::default()
        });
        s.cells += 1;
        s.cut_length += cell.cut_length;
        s.air_length += rapid + link;
        s.lifts += lift;
        s.tool_changes += change;
        s.machining_time += (cell.cut_length + link) * 60.0 / feed
            + rapid * 60.0 / m.rapid_feed
            + lift as f64 * m.lift_time
            + change as f64 * m.tool_change_time;
        prev = Some((exit, cell.tool.as_str()));
    }
    let mut out = Breakdown {
        layers: by.into_values().collect(),
        ..Breakdown::default()
    };
    if m.return_home
        && let Some((pexit, _)) = prev
    {
        out.return_air = (h - pexit[2]) + dist3([pexit[0], pexit[1], h], home);
        out.return_time = out.return_air * 60.0 / m.rapid_feed;
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use cellseq::checker::check;
    use cellseq::model::Objective;
    use std::collections::BTreeMap;

    fn casing() -> Instance {
        cellseq::generate::generate("casing", &BTreeMap::new(), 3).unwrap()
    }

    fn solve(inst: &Instance, name: &str) -> Sequence {
        cellseq::Solve::new(name.parse().unwrap())
            .objective(Objective::Time)
            .run(inst)
            .unwrap()
            .sequence
    }

    #[test]
    fn layers_add_up_to_the_checker_totals() {
        let inst = casing();
        for seq in [solve(&inst, "as-given"), solve(&inst, "greedy")] {
            let b = breakdown(&inst, &seq).unwrap();
            assert!(b.layers.len() >= 2, "casing has several layers");
            let cells: usize = b.layers.iter().map(|l| l.cells).sum();
            assert_eq!(cells, inst.n());
            {
                let r = check(&inst, &seq, Objective::Time).unwrap();
                let sum = |f: fn(&LayerStats) -> f64| b.layers.iter().map(f).sum::<f64>();
                assert!((sum(|l| l.cut_length) - r.cut_length).abs() < 1e-6);
                assert!((sum(|l| l.air_length) + b.return_air - r.air_length).abs() < 1e-6);
                assert!(
                    (sum(|l| l.machining_time) + b.return_time - r.machining_time).abs() < 1e-6
                );
                assert_eq!(b.layers.iter().map(|l| l.lifts).sum::<u64>(), r.lifts);
                assert_eq!(
                    b.layers.iter().map(|l| l.tool_changes).sum::<u64>(),
                    r.tool_changes
                );
            }
        }
    }

    #[test]
    fn moves_are_charged_to_the_layer_entered() {
        let mut inst = casing();
        let seq = solve(&inst, "as-given");
        let before = breakdown(&inst, &seq).unwrap();
        // move every cell to layer 0: one layer holding all the totals
        for c in &mut inst.cells {
            c.layer = 0;
        }
        let after = breakdown(&inst, &seq).unwrap();
        assert_eq!(after.layers.len(), 1);
        let total: f64 = before.layers.iter().map(|l| l.air_length).sum();
        assert!((after.layers[0].air_length - total).abs() < 1e-6);
    }
}

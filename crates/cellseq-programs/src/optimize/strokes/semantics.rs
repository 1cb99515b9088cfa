//! What a drawing's layers, colours and groups mean for its order: its pen and block
//! semantics.
//!
//! - **Pens.** The strokes of one pen are drawn together, pens in the file's order (a pen
//!   change, or a laser setting). `layer`: a layer is a pen (AxiDraw and Inkscape plot layer
//!   by layer; colours inside a layer mean nothing to them); `colour`: a stroke colour is a
//!   pen, inside each layer (vpype's `--attr stroke`, LightBurn's colour layers); `none`: one
//!   pen, no order between layers or colours at all.
//! - **Blocks.** `group`: a plain group that is a child of the root (not an Inkscape layer) is
//!   a part, drawn as one block with its own pen order; the order of a run of such blocks is
//!   free (boxes.py's parts). `none`: such groups are only grouping; a run of them is one unit
//!   whose strokes are ordered by pen alone.
//!
//! `auto` reads the file: Inkscape layers (`inkscape:groupmode="layer"`; every DXF layer)
//! make a layer a pen, else a colour is a pen; a boxes.py file's groups are parts, other
//! plain groups are grouping. When that reading differs from the strictest one (a colour is
//! a pen inside each layer, groups are parts: what every other reading allows), both are
//! solved and the one with less pen-up travel is kept ([`readings`]).
//!
//! boxes.py colours a part's strokes by operation (inner cuts, outer cut, etching) and draws
//! them in that order so that nothing is cut after the part is free. A part read as one pen
//! with its strokes *inner first* (every stroke inside a closed stroke before it, as
//! `--cut` orders them) keeps that promise by geometry instead of by colour; `auto` also
//! solves that reading for boxes.py files whose parts do not lie inside one another.

use crate::drawing::Drawing;
use std::collections::HashMap;

/// What a pen is ([module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pens {
    /// A layer is a pen (AxiDraw, Inkscape).
    Layer,
    /// A stroke colour is a pen, inside each layer (vpype `--attr stroke`, LightBurn).
    Colour,
    /// One pen: no order between layers or colours.
    None,
    /// Read from the file.
    Auto,
}

/// What a plain top-level group is ([module docs](self)).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blocks {
    /// A part: one block, the order of blocks free (boxes.py).
    Group,
    /// Only grouping: runs of plain groups are one unit.
    None,
    /// Read from the file.
    Auto,
}

impl Pens {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Pens::Layer => "layer",
            Pens::Colour => "colour",
            Pens::None => "none",
            Pens::Auto => "auto",
        }
    }
    /// From a name (`color` too); `None` for an unknown one.
    pub fn parse(s: &str) -> Option<Pens> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "layer" | "layers" => Pens::Layer,
            "colour" | "color" | "colours" | "colors" => Pens::Colour,
            "none" => Pens::None,
            "auto" => Pens::Auto,
            _ => return None,
        })
    }
}

impl Blocks {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Blocks::Group => "group",
            Blocks::None => "none",
            Blocks::Auto => "auto",
        }
    }
    /// From a name; `None` for an unknown one.
    pub fn parse(s: &str) -> Option<Blocks> {
        Some(match s.trim().to_ascii_lowercase().as_str() {
            "group" | "groups" => Blocks::Group,
            "none" => Blocks::None,
            "auto" => Blocks::Auto,
            _ => return None,
        })
    }
}

/// A reading of the drawing: pens and blocks, neither `Auto`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reading {
    /// What a pen is.
    pub pens: Pens,
    /// What a plain top-level group is.
    pub blocks: Blocks,
    /// Each scope's strokes in containment order (every stroke inside a closed stroke before
    /// it, as `--cut` orders them): how a boxes.py part read as one pen keeps its inner cuts
    /// before its outer cut ([module docs](self)).
    pub inner_first: bool,
}

impl Reading {
    /// The strictest reading, which every other allows: a colour is a pen inside each layer,
    /// a plain group is a part.
    pub const STRICT: Reading = Reading::new(Pens::Colour, Blocks::Group);

    /// A reading of `pens` and `blocks`, in the order the search finds best within a scope.
    pub const fn new(pens: Pens, blocks: Blocks) -> Reading {
        Reading {
            pens,
            blocks,
            inner_first: false,
        }
    }
}

impl std::fmt::Display for Reading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "pens {}, blocks {}{}",
            self.pens.name(),
            self.blocks.name(),
            if self.inner_first {
                ", inner first"
            } else {
                ""
            }
        )
    }
}

/// True for a plain group that is a child of the root (not the root, not an Inkscape layer).
pub fn is_plain_group(d: &Drawing, layer: usize) -> bool {
    layer != 0 && !d.layers[layer].inkscape
}

/// The unit each layer's strokes belong to under `blocks` (a layer index): its own layer,
/// except that with [`Blocks::None`] a run of consecutive plain groups is one unit (the run's
/// first group).
pub fn units(d: &Drawing, blocks: Blocks) -> Vec<usize> {
    let mut u: Vec<usize> = (0..d.layers.len()).collect();
    if blocks == Blocks::None {
        for l in 2..d.layers.len() {
            if is_plain_group(d, l) && is_plain_group(d, l - 1) {
                u[l] = u[l - 1];
            }
        }
    }
    u
}

/// What the drawing says about its semantics.
#[derive(Debug, Clone, Copy, Default)]
struct Facts {
    inkscape_layers: bool,
    plain_groups: bool,
    boxes_py: bool,
}

fn facts(d: &Drawing) -> Facts {
    let mut with_strokes = vec![false; d.layers.len()];
    for s in &d.strokes {
        with_strokes[s.layer] = true;
    }
    Facts {
        inkscape_layers: (1..d.layers.len()).any(|l| d.layers[l].inkscape && with_strokes[l]),
        plain_groups: (1..d.layers.len()).any(|l| is_plain_group(d, l) && with_strokes[l]),
        boxes_py: d.generator.as_deref() == Some("boxes.py"),
    }
}

/// True when merging runs of plain groups by colour ([`Blocks::None`] with
/// [`Pens::Colour`]) keeps every group's own colour order: each group's colours, in the
/// order they first appear in it, appear in that order in its run too. When not, a group
/// drawn in another colour order could be a part cut outer contour first.
pub fn colour_orders_agree(d: &Drawing) -> bool {
    let units = units(d, Blocks::None);
    // per unit: colour -> rank of first appearance; per group: highest rank seen so far
    let mut rank: HashMap<(usize, &str), usize> = HashMap::new();
    let mut next_rank: HashMap<usize, usize> = HashMap::new();
    let mut seen: HashMap<(usize, &str), ()> = HashMap::new();
    let mut top: HashMap<usize, usize> = HashMap::new();
    for s in &d.strokes {
        if !is_plain_group(d, s.layer) {
            continue;
        }
        let u = units[s.layer];
        let colour = d.styles[s.style].stroke.as_str();
        let r = *rank.entry((u, colour)).or_insert_with(|| {
            let n = next_rank.entry(u).or_insert(0);
            *n += 1;
            *n
        });
        if seen.insert((s.layer, colour), ()).is_none() {
            let t = top.entry(s.layer).or_insert(0);
            if r < *t {
                return false;
            }
            *t = r;
        }
    }
    true
}

/// The readings to solve, the one following the file's conventions first, and why. With
/// both options given, that one; with `Auto`, the convention the file shows ([module
/// docs](self)) and, when it differs, the strictest reading with the same explicit choices.
pub fn readings(d: &Drawing, pens: Pens, blocks: Blocks) -> (Vec<Reading>, String) {
    let f = facts(d);
    let mut why = Vec::new();
    let p = match pens {
        Pens::Auto if f.inkscape_layers => {
            why.push("Inkscape layers: a layer is a pen (AxiDraw, Inkscape)");
            Pens::Layer
        }
        Pens::Auto => {
            why.push("no Inkscape layers: a colour is a pen (vpype, LightBurn)");
            Pens::Colour
        }
        given => given,
    };
    let b = match blocks {
        Blocks::Auto if !f.plain_groups => Blocks::Group,
        Blocks::Auto if f.boxes_py => {
            why.push("boxes.py: a group is a part");
            Blocks::Group
        }
        Blocks::Auto => {
            why.push("plain top-level groups: grouping, not parts");
            Blocks::None
        }
        given => given,
    };
    let mut first = Reading::new(p, b);
    if blocks == Blocks::Auto
        && first.blocks == Blocks::None
        && first.pens == Pens::Colour
        && !colour_orders_agree(d)
    {
        why.push("groups order their colours differently: kept as parts");
        first.blocks = Blocks::Group;
    }
    let strict = Reading::new(
        if pens == Pens::Auto { Pens::Colour } else { p },
        if blocks == Blocks::Auto {
            Blocks::Group
        } else {
            b
        },
    );
    let mut out = vec![first];
    if strict != first && first.pens != Pens::None {
        out.push(strict);
    }
    if f.boxes_py && pens == Pens::Auto && f.plain_groups && first.blocks == Blocks::Group {
        // a part as one pen, inner strokes first ([module docs](self)); the pipeline drops
        // it when a part lies inside another ([`parts_apart`])
        out.push(Reading {
            pens: Pens::Layer,
            blocks: Blocks::Group,
            inner_first: true,
        });
    }
    let why = if why.is_empty() {
        "as given".to_string()
    } else {
        why.join("; ")
    };
    (out, why)
}

/// True when no stroke of one scope lies inside a closed stroke of another: drawing a part
/// inner first then frees nothing another part still needs. `containment` gives the
/// (inner, outer) pairs of the strokes of all scopes, in the order of `all`.
pub fn parts_apart(sc: &[Vec<usize>], containment: &[(usize, usize)], strokes: usize) -> bool {
    let mut scope_of = vec![usize::MAX; strokes];
    let mut all = Vec::new();
    for (k, s) in sc.iter().enumerate() {
        for &i in s {
            scope_of[i] = k;
            all.push(i);
        }
    }
    containment
        .iter()
        .all(|&(a, b)| scope_of[all[a]] == scope_of[all[b]])
}

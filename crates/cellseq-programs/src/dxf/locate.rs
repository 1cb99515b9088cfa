//! Line numbers of DXF entities, for messages. The `dxf` crate keeps none, so an entity is
//! found again in the text: by its handle (group code 5), else by its place among the
//! top-level entities of the ENTITIES section. Built only when a message needs it; a binary
//! DXF has no lines.

use std::collections::HashMap;

/// Where the entities of an ASCII DXF start.
#[derive(Debug, Default)]
pub struct Lines {
    /// Handle (upper case) → line of the `0` group that starts its entity, and the type that
    /// group names.
    by_handle: HashMap<String, (usize, String)>,
    /// Top-level entities of the ENTITIES section in file order: (line, type name).
    top: Vec<(usize, String)>,
}

/// Group codes that start a sub-entity of the entity before them, not a new top-level one.
const SUB: [&str; 3] = ["VERTEX", "SEQEND", "ATTRIB"];

impl Lines {
    /// Scans the text of a DXF (nothing for a binary one).
    pub fn new(bytes: &[u8]) -> Lines {
        let mut out = Lines::default();
        if bytes.starts_with(b"AutoCAD Binary DXF") {
            return out;
        }
        let text = String::from_utf8_lossy(bytes);
        let mut lines = text.lines().enumerate();
        let mut section = String::new();
        let mut expect_name = false;
        let mut start = 0usize;
        let mut kind = String::new();
        while let (Some((i, code)), Some((_, value))) = (lines.next(), lines.next()) {
            let (code, value) = (code.trim(), value.trim());
            match code {
                "0" => {
                    start = i + 1;
                    kind = value.to_ascii_uppercase();
                    expect_name = value == "SECTION";
                    if value == "ENDSEC" {
                        section.clear();
                    } else if section == "ENTITIES" && !SUB.contains(&value) {
                        out.top.push((start, value.to_ascii_uppercase()));
                    }
                }
                "2" if expect_name => {
                    section = value.to_ascii_uppercase();
                    expect_name = false;
                }
                "5" => {
                    out.by_handle
                        .entry(value.to_ascii_uppercase())
                        .or_insert((start, kind.clone()));
                }
                _ => {}
            }
        }
        out
    }

    /// The line of the entity of type `kind` that the file gives this handle (the `dxf`
    /// crate numbers entities that have none, and such a number may be another object's).
    pub fn by_handle(&self, handle: &str, kind: &str) -> Option<usize> {
        match self.by_handle.get(&handle.to_ascii_uppercase()) {
            Some((l, k)) if k == kind => Some(*l),
            _ => None,
        }
    }

    /// The line of the entity with `handle` ("0" when the file gave it none) of type `kind`,
    /// the `top`-th top-level entity (or inside the block that entity inserts).
    pub fn find(&self, handle: &str, kind: &str, top: usize) -> Option<usize> {
        if let Some(l) = self.by_handle(handle, kind) {
            return Some(l);
        }
        let (line, name) = self.top.get(top)?;
        (name == kind || name == "INSERT").then_some(*line)
    }
}

/// The first line at which an ASCII DXF names more than `max` distinct layers (group code 8)
/// or line types (6), with which of the two; `None` within the limit or for a binary DXF.
/// The `dxf` crate looks each entity's layer and line type up in a list, so its reading time
/// grows with the entities times these names: this is checked before it reads.
pub fn too_many_names(bytes: &[u8], max: usize) -> Option<(usize, &'static str)> {
    use std::collections::HashSet;
    if bytes.starts_with(b"AutoCAD Binary DXF") {
        return None;
    }
    let text = String::from_utf8_lossy(bytes);
    let mut lines = text.lines().enumerate();
    let (mut layers, mut types) = (HashSet::new(), HashSet::new());
    while let (Some((i, code)), Some((_, value))) = (lines.next(), lines.next()) {
        let (set, what) = match code.trim() {
            "8" => (&mut layers, "layer"),
            "6" => (&mut types, "line type"),
            _ => continue,
        };
        if set.len() < max + 1 && set.insert(value.trim()) && set.len() > max {
            return Some((i + 2, what));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn entities_are_found_by_handle_or_place() {
        let t = "0\nSECTION\n2\nENTITIES\n0\nLINE\n5\n2A\n8\n0\n0\nPOLYLINE\n8\n0\n0\nVERTEX\n8\n0\n0\nSEQEND\n0\nCIRCLE\n8\n0\n40\n-1\n0\nENDSEC\n0\nEOF\n";
        let l = Lines::new(t.as_bytes());
        assert_eq!(l.find("2a", "LINE", 0), Some(5));
        assert_eq!(l.by_handle("2A", "LINE"), Some(5));
        assert_eq!(l.by_handle("2A", "ARC"), None);
        assert_eq!(l.by_handle("2B", "LINE"), None);
        assert_eq!(l.find("0", "POLYLINE", 1), Some(11));
        assert_eq!(l.find("0", "CIRCLE", 2), Some(21));
        // a place that does not hold that kind of entity gives no line
        assert_eq!(l.find("0", "ARC", 2), None);
        assert_eq!(l.find("0", "ARC", 9), None);
    }

    #[test]
    fn too_many_layer_names_are_found_at_their_line() {
        let t = "0\nLINE\n8\nA\n0\nLINE\n8\nB\n0\nLINE\n8\nA\n0\nLINE\n8\nC\n";
        assert_eq!(too_many_names(t.as_bytes(), 3), None);
        assert_eq!(too_many_names(t.as_bytes(), 2), Some((16, "layer")));
    }
}

//! Helpers shared by the integration tests.
#![allow(dead_code)]

use cellseq::geom::Point3;
use cellseq::model::{Cell, Instance, Machine, Mode, Tool, Visit};
use std::path::PathBuf;

/// Path of a file shipped in `instances/`.
pub fn instance_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("instances")
        .join(rel)
}

/// A small geometric instance: `n` cells on a line, two tools, optional precedence chain.
pub fn line_instance(n: usize, reversible: bool) -> Instance {
    let cells = (0..n)
        .map(|i| {
            let x = (i * 37 % 11) as f64 * 10.0;
            let y = (i * 17 % 7) as f64 * 10.0;
            let e = Point3::new(x, y, -1.0);
            let f = Point3::new(x + 5.0, y, -1.0);
            let mut modes = vec![Mode::new(e, f)];
            if reversible {
                modes.push(Mode::new(f, e));
            }
            let mut c = Cell::new(format!("c{i}"), if i % 3 == 0 { "T2" } else { "T1" }, modes);
            c.reversible = reversible;
            c.cut_length = 5.0;
            c.z = -1.0;
            c
        })
        .collect();
    Instance {
        name: format!("line{n}"),
        machine: Machine::default(),
        tools: vec![
            Tool {
                id: "T1".into(),
                diameter: 6.0,
                name: None,
                feed: None,
            },
            Tool {
                id: "T2".into(),
                diameter: 10.0,
                name: Some("rougher".into()),
                feed: Some(800.0),
            },
        ],
        cells,
        precedence: vec![],
        as_given: Some((0..n).map(|c| Visit::new(c, 0)).collect()),
        ..Instance::default()
    }
}

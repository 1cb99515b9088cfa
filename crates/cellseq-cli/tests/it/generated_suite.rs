//! The shipped suite `instances/generated/` is what `scripts/generate-suite.sh` makes: the
//! small instances are regenerated here and compared byte for byte; all of them validate.

use cellseq::formats::json::instance_to_json;
use std::collections::BTreeMap;

struct Entry {
    file: String,
    kind: String,
    seed: u64,
    params: BTreeMap<String, String>,
}

fn suite() -> Vec<Entry> {
    let dir = crate::common::instance_path("generated");
    let text = std::fs::read_to_string(dir.join("suite.tsv")).unwrap();
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let cols: Vec<&str> = l.split('\t').collect();
            assert_eq!(cols.len(), 4, "suite.tsv line '{l}'");
            let params = if cols[3] == "-" {
                BTreeMap::new()
            } else {
                cols[3]
                    .split_whitespace()
                    .map(|kv| {
                        let (k, v) = kv.split_once('=').unwrap();
                        (k.to_string(), v.to_string())
                    })
                    .collect()
            };
            Entry {
                file: cols[0].into(),
                kind: cols[1].into(),
                seed: cols[2].parse().unwrap(),
                params,
            }
        })
        .collect()
}

#[test]
fn small_suite_instances_regenerate_byte_for_byte() {
    let dir = crate::common::instance_path("generated");
    let mut compared = 0;
    for e in suite()
        .iter()
        .filter(|e| !e.file.starts_with("large/") && !e.file.contains("-1000"))
    {
        let inst = cellseq::generate::generate(&e.kind, &e.params, e.seed).unwrap();
        let shipped = std::fs::read_to_string(dir.join(&e.file)).unwrap();
        assert!(
            instance_to_json(&inst) == shipped,
            "{} differs from its regeneration: run scripts/generate-suite.sh",
            e.file
        );
        compared += 1;
    }
    assert!(compared >= 6);
}

#[test]
fn every_shipped_instance_validates() {
    let dir = crate::common::instance_path("generated");
    for e in suite().iter().filter(|e| !e.file.starts_with("large/")) {
        let path = dir.join(&e.file);
        let inst = cellseq::formats::load_instance(&path).unwrap();
        assert_eq!(inst.meta.generator.as_deref(), Some(e.kind.as_str()));
        assert_eq!(inst.meta.seed, Some(e.seed));
        let seq = inst.as_given.as_ref().unwrap();
        cellseq::check(&inst, seq, cellseq::Objective::Time).unwrap();
    }
}

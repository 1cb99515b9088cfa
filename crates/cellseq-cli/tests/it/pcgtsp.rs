//! The PCGTSP reader on real PCGTSPLIB files (`tests/fixtures/pcgtsp/`, see SOURCES.md):
//! dispatch by extension and by `TYPE:`, agreement with the integer PCGLNS version of the same
//! instance, and solving. Mutated copies (an error naming the file, never a panic) are run by
//! `tests/mutations.rs` `pcgtsp_reader_survives_mutations` with the other readers.

use cellseq::formats::{self, Format};
use cellseq::model::Objective;
use cellseq::solvers::{self, Budget, NoObserver};
use std::collections::BTreeMap;
use std::path::PathBuf;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .join(format!("tests/fixtures/pcgtsp/{name}"))
}

#[test]
fn real_files_load_by_extension_and_by_type() {
    for (name, groups, nodes) in [("ESC07.pcgtsp", 8, 39), ("br17.10.pcgtsp", 17, 88)] {
        let inst = formats::load_instance(&fixture(name)).unwrap();
        assert_eq!(inst.n(), groups, "{name}");
        assert_eq!(inst.matrix.as_ref().unwrap().size, nodes);
        assert_eq!(inst.first, Some(0));
        assert!(inst.closed);
        let text = std::fs::read_to_string(fixture(name)).unwrap();
        assert_eq!(
            formats::detect(std::path::Path::new("x.txt"), &text),
            Some(Format::Pcgtsp)
        );
    }
}

#[test]
fn agrees_with_the_integer_pcglns_file_of_the_same_instance() {
    let float = formats::load_instance(&fixture("ESC07.pcgtsp")).unwrap();
    let int_path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .join("instances/pcgtsplib/ESC07.pcglns");
    let int = formats::load_instance(&int_path).unwrap();
    let modes = |i: &cellseq::model::Instance| -> Vec<usize> {
        i.cells.iter().map(|c| c.modes.len()).collect()
    };
    assert_eq!(modes(&float), modes(&int));
    assert_eq!(float.precedence, int.precedence);
    let (a, b) = (float.matrix.unwrap(), int.matrix.unwrap());
    for (x, y) in a.costs.iter().zip(&b.costs) {
        // the PCGLNS file holds the same costs rounded to integers
        assert!((x - y).abs() <= 0.5 + 1e-9, "{x} vs {y}");
    }
}

#[test]
fn solvers_solve_it_and_the_checker_agrees() {
    let inst = formats::load_instance(&fixture("br17.10.pcgtsp")).unwrap();
    let budget = Budget {
        time_limit: None,
        max_evals: Some(200_000),
    };
    for solver in ["greedy", "auto"] {
        let r = solvers::run(
            solver,
            &inst,
            Objective::Matrix,
            &BTreeMap::new(),
            1,
            budget,
            &mut NoObserver,
        )
        .unwrap();
        let rep = cellseq::check(&inst, &r.outcome.sequence, Objective::Matrix).unwrap();
        assert!((rep.cost - r.outcome.cost).abs() < 1e-6 * rep.cost.max(1.0));
        assert!(rep.cost > 0.0);
    }
}

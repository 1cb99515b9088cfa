//! Kept solutions that improve on a published best known value stay feasible and keep their
//! cost under the independent checker (`results/reference/sop/`).

use cellseq::files::read_text;
use cellseq::formats::{json, load_instance};
use cellseq::model::Objective;

#[test]
fn prob100_paths_below_the_published_best_known_are_feasible() {
    let root = crate::common::root();
    let inst = load_instance(&root.join("instances/tsplib-sop/prob.100.sop")).unwrap();
    // the shipped best known value (the literature's) is 1163
    let bks = std::fs::read_to_string(root.join("instances/tsplib-sop/bks.csv")).unwrap();
    let line = bks.lines().find(|l| l.starts_with("prob.100,")).unwrap();
    let best: f64 = line.split(',').nth(2).unwrap().parse().unwrap();
    assert_eq!(best, 1163.0);
    for cost in [1141, 1139, 1134, 1126] {
        let name = format!("prob.100-{cost}.json");
        let text = read_text(&root.join("results/reference/sop").join(&name)).unwrap();
        let sol = json::parse_solution(&name, &text).unwrap();
        let seq = json::from_refs(&inst, &sol.sequence, &name).unwrap();
        let rep = cellseq::check(&inst, &seq, Objective::Matrix).expect("feasible");
        assert_eq!(rep.cost, cost as f64, "{name}");
        assert!(rep.cost < best, "{name}");
    }
}

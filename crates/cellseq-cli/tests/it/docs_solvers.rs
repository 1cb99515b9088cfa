//! `docs/solvers.md` is generated from the solver registry; this test fails when the committed
//! file is not what `cellseq solvers --markdown` prints now, and says how to regenerate it.

const REGENERATE: &str = "cargo run --release -- solvers --markdown > docs/solvers.md";

#[test]
fn docs_solvers_md_is_current() {
    let path = crate::common::root().join("docs/solvers.md");
    let committed = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("{}: {e}; create it with `{REGENERATE}`", path.display()));
    let current = cellseq::solvers::markdown();
    if committed != current {
        let line = committed
            .lines()
            .zip(current.lines())
            .position(|(a, b)| a != b)
            .unwrap_or_else(|| committed.lines().count().min(current.lines().count()));
        panic!(
            "{} is not current (first difference at line {}): regenerate it with `{REGENERATE}`",
            path.display(),
            line + 1
        );
    }
}

#[test]
fn docs_solvers_md_describes_every_registered_solver() {
    let md = cellseq::solvers::markdown();
    for s in cellseq::solvers::registry() {
        assert!(md.contains(&format!("## `{}`", s.name)), "{}", s.name);
        assert!(
            md.contains(s.description.trim()),
            "solver {}: its description is not in the file",
            s.name
        );
    }
}

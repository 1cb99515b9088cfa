//! `docs/solvers.md`, generated from the registry (`cellseq solvers --markdown >
//! docs/solvers.md`): every solver's summary, description and parameters come from its own
//! `INFO` ([`SolverInfo`]); a test in the CLI's suite requires the file to equal [`markdown`].

use super::{DEFAULT_SOLVER, SolverInfo, registry};
use crate::params::ParamKind;

/// A parameter kind as the listings show it: `int` or `float` with the range it accepts
/// (`int [1, 1000]`, `float (0, 1]`), `bool`, `text`, or the choices joined by `|`.
pub fn kind_label(kind: &ParamKind) -> String {
    match kind {
        ParamKind::Int(r) => format!("int {r}"),
        ParamKind::Float(r) => format!("float {r}"),
        ParamKind::Bool => "bool".to_string(),
        ParamKind::Choice(c) => c.join("|"),
        ParamKind::Text => "text".to_string(),
    }
}

/// Text for a Markdown table cell: `|` escaped, line breaks turned into spaces.
fn cell(text: &str) -> String {
    text.replace('|', "\\|").replace('\n', " ")
}

/// The heading anchor GitHub gives `## \`name\``: the name itself (registry names are lower
/// case letters, digits and hyphens).
fn anchor(name: &str) -> String {
    name.chars()
        .filter(|c| c.is_ascii_alphanumeric() || *c == '-' || *c == '_')
        .collect()
}

/// One solver's section: summary, longer description and parameter table.
fn section(out: &mut String, s: &SolverInfo) {
    out.push_str(&format!("## `{}`\n\n", s.name));
    out.push_str(&format!("*{}*\n\n", s.summary.trim()));
    out.push_str(s.description.trim());
    out.push_str("\n\n");
    if s.params.is_empty() {
        out.push_str("No parameters.\n\n");
        return;
    }
    out.push_str("| parameter | default | type | meaning |\n|---|---|---|---|\n");
    for p in s.params {
        out.push_str(&format!(
            "| `{}` | `{}` | {} | {} |\n",
            p.name,
            cell(p.default),
            cell(&kind_label(&p.kind)),
            cell(p.help)
        ));
    }
    out.push('\n');
}

/// The whole of `docs/solvers.md`: an overview table of the registry, then one section per
/// solver with its longer description and its parameters.
pub fn markdown() -> String {
    let mut out = String::from("# Solvers\n\n");
    out.push_str(
        "<!-- Generated from the solver registry (each solver's `INFO` in \
`crates/cellseq/src/solvers/*.rs`: summary, description, parameters) by \
`cargo run --release -- solvers --markdown > docs/solvers.md`; do not edit by hand. -->\n\n",
    );
    out.push_str(
        "`cellseq solve FILE --solver NAME --param KEY=VALUE ...` runs one solver (default \
`auto`); `cellseq solvers` lists them in the terminal. Budgets: `--time-limit SECONDS` or \
`--max-evals N` (an evaluation budget makes a run deterministic on any machine). Unknown or \
malformed parameters are refused. Every result is checked by the independent checker \
before it is reported or written.\n\n",
    );
    out.push_str("| solver | what it is |\n|---|---|\n");
    for s in registry() {
        let default = if s.name == DEFAULT_SOLVER && !s.summary.contains("(default)") {
            " (default)"
        } else {
            ""
        };
        out.push_str(&format!(
            "| [`{}`](#{}){default} | {} |\n",
            s.name,
            anchor(s.name),
            cell(s.summary.trim())
        ));
    }
    out.push('\n');
    for s in registry() {
        section(&mut out, s);
    }
    out.truncate(out.trim_end().len());
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_registered_solver_has_a_description() {
        for s in registry() {
            assert!(!s.description.trim().is_empty(), "{} has no description", s.name);
            assert!(!s.summary.trim().is_empty(), "{} has no summary", s.name);
        }
    }

    #[test]
    fn markdown_has_one_section_and_one_row_per_solver() {
        let md = markdown();
        for s in registry() {
            assert_eq!(
                md.matches(&format!("\n## `{}`\n", s.name)).count(),
                1,
                "{}",
                s.name
            );
            assert!(
                md.contains(&format!("| [`{}`](#{})", s.name, s.name)),
                "{}",
                s.name
            );
            for p in s.params {
                assert!(
                    md.contains(&format!("| `{}` |", p.name)),
                    "{} {}",
                    s.name,
                    p.name
                );
            }
        }
    }

    #[test]
    fn table_cells_escape_pipes() {
        assert_eq!(cell("auto|on|off"), "auto\\|on\\|off");
        assert_eq!(cell("a\nb"), "a b");
    }
}

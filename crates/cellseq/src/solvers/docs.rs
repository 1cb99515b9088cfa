//! User-facing descriptions of the registry's solvers, and `docs/solvers.md` generated from
//! them (`cellseq solvers --markdown > docs/solvers.md`).
//!
//! The registry entries ([`SolverInfo`]) keep the one-line summary and the parameters; the
//! longer text lives here, in a table keyed by registry name, so that the registry stays a
//! list of what each solver is and can do. A unit test requires one entry per registered
//! solver and no other; an integration test requires `docs/solvers.md` to equal
//! [`markdown`].

use super::{DEFAULT_SOLVER, SolverInfo, registry};
use crate::params::ParamKind;

/// The longer description of each registry solver (Markdown), keyed by registry name.
pub static DETAILS: &[(&str, &str)] = &[
    (
        "auto",
        "A portfolio: phases of other solvers, each given a share of what is left of the budget \
(evaluations as well as time, so a run under `--max-evals` stays deterministic), each later \
phase able to start from the best sequence so far; the best sequence wins. What runs is data: \
`auto` computes the instance's features once (cells, modes per cell, geometric or matrix, \
symmetric costs, precedence closure density, free density, widest precedence level, share of \
zero-cost arcs, cost spread) and takes the first rule of a portfolio file whose conditions \
hold; the built-in file is `src/solvers/auto/portfolio.toml`, `--portfolio FILE` (or \
`--param portfolio=FILE`) names another. The format, the features and what is refused: \
[portfolio.md](portfolio.md).

1. A `beam` proof attempt gets the rule's beam share of the budget, on instances of at most \
its `max_cells` cells and, under a wall-clock budget, only when that budget is at least its \
`min_seconds`; when it proves the optimum, `auto` stops there.
2. Then the rule's phases (or its `after_beam` phases after a beam phase that ran). The \
built-in rules: **symmetric** cost matrices with one mode per cell (a short `local-search`, \
then `ils` with Lin–Kernighan chains in a 1 % acceptance band, from the beam's sequence when \
the beam ran) and **symmetric-modes**, several modes per cell (a colony before `ils`); \
**free** asymmetric matrices with no precedence apart from a fixed start and end (`atsp`); \
**sparse** precedence (a short `local-search`, a colony run backwards, `ils` in a 1 % then a 3 \
% acceptance band with the bounded-shift DP ending every repair, window re-optimization of the \
best), and with several modes per cell on up to 300 cells **sparse-modes** (three rounds of a \
fresh colony, each polished by `ils` in the 1 % band, then `ils` in the 3 % band from the best \
of the three and window re-optimization); **dense** precedence (a short `local-search`, then \
`ils` with kicks that reorder up to 45 cells; on up to 300 cells, when the beam runs, half the \
budget for the beam, then the default phases); **geometric free** instances (geometric, no or \
very sparse precedence, links that cost the same both ways: `local-search` on the two-level \
list with local and random-walk double-bridge kicks for the whole budget); and the catch-all \
**default**, the other geometric instances among them (`local-search`, an `eacs` colony of its \
own, `ils` from the best so far).

`cellseq solve F --explain` prints the features, the rule and its plan before solving; \
`CELLSEQ_TRACE=1` prints them and one line per phase on stderr. `--param plan=...` skips the \
rules: its phases run with the beam settings of the portfolio's last rule. Plan syntax: \
`solver[key=value;...]:share,...`, where the share is a fraction of what is left. After the \
name, `*` starts the phase from the best sequence so far and `+` from the previous phase's \
sequence; `~` before the name runs the phase on the instance travelled backwards (matrix \
instances; elsewhere the phase runs forwards). A solver named twice gets a new seed each time. \
Example: `cellseq solve F --param plan=local-search:0.3,eacs:0.5,ils*:1`. How the built-in \
rules were chosen: [notes/portfolio.md](../notes/portfolio.md).",
    ),
    (
        "as-given",
        "The order the instance was programmed in (its `as_given` order; else file \
order), repaired to respect precedence: the \"unoptimized\" baseline the papers compare \
against.",
    ),
    (
        "greedy",
        "Precedence-aware nearest neighbour: from the current cell, the cheapest next cell whose \
predecessors are all done. On geometric instances the candidates come from a k-d tree per \
tool, so 10^5 cells take well under a second. `randomize` makes it a randomized start for \
multi-start solvers.",
    ),
    (
        "greedy-edge",
        "Greedy matching: the cheapest links first (candidates from k-d trees), each accepted \
when it joins two chain ends without closing a cycle; the chains are then joined by nearest \
neighbour. Applies to geometric instances without precedence and with one tool; anything \
else gets `greedy`. On uniform strokes it reaches 0.91–0.93 × greedy's air length.",
    ),
    (
        "insertion",
        "Cheapest precedence-feasible insertion: cells in a topological order that takes those \
with more descendants first (ties at random, by `--seed`), each put into the cheapest place \
after its last predecessor. Order labels on a linked path answer \"after the predecessor?\" \
in O(1). On geometric instances the places tried are the `k` feasible ones next to nearby \
cells (grids of exits and entries); on matrix instances every place. On sparse random \
precedence (`uniform preds=1`) it reaches 0.61–0.67 × greedy's air at 2000–5000 cells, and \
it is what `local-search` starts from on geometric instances with precedence.",
    ),
    (
        "ils",
        "Iterated local search.

- **Kick**: a random feasible reorder of a window (`perturb=shuffle`), random segment swaps \
(`swap`), or ruin and recreate (`ruin`: strings of cells around a random cell removed and \
reinserted at their cheapest feasible places; `ruin-size`, `ruin-string`).
- **Repair**: Or-opt and SOP-3-exchange (both directions with `two-way`) from the cells the \
kick touched; on costs that read the same backwards also Lin–Kernighan chains of reversals \
(`lk`, `lk-depth`, `lk-breadth`) that may pass through up to `lk-max-viol` broken \
precedence pairs, each charged `lk-penalty` in the gain criterion, keeping only feasible \
prefixes. `shift-repair=K` ends every repair with the bounded-shift DP of Balas and \
Simonetti over the kicked span (the best reorder, with modes, in which no cell passes one \
that lay K or more places after it).
- **Crossover** (`cross`): each repaired kick is recombined with the best by partition \
crossover: the two sequences are cut wherever their prefixes hold the same cells and the \
cheapest feasible mix of segments is kept, in O(n).
- **Acceptance**: record-to-record, within `accept` above the best; a restart from the best \
after `restart` kicks without a gain.
- On instances whose cells have several modes (PCGTSPLIB), the polish of a new best adds \
window moves with modes (a cell moved inside a 5-position window while the modes around it \
are re-chosen); `window-repair=true` runs them in every repair as well.",
    ),
    (
        "atsp",
        "For asymmetric costs with little or no precedence (an asymmetric TSP as an open path).

- **Start**: the better of `greedy` and the assignment problem's solution (a dummy node \
closes the path) whose cycles are patched into one path (`patch=greedy`: the cheapest join of \
any two cycles first; `karp`: into the largest cycle); arcs no feasible order can use are left \
out, and a patched path that breaks the precedence is repaired by a topological sort that \
follows it. Above `ap-max-cells` no assignment is solved.
- **Search**: iterated Or-3opt (two adjacent blocks swap places, no reversal) on candidate \
lists ranked by the assignment's reduced costs (`cand=reduced`, ties by raw cost; `k` per \
cell), precedence checked on every move; kicks swap two blocks across a third (`kick=far`) \
or two adjacent blocks (`near`), of up to `kick-len` cells; equal-or-better results are \
accepted.
- `auto` runs it (the built-in portfolio's `free` rule) on asymmetric matrix instances whose \
`free_density` (the closure density apart from cells ordered against every other: a fixed \
start and end) is at most 0.001; notes/atsp.md has the measurements.",
    ),
    (
        "exact",
        "Held–Karp dynamic programming over precedence-closed subsets of cells, with modes: the \
optimum, proven. The number of precedence-closed subsets decides its memory; an instance \
whose tables would pass `memory_mb`, or with more than `max_cells` cells, is refused with an \
error rather than started.",
    ),
    (
        "beam",
        "The exact/anytime tree search, and the one that proves optimality on instances too large \
for `exact`.

- A short deterministic `ils` run (`warm_evals`) gives the incumbent.
- Iterative beam search over the precedence fringe: prefixes with the same visited set and \
last (cell, mode) are merged (prefix dominance), interchangeable cells are visited in index \
order (`twins`), and every prefix whose lower bound cannot beat the incumbent is pruned.
- Node bounds: the `sec` relaxation (assignment with Lagrangian subtour-elimination \
multipliers sharpened by precedence: each prefix is charged the prices of the sets it must \
still leave; `sec=false` falls back to the plain assignment duals), cluster bounds, and the \
`qpath` bound (a position-indexed path relaxation priced by Lagrange multipliers; \
`qpath=false` turns it off).
- Widths double per pass and grow ×`growth` from 1024; after the pass of width \
`exhaustive_from`, one pass without a width limit, stopped only by `memory_mb`.
- A pass that never had to drop a prefix for its width was exhaustive: the result is then \
reported as proven optimal. Within 60 s this proves ESC07–ESC63, br17.*, rbg048a, rbg050c, \
rbg109a, prob.42, p43.1–p43.4, ft53.4 and ry48p.4 (p43.2 the slowest, at about 55 s). \
`CELLSEQ_TRACE=1` prints each pass. Design: [notes/bounds.md](../notes/bounds.md).",
    ),
    (
        "reopt",
        "Window re-optimization (POPMUSIC with an exact sub-solver). Windows of `window` \
consecutive cells, `step` apart, are each made an instance of their own between the fixed \
cells either side and searched by `beam` from the window's order, so a window never gets \
worse. A later sweep has windows a quarter larger, centred where the last sweep could not \
prove its windows optimal, up to `max-window`; one window gets at most `window-share` of the \
budget, and a gain is polished by the VND. Alone it starts from `greedy`; in `auto` it ends \
the built-in portfolio's `sparse` rule, from the best so far. On rbg323a it turns `ils`'s 3141 into the optimum 3140.",
    ),
    (
        "two-opt",
        "`greedy`, then 2-opt with mode flip to a local optimum: a segment is reversed only when \
no precedence pair lies inside it and every cell in it may be cut backwards (reversed cells \
change mode).",
    ),
    (
        "local-search",
        "The workhorse improvement solver.

- **Start**: the better of `greedy` and `greedy-edge` (only `greedy-edge` above 50 000 \
cells where it applies) and, on geometric instances with precedence up to 200 000 cells, \
`insertion`.
- **From 200 000 cells**: first an Or-opt pass on a linked list (O(1) per move, precedence \
checked with order labels); `vnd=false` stops after it.
- **VND** over Or-opt, 2-opt, SOP-3-exchange (blocks up to `max-block`), mode change, the \
mode DP and, where cells have several modes (up to 5000 cells), window moves with modes; \
then iterated VND with `kicks` random Or-opt kicks of `strength` moves.
- **Large instances without precedence** (from 20 000 cells, on costs that read the same \
backwards: air length, or time without linking at cutting feed): the search runs on a \
two-level list instead (2-opt, Or-opt and mode moves at O(√n) each, then local double-bridge \
kicks with undo; `two-level`, `kick-block`), and one VND finishes. At 10^5 uniform cells it \
reaches 0.78 × greedy's air in 10 s; with sparse precedence, from the insertion start, \
0.715.",
    ),
    (
        "sa",
        "Simulated annealing as in paper 000: Metropolis acceptance over Markov chains of length \
`chain` × n per temperature, geometric cooling by `alpha` from a temperature at which an \
average worsening move is accepted with probability `accept0`, a stop after `stall` chains \
without a new best, re-annealing from the best (`reheats`), open- or closed-loop evaluation \
(`eval`), and a VND polish of the best (`polish`).",
    ),
    (
        "tabu",
        "Multi-start tabu search as in paper 004: each iteration takes one cell out with its \
entry/exit pair and re-inserts it at the best non-tabu place, possibly with the pair swapped \
(any mode of the cell), among places next to its `k` candidate neighbours inside its \
precedence window; a move that beats the best is allowed even when tabu (aspiration), and a \
moved cell stays tabu for `tenure` iterations. Starts: every ready start cell and mode first, then randomized greedy, up to \
`starts`.",
    ),
    (
        "aco",
        "Ant colony system after patent 003 and HAS-SOP: ants build sequences over the \
precedence fringe with a heuristic that charges tool changes, local and global pheromone \
updates on cell → cell arcs, local search on every ant, the iteration best or none (`ls`), \
and the mode DP.",
    ),
    (
        "eacs",
        "The enhanced ant colony system of Gambardella, Montemanni and Weyland: ants copy the \
best solution's successor with probability q0 = 1 − `s`/n; the local search (Or-opt, \
SOP-3-exchange searched forward and backward, 2-opt, the mode DP) runs only on ants within \
`ls-band` of the best and starts only from the cells whose neighbours differ from the best \
solution. Each ant's local optimum is recombined with the best by partition crossover \
(`cross`).",
    ),
    (
        "process",
        "Process-based sequencing as in paper 000: cells are grouped on four levels (cutter; the \
cutter's main working-step type against the supplementary ones; working-step type; layer), \
groups are ordered by the process scheme (cutter order, supplementary steps before the \
target group, layers top-down), and simulated annealing (the parameters of `sa`) reorders \
the cells inside each level-4 group.",
    ),
    (
        "rules",
        "The knowledge rules 1–5 of paper 002 (tool size, outer before inner, upper before lower, \
step order, symmetry) applied in turn, with no search: the papers' rule-based baseline.",
    ),
    (
        "drawing",
        "The default of `cellseq optimize` on SVG and DXF drawings: strokes are cells that may be \
drawn either way (and closed paths from any vertex). Greedy on k-d trees, then 2-opt with \
stroke reversal, Or-opt and start-vertex moves on candidate lists, then iterated local \
search until the budget. Other instances get `local-search`. Details: \
[drawings.md](drawings.md).",
    ),
];

/// The longer description of the solver `name` (Markdown), if the table has one.
pub fn details(name: &str) -> Option<&'static str> {
    DETAILS.iter().find(|(n, _)| *n == name).map(|(_, d)| *d)
}

/// A parameter kind as the listings show it: `int`, `float`, `bool`, `text`, or the choices
/// joined by `|`.
pub fn kind_label(kind: &ParamKind) -> String {
    match kind {
        ParamKind::Int => "int".to_string(),
        ParamKind::Float => "float".to_string(),
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
    if let Some(d) = details(s.name) {
        out.push_str(d.trim());
        out.push_str("\n\n");
    }
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
        "<!-- Generated from the solver registry (summaries and parameters in \
`src/solvers/*.rs`, descriptions in `src/solvers/docs.rs`) by \
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
    fn every_registered_solver_has_details_and_no_other_name_does() {
        let names: Vec<&str> = registry().iter().map(|s| s.name).collect();
        for n in &names {
            assert!(details(n).is_some(), "no entry for solver {n} in DETAILS");
        }
        for (n, _) in DETAILS {
            assert!(
                names.contains(n),
                "DETAILS names {n}, which is not registered"
            );
        }
        assert_eq!(DETAILS.len(), names.len(), "a solver is described twice");
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

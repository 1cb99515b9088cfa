//! LaTeX tables for papers, written by `cellseq report` beside the Markdown and CSV ones:
//! booktabs rules (`\toprule`, `\midrule`, `\bottomrule`), no vertical lines, numbers right
//! aligned with a real minus sign, every text cell escaped. Each file is a complete `table`
//! float to `\input`; it needs `\usepackage{booktabs}` in the preamble.

use std::fmt::Write as _;

/// Column alignment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Align {
    /// Text, left aligned.
    Left,
    /// Numbers, right aligned.
    Right,
}

/// A table: caption, label, header, and row groups separated by `\midrule`.
#[derive(Debug, Clone)]
pub struct Table {
    /// Caption (plain text; escaped when written).
    pub caption: String,
    /// `\label` key, e.g. `tab:summary`.
    pub label: String,
    /// Column titles (plain text) and alignments.
    pub columns: Vec<(String, Align)>,
    /// Groups of rows; cells are LaTeX already (use [`text`] and [`num`]).
    pub groups: Vec<Vec<Vec<String>>>,
}

/// Escapes plain text for LaTeX (`_`, `%`, `&`, `#`, `$`, `{`, `}`, `~`, `^`, `\`), and writes
/// `%`-style symbols and Unicode the report uses in a form pdfLaTeX accepts.
pub fn text(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '\\' => o.push_str(r"\textbackslash{}"),
            '&' | '%' | '$' | '#' | '_' | '{' | '}' => {
                o.push('\\');
                o.push(c);
            }
            '~' => o.push_str(r"\textasciitilde{}"),
            '^' => o.push_str(r"\textasciicircum{}"),
            '–' => o.push_str("--"),
            '−' => o.push_str("$-$"),
            '×' => o.push_str(r"$\times$"),
            '≤' => o.push_str(r"$\le$"),
            'τ' => o.push_str(r"$\tau$"),
            _ => o.push(c),
        }
    }
    o
}

/// A number for a table cell: `–` for NaN, 3 decimals (scientific beyond 10⁵ or below 10⁻³),
/// a math minus for negative values.
pub fn num(x: f64) -> String {
    if x.is_nan() {
        return "--".into();
    }
    if x.is_infinite() {
        return if x > 0.0 { r"$\infty$" } else { r"$-\infty$" }.into();
    }
    let a = x.abs();
    let body = if a != 0.0 && !(1e-3..1e5).contains(&a) {
        let mut e = a.log10().floor() as i32;
        let mut m = a / 10f64.powi(e);
        if m >= 9.995 {
            // 9.999e5 is 1.00e6, not 10.00e5
            m /= 10.0;
            e += 1;
        }
        format!("{m:.2}\\times 10^{{{e}}}")
    } else {
        format!("{a:.3}")
    };
    let neg = x < 0.0 && body.chars().any(|c| ('1'..='9').contains(&c));
    if body.contains("times") {
        format!("${}{body}$", if neg { "-" } else { "" })
    } else if neg {
        format!("$-${body}")
    } else {
        body
    }
}

/// Bold cell content.
pub fn bold(cell: &str) -> String {
    format!("\\textbf{{{cell}}}")
}

/// Rows above which a table is written as a `longtable` (breaks across pages, header repeated)
/// instead of a `table` float.
pub const LONG_ROWS: usize = 40;

/// Renders the table: a `table` float with a booktabs `tabular`, or, beyond [`LONG_ROWS`] rows,
/// a booktabs `longtable`.
pub fn render(t: &Table) -> String {
    let mut s = String::new();
    let spec: String = t
        .columns
        .iter()
        .map(|(_, a)| if *a == Align::Left { 'l' } else { 'r' })
        .collect();
    let head: Vec<String> = t.columns.iter().map(|(c, _)| text(c)).collect();
    let head = head.join(" & ");
    let long = t.groups.iter().map(Vec::len).sum::<usize>() > LONG_ROWS;
    let caption = text(&t.caption);
    if long {
        let _ = writeln!(
            s,
            "% Written by `cellseq report`; needs \\usepackage{{booktabs,longtable}}."
        );
        let _ = writeln!(s, "{{\\small\n\\begin{{longtable}}{{{spec}}}");
        let _ = writeln!(s, "\\caption{{{caption}}}\\label{{{}}} \\\\", t.label);
        let _ = writeln!(s, "\\toprule\n{head} \\\\\n\\midrule\n\\endfirsthead");
        let _ = writeln!(
            s,
            "\\multicolumn{{{}}}{{l}}{{\\emph{{(continued)}}}} \\\\\n\\toprule\n{head} \\\\\n\\midrule\n\\endhead",
            t.columns.len()
        );
        let _ = writeln!(s, "\\bottomrule\n\\endlastfoot");
    } else {
        let _ = writeln!(
            s,
            "% Written by `cellseq report`; needs \\usepackage{{booktabs}}."
        );
        let _ = writeln!(s, "\\begin{{table}}[htbp]\n\\centering\n\\small");
        let _ = writeln!(s, "\\caption{{{caption}}}");
        let _ = writeln!(s, "\\label{{{}}}", t.label);
        let _ = writeln!(s, "\\begin{{tabular}}{{{spec}}}\n\\toprule");
        let _ = writeln!(s, "{head} \\\\\n\\midrule");
    }
    for (g, rows) in t.groups.iter().enumerate() {
        if g > 0 {
            let _ = writeln!(s, "\\midrule");
        }
        for r in rows {
            let mut cells = r.clone();
            cells.resize(t.columns.len(), String::new());
            let _ = writeln!(s, "{} \\\\", cells.join(" & "));
        }
    }
    if long {
        let _ = writeln!(s, "\\end{{longtable}}\n}}");
    } else {
        let _ = writeln!(s, "\\bottomrule\n\\end{{tabular}}\n\\end{{table}}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_numbers() {
        assert_eq!(text("a_b 5 % & #1"), r"a\_b 5 \% \& \#1");
        assert_eq!(
            text(r"x\y~^{}"),
            r"x\textbackslash{}y\textasciitilde{}\textasciicircum{}\{\}"
        );
        assert_eq!(num(1.5), "1.500");
        assert_eq!(num(-2.25), "$-$2.250");
        assert_eq!(num(-0.0001), "$-1.00\\times 10^{-4}$");
        assert_eq!(num(123456.0), "$1.23\\times 10^{5}$");
        assert_eq!(num(f64::NAN), "--");
        assert_eq!(num(-0.0), "0.000");
    }

    #[test]
    fn renders_booktabs_with_a_cell_per_column() {
        let t = Table {
            caption: "Costs (mean) & 95 % CI".into(),
            label: "tab:x".into(),
            columns: vec![
                ("solver_id".into(), Align::Left),
                ("mean".into(), Align::Right),
            ],
            groups: vec![
                vec![vec![text("greedy"), num(1.0)]],
                vec![vec![text("two-opt"), bold(&num(0.5))]],
            ],
        };
        let s = render(&t);
        assert!(
            s.contains("\\begin{tabular}{lr}\n\\toprule\nsolver\\_id & mean \\\\\n\\midrule\n")
        );
        assert!(s.contains(
            "greedy & 1.000 \\\\\n\\midrule\ntwo-opt & \\textbf{0.500} \\\\\n\\bottomrule"
        ));
        assert!(s.contains("\\caption{Costs (mean) \\& 95 \\% CI}"));
        assert!(!s.contains('|'));
        let long = Table {
            groups: vec![
                (0..=LONG_ROWS)
                    .map(|k| vec![k.to_string(), num(1.0)])
                    .collect(),
            ],
            ..t
        };
        let s = render(&long);
        assert!(s.contains("\\begin{longtable}{lr}") && s.contains("\\endhead"));
        assert_eq!(s.matches(" \\\\\n").count(), LONG_ROWS + 1 + 4);
    }
}

// ---------------------------------------------------------------------------------------------
// The report's tables

use super::report::{SummaryRow, TestRow};

/// One line of the per-solver overview.
#[derive(Debug, Clone)]
pub struct SolverLine {
    /// Solver id.
    pub solver: String,
    /// Feasible trials.
    pub ok: usize,
    /// Trials.
    pub runs: usize,
    /// Mean reduction against as-given, %.
    pub mean_red: f64,
    /// Median reduction, %.
    pub median_red: f64,
    /// Mean lifts.
    pub lifts: f64,
    /// Mean tool changes.
    pub tool_changes: f64,
    /// Mean wall seconds.
    pub wall: f64,
}

/// Per instance and solver: mean, median, best, std, 95 % CI, reduction, lifts, gap to the best
/// known; the lowest mean of each instance in bold.
pub fn summary_table(rows: &[SummaryRow], objective: &str) -> Table {
    let mut groups: Vec<Vec<Vec<String>>> = Vec::new();
    let mut k = 0;
    while k < rows.len() {
        let inst = &rows[k].instance;
        let end = k + rows[k..].iter().take_while(|r| &r.instance == inst).count();
        let best = rows[k..end]
            .iter()
            .map(|r| r.mean)
            .filter(|m| m.is_finite())
            .fold(f64::INFINITY, f64::min);
        let g = rows[k..end]
            .iter()
            .enumerate()
            .map(|(j, r)| {
                let mean = num(r.mean);
                vec![
                    if j == 0 {
                        text(&r.instance)
                    } else {
                        String::new()
                    },
                    text(&r.solver),
                    format!("{}/{}", r.feasible, r.runs),
                    if r.mean == best { bold(&mean) } else { mean },
                    num(r.median),
                    num(r.best),
                    num(r.std),
                    format!("[{}, {}]", num(r.ci95_lo), num(r.ci95_hi)),
                    num(r.reduction_pct),
                    num(r.lifts),
                    num(r.gap_bks_pct),
                ]
            })
            .collect();
        groups.push(g);
        k = end;
    }
    let cols = [
        ("instance", Align::Left),
        ("solver", Align::Left),
        ("ok/runs", Align::Right),
        ("mean", Align::Right),
        ("median", Align::Right),
        ("best", Align::Right),
        ("std", Align::Right),
        ("95 % CI of the mean", Align::Right),
        ("red. %", Align::Right),
        ("lifts", Align::Right),
        ("gap bks %", Align::Right),
    ];
    Table {
        caption: format!(
            "Cost ({objective}) per instance and solver; lowest mean per instance in bold; \
             CI: percentile bootstrap; red.: reduction against the as-given order; \
             gap bks: to the best known value."
        ),
        label: "tab:cellseq-summary".into(),
        columns: cols.iter().map(|(c, a)| (c.to_string(), *a)).collect(),
        groups,
    }
}

/// Per solver over every instance.
pub fn solver_table(lines: &[SolverLine]) -> Table {
    let cols = [
        ("solver", Align::Left),
        ("ok/runs", Align::Right),
        ("mean red. %", Align::Right),
        ("median red. %", Align::Right),
        ("mean lifts", Align::Right),
        ("mean tool changes", Align::Right),
        ("mean wall s", Align::Right),
    ];
    Table {
        caption: "Per solver over all instances: reduction against the as-given order, lifts, \
                  tool changes and wall time (machine-dependent)."
            .into(),
        label: "tab:cellseq-solvers".into(),
        columns: cols.iter().map(|(c, a)| (c.to_string(), *a)).collect(),
        groups: vec![
            lines
                .iter()
                .map(|l| {
                    vec![
                        text(&l.solver),
                        format!("{}/{}", l.ok, l.runs),
                        num(l.mean_red),
                        num(l.median_red),
                        num(l.lifts),
                        num(l.tool_changes),
                        num(l.wall),
                    ]
                })
                .collect(),
        ],
    }
}

/// Wilcoxon signed-rank tests against the reference: the pooled rows, then per instance.
pub fn wilcoxon_table(pooled: &[TestRow], per_instance: &[TestRow], reference: &str) -> Table {
    let line = |t: &TestRow| {
        vec![
            text(&t.instance),
            text(&t.solver),
            t.pairs.to_string(),
            num(t.mean_diff),
            num(t.v),
            num(t.p),
            num(t.p_holm),
            text(&t.verdict),
        ]
    };
    let cols = [
        ("instance", Align::Left),
        ("solver", Align::Left),
        ("pairs", Align::Right),
        ("mean diff.", Align::Right),
        ("V", Align::Right),
        ("p", Align::Right),
        ("p (Holm)", Align::Right),
        ("verdict", Align::Left),
    ];
    Table {
        caption: format!(
            "Paired two-sided Wilcoxon signed-rank tests of each solver's cost against {reference} \
             (pairs: replicates of an instance; ALL pools every instance); Holm correction; \
             better/worse at the 5 % level."
        ),
        label: "tab:cellseq-wilcoxon".into(),
        columns: cols.iter().map(|(c, a)| (c.to_string(), *a)).collect(),
        groups: [pooled, per_instance]
            .iter()
            .filter(|g| !g.is_empty())
            .map(|g| g.iter().map(line).collect())
            .collect(),
    }
}

/// Friedman average ranks (1 = best) with the test's statistic in the caption.
pub fn friedman_table(
    ranks: &[(String, f64)],
    statistic: f64,
    df: f64,
    p: f64,
    blocks: usize,
) -> Table {
    Table {
        caption: format!(
            "Average Friedman rank per solver (1 = best) over {blocks} instances; \
             chi-squared = {}, df = {df:.0}, p = {}.",
            num_plain(statistic),
            num_plain(p)
        ),
        label: "tab:cellseq-friedman".into(),
        columns: vec![
            ("solver".into(), Align::Left),
            ("average rank".into(), Align::Right),
        ],
        groups: vec![ranks.iter().map(|(s, r)| vec![text(s), num(*r)]).collect()],
    }
}

/// A number for running text (a caption): like [`num`], unescaped when plain.
fn num_plain(x: f64) -> String {
    if x.is_finite() && (x == 0.0 || (1e-3..1e5).contains(&x.abs())) {
        format!("{x:.3}")
    } else {
        format!("{x:.3e}")
    }
}

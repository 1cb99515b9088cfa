//! Splitting one RS-274 line into words, with comments removed, parameters and expressions
//! evaluated (see [`super::expr`]).

use super::expr::{self, Cursor, Param, Params};

/// One parsed line: its words (upper-case letter, value) and whether it had any text.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Words {
    /// The words in line order, line number (`N`) excluded.
    pub words: Vec<(char, f64)>,
    /// The line number word, if any.
    pub n: Option<f64>,
    /// True when the line held a comment.
    pub has_comment: bool,
    /// True for a controller system line (GRBL `$X`, `$H`, `$$`…), carried through as is.
    pub dialect: bool,
    /// True for GRBL's homing cycle `$H` (the position is unknown afterwards).
    pub homing: bool,
    /// True for a program-number line (`O1001`, `O01001 (NAME)`): kept in place, no effect.
    pub program_number: bool,
    /// Parameter settings on the line (`#1=6.35`, `#<depth>=-2`), in line order, with the
    /// values they were given; they take effect after the whole line is read.
    pub assigns: Vec<(Param, f64)>,
    /// True when a word's value came from a parameter, an expression or a function: the line
    /// is written back with its evaluated numbers ([`Words::evaluated`]).
    pub computed: bool,
}

impl Words {
    /// All values of a letter.
    pub fn all(&self, c: char) -> impl Iterator<Item = f64> + '_ {
        self.words.iter().filter(move |w| w.0 == c).map(|w| w.1)
    }
    /// The value of a letter that may appear at most once.
    pub fn get(&self, c: char) -> Option<f64> {
        self.all(c).next()
    }
    /// True when a letter appears.
    pub fn has(&self, c: char) -> bool {
        self.words.iter().any(|w| w.0 == c)
    }
    /// True when the G code `code` (e.g. 90.1) appears.
    pub fn has_g(&self, code: f64) -> bool {
        self.all('G').any(|g| (g - code).abs() < 1e-6)
    }
    /// True when the M code appears.
    pub fn has_m(&self, code: f64) -> bool {
        self.all('M').any(|g| (g - code).abs() < 1e-6)
    }
    /// True when the line has no words.
    pub fn is_empty(&self) -> bool {
        self.words.is_empty()
    }

    /// The line as it is written when its values were computed: the line number, the words
    /// and parameter settings with the numbers they had in the original (each value exactly,
    /// shortest form), then the original's comments. Where a line is written, its motion is
    /// then the original's whatever parameters are in force there.
    pub fn evaluated(&self, original: &str) -> String {
        let mut s = String::new();
        if let Some(n) = self.n {
            s.push_str(&format!("N{} ", exact(n)));
        }
        for &(c, v) in &self.words {
            s.push_str(&format!("{c}{} ", exact(v)));
        }
        for (p, v) in &self.assigns {
            s.push_str(&format!("{p}={} ", exact(*v)));
        }
        for c in comments(original) {
            s.push_str(c);
            s.push(' ');
        }
        s.truncate(s.trim_end().len());
        s
    }
}

/// A number in its shortest exact form, never in exponent form (what G-code reads).
pub fn exact(v: f64) -> String {
    let s = format!("{v}");
    if s == "-0" { "0".into() } else { s }
}

/// The comments of a line (`( … )` groups and a `;` tail), as written.
fn comments(line: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, ch) in line.char_indices() {
        match (ch, start) {
            ('(', None) => start = Some(i),
            (')', Some(s)) => {
                out.push(&line[s..=i]);
                start = None;
            }
            (';', None) => {
                out.push(&line[i..]);
                break;
            }
            _ => {}
        }
    }
    out
}

/// The line with every whitespace character outside comments made an ASCII space (LinuxCNC
/// refuses U+00A0, U+0085, U+2028, a carriage return inside a line … with "Bad character"), and
/// an error for any other non-ASCII or control character outside comments. Comments (`( … )`,
/// `;` to the end) are kept as they are: LinuxCNC accepts any character there.
pub fn normalize(line: &str) -> Result<std::borrow::Cow<'_, str>, String> {
    let odd = |c: char| !c.is_ascii() || (c.is_ascii_control() && c != '\t');
    if !line.chars().any(odd) {
        return Ok(std::borrow::Cow::Borrowed(line));
    }
    let mut out = String::with_capacity(line.len());
    let mut depth = 0usize;
    let mut rest_comment = false;
    for c in line.chars() {
        let in_comment = rest_comment || depth > 0 || c == ')';
        match c {
            '(' if !rest_comment => depth += 1,
            ')' if depth > 0 => depth -= 1,
            ';' if depth == 0 => rest_comment = true,
            _ => {}
        }
        if in_comment || c == '(' || c == ';' || !odd(c) {
            out.push(c);
        } else if c.is_whitespace() {
            out.push(' ');
        } else {
            return Err(format!(
                "character {c:?} (U+{:04X}) outside a comment: controllers refuse it (\"Bad \
                 character\"); remove it or put it in a comment",
                c as u32
            ));
        }
    }
    Ok(std::borrow::Cow::Owned(out))
}

/// Tokenizes a line, evaluating parameters and expressions with `params` (the parameters the
/// program has set before this line) and applying the line's parameter settings to them
/// afterwards. Errors name the problem (the caller adds file and line).
///
/// Handles `( … )` and `;` comments, `%` lines, spaces inside words, lower case, program
/// numbers (`O1001`). Refuses O-word control flow (`o100 sub`, `call`, `if`, `while`,
/// `repeat` …) and block delete `/`: cellseq does not expand them, and skipping them would
/// silently change the program.
pub fn tokenize(line: &str, params: &mut Params) -> Result<Words, String> {
    let mut out = Words::default();
    let trimmed = line.trim();
    if trimmed == "%" || trimmed.is_empty() {
        return Ok(out);
    }
    if let Some(rest) = trimmed.strip_prefix('$') {
        let rest = rest.trim_start().to_ascii_uppercase();
        if rest.starts_with('J') {
            return Err(
                "GRBL jog line '$J=' moves the machine in a way cellseq does not follow; \
                        remove it or run it by hand"
                    .into(),
            );
        }
        out.dialect = true;
        out.homing = rest.starts_with('H');
        return Ok(out);
    }
    let code = strip_comments(line, &mut out)?;
    let code: String = code
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect::<String>()
        .to_ascii_lowercase();
    let mut c = Cursor::new(code.as_bytes());
    let mut assigns: Vec<(Param, f64)> = Vec::new();
    while let Some(b) = c.peek() {
        match b {
            b'#' => assigns.push(expr::setting(&mut c, params)?),
            b'o' if out.words.is_empty() && assigns.is_empty() => {
                program_number(&mut c)?;
                out.program_number = true;
            }
            b'o' => {
                return Err(
                    "an O-word inside a line; O-words (program numbers) must start their line"
                        .into(),
                );
            }
            b'/' => return Err("block delete '/' is not supported; remove the '/' lines or the '/' marks and try again".into()),
            b'a'..=b'z' => {
                c.i += 1;
                let letter = (b as char).to_ascii_uppercase();
                let v = expr::value(&mut c, params)
                    .map_err(|e| format!("word '{letter}': {e}"))?;
                if letter == 'N' {
                    if out.n.is_some() || !out.words.is_empty() {
                        return Err("line number N must come first, once".into());
                    }
                    out.n = Some(v);
                } else {
                    out.words.push((letter, v));
                }
            }
            _ => return Err(format!("unexpected character '{}'", b as char)),
        }
    }
    out.computed = c.computed;
    for (p, v) in &assigns {
        params.set(p.clone(), *v);
    }
    out.assigns = assigns;
    Ok(out)
}

/// The line without its comments (noting that it had one), refusing unbalanced ones.
fn strip_comments(line: &str, out: &mut Words) -> Result<String, String> {
    let mut code = String::with_capacity(line.len());
    let mut depth = 0usize;
    for ch in line.chars() {
        match ch {
            '(' => {
                depth += 1;
                out.has_comment = true;
                if depth > 1 {
                    return Err("nested comment".into());
                }
            }
            ')' if depth > 0 => depth -= 1,
            ')' => return Err("unbalanced ')'".into()),
            ';' if depth == 0 => {
                out.has_comment = true;
                break;
            }
            _ if depth > 0 => {}
            _ => code.push(ch),
        }
    }
    if depth > 0 {
        return Err("unclosed comment".into());
    }
    Ok(code)
}

/// An O-word at the start of a line: a program number alone on its line (Fanuc, Haas, Mach3
/// `O1001`, `O01001 (NAME)`) is accepted; O-word control flow and a number followed by other
/// words are refused, naming the construct.
fn program_number(c: &mut Cursor) -> Result<(), String> {
    const KEYWORDS: [&str; 15] = [
        "sub",
        "endsub",
        "call",
        "do",
        "while",
        "endwhile",
        "if",
        "elseif",
        "else",
        "endif",
        "break",
        "continue",
        "repeat",
        "endrepeat",
        "return",
    ];
    let all = c.rest();
    c.i += 1;
    let name_end = if c.peek() == Some(b'<') {
        all.find('>').map(|k| k + 1).unwrap_or(all.len())
    } else {
        1 + all[1..]
            .find(|ch: char| !(ch.is_ascii_digit() || ch == '.'))
            .unwrap_or(all.len() - 1)
    };
    let (name, rest) = all.split_at(name_end);
    let name = name.to_ascii_uppercase();
    if let Some(k) = KEYWORDS.iter().find(|k| rest.starts_with(*k)) {
        return Err(format!(
            "O-word control flow '{name} {k}' (subroutines, calls, loops, conditionals) is not \
             supported: expand it into straight-line G-code first (the program without \
             O-words), or run the program as it is"
        ));
    }
    if name.len() < 2 || name.starts_with("O<") || name[1..].parse::<f64>().is_err() {
        return Err(format!(
            "O-word '{name}' is neither a program number nor a control-flow line; remove it"
        ));
    }
    if !rest.is_empty() {
        return Err(format!(
            "program number {name} followed by other words on its line (LinuxCNC refuses it: \
             \"Unknown control command in o word\"); put the words on a line of their own"
        ));
    }
    c.i = c.i - 1 + all.len();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_comments() {
        let t = |l: &str| tokenize(l, &mut Params::default());
        let w = t("N10 g1 x1.5 Y-.5 (cut) F 100 ; tail").unwrap();
        assert_eq!(w.n, Some(10.0));
        assert_eq!(
            w.words,
            vec![('G', 1.0), ('X', 1.5), ('Y', -0.5), ('F', 100.0)]
        );
        assert!(w.has_comment);
        assert!(t("G1 X#1").is_err());
        assert!(t("o100 sub").is_err());
        assert!(t("G1 X(").is_err());
        assert!(t("G1 X").is_err());
        assert!(t("$H").unwrap().homing);
        assert!(t("$X").unwrap().dialect);
        assert!(t("$J=G91 X1 F100").is_err());
    }

    #[test]
    fn program_numbers_are_accepted_control_flow_is_refused() {
        let t = |l: &str| tokenize(l, &mut Params::default());
        for ok in ["O1001 (NAME)", "O01001", "o 1003", "N5 O2"] {
            let w = t(ok).unwrap();
            assert!(w.program_number && w.words.is_empty(), "{ok}");
        }
        for (bad, says) in [
            ("o100 sub", "'O100 sub'"),
            ("O100 call [1] [2]", "'O100 call'"),
            ("o<loop> while [#1 LT 3]", "'O<LOOP> while'"),
            ("o101 endif", "'O101 endif'"),
            ("O1001 G21 G0 X2", "followed by other words"),
            ("G0 X1 O5", "inside a line"),
        ] {
            let e = t(bad).map(|_| ()).unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
    }

    #[test]
    fn parameters_take_effect_after_the_line() {
        let mut p = Params::default();
        let w = tokenize("#1 = 6.350 #2=[#1*2]", &mut p);
        // #1 is not set yet while the line is read
        assert!(w.is_err());
        let mut p = Params::default();
        tokenize("#1 = 6.350", &mut p).unwrap();
        let w = tokenize("G1 Z-#1 X[#1 * 0.5] #1=2 (c1) ; tail", &mut p).unwrap();
        assert_eq!(w.words, vec![('G', 1.0), ('Z', -6.35), ('X', 3.175)]);
        assert!(w.computed);
        assert_eq!(
            w.evaluated("G1 Z-#1 X[#1 * 0.5] #1=2 (c1) ; tail"),
            "G1 Z-6.35 X3.175 #1=2 (c1) ; tail"
        );
        let w = tokenize("G1 X#1", &mut p).unwrap();
        assert_eq!(w.words[1], ('X', 2.0));
        let w = tokenize("#<Depth> = -1.5", &mut p).unwrap();
        assert!(!w.computed && w.assigns.len() == 1);
        assert_eq!(
            tokenize("Z#<depth>", &mut p).unwrap().words,
            vec![('Z', -1.5)]
        );
        assert!(tokenize("#5221 = 3", &mut p).is_err());
    }

    #[test]
    fn unicode_whitespace_is_made_ascii_outside_comments() {
        assert_eq!(
            normalize("G1\u{a0}X1 (caf\u{e9}\u{a0})").unwrap(),
            "G1 X1 (caf\u{e9}\u{a0})"
        );
        assert_eq!(normalize("G\r1 X\u{2028}2\u{85}").unwrap(), "G 1 X 2 ");
        assert_eq!(normalize("G1 X1 ; \u{e9}").unwrap(), "G1 X1 ; \u{e9}");
        assert!(normalize("G1 X\u{e9}1").is_err());
        assert!(normalize("G1 X1\0").is_err());
    }
}

//! Splitting one RS-274 line into words, with comments removed.

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

/// Tokenizes a line. Errors name the problem (the caller adds file and line).
///
/// Handles `( … )` and `;` comments, `%` lines, spaces inside words, lower case. Refuses `#`
/// parameters, `[ … ]` expressions, O-words and block delete `/`: cellseq does not expand them,
/// and skipping them would silently change the program.
pub fn tokenize(line: &str) -> Result<Words, String> {
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
    // strip comments
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
    let chars: Vec<char> = code.chars().filter(|c| !c.is_whitespace()).collect();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i].to_ascii_uppercase();
        match c {
            '#' => return Err("'#' parameters are not supported (expand them first)".into()),
            '[' | ']' => return Err("expressions '[...]' are not supported".into()),
            'O' => return Err("O-words (subroutines, program numbers) are not supported (expand them first)".into()),
            '/' => return Err("block delete '/' is not supported; remove the '/' lines or the '/' marks and try again".into()),
            'A'..='Z' => {}
            _ => return Err(format!("unexpected character '{}'", chars[i])),
        }
        i += 1;
        let start = i;
        while i < chars.len() && (chars[i].is_ascii_digit() || matches!(chars[i], '.' | '-' | '+'))
        {
            i += 1;
        }
        let num: String = chars[start..i].iter().collect();
        let v: f64 = num
            .parse()
            .map_err(|_| format!("word '{c}' has no valid number ('{num}')"))?;
        if !v.is_finite() {
            return Err(format!("word '{c}' has a non-finite value"));
        }
        if c == 'N' {
            if out.n.is_some() || !out.words.is_empty() {
                return Err("line number N must come first, once".into());
            }
            out.n = Some(v);
        } else {
            out.words.push((c, v));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_and_comments() {
        let w = tokenize("N10 g1 x1.5 Y-.5 (cut) F 100 ; tail").unwrap();
        assert_eq!(w.n, Some(10.0));
        assert_eq!(
            w.words,
            vec![('G', 1.0), ('X', 1.5), ('Y', -0.5), ('F', 100.0)]
        );
        assert!(w.has_comment);
        assert!(tokenize("G1 X#1").is_err());
        assert!(tokenize("o100 sub").is_err());
        assert!(tokenize("G1 X(").is_err());
        assert!(tokenize("G1 X").is_err());
        assert!(tokenize("$H").unwrap().homing);
        assert!(tokenize("$X").unwrap().dialect);
        assert!(tokenize("$J=G91 X1 F100").is_err());
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

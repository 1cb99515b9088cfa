//! Parameters and expressions as LinuxCNC reads them in straight-line code: numbered (`#1`)
//! and named (`#<depth>`, `#<_global>`) parameters, `[ … ]` expressions with LinuxCNC's
//! operators and precedence, and the unary functions (trigonometry in degrees).
//!
//! The rules followed (LinuxCNC's `interp_read.cc` / `interp_execute.cc`):
//! - a value is a number, `#` parameter, `[expression]`, unary function, or `+`/`-` before
//!   one of those;
//! - binary operators by precedence, left to right within one level: `**`; `*` `/` `MOD`;
//!   `+` `-`; `EQ` `NE` `GT` `GE` `LT` `LE` (equal within 10⁻⁴, as LinuxCNC 2.9); `AND` `OR` `XOR`;
//! - `/` by zero, `**` of a negative base to a non-integer power, `SQRT` of a negative,
//!   `LN` of a non-positive, `ACOS`/`ASIN` outside [-1, 1] and any result that is not a finite
//!   number are errors; `MOD` is always non-negative; `ROUND` rounds half away from zero;
//! - parameter assignments on a line take effect after the whole line is read.
//!
//! What LinuxCNC takes from its own memory is refused, since a program that relies on it does
//! not say what it cuts: reading a parameter the program has not set (numbered ones start at
//! 0 only on a fresh controller, named ones are undefined), the system parameters from 5000
//! up (offsets, positions, tool data) and the predefined `#<_…>` names.

use std::collections::HashMap;

/// The largest parameter number LinuxCNC has (`RS274NGC_MAX_PARAMETERS` − 1).
pub const MAX_PARAMETER: u32 = 5601;
/// Numbered parameters from here up are the controller's (coordinate systems, tool data,
/// positions): refused.
pub const FIRST_SYSTEM_PARAMETER: u32 = 5000;

/// A parameter: numbered or named (names lower case, as LinuxCNC folds them).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Param {
    /// `#n`.
    Num(u32),
    /// `#<name>`.
    Named(String),
}

impl std::fmt::Display for Param {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Param::Num(n) => write!(f, "#{n}"),
            Param::Named(s) => write!(f, "#<{s}>"),
        }
    }
}

/// The parameters a program has set so far.
#[derive(Debug, Clone, Default)]
pub struct Params {
    values: HashMap<Param, f64>,
}

impl Params {
    /// The value of `p`, refused when the program has not set it.
    pub fn get(&self, p: &Param) -> Result<f64, String> {
        if let Some(v) = self.values.get(p) {
            return Ok(*v);
        }
        Err(match p {
            Param::Num(n) if *n >= FIRST_SYSTEM_PARAMETER => format!(
                "parameter #{n} is a system parameter (offsets, tool data, positions): its value \
                 is the controller's, not the program's; replace it with the number it stands for"
            ),
            Param::Named(s) if s.starts_with('_') => format!(
                "parameter #<{s}> is read before the program sets it: it may be one of the \
                 controller's predefined parameters, whose value the program does not give; \
                 set it in the program or replace it with its value"
            ),
            _ => format!(
                "parameter {p} is read before the program sets it: its value is whatever the \
                 controller holds; set it in the program first"
            ),
        })
    }

    /// Sets `p` (after the line that assigns it has been read).
    pub fn set(&mut self, p: Param, v: f64) {
        self.values.insert(p, v);
    }

    /// True when the program has set `p`.
    pub fn has(&self, p: &Param) -> bool {
        self.values.contains_key(p)
    }
}

/// A cursor over a line made lower case, without whitespace and comments.
pub struct Cursor<'a> {
    s: &'a [u8],
    /// Position in `s`.
    pub i: usize,
    /// Set when a parameter, expression or function was evaluated.
    pub computed: bool,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `s` (lower case, no whitespace).
    pub fn new(s: &'a [u8]) -> Self {
        Cursor {
            s,
            i: 0,
            computed: false,
        }
    }
    /// The byte at the cursor.
    pub fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }
    fn at(&self, k: usize) -> Option<u8> {
        self.s.get(self.i + k).copied()
    }
    fn starts(&self, w: &str) -> bool {
        self.s[self.i..].starts_with(w.as_bytes())
    }
    /// True at the end of the line.
    pub fn done(&self) -> bool {
        self.i >= self.s.len()
    }
    fn expect(&mut self, c: u8, what: &str) -> Result<(), String> {
        if self.peek() == Some(c) {
            self.i += 1;
            Ok(())
        } else {
            Err(format!("expected '{}' {what}", c as char))
        }
    }
    /// The rest of the line from the cursor, for messages.
    pub fn rest(&self) -> String {
        String::from_utf8_lossy(&self.s[self.i..]).into_owned()
    }
}

/// Reads a value (number, parameter, expression, unary function, signed value) as LinuxCNC's
/// `read_real_value` does.
pub fn value(c: &mut Cursor, p: &Params) -> Result<f64, String> {
    let v = match (c.peek(), c.at(1)) {
        (None, _) => return Err("a word without a value".into()),
        (Some(b'['), _) => {
            c.computed = true;
            expression(c, p)?
        }
        (Some(b'#'), _) => {
            c.computed = true;
            let k = param(c, p)?;
            p.get(&k)?
        }
        (Some(s @ (b'+' | b'-')), Some(n)) if !n.is_ascii_digit() && n != b'.' => {
            c.i += 1;
            let v = value(c, p)?;
            if s == b'-' { -v } else { v }
        }
        (Some(b'a'..=b'z'), _) => {
            c.computed = true;
            unary(c, p)?
        }
        _ => number(c)?,
    };
    if !v.is_finite() {
        return Err("the calculation gives a value that is not a finite number".into());
    }
    Ok(v)
}

/// A plain number: optional signs, digits and a point (no exponent).
fn number(c: &mut Cursor) -> Result<f64, String> {
    let start = c.i;
    while matches!(c.peek(), Some(b'+' | b'-')) {
        c.i += 1;
    }
    while matches!(c.peek(), Some(b'0'..=b'9' | b'.')) {
        c.i += 1;
    }
    let t = String::from_utf8_lossy(&c.s[start..c.i]).into_owned();
    t.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("bad number '{t}'"))
}

/// After `#`: the parameter named (`<name>`) or numbered (a value, rounded like LinuxCNC's
/// integer reads; `##1` reads indirectly).
pub fn param(c: &mut Cursor, p: &Params) -> Result<Param, String> {
    c.expect(b'#', "")?;
    if c.peek() == Some(b'<') {
        c.i += 1;
        let start = c.i;
        while c.peek().is_some_and(|b| b != b'>') {
            c.i += 1;
        }
        let name = String::from_utf8_lossy(&c.s[start..c.i]).into_owned();
        c.expect(b'>', "to close a parameter name")?;
        if name.is_empty() {
            return Err("empty parameter name '#<>'".into());
        }
        return Ok(Param::Named(name));
    }
    let v = value(c, p)?;
    let n = v.round();
    if (v - n).abs() > 1e-4 {
        return Err(format!("parameter number {v} is not an integer"));
    }
    if !(1.0..=MAX_PARAMETER as f64).contains(&n) {
        return Err(format!(
            "parameter number {n} is out of range (1 to {MAX_PARAMETER})"
        ));
    }
    Ok(Param::Num(n as u32))
}

/// A binary operator: its precedence (LinuxCNC's) and how it applies.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Op {
    Pow,
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

impl Op {
    fn precedence(self) -> u8 {
        match self {
            Op::Pow => 6,
            Op::Mul | Op::Div | Op::Mod => 5,
            Op::Add | Op::Sub => 4,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 3,
            Op::And | Op::Or | Op::Xor => 2,
        }
    }

    fn apply(self, a: f64, b: f64) -> Result<f64, String> {
        // LinuxCNC 2.9 (the Debian `rs274`): equal within 10⁻⁴ (later versions: 10⁻⁶)
        const TOL: f64 = 1e-4;
        let t = |x: bool| if x { 1.0 } else { 0.0 };
        Ok(match self {
            Op::Pow => {
                if a < 0.0 && b.floor() != b {
                    return Err("a negative number raised to a non-integer power".into());
                }
                a.powf(b)
            }
            Op::Mul => a * b,
            Op::Div => {
                if b == 0.0 {
                    return Err("division by zero".into());
                }
                a / b
            }
            Op::Mod => {
                let m = a % b;
                if m < 0.0 { m + b.abs() } else { m }
            }
            Op::Add => a + b,
            Op::Sub => a - b,
            Op::Eq => t((a - b).abs() < TOL),
            Op::Ne => t((a - b).abs() >= TOL),
            Op::Gt => t(a > b),
            Op::Ge => t((a - b).abs() < TOL || a >= b),
            Op::Lt => t(a < b),
            Op::Le => t((a - b).abs() < TOL || a <= b),
            Op::And => t(a != 0.0 && b != 0.0),
            Op::Or => t(a != 0.0 || b != 0.0),
            Op::Xor => t((a == 0.0) != (b == 0.0)),
        })
    }
}

/// The operator at the cursor, or `None` at `]`.
fn operator(c: &mut Cursor) -> Result<Option<Op>, String> {
    const NAMED: [(&str, Op); 15] = [
        ("**", Op::Pow),
        ("*", Op::Mul),
        ("/", Op::Div),
        ("mod", Op::Mod),
        ("+", Op::Add),
        ("-", Op::Sub),
        ("eq", Op::Eq),
        ("ne", Op::Ne),
        ("gt", Op::Gt),
        ("ge", Op::Ge),
        ("lt", Op::Lt),
        ("le", Op::Le),
        ("and", Op::And),
        ("or", Op::Or),
        ("xor", Op::Xor),
    ];
    if c.peek() == Some(b']') {
        c.i += 1;
        return Ok(None);
    }
    for (name, op) in NAMED {
        if c.starts(name) {
            c.i += name.len();
            return Ok(Some(op));
        }
    }
    match c.peek() {
        None => Err("unclosed expression: ']' missing".into()),
        Some(_) => Err(format!("unknown operator at '{}'", c.rest())),
    }
}

/// `[ … ]`: operands and operators reduced by precedence, left to right within a level.
fn expression(c: &mut Cursor, p: &Params) -> Result<f64, String> {
    c.expect(b'[', "")?;
    let mut vals = vec![value(c, p)?];
    let mut ops: Vec<Op> = Vec::new();
    let reduce = |vals: &mut Vec<f64>, ops: &mut Vec<Op>| -> Result<(), String> {
        let op = ops.pop().expect("an operator to reduce");
        let b = vals.pop().expect("a right operand");
        let a = vals.pop().expect("a left operand");
        vals.push(op.apply(a, b)?);
        Ok(())
    };
    while let Some(op) = operator(c)? {
        while ops
            .last()
            .is_some_and(|top| top.precedence() >= op.precedence())
        {
            reduce(&mut vals, &mut ops)?;
        }
        ops.push(op);
        vals.push(value(c, p)?);
    }
    while !ops.is_empty() {
        reduce(&mut vals, &mut ops)?;
    }
    let v = vals.pop().unwrap_or(0.0);
    if !v.is_finite() {
        return Err("the calculation gives a value that is not a finite number".into());
    }
    Ok(v)
}

/// A unary function (`ABS[…]`, `ATAN[…]/[…]`, `EXISTS[#<name>]` …); angles in degrees.
fn unary(c: &mut Cursor, p: &Params) -> Result<f64, String> {
    const NAMES: [&str; 14] = [
        "abs", "acos", "asin", "atan", "cos", "exists", "exp", "fix", "fup", "ln", "round", "sin",
        "sqrt", "tan",
    ];
    let Some(name) = NAMES.iter().copied().find(|n| c.starts(n)) else {
        return Err(format!("unknown word or function at '{}'", c.rest()));
    };
    c.i += name.len();
    if name == "exists" {
        c.expect(b'[', "after EXISTS")?;
        let k = param(c, p)?;
        c.expect(b']', "after EXISTS[#<name>")?;
        return match &k {
            _ if p.has(&k) => Ok(1.0),
            Param::Named(s) if !s.starts_with('_') => Ok(0.0),
            _ => Err(format!(
                "EXISTS[{k}]: whether the controller defines it is not known from the program"
            )),
        };
    }
    let a = expression(c, p)?;
    let deg = |r: f64| r * 180.0 / std::f64::consts::PI;
    let rad = |d: f64| d * std::f64::consts::PI / 180.0;
    let v = match name {
        "abs" => a.abs(),
        "acos" | "asin" if !(-1.0..=1.0).contains(&a) => {
            return Err(format!("{} of {a}: outside -1 to 1", name.to_uppercase()));
        }
        "acos" => deg(a.acos()),
        "asin" => deg(a.asin()),
        "atan" => {
            c.expect(b'/', "in ATAN[y]/[x]")?;
            let b = expression(c, p)?;
            deg(a.atan2(b))
        }
        "cos" => rad(a).cos(),
        "exp" => a.exp(),
        "fix" => a.floor(),
        "fup" => a.ceil(),
        "ln" if a <= 0.0 => return Err(format!("LN of {a}: not positive")),
        "ln" => a.ln(),
        "round" => (a + if a < 0.0 { -0.5 } else { 0.5 }).trunc(),
        "sin" => rad(a).sin(),
        "sqrt" if a < 0.0 => return Err(format!("SQRT of {a}: negative")),
        "sqrt" => a.sqrt(),
        _ => rad(a).tan(),
    };
    Ok(v)
}

/// After the `#` of a parameter setting: the parameter, `=` and its value. Settings of system
/// parameters (from #5000) and of predefined names are refused.
pub fn setting(c: &mut Cursor, p: &Params) -> Result<(Param, f64), String> {
    let k = param(c, p)?;
    if let Param::Num(n) = k
        && n >= FIRST_SYSTEM_PARAMETER
    {
        return Err(format!(
            "setting system parameter #{n} (offsets, tool data) changes the controller's \
             memory: not supported; use G10 or the program's own parameters instead"
        ));
    }
    c.expect(b'=', &format!("after {k} in a parameter setting"))?;
    let v = value(c, p)?;
    Ok((k, v))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn eval(s: &str, p: &Params) -> Result<f64, String> {
        let t: String = s
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect::<String>()
            .to_ascii_lowercase();
        let mut c = Cursor::new(t.as_bytes());
        let v = value(&mut c, p)?;
        assert!(c.done(), "{s}: left '{}'", c.rest());
        Ok(v)
    }

    #[test]
    fn precedence_and_left_to_right() {
        let p = Params::default();
        assert_eq!(eval("[1 + 2 * 3]", &p).unwrap(), 7.0);
        assert_eq!(eval("[2 ** 3 ** 2]", &p).unwrap(), 64.0);
        assert_eq!(eval("[8 / 4 / 2]", &p).unwrap(), 1.0);
        assert_eq!(eval("[10 - 4 - 3]", &p).unwrap(), 3.0);
        assert_eq!(eval("[1 + 1 EQ 2]", &p).unwrap(), 1.0);
        assert_eq!(eval("[1 LT 2 AND 3 GT 4]", &p).unwrap(), 0.0);
        assert_eq!(eval("[1 OR 0 XOR 1]", &p).unwrap(), 0.0);
        assert_eq!(eval("[-7 MOD 3]", &p).unwrap(), 2.0);
        assert_eq!(eval("[1 EQ 1.0000001]", &p).unwrap(), 1.0);
        assert_eq!(eval("-[2]", &p).unwrap(), -2.0);
        assert_eq!(eval("-.5", &p).unwrap(), -0.5);
    }

    #[test]
    fn functions_in_degrees() {
        let p = Params::default();
        assert!((eval("SIN[30]", &p).unwrap() - 0.5).abs() < 1e-12);
        assert!((eval("ATAN[1]/[1]", &p).unwrap() - 45.0).abs() < 1e-12);
        assert!((eval("ATAN[1]/[-1]", &p).unwrap() - 135.0).abs() < 1e-12);
        assert_eq!(eval("ROUND[-2.5]", &p).unwrap(), -3.0);
        assert_eq!(eval("ROUND[2.4]", &p).unwrap(), 2.0);
        assert_eq!(eval("FIX[-2.5]", &p).unwrap(), -3.0);
        assert_eq!(eval("FUP[2.1]", &p).unwrap(), 3.0);
        assert_eq!(eval("ABS[-3]", &p).unwrap(), 3.0);
        assert_eq!(eval("SQRT[[3*3]+[4*4]]", &p).unwrap(), 5.0);
        for bad in [
            "SQRT[-1]",
            "LN[0]",
            "ACOS[2]",
            "[1/0]",
            "[-8 ** 0.5]",
            "[1 + ]",
            "[1",
        ] {
            assert!(eval(bad, &p).is_err(), "{bad}");
        }
    }

    #[test]
    fn parameters_must_be_set_by_the_program() {
        let mut p = Params::default();
        p.set(Param::Num(1), 6.35);
        p.set(Param::Named("depth".into()), -2.0);
        assert_eq!(eval("[#1 * 0.5]", &p).unwrap(), 3.175);
        assert_eq!(eval("#<DePth>", &p).unwrap(), -2.0);
        assert_eq!(eval("-#1", &p).unwrap(), -6.35);
        assert_eq!(eval("EXISTS[#<depth>]", &p).unwrap(), 1.0);
        assert_eq!(eval("EXISTS[#<other>]", &p).unwrap(), 0.0);
        for bad in [
            "#2",
            "#<nope>",
            "#<_x>",
            "#5221",
            "EXISTS[#<_metric>]",
            "#0",
            "#1.5",
        ] {
            assert!(eval(bad, &p).is_err(), "{bad}");
        }
    }
}

//! Named, typed, documented parameters (`--param KEY=VALUE`) shared by solvers and generators.

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The type of a parameter, with the values it accepts: every number a user can give has a
/// declared range, checked where it enters ([`Params::new`], [`ParamValue::check`]) and shown
/// by `cellseq solvers`, `docs/solvers.md` and `docs/bad-input.md`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamKind {
    /// A whole number in a range.
    Int(IntRange),
    /// A finite number in a range.
    Float(FloatRange),
    /// `true` or `false`.
    Bool,
    /// One of the listed words.
    Choice(&'static [&'static str]),
    /// Free text (a file path, a list); the owner checks it.
    Text,
}

impl ParamKind {
    /// A whole number in `min..=max`.
    pub const fn int(min: u64, max: u64) -> ParamKind {
        ParamKind::Int(IntRange { min, max })
    }
    /// A number in `[min, max]`.
    pub const fn float(min: f64, max: f64) -> ParamKind {
        ParamKind::Float(FloatRange::closed(min, max))
    }
    /// A number in `(min, max]`: above `min`, at most `max`.
    pub const fn float_above(min: f64, max: f64) -> ParamKind {
        ParamKind::Float(FloatRange {
            min_open: true,
            ..FloatRange::closed(min, max)
        })
    }
    /// A number in `[min, max)`: at least `min`, below `max`.
    pub const fn float_below(min: f64, max: f64) -> ParamKind {
        ParamKind::Float(FloatRange {
            max_open: true,
            ..FloatRange::closed(min, max)
        })
    }
    /// A number in `(min, max)`.
    pub const fn float_open(min: f64, max: f64) -> ParamKind {
        ParamKind::Float(FloatRange {
            min_open: true,
            max_open: true,
            ..FloatRange::closed(min, max)
        })
    }
}

/// An inclusive range of whole numbers, `[min, max]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct IntRange {
    /// Smallest value accepted.
    pub min: u64,
    /// Largest value accepted.
    pub max: u64,
}

impl IntRange {
    /// `min..=max`.
    pub const fn new(min: u64, max: u64) -> IntRange {
        IntRange { min, max }
    }
    /// True when `v` lies in the range.
    pub fn contains(&self, v: u64) -> bool {
        self.min <= v && v <= self.max
    }
    /// `v` when it lies in the range; otherwise a message naming `what`, the range and `v`.
    pub fn check(&self, what: &str, v: u64) -> std::result::Result<u64, String> {
        if self.contains(v) {
            Ok(v)
        } else {
            Err(format!("{what} must be a whole number in {self}, got {v}"))
        }
    }
}

impl std::fmt::Display for IntRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "[{}, {}]", int_text(self.min), int_text(self.max))
    }
}

/// A range of finite numbers; each end is open (excluded) or closed (included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FloatRange {
    /// Lower end.
    pub min: f64,
    /// Upper end.
    pub max: f64,
    /// True when `min` itself is excluded.
    pub min_open: bool,
    /// True when `max` itself is excluded.
    pub max_open: bool,
}

impl FloatRange {
    /// `[min, max]`.
    pub const fn closed(min: f64, max: f64) -> FloatRange {
        FloatRange {
            min,
            max,
            min_open: false,
            max_open: false,
        }
    }
    /// `(min, max]`.
    pub const fn above(min: f64, max: f64) -> FloatRange {
        FloatRange {
            min_open: true,
            ..FloatRange::closed(min, max)
        }
    }
    /// True when `x` is finite and lies in the range (NaN never does).
    pub fn contains(&self, x: f64) -> bool {
        let lo = if self.min_open {
            x > self.min
        } else {
            x >= self.min
        };
        let hi = if self.max_open {
            x < self.max
        } else {
            x <= self.max
        };
        x.is_finite() && lo && hi
    }
    /// `x` when it lies in the range; otherwise a message naming `what`, the range and `x`.
    pub fn check(&self, what: &str, x: f64) -> std::result::Result<f64, String> {
        if self.contains(x) {
            Ok(x)
        } else {
            Err(format!(
                "{what} must be a finite number in {self}, got {}",
                float_text(x)
            ))
        }
    }
}

impl std::fmt::Display for FloatRange {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}{}, {}{}",
            if self.min_open { '(' } else { '[' },
            float_text(self.min),
            float_text(self.max),
            if self.max_open { ')' } else { ']' }
        )
    }
}

/// A whole number as ranges show it: digits, or the shorter exponent form from 10⁵ on
/// (`1e9`), `2^64-1` for the largest.
pub fn int_text(v: u64) -> String {
    if v == u64::MAX {
        return "2^64-1".to_string();
    }
    let (e, d) = (format!("{v:e}"), v.to_string());
    if v >= 100_000 && e.len() < d.len() {
        e
    } else {
        d
    }
}

/// A number as ranges and messages show it: `0.5`, `1e9`, `1e-9`, `NaN`, `inf` (the shorter
/// exponent form from 10⁵ on and below 10⁻⁴).
pub fn float_text(x: f64) -> String {
    let a = x.abs();
    let (e, d) = (format!("{x:e}"), x.to_string());
    if x.is_finite() && a != 0.0 && !(1e-4..1e5).contains(&a) && e.len() < d.len() {
        e
    } else {
        d
    }
}

/// Longest time limit accepted, in seconds (about 11.5 days): longer ones are refused rather
/// than overflowing a clock. Every time limit (`--time-limit`, a plan's `budget.seconds`,
/// `auto`'s `seconds`) lies in (0, `MAX_SECONDS`].
pub const MAX_SECONDS: f64 = 1.0e6;

/// Upper end of the counts of iterations, kicks, restarts and stalls: 10⁹. A run ends at its
/// budget anyway; a larger count would mean "until the budget ends" just as well.
pub const MAX_ITERATIONS: u64 = 1_000_000_000;

/// Upper end of lengths counted in cells (blocks, windows, segments, kicks, tenures) and of
/// generated instance sizes: 10⁷ cells (about 15 GB of memory once generated); a length
/// beyond the instance's size means the whole instance.
pub const MAX_CELLS: u64 = 10_000_000;

/// Upper end of candidate-list lengths `k`: the lists hold n·k entries (at 10⁶ cells and
/// k = 1000, 8 GB), and no search here gains from more than a few dozen candidates.
pub const MAX_NEIGHBOURS: u64 = 1000;

/// Upper end of memory caps in MiB: 2²⁰ MiB = 1 TiB.
pub const MAX_MEMORY_MB: u64 = 1 << 20;

/// One documented solver parameter.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    /// Name used in `--param NAME=VALUE`.
    pub name: &'static str,
    /// Default value, as text.
    pub default: &'static str,
    /// Type.
    pub kind: ParamKind,
    /// One-line description.
    pub help: &'static str,
}

/// A parameter value as a program gives it: typed, checked against the declared
/// [`ParamKind`] when a solver or generator is built (an integer for an `Int`, a number for a
/// `Float`, `true`/`false` for a `Bool`, text for a `Choice` or `Text`; text that parses as
/// the declared type is accepted too, as on the command line).
#[derive(Debug, Clone, PartialEq)]
pub enum ParamValue {
    /// A whole number.
    Int(u64),
    /// A number.
    Float(f64),
    /// A truth value.
    Bool(bool),
    /// Text: a choice, a path, a list, or any value in its command-line spelling.
    Text(String),
}

impl ParamValue {
    /// The value in its command-line spelling (`--param KEY=VALUE`).
    pub fn to_text(&self) -> String {
        match self {
            ParamValue::Int(v) => v.to_string(),
            ParamValue::Float(v) => v.to_string(),
            ParamValue::Bool(v) => v.to_string(),
            ParamValue::Text(v) => v.clone(),
        }
    }

    /// Checks the value's type against `spec`: an error names the owner, the parameter, the
    /// type it needs and the value given.
    pub fn check(&self, owner: &str, spec: &ParamSpec) -> Result<()> {
        let fits = matches!(
            (self, spec.kind),
            (ParamValue::Text(_), _)
                | (ParamValue::Int(_), ParamKind::Int(_) | ParamKind::Float(_))
                | (ParamValue::Float(_), ParamKind::Float(_))
                | (ParamValue::Bool(_), ParamKind::Bool)
        );
        if !fits {
            return Err(Error::Param(format!(
                "'{owner}': parameter '{}' must be {}, got {self:?}",
                spec.name,
                wanted(spec.kind)
            )));
        }
        check_value(owner, spec, &self.to_text())
    }
}

macro_rules! int_value {
    ($($t:ty),*) => {$(
        impl From<$t> for ParamValue {
            fn from(v: $t) -> Self {
                ParamValue::Int(v as u64)
            }
        }
    )*};
}
int_value!(u8, u16, u32, u64, usize);

macro_rules! signed_value {
    ($($t:ty),*) => {$(
        /// A whole number: `.param("k", 6)` without a suffix; a negative one is kept as text and
        /// refused by the parameter's range when checked.
        impl From<$t> for ParamValue {
            fn from(v: $t) -> Self {
                match u64::try_from(v) {
                    Ok(u) => ParamValue::Int(u),
                    Err(_) => ParamValue::Text(v.to_string()),
                }
            }
        }
    )*};
}
signed_value!(i8, i16, i32, i64, isize);

impl From<f64> for ParamValue {
    fn from(v: f64) -> Self {
        ParamValue::Float(v)
    }
}

impl From<f32> for ParamValue {
    fn from(v: f32) -> Self {
        ParamValue::Float(v as f64)
    }
}

impl From<bool> for ParamValue {
    fn from(v: bool) -> Self {
        ParamValue::Bool(v)
    }
}

impl From<&str> for ParamValue {
    fn from(v: &str) -> Self {
        ParamValue::Text(v.to_string())
    }
}

impl From<String> for ParamValue {
    fn from(v: String) -> Self {
        ParamValue::Text(v)
    }
}

/// Validated parameter values (defaults filled in).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Params {
    values: BTreeMap<String, String>,
}

impl Params {
    /// Validates `given` against `specs`: unknown names and malformed values are errors.
    pub fn new(
        owner: &str,
        specs: &[ParamSpec],
        given: &BTreeMap<String, String>,
    ) -> Result<Params> {
        let mut values = BTreeMap::new();
        for (k, v) in given {
            let Some(spec) = specs.iter().find(|s| s.name == k) else {
                let known: Vec<&str> = specs.iter().map(|s| s.name).collect();
                return Err(Error::Param(format!(
                    "'{owner}' has no parameter '{k}' (known: {})",
                    if known.is_empty() {
                        "none".to_string()
                    } else {
                        known.join(", ")
                    }
                )));
            };
            check_value(owner, spec, v)?;
            values.insert(k.clone(), v.clone());
        }
        for s in specs {
            values
                .entry(s.name.to_string())
                .or_insert_with(|| s.default.to_string());
        }
        Ok(Params { values })
    }
    /// Validates typed values against `specs` ([`ParamValue::check`]): unknown names list the
    /// known ones; the result is the same as [`Params::new`] with the values' text.
    pub fn typed(
        owner: &str,
        specs: &[ParamSpec],
        given: &[(String, ParamValue)],
    ) -> Result<Params> {
        let mut text = BTreeMap::new();
        for (k, v) in given {
            if let Some(spec) = specs.iter().find(|s| s.name == k) {
                v.check(owner, spec)?;
            }
            text.insert(k.clone(), v.to_text());
        }
        Params::new(owner, specs, &text)
    }
    /// All values, defaults included.
    pub fn values(&self) -> &BTreeMap<String, String> {
        &self.values
    }
    fn raw(&self, name: &str) -> &str {
        self.values
            .get(name)
            .map(|s| s.as_str())
            .unwrap_or_else(|| panic!("parameter '{name}' is not declared by this solver"))
    }
    /// An integer parameter.
    pub fn int(&self, name: &str) -> u64 {
        self.raw(name).parse().unwrap_or(0)
    }
    /// A numeric parameter.
    pub fn float(&self, name: &str) -> f64 {
        self.raw(name).parse().unwrap_or(0.0)
    }
    /// A boolean parameter.
    pub fn bool(&self, name: &str) -> bool {
        self.raw(name) == "true"
    }
    /// A word parameter.
    pub fn word(&self, name: &str) -> &str {
        self.raw(name)
    }
    /// A three-way switch (a `Choice` of `auto` and on/off words): `Some(true)` for `true` or
    /// `on`, `Some(false)` for `false` or `off`, `None` (decide automatically) otherwise.
    pub fn switch(&self, name: &str) -> Option<bool> {
        match self.raw(name) {
            "true" | "on" => Some(true),
            "false" | "off" => Some(false),
            _ => None,
        }
    }
}

fn check_value(owner: &str, spec: &ParamSpec, v: &str) -> Result<()> {
    let ok = match spec.kind {
        ParamKind::Int(r) => v.parse::<u64>().is_ok_and(|x| r.contains(x)),
        ParamKind::Float(r) => v.parse::<f64>().is_ok_and(|x| r.contains(x)),
        ParamKind::Bool => v == "true" || v == "false",
        ParamKind::Choice(c) => c.contains(&v),
        ParamKind::Text => !v.is_empty(),
    };
    if ok {
        Ok(())
    } else {
        Err(Error::Param(format!(
            "'{owner}': parameter '{}' must be {}, got '{v}'",
            spec.name,
            wanted(spec.kind)
        )))
    }
}

/// What a parameter of `kind` must be, in words.
fn wanted(kind: ParamKind) -> String {
    match kind {
        ParamKind::Int(r) => format!("a whole number in {r}"),
        ParamKind::Float(r) => format!("a finite number in {r}"),
        ParamKind::Bool => "true or false".to_string(),
        ParamKind::Choice(c) => format!("one of {}", c.join(", ")),
        ParamKind::Text => "non-empty text".to_string(),
    }
}

/// Parses `KEY=VALUE` strings into a map.
pub fn parse_kv(pairs: &[String]) -> Result<BTreeMap<String, String>> {
    let mut m = BTreeMap::new();
    for p in pairs {
        let Some((k, v)) = p.split_once('=') else {
            return Err(Error::Param(format!(
                "malformed parameter '{p}': expected KEY=VALUE"
            )));
        };
        if k.trim().is_empty() {
            return Err(Error::Param(format!(
                "malformed parameter '{p}': empty key"
            )));
        }
        m.insert(k.trim().to_string(), v.trim().to_string());
    }
    Ok(m)
}

/// A TOML scalar (string, integer, float, boolean) as `--param` text; none for tables and
/// arrays. Plans and portfolio files give parameters this way.
pub fn toml_text(v: &toml::Value) -> Option<String> {
    match v {
        toml::Value::String(s) => Some(s.clone()),
        toml::Value::Integer(i) => Some(i.to_string()),
        toml::Value::Float(f) => Some(f.to_string()),
        toml::Value::Boolean(b) => Some(b.to_string()),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPECS: &[ParamSpec] = &[
        ParamSpec {
            name: "n",
            default: "10",
            kind: ParamKind::int(1, 100),
            help: "",
        },
        ParamSpec {
            name: "share",
            default: "0.5",
            kind: ParamKind::float_above(0.0, 1.0),
            help: "",
        },
    ];

    fn given(k: &str, v: &str) -> BTreeMap<String, String> {
        BTreeMap::from([(k.to_string(), v.to_string())])
    }

    #[test]
    fn ranges_are_checked_where_values_enter() {
        for (k, v) in [
            ("n", "1"),
            ("n", "100"),
            ("share", "1"),
            ("share", "1e-300"),
        ] {
            assert!(Params::new("t", SPECS, &given(k, v)).is_ok(), "{k}={v}");
        }
        for (k, v) in [
            ("n", "0"),
            ("n", "101"),
            ("n", "18446744073709551615"),
            ("n", "18446744073709551616"),
            ("n", "-1"),
            ("n", "1e3"),
            ("share", "0"),
            ("share", "1.0000001"),
            ("share", "NaN"),
            ("share", "inf"),
            ("share", "-inf"),
            ("share", "1e300"),
        ] {
            let e = Params::new("t", SPECS, &given(k, v))
                .unwrap_err()
                .to_string();
            assert!(e.contains(&format!("parameter '{k}'")), "{e}");
            assert!(
                e.contains(if k == "n" { "[1, 100]" } else { "(0, 1]" }),
                "{e}"
            );
        }
        // typed values are held to the same ranges
        let typed = |k: &str, v: ParamValue| Params::typed("t", SPECS, &[(k.to_string(), v)]);
        assert!(typed("n", ParamValue::Int(0)).is_err());
        assert!(typed("n", ParamValue::Int(50)).is_ok());
        assert!(typed("share", ParamValue::Float(f64::NAN)).is_err());
        assert!(typed("share", ParamValue::Int(1)).is_ok());
    }

    #[test]
    fn ranges_print_as_intervals() {
        assert_eq!(IntRange::new(1, 1000).to_string(), "[1, 1000]");
        assert_eq!(IntRange::new(0, 10_000_000).to_string(), "[0, 1e7]");
        assert_eq!(IntRange::new(0, 12_345_678).to_string(), "[0, 12345678]");
        assert_eq!(IntRange::new(0, u64::MAX).to_string(), "[0, 2^64-1]");
        assert_eq!(FloatRange::above(0.0, 1e6).to_string(), "(0, 1e6]");
        assert_eq!(FloatRange::closed(0.01, 1e-9).to_string(), "[0.01, 1e-9]");
        let ParamKind::Float(r) = ParamKind::float_open(0.0, 1.0) else {
            unreachable!()
        };
        assert_eq!(r.to_string(), "(0, 1)");
        assert!(!r.contains(0.0) && !r.contains(1.0) && r.contains(0.5));
        let ParamKind::Float(r) = ParamKind::float_below(0.0, 0.5) else {
            unreachable!()
        };
        assert_eq!(r.to_string(), "[0, 0.5)");
        assert_eq!(float_text(f64::NAN), "NaN");
        assert_eq!(float_text(1e300), "1e300");
    }
}

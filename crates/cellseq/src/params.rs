//! Named, typed, documented parameters (`--param KEY=VALUE`) shared by solvers and generators.

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The type of a parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ParamKind {
    /// A non-negative integer.
    Int,
    /// A finite number.
    Float,
    /// `true` or `false`.
    Bool,
    /// One of the listed words.
    Choice(&'static [&'static str]),
    /// Free text (a file path, a list); the owner checks it.
    Text,
}

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
    /// A non-negative integer.
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
                | (ParamValue::Int(_), ParamKind::Int | ParamKind::Float)
                | (ParamValue::Float(_), ParamKind::Float)
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
        impl From<$t> for ParamValue {
            /// A non-negative value is an [`ParamValue::Int`]; a negative one keeps its text, so
            /// that the check refuses it by name ("must be a non-negative integer, got '-3'").
            fn from(v: $t) -> Self {
                if v >= 0 {
                    ParamValue::Int(v as u64)
                } else {
                    ParamValue::Text(v.to_string())
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
        ParamKind::Int => v.parse::<u64>().is_ok(),
        ParamKind::Float => v.parse::<f64>().is_ok_and(|x| x.is_finite()),
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
        ParamKind::Int => "a non-negative integer".to_string(),
        ParamKind::Float => "a finite number".to_string(),
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

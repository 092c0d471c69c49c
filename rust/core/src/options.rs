//! Option sets declared once: each option's key, domain, unit, doc line and default live in
//! one declaration, and everything else is derived from it.
//!
//! Entry points:
//! - [`OptionInfo`] — what a user of an option needs to know: its key (the Python keyword;
//!   the CLI flag is `--key-with-dashes`), the scenario field it sets (if any), its
//!   [`Domain`], unit and doc line.
//! - [`OptionSpec`] — an [`OptionInfo`] plus how to read and set the option on the struct it
//!   configures (e.g. [`crate::scenario::Learning`]).
//! - [`OptionValue`] — a value as a caller gives it (bool, integer, number, text), before it
//!   is checked; [`Options`] — a set of them by key, the body of every request
//!   ([`crate::request`]).
//! - [`FromOption`] — a checked conversion of an [`OptionValue`] to a field's type; the
//!   error names the key and the value and says the domain, in the same words for every
//!   front end (scenario file, CLI flag, Python keyword).
//!
//! A scenario section is declared with the crate's `option_set!` macro (see
//! [`crate::scenario::Learning`]): one line per option gives the field, its type, its
//! default, its key, its domain and its unit, and the macro writes the struct (with serde's
//! derive, so scenario files use the same names), its `Default`, and its table
//! `OPTIONS: &[OptionSpec<Self>]`, from which the request layer, the CLI's flags, the Python
//! keywords, the type stub and the docs' tables are all derived.
//!
//! ```
//! use sixaxis_core::options::{Domain, FromOption, OptionValue};
//! let d = Domain::Float { min: 0.0, max: 1.0, open_min: true };
//! assert_eq!(f64::from_option("alpha", &d, &OptionValue::Float(0.5)).unwrap(), 0.5);
//! assert_eq!(
//!     f64::from_option("alpha", &d, &OptionValue::Int(0)).unwrap_err().to_string(),
//!     "invalid argument `alpha` = 0: must be a number in (0, 1]"
//! );
//! ```

use std::collections::BTreeMap;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The values an option can take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Domain {
    /// A whole number in `min..=max`.
    Int {
        /// Smallest value.
        min: i128,
        /// Largest value.
        max: i128,
    },
    /// A whole number in `min..=max`, or the word `auto`.
    IntOrAuto {
        /// Smallest value.
        min: i128,
        /// Largest value.
        max: i128,
    },
    /// A finite number in `[min, max]`, or `(min, max]` with `open_min`.
    Float {
        /// Lower bound.
        min: f64,
        /// Upper bound (`f64::INFINITY` for none).
        max: f64,
        /// Whether `min` itself is excluded.
        open_min: bool,
    },
    /// `true` or `false` (a CLI flag `--key` / `--no-key`).
    Bool,
    /// One of these names.
    Choice(&'static [&'static str]),
    /// Any non-empty text (a name or a path).
    Text,
}

impl Domain {
    /// Finite numbers > 0 (mm, deg, ...): "must be a finite number > 0".
    pub const POSITIVE: Domain = Domain::Float {
        min: 0.0,
        max: f64::INFINITY,
        open_min: true,
    };

    /// Finite numbers >= 0 (a penalty, a scale): "must be a finite number >= 0".
    pub const NON_NEGATIVE: Domain = Domain::Float {
        min: 0.0,
        max: f64::INFINITY,
        open_min: false,
    };

    /// Numbers in (0, 1] (eq. 6's alpha, a fraction that must move): "must be a number in (0, 1]".
    pub const UNIT_OPEN: Domain = Domain::Float {
        min: 0.0,
        max: 1.0,
        open_min: true,
    };

    /// Numbers in [0, 1] (a probability, a discount): "must be a number in [0, 1]".
    pub const UNIT: Domain = Domain::Float {
        min: 0.0,
        max: 1.0,
        open_min: false,
    };

    /// The integers of a `u32` field from `min`.
    pub const fn u32_from(min: i128) -> Domain {
        Domain::Int {
            min,
            max: u32::MAX as i128,
        }
    }

    /// The integers of a `u64` field from `min`.
    pub const fn u64_from(min: i128) -> Domain {
        Domain::Int {
            min,
            max: u64::MAX as i128,
        }
    }

    /// The domain in words, as every error about a value outside it says it.
    pub fn reason(&self) -> String {
        let ints = |min: i128, max: i128| {
            if max == u64::MAX as i128 {
                format!("an integer >= {min}")
            } else {
                format!("an integer in {min}..={max}")
            }
        };
        match *self {
            Domain::Int { min, max } => format!("must be {}", ints(min, max)),
            Domain::IntOrAuto { min, max } => format!("must be {} or \"auto\"", ints(min, max)),
            Domain::Float { min, max, open_min } => {
                let lo = if open_min { "(" } else { "[" };
                if max.is_infinite() {
                    let op = if open_min { ">" } else { ">=" };
                    format!("must be a finite number {op} {min}")
                } else {
                    format!("must be a number in {lo}{min}, {max}]")
                }
            }
            Domain::Bool => "must be true or false".to_string(),
            Domain::Choice(names) => format!("must be one of {}", names.join(", ")),
            Domain::Text => "must be a non-empty text".to_string(),
        }
    }

    /// A short name of the kind of value: `int`, `int|auto`, `float`, `bool`, `choice`.
    pub fn kind(&self) -> &'static str {
        match self {
            Domain::Int { .. } => "int",
            Domain::IntOrAuto { .. } => "int|auto",
            Domain::Float { .. } => "float",
            Domain::Bool => "bool",
            Domain::Choice(_) => "choice",
            Domain::Text => "text",
        }
    }

    /// The value written in `text` (a command-line argument), not yet checked against the
    /// domain; text that is no value of this kind gets the domain's error, naming `key`.
    pub fn parse_text(&self, key: &str, text: &str) -> Result<OptionValue> {
        let t = text.trim();
        let bad = || Error::argument(key, text, self.reason());
        match self {
            Domain::Int { .. } => t.parse::<i128>().map(OptionValue::Int).map_err(|_| bad()),
            Domain::IntOrAuto { .. } if t == "auto" => Ok(OptionValue::Text("auto".into())),
            Domain::IntOrAuto { .. } => t.parse::<i128>().map(OptionValue::Int).map_err(|_| bad()),
            Domain::Float { .. } => t.parse::<f64>().map(OptionValue::Float).map_err(|_| bad()),
            Domain::Bool => match t {
                "true" => Ok(OptionValue::Bool(true)),
                "false" => Ok(OptionValue::Bool(false)),
                _ => Err(bad()),
            },
            Domain::Choice(_) | Domain::Text => Ok(OptionValue::Text(t.to_string())),
        }
    }
}

/// A value as a caller gives it, before it is checked against an option's [`Domain`].
/// Serialises untagged: `true`, `3`, `0.5`, `"f32"`.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum OptionValue {
    /// A bool.
    Bool(bool),
    /// A whole number (wide enough to carry a value out of any field's range to its check).
    Int(i128),
    /// A number.
    Float(f64),
    /// A name, or the word `auto`.
    Text(String),
}

impl fmt::Display for OptionValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            OptionValue::Bool(b) => write!(f, "{b}"),
            OptionValue::Int(i) => write!(f, "{i}"),
            OptionValue::Float(x) => write!(f, "{x}"),
            OptionValue::Text(t) => write!(f, "{t}"),
        }
    }
}

impl<'de> Deserialize<'de> for OptionValue {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = OptionValue;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a bool, a number or a string")
            }
            fn visit_bool<E>(self, v: bool) -> std::result::Result<OptionValue, E> {
                Ok(OptionValue::Bool(v))
            }
            fn visit_i64<E>(self, v: i64) -> std::result::Result<OptionValue, E> {
                Ok(OptionValue::Int(v.into()))
            }
            fn visit_u64<E>(self, v: u64) -> std::result::Result<OptionValue, E> {
                Ok(OptionValue::Int(v.into()))
            }
            fn visit_f64<E>(self, v: f64) -> std::result::Result<OptionValue, E> {
                Ok(OptionValue::Float(v))
            }
            fn visit_str<E>(self, v: &str) -> std::result::Result<OptionValue, E> {
                Ok(OptionValue::Text(v.to_string()))
            }
        }
        d.deserialize_any(Visitor)
    }
}

macro_rules! option_value_from {
    ($($t:ty => $variant:ident),*) => {$(
        impl From<$t> for OptionValue {
            fn from(v: $t) -> Self {
                OptionValue::$variant(v.into())
            }
        }
    )*};
}
option_value_from!(bool => Bool, i32 => Int, i64 => Int, u32 => Int, u64 => Int, f64 => Float, &str => Text, String => Text);

/// Options of one request by key; a key left out takes the scenario's value.
pub type Options = BTreeMap<String, OptionValue>;

/// What a user needs to know of one option.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptionInfo {
    /// The key: the Python keyword, the request's JSON key; the CLI flag is
    /// `--key-with-dashes` (`--key` / `--no-key` for a bool).
    pub key: &'static str,
    /// The scenario field it overrides (e.g. `learning.seed`), or `""` for none.
    pub field: &'static str,
    /// Its values.
    pub domain: Domain,
    /// Its unit (`""` for none).
    pub unit: &'static str,
    /// What it does, in one or more lines.
    pub doc: &'static str,
}

impl OptionInfo {
    /// The CLI flag: `--` and the key with `-` for `_`.
    pub fn flag(&self) -> String {
        format!("--{}", self.key.replace('_', "-"))
    }

    /// The doc as one line.
    pub fn doc_line(&self) -> String {
        self.doc
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join(" ")
    }
}

/// One option of a struct `T`: what it is, and how to read and set it.
pub struct OptionSpec<T: 'static> {
    /// What it is.
    pub info: OptionInfo,
    /// Its value in a `T`.
    pub get: fn(&T) -> OptionValue,
    /// Set it in a `T` from a value, checked against the domain; the error names `key`.
    pub set: fn(&mut T, &str, &OptionValue) -> Result<()>,
}

impl<T> fmt::Debug for OptionSpec<T> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.info.fmt(f)
    }
}

/// Set every option of `table` that `values` holds on `target`, in the table's order (so a
/// rule that combines options, such as `assist` before `detour`, is the table's order);
/// a key of `values` that no option of `table` has is an error that lists the keys.
pub fn apply<T>(table: &[&OptionSpec<T>], values: &Options, target: &mut T) -> Result<()> {
    let keys: Vec<&str> = table.iter().map(|s| s.info.key).collect();
    reject_unknown(&keys, values)?;
    for spec in table {
        if let Some(v) = values.get(spec.info.key) {
            (spec.set)(target, spec.info.key, v)?;
        }
    }
    Ok(())
}

/// Check every field of `target` that `table` declares against its domain; the error is an
/// [`Error::InvalidScenario`] naming the scenario field.
pub fn check_fields<T: Clone>(table: &[OptionSpec<T>], target: &T) -> Result<()> {
    let fields = table.iter().filter(|s| !s.info.field.is_empty());
    check_all(fields, target, |i| i.field).map_err(|e| match e {
        Error::InvalidArgument {
            name,
            value,
            reason,
        } => Error::InvalidScenario {
            field: name,
            value,
            reason,
        },
        other => other,
    })
}

/// Check every option of `specs` as it stands in `target` against its domain (its value
/// read and set again on a copy); the error names the option by `name_of`.
pub fn check_all<'a, T: Clone + 'static>(
    specs: impl IntoIterator<Item = &'a OptionSpec<T>>,
    target: &T,
    name_of: impl Fn(&OptionInfo) -> &'static str,
) -> Result<()> {
    let mut copy = target.clone();
    for spec in specs {
        (spec.set)(&mut copy, name_of(&spec.info), &(spec.get)(target))?;
    }
    Ok(())
}

/// The error for the first key of `values` that is not one of `keys`, listing them.
pub fn reject_unknown(keys: &[&str], values: &Options) -> Result<()> {
    match values.keys().find(|k| !keys.contains(&k.as_str())) {
        Some(unknown) => Err(Error::argument(
            unknown.as_str(),
            &values[unknown],
            format!("is no option here; the options are {}", keys.join(", ")),
        )),
        None => Ok(()),
    }
}

/// A checked conversion of an [`OptionValue`] to a field's type.
pub trait FromOption: Sized {
    /// `v` as `Self` if it lies in `domain`; else the error names `key` and `v`.
    fn from_option(key: &str, domain: &Domain, v: &OptionValue) -> Result<Self>;
}

/// A field's value as an [`OptionValue`].
pub trait ToOption {
    /// The value.
    fn to_option(&self) -> OptionValue;
}

fn whole(key: &str, domain: &Domain, v: &OptionValue) -> Result<i128> {
    let bad = || Error::argument(key, v, domain.reason());
    let (min, max) = match *domain {
        Domain::Int { min, max } | Domain::IntOrAuto { min, max } => (min, max),
        _ => return Err(bad()),
    };
    match v {
        OptionValue::Int(i) if (min..=max).contains(i) => Ok(*i),
        _ => Err(bad()),
    }
}

macro_rules! from_option_int {
    ($($t:ty),*) => {$(
        impl FromOption for $t {
            fn from_option(key: &str, domain: &Domain, v: &OptionValue) -> Result<Self> {
                let i = whole(key, domain, v)?;
                <$t>::try_from(i).map_err(|_| Error::argument(key, v, domain.reason()))
            }
        }
        impl ToOption for $t {
            fn to_option(&self) -> OptionValue {
                OptionValue::Int(*self as i128)
            }
        }
    )*};
}
from_option_int!(u32, u64);

impl FromOption for f64 {
    fn from_option(key: &str, domain: &Domain, v: &OptionValue) -> Result<Self> {
        let bad = || Error::argument(key, v, domain.reason());
        let Domain::Float { min, max, open_min } = *domain else {
            return Err(bad());
        };
        let x = match v {
            OptionValue::Float(x) => *x,
            OptionValue::Int(i) => *i as f64,
            _ => return Err(bad()),
        };
        let above = if open_min { x > min } else { x >= min };
        if x.is_finite() && above && x <= max {
            Ok(x)
        } else {
            Err(bad())
        }
    }
}

impl ToOption for f64 {
    fn to_option(&self) -> OptionValue {
        OptionValue::Float(*self)
    }
}

impl FromOption for bool {
    fn from_option(key: &str, domain: &Domain, v: &OptionValue) -> Result<Self> {
        match v {
            OptionValue::Bool(b) => Ok(*b),
            _ => Err(Error::argument(key, v, domain.reason())),
        }
    }
}

impl ToOption for bool {
    fn to_option(&self) -> OptionValue {
        OptionValue::Bool(*self)
    }
}

impl FromOption for String {
    fn from_option(key: &str, domain: &Domain, v: &OptionValue) -> Result<Self> {
        match v {
            OptionValue::Text(t) if !t.trim().is_empty() => Ok(t.clone()),
            _ => Err(Error::argument(key, v, domain.reason())),
        }
    }
}

impl ToOption for String {
    fn to_option(&self) -> OptionValue {
        OptionValue::Text(self.clone())
    }
}

/// Check `v` against `domain` (whatever its field's type); the error names `key` and `v`.
pub fn check_value(key: &str, domain: &Domain, v: &OptionValue) -> Result<()> {
    match domain {
        Domain::Int { .. } => whole(key, domain, v).map(|_| ()),
        Domain::IntOrAuto { .. } => match v {
            OptionValue::Text(t) if t == "auto" => Ok(()),
            _ => whole(key, domain, v).map(|_| ()),
        },
        Domain::Float { .. } => f64::from_option(key, domain, v).map(|_| ()),
        Domain::Bool => bool::from_option(key, domain, v).map(|_| ()),
        Domain::Choice(_) => choice(key, domain, v).map(|_| ()),
        Domain::Text => String::from_option(key, domain, v).map(|_| ()),
    }
}

/// The name `v` holds, if it is one of `domain`'s choices; for enums with serde names.
pub fn choice<'a>(key: &str, domain: &Domain, v: &'a OptionValue) -> Result<&'a str> {
    match (domain, v) {
        (Domain::Choice(names), OptionValue::Text(t)) if names.contains(&t.as_str()) => Ok(t),
        _ => Err(Error::argument(key, v, domain.reason())),
    }
}

/// Declares a struct of options with serde names, a `Default`, and its table
/// `OPTIONS: &[OptionSpec<Self>]` (see the module docs). Each option is one line:
/// `/// doc` then `field: Type = default; "key", domain, "unit";` (key `""`: the field is in
/// the table for its checks and docs but takes no keyword or flag), optionally followed by
/// `set = <fn(&mut Self, &str, &OptionValue) -> Result<()>>` where setting it does more than
/// assign the field.
macro_rules! option_set {
    (
        $(#[$meta:meta])*
        pub struct $name:ident ($section:literal) {
            $(
                $(#[doc = $doc:literal])*
                $field:ident : $ty:ty = $default:expr ; $key:literal, $domain:expr, $unit:literal
                $(, set = $set:expr)? ;
            )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
        #[serde(deny_unknown_fields, default)]
        pub struct $name {
            $( $(#[doc = $doc])* pub $field: $ty, )*
        }

        impl Default for $name {
            fn default() -> Self {
                $name { $( $field: $default, )* }
            }
        }

        impl $name {
            /// Every option of this section, in the order the request layer applies them.
            pub const OPTIONS: &'static [$crate::options::OptionSpec<$name>] = &[
                $( $crate::options::OptionSpec {
                    info: $crate::options::OptionInfo {
                        key: $key,
                        field: concat!($section, ".", stringify!($field)),
                        domain: $domain,
                        unit: $unit,
                        doc: concat!($($doc, "\n"),*),
                    },
                    get: |o| $crate::options::ToOption::to_option(&o.$field),
                    set: $crate::options::option_set!(@set $field, $ty, $domain $(, $set)?),
                }, )*
            ];

            /// Check every field against its domain; the error names the scenario field.
            pub fn check(&self) -> $crate::error::Result<()> {
                $crate::options::check_fields(Self::OPTIONS, self)
            }
        }
    };
    (@set $field:ident, $ty:ty, $domain:expr) => {
        |o, key, v| {
            o.$field = <$ty as $crate::options::FromOption>::from_option(key, &$domain, v)?;
            Ok(())
        }
    };
    (@set $field:ident, $ty:ty, $domain:expr, $set:expr) => {
        $set
    };
}
pub(crate) use option_set;

/// Declares an enum named by the names it is written with in scenario files, requests,
/// results, CLI flags and Python keywords: the names are given once, and the macro writes
/// `NAMES`, `name()`, `from_name()`, serde's `Serialize`/`Deserialize` (as the name),
/// `Default`, [`FromOption`] and [`ToOption`] (domain [`Domain::Choice`] of `NAMES`).
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        pub enum $name:ident (default $default:ident) {
            $( $(#[doc = $doc:literal])* $variant:ident = $text:literal, )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
        pub enum $name {
            $( $(#[doc = $doc])* $variant, )*
        }

        impl Default for $name {
            fn default() -> Self {
                $name::$default
            }
        }

        impl $name {
            /// Every name, in the order of the docs.
            pub const NAMES: &'static [&'static str] = &[$($text),*];
            /// The domain of an option of this type.
            pub const DOMAIN: $crate::options::Domain = $crate::options::Domain::Choice(Self::NAMES);

            /// The name used in scenario files, requests, results and flags.
            pub fn name(self) -> &'static str {
                match self { $( $name::$variant => $text, )* }
            }

            /// The value of a name; the error names `key` and the value and lists the names.
            pub fn from_name(key: &str, name: &str) -> $crate::error::Result<Self> {
                match name {
                    $( $text => Ok($name::$variant), )*
                    _ => Err($crate::error::Error::argument(
                        key,
                        name,
                        Self::DOMAIN.reason(),
                    )),
                }
            }
        }

        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl serde::Serialize for $name {
            fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }

        impl<'de> serde::Deserialize<'de> for $name {
            fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
                let text = <String as serde::Deserialize>::deserialize(d)?;
                $name::from_name("", &text).map_err(|_| {
                    serde::de::Error::custom(format!("= {text}: {}", Self::DOMAIN.reason()))
                })
            }
        }

        impl $crate::options::FromOption for $name {
            fn from_option(
                key: &str,
                domain: &$crate::options::Domain,
                v: &$crate::options::OptionValue,
            ) -> $crate::error::Result<Self> {
                let name = $crate::options::choice(key, domain, v)?;
                $name::from_name(key, name)
            }
        }

        impl $crate::options::ToOption for $name {
            fn to_option(&self) -> $crate::options::OptionValue {
                $crate::options::OptionValue::Text(self.name().to_string())
            }
        }
    };
}
pub(crate) use named_enum;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn domains_in_words() {
        assert_eq!(
            Domain::u64_from(0).reason(),
            "must be an integer >= 0".to_string()
        );
        assert_eq!(
            Domain::u32_from(1).reason(),
            "must be an integer in 1..=4294967295"
        );
        assert_eq!(Domain::UNIT.reason(), "must be a number in [0, 1]");
        assert_eq!(Domain::UNIT_OPEN.reason(), "must be a number in (0, 1]");
        assert_eq!(Domain::POSITIVE.reason(), "must be a finite number > 0");
        assert_eq!(
            Domain::NON_NEGATIVE.reason(),
            "must be a finite number >= 0"
        );
        assert_eq!(Domain::Choice(&["a", "b"]).reason(), "must be one of a, b");
    }

    #[test]
    fn conversions_check_the_domain() {
        let d = Domain::u32_from(1);
        assert_eq!(u32::from_option("n", &d, &OptionValue::Int(7)).unwrap(), 7);
        for bad in [
            OptionValue::Int(0),
            OptionValue::Int(1 << 40),
            OptionValue::Float(2.0),
            OptionValue::Bool(true),
            OptionValue::Text("7".into()),
        ] {
            let e = u32::from_option("n", &d, &bad).unwrap_err().to_string();
            assert!(e.starts_with("invalid argument `n` = "), "{e}");
        }
        let f = Domain::POSITIVE;
        assert!(f64::from_option("x", &f, &OptionValue::Float(f64::NAN)).is_err());
        assert!(f64::from_option("x", &f, &OptionValue::Float(0.0)).is_err());
        assert_eq!(
            f64::from_option("x", &f, &OptionValue::Int(3)).unwrap(),
            3.0
        );
        assert!(bool::from_option("b", &Domain::Bool, &OptionValue::Int(1)).is_err());
        let n = Domain::NON_NEGATIVE;
        assert_eq!(
            f64::from_option("x", &n, &OptionValue::Float(0.0)).unwrap(),
            0.0
        );
        assert_eq!(
            f64::from_option("x", &n, &OptionValue::Float(-0.5))
                .unwrap_err()
                .to_string(),
            "invalid argument `x` = -0.5: must be a finite number >= 0"
        );
    }

    #[test]
    fn text_of_each_kind() {
        let d = Domain::IntOrAuto { min: 1, max: 9 };
        assert_eq!(
            d.parse_text("episodes", "auto").unwrap(),
            OptionValue::Text("auto".into())
        );
        assert_eq!(
            d.parse_text("episodes", " 4 ").unwrap(),
            OptionValue::Int(4)
        );
        assert_eq!(
            d.parse_text("episodes", "often").unwrap_err().to_string(),
            "invalid argument `episodes` = often: must be an integer in 1..=9 or \"auto\""
        );
        assert!(Domain::Bool.parse_text("b", "yes").is_err());
    }

    #[test]
    fn values_serialise_untagged() {
        let o: Options =
            serde_json::from_str(r#"{"a": 1, "b": 0.5, "c": true, "d": "x"}"#).unwrap();
        assert_eq!(o["a"], OptionValue::Int(1));
        assert_eq!(o["b"], OptionValue::Float(0.5));
        assert_eq!(o["c"], OptionValue::Bool(true));
        assert_eq!(o["d"], OptionValue::Text("x".into()));
        let back: Options = serde_json::from_str(&serde_json::to_string(&o).unwrap()).unwrap();
        assert_eq!(back, o);
    }
}

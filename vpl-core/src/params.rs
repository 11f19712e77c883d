//! Key–value parameters of a component, read by the component itself (as
//! pbrt-v4's `ParameterDictionary`): a sampler's crate owns its settings and
//! parses them from a [`Params`], so a registry can build any sampler, a
//! user's too, from one string map.
//!
//! Values are kept as text and parsed by whoever reads them into the type
//! it expects; every read marks its key, so the keys no reader took can be
//! reported ([`Params::check_used`]) instead of being silently ignored.
//! Keys given by a user are *required* to be read; keys a harness merely
//! *offers* ([`Params::offer`], e.g. "fresh paths if you trace paths") may go
//! unread.
//!
//! ```
//! use vpl_core::params::{ParamError, Params};
//!
//! let p = Params::parse(["m-max=8", "warmup=20"]).unwrap();
//! assert_eq!(p.get_or("m-max", 16usize).unwrap(), 8);
//! assert_eq!(p.get_or("knn-k", 4usize).unwrap(), 4);
//! assert!(matches!(p.check_used("smc"), Err(ParamError::Unused { .. })));
//! assert_eq!(p.get_or("warmup", 100u32).unwrap(), 20);
//! assert!(p.check_used("smc").is_ok());
//! ```

use std::cell::Cell;
use std::fmt;

/// The largest count [`Params::count_or`] accepts (2²⁴ = 16,777,216: a
/// thousand times the papers' largest settings).
pub const MAX_COUNT: u64 = 1 << 24;

/// Errors of reading parameters; each names the key.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
pub enum ParamError {
    /// A `key=value` item without `=` or with an empty key.
    #[error("'{0}' is not key=value")]
    Syntax(String),
    /// The same key given twice.
    #[error("{key} is given twice ({first} and {second})")]
    Duplicate {
        /// The key.
        key: String,
        /// Its first value.
        first: String,
        /// The second.
        second: String,
    },
    /// The value does not parse as the type the reader expects.
    #[error("{key}={value}: expected {expected}")]
    Invalid {
        /// The key.
        key: String,
        /// Its value.
        value: String,
        /// What the reader expects (`a whole number`, …).
        expected: &'static str,
    },
    /// The value parses but lies outside what the reader accepts.
    #[error("{key}={value}: must be {allowed}")]
    OutOfRange {
        /// The key.
        key: String,
        /// Its value.
        value: String,
        /// What is allowed (`at least 1`, `in (0, 1]`, …).
        allowed: String,
    },
    /// Keys that were given but that no reader took.
    #[error("{reader} does not read {}", keys.join(", "))]
    Unused {
        /// Who read the parameters (`sampler 'ir'`).
        reader: String,
        /// The keys nobody read.
        keys: Vec<String>,
    },
}

/// A value type a parameter can be read as.
pub trait FromParam: Sized {
    /// What the text must look like, for errors (`a whole number`).
    const EXPECTED: &'static str;
    /// Parses `text`, or `None` when it is not of this type.
    fn from_param(text: &str) -> Option<Self>;
}

macro_rules! from_param_via_parse {
    ($($t:ty => $what:literal),* $(,)?) => {$(
        impl FromParam for $t {
            const EXPECTED: &'static str = $what;
            fn from_param(text: &str) -> Option<Self> {
                text.trim().parse().ok()
            }
        }
    )*};
}

from_param_via_parse!(
    usize => "a whole number",
    u32 => "a whole number below 2^32",
    u64 => "a whole number",
    i64 => "an integer",
);

impl FromParam for f32 {
    const EXPECTED: &'static str = "a finite number";
    fn from_param(text: &str) -> Option<Self> {
        text.trim().parse::<f32>().ok().filter(|v| v.is_finite())
    }
}

impl FromParam for f64 {
    const EXPECTED: &'static str = "a finite number";
    fn from_param(text: &str) -> Option<Self> {
        text.trim().parse::<f64>().ok().filter(|v| v.is_finite())
    }
}

impl FromParam for bool {
    const EXPECTED: &'static str = "true or false";
    fn from_param(text: &str) -> Option<Self> {
        match text.trim().to_ascii_lowercase().as_str() {
            "true" | "1" | "yes" | "on" => Some(true),
            "false" | "0" | "no" | "off" => Some(false),
            _ => None,
        }
    }
}

impl FromParam for String {
    const EXPECTED: &'static str = "text";
    fn from_param(text: &str) -> Option<Self> {
        Some(text.to_string())
    }
}

#[derive(Clone, Debug)]
struct Entry {
    key: String,
    value: String,
    /// Given by a user: an error when unread.
    required: bool,
    used: Cell<bool>,
}

/// A set of `key=value` parameters and which of them were read.
#[derive(Clone, Debug, Default)]
pub struct Params {
    entries: Vec<Entry>,
}

impl Params {
    /// No parameters.
    pub fn new() -> Params {
        Params::default()
    }

    /// Parses `key=value` items (surrounding spaces trimmed); a key given
    /// twice is an error.
    pub fn parse<I, S>(items: I) -> Result<Params, ParamError>
    where
        I: IntoIterator<Item = S>,
        S: AsRef<str>,
    {
        let mut p = Params::new();
        for item in items {
            let item = item.as_ref();
            let (k, v) = item.split_once('=').ok_or_else(|| ParamError::Syntax(item.to_string()))?;
            p.insert(k, v)?;
        }
        Ok(p)
    }

    /// Adds `key` = `value`, which some reader must take; a key already
    /// given is an error.
    pub fn insert(&mut self, key: &str, value: impl fmt::Display) -> Result<&mut Params, ParamError> {
        let key = key.trim();
        if key.is_empty() {
            return Err(ParamError::Syntax(format!("={value}")));
        }
        let value = value.to_string().trim().to_string();
        if let Some(e) = self.entries.iter().find(|e| e.key == key) {
            if e.required {
                return Err(ParamError::Duplicate { key: key.into(), first: e.value.clone(), second: value });
            }
            self.entries.retain(|e| e.key != key);
        }
        self.entries.push(Entry { key: key.into(), value, required: true, used: Cell::new(false) });
        Ok(self)
    }

    /// Offers `key` = `value` to readers that want it: no error when nobody
    /// reads it, and a value [`Params::insert`]ed for the same key wins.
    pub fn offer(&mut self, key: &str, value: impl fmt::Display) -> &mut Params {
        let key = key.trim();
        if !self.entries.iter().any(|e| e.key == key) {
            self.entries.push(Entry { key: key.into(), value: value.to_string(), required: false, used: Cell::new(false) });
        }
        self
    }

    /// Whether `key` was given ([`Params::insert`]), not merely offered.
    pub fn is_given(&self, key: &str) -> bool {
        self.entries.iter().any(|e| e.key == key && e.required)
    }

    /// Whether `key` was given or offered.
    pub fn contains(&self, key: &str) -> bool {
        self.entries.iter().any(|e| e.key == key)
    }

    /// The value of `key` as `T`, `None` when absent; marks `key` read.
    pub fn get<T: FromParam>(&self, key: &str) -> Result<Option<T>, ParamError> {
        let Some(e) = self.entries.iter().find(|e| e.key == key) else {
            return Ok(None);
        };
        e.used.set(true);
        T::from_param(&e.value).map(Some).ok_or_else(|| ParamError::Invalid {
            key: key.into(),
            value: e.value.clone(),
            expected: T::EXPECTED,
        })
    }

    /// The value of `key` as `T`, or `default` when absent.
    pub fn get_or<T: FromParam>(&self, key: &str, default: T) -> Result<T, ParamError> {
        Ok(self.get(key)?.unwrap_or(default))
    }

    /// [`Params::get_or`] for a count that must be at least `least` and
    /// at most [`MAX_COUNT`].
    ///
    /// Counts size buffers and loops (camera samples, chains, paths a VPL);
    /// the upper bound keeps every one of them inside what a memory
    /// estimate can weigh, so `camera-samples=4294967296` is one error
    /// line rather than a "capacity overflow" abort.
    pub fn count_or<T>(&self, key: &str, default: T, least: T) -> Result<T, ParamError>
    where
        T: FromParam + PartialOrd + fmt::Display + Copy + TryInto<u64>,
    {
        let v = self.get_or(key, default)?;
        let too_many = v.try_into().map_or(true, |n| n > MAX_COUNT);
        if v < least || too_many {
            return Err(self.out_of_range(key, v, format!("from {least} to {MAX_COUNT}")));
        }
        Ok(v)
    }

    /// An [`ParamError::OutOfRange`] for `key` holding `value`.
    pub fn out_of_range(&self, key: &str, value: impl fmt::Display, allowed: impl Into<String>) -> ParamError {
        ParamError::OutOfRange { key: key.into(), value: value.to_string(), allowed: allowed.into() }
    }

    /// The keys given by a user (not merely offered) that nobody read.
    pub fn unused(&self) -> Vec<&str> {
        self.entries.iter().filter(|e| e.required && !e.used.get()).map(|e| e.key.as_str()).collect()
    }

    /// An error naming the keys given but not read, by `reader` (`sampler 'ir'`).
    pub fn check_used(&self, reader: &str) -> Result<(), ParamError> {
        let keys = self.unused();
        if keys.is_empty() {
            return Ok(());
        }
        Err(ParamError::Unused { reader: reader.into(), keys: keys.into_iter().map(String::from).collect() })
    }

    /// Every key and value, in the order given.
    pub fn iter(&self) -> impl Iterator<Item = (&str, &str)> {
        self.entries.iter().map(|e| (e.key.as_str(), e.value.as_str()))
    }
}

impl fmt::Display for Params {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (k, v)) in self.iter().enumerate() {
            if i > 0 {
                f.write_str(" ")?;
            }
            write!(f, "{k}={v}")?;
        }
        Ok(())
    }
}

/// A key a component reads, for help texts and registries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamKey {
    /// The key (`m-max`).
    pub key: &'static str,
    /// Its default, in words (`16`, `max(1, ⌊√(I/32)⌋)`).
    pub default: &'static str,
    /// What it sets.
    pub about: &'static str,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_types_and_names_keys_in_errors() {
        let p = Params::parse(["a=3", " b = 0.5 ", "c=yes", "d=x"]).unwrap();
        assert_eq!(p.get::<usize>("a").unwrap(), Some(3));
        assert_eq!(p.get::<f32>("b").unwrap(), Some(0.5));
        assert_eq!(p.get::<bool>("c").unwrap(), Some(true));
        let e = p.get::<u32>("d").unwrap_err();
        assert_eq!(e.to_string(), "d=x: expected a whole number below 2^32");
        assert_eq!(p.get::<u32>("zz").unwrap(), None);
        assert!(p.check_used("me").is_ok());
        assert!(matches!(Params::parse(["novalue"]), Err(ParamError::Syntax(_))));
        assert!(matches!(Params::parse(["=1"]), Err(ParamError::Syntax(_))));
        assert!(matches!(Params::parse(["a=1", "a=2"]), Err(ParamError::Duplicate { .. })));
        assert!(matches!(Params::parse(["x=inf"]).unwrap().get::<f32>("x"), Err(ParamError::Invalid { .. })));
    }

    #[test]
    fn unread_keys_are_reported_but_offers_are_not() {
        let mut p = Params::parse(["used=1", "stray=2"]).unwrap();
        p.offer("hint", true);
        p.offer("used", 7);
        assert_eq!(p.get_or("used", 0u32).unwrap(), 1, "a given value beats an offer");
        let e = p.check_used("sampler 'ir'").unwrap_err();
        assert_eq!(e.to_string(), "sampler 'ir' does not read stray");
        let mut q = Params::new();
        q.offer("k", 1);
        q.insert("k", 2).unwrap();
        assert_eq!(q.get_or("k", 0u32).unwrap(), 2, "an insert replaces an offer");
    }

    #[test]
    fn counts_check_their_least_and_largest_value() {
        let p = Params::parse(["n=0"]).unwrap();
        let e = p.count_or("n", 4usize, 1).unwrap_err();
        assert_eq!(e.to_string(), "n=0: must be from 1 to 16777216");
        assert_eq!(Params::new().count_or("n", 4usize, 1).unwrap(), 4);
        // 2³² camera samples aborted with "capacity overflow"; 2²⁴ is the bound.
        let p = Params::parse(["n=4294967296"]).unwrap();
        assert_eq!(p.count_or("n", 4usize, 1).unwrap_err().to_string(), "n=4294967296: must be from 1 to 16777216");
        let p = Params::parse(["n=16777216"]).unwrap();
        assert_eq!(p.count_or("n", 4u64, 1).unwrap(), 1 << 24);
    }
}

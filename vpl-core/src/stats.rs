//! Typed statistics of a stage's last frame: named counts, values and
//! milliseconds that a harness prints, writes to CSV and JSON, or reads by
//! key (`acceptance`, `stored`, `moved`, …), instead of a free-form line.
//!
//! ```
//! use vpl_core::stats::Stats;
//!
//! let s = Stats::new().count("stored", 2048).value("acceptance", 0.31).ms("ms", 12.5);
//! assert_eq!(s.get("stored"), Some(2048.0));
//! assert_eq!(s.to_string(), "stored 2048, acceptance 0.31, ms 12.5");
//! ```

use std::fmt;

/// One statistic's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Stat {
    /// A count (VPLs stored, rays cast).
    Count(u64),
    /// A real value (an acceptance rate, a coefficient of variation).
    Value(f64),
    /// Milliseconds.
    Ms(f64),
}

impl Stat {
    /// The value as a number.
    pub fn as_f64(self) -> f64 {
        match self {
            Stat::Count(n) => n as f64,
            Stat::Value(v) | Stat::Ms(v) => v,
        }
    }
}

impl fmt::Display for Stat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Stat::Count(n) => write!(f, "{n}"),
            Stat::Value(v) => write!(f, "{}", Short(*v)),
            Stat::Ms(v) => write!(f, "{v:.1}"),
        }
    }
}

/// A real value with four significant digits, without trailing zeros.
struct Short(f64);

impl fmt::Display for Short {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v == 0.0 || !v.is_finite() {
            return write!(f, "{v}");
        }
        let digits = (3 - v.abs().log10().floor() as i32).clamp(0, 12) as usize;
        let s = format!("{v:.digits$}");
        let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
        f.write_str(&s)
    }
}

/// Named statistics in a fixed order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stats {
    entries: Vec<(&'static str, Stat)>,
}

impl Stats {
    /// No statistics.
    pub fn new() -> Stats {
        Stats::default()
    }

    /// Adds (or replaces) `key` with `stat`.
    pub fn with(mut self, key: &'static str, stat: Stat) -> Stats {
        self.set(key, stat);
        self
    }

    /// Sets `key` to `stat`, in place.
    pub fn set(&mut self, key: &'static str, stat: Stat) {
        match self.entries.iter_mut().find(|(k, _)| *k == key) {
            Some(e) => e.1 = stat,
            None => self.entries.push((key, stat)),
        }
    }

    /// Adds a count.
    pub fn count(self, key: &'static str, n: usize) -> Stats {
        self.with(key, Stat::Count(n as u64))
    }

    /// Adds a real value.
    pub fn value(self, key: &'static str, v: f64) -> Stats {
        self.with(key, Stat::Value(v))
    }

    /// Adds milliseconds.
    pub fn ms(self, key: &'static str, ms: f64) -> Stats {
        self.with(key, Stat::Ms(ms))
    }

    /// The statistic `key` as a number.
    pub fn get(&self, key: &str) -> Option<f64> {
        self.stat(key).map(Stat::as_f64)
    }

    /// The statistic `key`.
    pub fn stat(&self, key: &str) -> Option<Stat> {
        self.entries.iter().find(|(k, _)| *k == key).map(|e| e.1)
    }

    /// Every statistic, in order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, Stat)> + '_ {
        self.entries.iter().copied()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The keys, in order.
    pub fn keys(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.entries.iter().map(|e| e.0)
    }
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (k, v)) in self.entries.iter().enumerate() {
            if i > 0 {
                f.write_str(", ")?;
            }
            write!(f, "{k} {v}")?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_keep_their_order_and_replace_in_place() {
        let mut s = Stats::new().count("a", 1).value("b", 0.123456).ms("c", 2.0);
        s.set("a", Stat::Count(5));
        assert_eq!(s.keys().collect::<Vec<_>>(), ["a", "b", "c"]);
        assert_eq!(s.to_string(), "a 5, b 0.1235, c 2.0");
        assert_eq!(s.get("b"), Some(0.123456));
        assert_eq!(s.get("zz"), None);
        assert_eq!(Stats::new().value("x", 12345.678).to_string(), "x 12346");
        assert_eq!(Stats::new().value("x", 3.2e-5).to_string(), "x 0.00003200".trim_end_matches('0'));
    }
}

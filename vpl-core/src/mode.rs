//! Which light paths an image contains, counted by scattering vertices.
//!
//! A path from the camera to a light with k scattering vertices has k + 1
//! segments. Depth follows Mitsuba 3: `max_depth` bounds the number of
//! segments, so k ≤ `max_depth − 1`; 5 means direct light plus three
//! indirect bounces. The modes select paths by k: `full` (any), `direct`
//! (k ≤ 1: emitters seen directly and single scattering), `indirect` (k ≥ 2:
//! exactly what VPL methods render, and `full − direct` path by path).

/// Which paths an estimate includes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Mode {
    /// All paths up to `max_depth`.
    Full,
    /// Emission seen directly and single scattering (k ≤ 1).
    Direct,
    /// Paths with at least two scattering vertices (k ≥ 2).
    Indirect,
}

impl Mode {
    /// The range `min_k..=max_k` of scattering-vertex counts this mode keeps
    /// at depth `max_depth` (empty when `min_k > max_k`).
    #[inline]
    pub fn k_range(self, max_depth: u32) -> (u32, u32) {
        let max_k = max_depth.saturating_sub(1);
        match self {
            Mode::Full => (0, max_k),
            Mode::Direct => (0, max_k.min(1)),
            Mode::Indirect => (2, max_k),
        }
    }

    /// Whether paths with `k` scattering vertices count at depth `max_depth`.
    #[inline]
    pub fn includes(self, k: u32, max_depth: u32) -> bool {
        let (lo, hi) = self.k_range(max_depth);
        max_depth > 0 && k >= lo && k <= hi
    }
}

/// A mode name that is none of `full`, `direct`, `indirect`.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown mode '{0}' (full, direct, indirect)")]
pub struct UnknownMode(pub String);

impl std::fmt::Display for Mode {
    /// The spelling [`Mode`]'s `FromStr` reads: `full`, `direct`, `indirect`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Mode::Full => "full",
            Mode::Direct => "direct",
            Mode::Indirect => "indirect",
        })
    }
}

impl std::str::FromStr for Mode {
    type Err = UnknownMode;
    fn from_str(s: &str) -> Result<Self, UnknownMode> {
        match s {
            "full" => Ok(Mode::Full),
            "direct" => Ok(Mode::Direct),
            "indirect" => Ok(Mode::Indirect),
            _ => Err(UnknownMode(s.to_string())),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_follow_mitsuba_depth() {
        assert_eq!(Mode::Full.k_range(5), (0, 4));
        assert_eq!(Mode::Direct.k_range(5), (0, 1));
        assert_eq!(Mode::Indirect.k_range(5), (2, 4));
        assert!(!Mode::Indirect.includes(2, 2));
        assert!(Mode::Indirect.includes(4, 5) && !Mode::Indirect.includes(5, 5));
        assert!(!Mode::Full.includes(0, 0));
    }
}

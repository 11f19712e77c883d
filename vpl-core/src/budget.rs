//! The VPL budget and path depth of a renderer: set once, where the
//! renderer is built, and read by every stage (the sampler's slots and
//! bounces, the geometry clamp, the shadow-map atlas, the frame's paths).

/// How many VPLs a frame holds and how long its paths are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Budget {
    /// I: VPL slots per frame.
    pub vpls: usize,
    /// Longest path in segments (Mitsuba 3's convention: 5 = direct light
    /// and three indirect bounces). VPLs carry paths of ≥ 2 scattering
    /// vertices, so they need at least 3.
    pub max_depth: u32,
}

impl Default for Budget {
    /// The papers' defaults: I = 2048, three indirect bounces.
    fn default() -> Self {
        Budget { vpls: 2048, max_depth: 5 }
    }
}

impl Budget {
    /// A budget of `vpls` slots with paths of at most `max_depth` segments.
    pub fn new(vpls: usize, max_depth: u32) -> Budget {
        Budget { vpls, max_depth }
    }

    /// Light-path bounces whose vertices may hold a VPL: `max_depth − 2`.
    pub fn bounces(&self) -> u32 {
        self.max_depth.saturating_sub(2)
    }

    /// Scattering vertices after a VPL in the paths that estimate its
    /// radiosity: `max_depth − 3`.
    pub fn radiosity_bounces(&self) -> u32 {
        self.max_depth.saturating_sub(3)
    }

    /// Whether paths are long enough for VPLs to carry light (max depth ≥ 3).
    pub fn has_indirect(&self) -> bool {
        self.max_depth >= 3
    }
}

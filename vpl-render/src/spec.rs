//! What the stages after sampling are: visibility, shading, clamp.

use vpl_core::{GeometryClamp, Scene};

/// VPL-to-pixel visibility.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VisibilitySpec {
    /// Exact BVH shadow rays.
    RayTraced,
    /// Paraboloid shadow maps of this side in texels.
    ShadowMaps(u32),
}

impl Default for VisibilitySpec {
    /// Shadow maps of 128² texels, the SMC paper's.
    fn default() -> Self {
        VisibilitySpec::ShadowMaps(vpl_visibility::DEFAULT_RESOLUTION)
    }
}

/// Indirect shading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingSpec {
    /// 4×4 interleaved subsets, with or without the cross-bilateral filter.
    Interleaved {
        /// Whether to filter.
        filter: bool,
    },
    /// Every VPL at every pixel.
    Exhaustive,
}

impl Default for ShadingSpec {
    /// Interleaved and filtered, as the SMC paper renders.
    fn default() -> Self {
        ShadingSpec::Interleaved { filter: true }
    }
}

/// The geometry-term clamp of VPL shading.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Clamp {
    /// G_max = I / A: a VPL nearer a receiver than the mean VPL spacing
    /// √(A/I) is clamped ([`GeometryClamp::for_budget`]).
    #[default]
    Auto,
    /// No clamp (unbiased, noisy near corners).
    Off,
    /// This clamp.
    Value(GeometryClamp),
}

impl Clamp {
    /// The clamp for a budget of `vpls` on `scene`.
    pub fn resolve(self, vpls: usize, scene: &Scene) -> Option<GeometryClamp> {
        match self {
            Clamp::Auto => Some(GeometryClamp::for_budget(vpls, scene.surface_area())),
            Clamp::Off => None,
            Clamp::Value(c) => Some(c),
        }
    }
}

impl From<Option<GeometryClamp>> for Clamp {
    fn from(c: Option<GeometryClamp>) -> Clamp {
        c.map_or(Clamp::Off, Clamp::Value)
    }
}

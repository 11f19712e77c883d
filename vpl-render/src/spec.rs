//! What the stages after sampling are: visibility, shading, clamp.

use vpl_core::{Camera, GeometryClamp, Scene};

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
    /// G_max = I / A_view from the view of each frame a renderer draws
    /// ([`GeometryClamp::for_view`]): it follows the camera (resolved anew
    /// when the camera moves, and kept while it stands still).
    #[default]
    Auto,
    /// G_max = I / A with A the whole scene's surface area
    /// ([`GeometryClamp::for_scene_area`]).
    SceneArea,
    /// No clamp (unbiased, noisy near corners).
    Off,
    /// This clamp.
    Value(GeometryClamp),
}

impl Clamp {
    /// The clamp for a budget of `vpls` on `scene` seen by `camera`.
    pub fn resolve(self, vpls: usize, scene: &Scene, camera: &Camera) -> Option<GeometryClamp> {
        match self {
            Clamp::Auto => Some(GeometryClamp::for_view(vpls, scene, camera)),
            other => other.without_view(vpls, scene).flatten(),
        }
    }

    /// The clamp when the rule needs no view (every rule but `Auto`).
    pub(crate) fn without_view(self, vpls: usize, scene: &Scene) -> Option<Option<GeometryClamp>> {
        match self {
            Clamp::Auto => None,
            Clamp::SceneArea => Some(Some(GeometryClamp::for_scene_area(vpls, scene.surface_area()))),
            Clamp::Off => Some(None),
            Clamp::Value(c) => Some(Some(c)),
        }
    }
}

impl From<Option<GeometryClamp>> for Clamp {
    fn from(c: Option<GeometryClamp>) -> Clamp {
        c.map_or(Clamp::Off, Clamp::Value)
    }
}

/// What a frame brings to the host when its stages run on a device. The
/// CPU backend has everything on the host and ignores it.
///
/// A frame stays on the device only where every stage of it can: indirect
/// light, or emission and direct light too where the shader adds them on
/// the device ([`vpl_core::IndirectShader::finishes_on_device`]; not
/// [`vpl_core::Mode::Direct`] alone), no bias compensation, a shader and
/// visibility on the device, and a sampler that does not read the previous
/// image. Otherwise the frame reads back what its host stages need, as
/// with [`ReadBack::All`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ReadBack {
    /// The G-buffer and the image, every frame (the default).
    #[default]
    All,
    /// The image every frame; the G-buffer stays on the device
    /// ([`vpl_core::GBuffer::on_device`] in the output).
    Image,
    /// Nothing: the image stays on the device too
    /// ([`vpl_core::Image::on_device`] in the output) until
    /// [`crate::Renderer::read_image`] asks for it.
    Nothing,
}

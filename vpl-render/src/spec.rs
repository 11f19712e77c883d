//! What the stages after sampling are: visibility, shading, clamp. Each
//! has one spelling, which `Display` prints and `FromStr` reads, shared by
//! the command line, Python and the viewer:
//!
//! | value | spelling |
//! | --- | --- |
//! | [`VisibilitySpec`] | `raytrace`, `shadowmap` (128² texels), `shadowmap:N` |
//! | [`ShadingSpec`] | `interleaved` (filtered), `interleaved-unfiltered`, `exhaustive`, `lightcuts` (a cut of 32), `lightcuts:N`, `culled` (bound 4), `culled:X` |
//! | [`Clamp`] | `auto`, `scene-area`, `off`, or G_max as a positive number |
//!
//! ```
//! use vpl_render::{Clamp, ShadingSpec, VisibilitySpec};
//!
//! assert_eq!("shadowmap:256".parse::<VisibilitySpec>().unwrap(), VisibilitySpec::ShadowMaps(256));
//! assert_eq!(VisibilitySpec::default().to_string(), "shadowmap:128");
//! assert_eq!("interleaved-unfiltered".parse::<ShadingSpec>().unwrap(), ShadingSpec::Interleaved { filter: false });
//! assert_eq!("lightcuts".parse::<ShadingSpec>().unwrap().to_string(), "lightcuts:32");
//! assert!("lightcuts:0".parse::<ShadingSpec>().is_err());
//! assert_eq!("culled:2.5".parse::<ShadingSpec>().unwrap(), ShadingSpec::Culled { bound: 2.5 });
//! assert_eq!("culled".parse::<ShadingSpec>().unwrap().to_string(), "culled:4");
//! assert_eq!("scene-area".parse::<Clamp>().unwrap(), Clamp::SceneArea);
//! for c in ["auto", "scene-area", "off", "2.5"] {
//!     assert_eq!(c.parse::<Clamp>().unwrap().to_string(), c);
//! }
//! assert!("-1".parse::<Clamp>().is_err());
//! ```

use std::fmt;
use std::str::FromStr;
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

impl fmt::Display for VisibilitySpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            VisibilitySpec::RayTraced => f.write_str("raytrace"),
            VisibilitySpec::ShadowMaps(res) => write!(f, "shadowmap:{res}"),
        }
    }
}

impl FromStr for VisibilitySpec {
    type Err = String;
    /// `raytrace`, `shadowmap` or `shadowmap:N` (N texels a side, at least
    /// 1). `raytraced`, `ray-traced`, `rays` and `shadow-map` are read too,
    /// as Python scripts wrote them.
    fn from_str(s: &str) -> Result<Self, String> {
        let (kind, res) = match s.split_once(':') {
            Some((k, r)) => (k, Some(r)),
            None => (s, None),
        };
        match (kind, res) {
            ("raytrace" | "raytraced" | "ray-traced" | "rays", None) => Ok(VisibilitySpec::RayTraced),
            ("shadowmap" | "shadow-map", None) => Ok(VisibilitySpec::default()),
            ("shadowmap" | "shadow-map", Some(r)) => match r.parse::<u32>() {
                Ok(n) if n >= 1 => Ok(VisibilitySpec::ShadowMaps(n)),
                _ => Err(format!("visibility '{s}': the shadow maps' side must be a positive whole number of texels")),
            },
            _ => Err(format!("unknown visibility '{s}' (raytrace, shadowmap, shadowmap:N)")),
        }
    }
}

/// Indirect shading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadingSpec {
    /// 4×4 interleaved subsets, with or without the cross-bilateral filter.
    Interleaved {
        /// Whether to filter.
        filter: bool,
    },
    /// Every VPL at every pixel.
    Exhaustive,
    /// Stochastic lightcuts: `cut` VPLs a pixel, sampled through a light
    /// tree (`vpl_shading::LightcutShader`; on the GPU backend it runs on
    /// the host).
    Lightcuts {
        /// VPLs sampled at each pixel (at least 1).
        cut: u32,
    },
    /// Every VPL at every pixel, each VPL's range cut by Russian roulette
    /// (`vpl_shading::CulledShader`): unbiased, so with the clamp off it
    /// converges to the unclamped image; on the GPU backend it runs on the
    /// host.
    Culled {
        /// The roulette's threshold relative to the mean VPL's irradiance
        /// at the receivers' diagonal (positive; larger culls more).
        bound: f32,
    },
}

impl ShadingSpec {
    /// The cut of `lightcuts` without a size.
    pub const DEFAULT_CUT: u32 = 32;
    /// The bound of `culled` without one.
    pub const DEFAULT_BOUND: f32 = 4.0;
}

impl Default for ShadingSpec {
    /// Interleaved and filtered, as the SMC paper renders.
    fn default() -> Self {
        ShadingSpec::Interleaved { filter: true }
    }
}

impl fmt::Display for ShadingSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ShadingSpec::Interleaved { filter: true } => f.write_str("interleaved"),
            ShadingSpec::Interleaved { filter: false } => f.write_str("interleaved-unfiltered"),
            ShadingSpec::Exhaustive => f.write_str("exhaustive"),
            ShadingSpec::Lightcuts { cut } => write!(f, "lightcuts:{cut}"),
            ShadingSpec::Culled { bound } => write!(f, "culled:{bound}"),
        }
    }
}

impl FromStr for ShadingSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "interleaved" => Ok(ShadingSpec::Interleaved { filter: true }),
            "interleaved-unfiltered" => Ok(ShadingSpec::Interleaved { filter: false }),
            "exhaustive" => Ok(ShadingSpec::Exhaustive),
            "lightcuts" => Ok(ShadingSpec::Lightcuts { cut: ShadingSpec::DEFAULT_CUT }),
            "culled" => Ok(ShadingSpec::Culled { bound: ShadingSpec::DEFAULT_BOUND }),
            _ if s.starts_with("culled:") => match s["culled:".len()..].parse::<f32>() {
                Ok(bound) if bound.is_finite() && bound > 0.0 => Ok(ShadingSpec::Culled { bound }),
                _ => Err(format!("shading '{s}': the culling bound must be a positive number")),
            },
            _ => match s.strip_prefix("lightcuts:").map(str::parse::<u32>) {
                Some(Ok(cut)) if cut >= 1 => Ok(ShadingSpec::Lightcuts { cut }),
                Some(_) => Err(format!("shading '{s}': the cut must be a positive whole number of VPLs")),
                None => Err(format!(
                    "unknown shading '{s}' (interleaved, interleaved-unfiltered, exhaustive, lightcuts, lightcuts:N, culled, culled:X)"
                )),
            },
        }
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

impl fmt::Display for Clamp {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Clamp::Auto => f.write_str("auto"),
            Clamp::SceneArea => f.write_str("scene-area"),
            Clamp::Off => f.write_str("off"),
            Clamp::Value(c) => write!(f, "{}", c.g_max),
        }
    }
}

impl FromStr for Clamp {
    type Err = String;
    /// `auto`, `scene-area`, `off` or G_max (a positive, finite number);
    /// `area` is read as `scene-area`, as the command line spelled it.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Clamp::Auto),
            "scene-area" | "area" => Ok(Clamp::SceneArea),
            "off" => Ok(Clamp::Off),
            _ => match s.parse::<f32>() {
                Ok(g) if g.is_finite() && g > 0.0 => Ok(Clamp::Value(GeometryClamp::new(g))),
                _ => Err(format!("clamp '{s}' must be 'auto', 'scene-area', 'off' or G_max as a positive number")),
            },
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

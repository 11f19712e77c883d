//! Light sources: one-sided emissive triangles, point, spot, directional
//! (sun) and the environment (sky).

use crate::environment::Sky;
use glam::Vec3;
use std::f32::consts::PI;

/// A light source.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// An emissive triangle of the scene mesh, emitting `radiance` from its
    /// front side (the side its winding normal points to).
    Area {
        /// Index of the triangle in the scene.
        triangle: u32,
        /// Emitted radiance Le.
        radiance: Vec3,
    },
    /// An isotropic point light.
    Point {
        /// Position.
        position: Vec3,
        /// Radiant intensity (W/sr), linear RGB.
        intensity: Vec3,
    },
    /// A spot light: intensity `intensity` inside a cone of half-angle
    /// `acos(cos_falloff_start)`, smoothly falling to zero at `acos(cos_total)`.
    Spot {
        /// Position.
        position: Vec3,
        /// Unit axis of the cone.
        direction: Vec3,
        /// Radiant intensity on the axis (W/sr).
        intensity: Vec3,
        /// Cosine of the half-angle where the falloff begins.
        cos_falloff_start: f32,
        /// Cosine of the half-angle outside which nothing is emitted.
        cos_total: f32,
    },
    /// A distant light (the sun).
    Directional {
        /// Unit direction in which light travels.
        direction: Vec3,
        /// Irradiance (W/m²) on a surface facing the light.
        irradiance: Vec3,
    },
    /// Light arriving from infinitely far away in every direction: what a
    /// ray that leaves the scene sees ([`Sky`]).
    Environment {
        /// Radiance by direction.
        sky: Sky,
    },
}

/// Mean of the RGB channels: the scalar that power-proportional selection uses.
#[inline]
pub fn channel_mean(c: Vec3) -> f32 {
    (c.x + c.y + c.z) * (1.0 / 3.0)
}

impl Light {
    /// Emitted power Φ (scalar, channel mean): π·A·Le for a one-sided area light,
    /// 4π·I for a point light, 2π·I·(1 − (cos_start + cos_total)/2) for a spot
    /// (pbrt-v4 §12.2.2), π·r²·E for the sun and π·r²·∫L dω for the
    /// environment over a scene of bounding radius r.
    /// `area` is the triangle's area (ignored for other lights).
    pub fn power(&self, area: f32, scene_radius: f32) -> f32 {
        match self {
            Light::Area { radiance, .. } => PI * area * channel_mean(*radiance),
            Light::Point { intensity, .. } => 4.0 * PI * channel_mean(*intensity),
            Light::Spot { intensity, cos_falloff_start, cos_total, .. } => {
                2.0 * PI * channel_mean(*intensity) * (1.0 - 0.5 * (cos_falloff_start + cos_total))
            }
            Light::Directional { irradiance, .. } => PI * scene_radius * scene_radius * channel_mean(*irradiance),
            Light::Environment { sky } => sky.power(scene_radius),
        }
    }

    /// True for lights of one position or one direction (point, spot, sun):
    /// no other sampling technique can find them, so they take no MIS.
    pub fn is_delta(&self) -> bool {
        !matches!(self, Light::Area { .. } | Light::Environment { .. })
    }

    /// True for the lights a scene holds besides its emissive triangles
    /// (what a scene file describes, and an animation moves).
    pub fn is_extra(&self) -> bool {
        !matches!(self, Light::Area { .. })
    }

    /// Spot falloff (smoothstep between the two cone angles, pbrt-v4 §12.2.2).
    #[inline]
    pub fn spot_falloff(cos_theta: f32, cos_falloff_start: f32, cos_total: f32) -> f32 {
        if cos_theta >= cos_falloff_start {
            return 1.0;
        }
        if cos_theta <= cos_total {
            return 0.0;
        }
        let t = ((cos_theta - cos_total) / (cos_falloff_start - cos_total)).clamp(0.0, 1.0);
        t * t * (3.0 - 2.0 * t)
    }
}

/// A light sample seen from a receiving point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the receiver toward the light.
    pub wi: Vec3,
    /// Distance to the sampled point (infinite for the sun).
    pub dist: f32,
    /// Incident radiance (area) or irradiance-like term (delta lights: I/d², E) carried along `wi`.
    pub li: Vec3,
    /// Solid-angle density of the sample given the light (1 for delta lights).
    pub pdf: f32,
    /// Whether the light is a delta light (no MIS).
    pub delta: bool,
}

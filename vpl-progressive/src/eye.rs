//! Eye paths (§3.1, Fig. 3a): one per pixel and pass, through specular
//! vertices to the first diffuse one, with a ray cone that gives the caustic
//! bin radius (§5.3).
//!
//! The cone is an isotropic ray differential (Igehy 1999 reduced to one
//! width and one spread angle, as in the ray cones of Akenine-Möller et al.
//! 2019): it starts as the pixel's footprint (spread γ, the angle a pixel
//! subtends), widens by the spread along each segment, and at a specular
//! vertex the surface's curvature c (from its shading normals) bends it:
//! reflection adds 2·c·w to the spread, refraction with relative index η
//! scales the spread by η and adds (η − 1)·c·w, c counted positive where
//! the surface is convex toward the arriving ray. The bin radius is half
//! the width at the diffuse vertex.

use crate::config::ProgressiveConfig;
use crate::vertex::roulette;
use vpl_core::bsdf::scatter;
use vpl_core::bsdf::{Layer, LayerKind};
use vpl_core::glam::Vec3;
use vpl_core::{Camera, Purpose, Ray, Scene, SurfacePoint, stream};

/// The diffuse vertex an eye path ends on: a gather point for VPLs and a
/// caustic histogram bin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyeVertex {
    /// Pixel index y·w + x.
    pub pixel: u32,
    /// The surface point (turned toward the eye for opaque surfaces).
    pub x: SurfacePoint,
    /// Direction back along the eye path.
    pub wo: Vec3,
    /// Throughput from the camera (specular weights, spectral weight).
    pub beta: Vec3,
    /// Specular vertices before this one (0: seen directly).
    pub specular: u32,
    /// Bin radius: half a pixel's footprint carried along the path.
    pub radius: f32,
    /// The diffuse layer chosen here.
    pub layer: Layer,
    /// Index of refraction at the path's wavelength.
    pub eta: f32,
}

/// What one eye path gives: the ES*L radiance it found and where it ended diffusely.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EyePath {
    /// Radiance of ES*L paths (lights seen directly or through specular vertices).
    pub direct: Vec3,
    /// The diffuse vertex, if the path reached one.
    pub vertex: Option<EyeVertex>,
}

/// A ray cone: footprint width and spread angle (radians; negative converges).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayCone {
    /// Width of the footprint where the cone stands.
    pub width: f32,
    /// Spread angle.
    pub spread: f32,
}

impl RayCone {
    /// The cone after a segment of length `t`.
    #[inline]
    pub fn travel(self, t: f32) -> RayCone {
        RayCone { width: self.width + self.spread * t, ..self }
    }

    /// The cone after a mirror reflection at curvature `c` (convex toward the ray > 0).
    #[inline]
    pub fn reflect(self, c: f32) -> RayCone {
        RayCone { spread: self.spread + 2.0 * c * self.width.abs(), ..self }
    }

    /// The cone after a refraction with relative index `eta` (η of the
    /// arriving side over η of the other) at curvature `c`.
    #[inline]
    pub fn refract(self, eta: f32, c: f32) -> RayCone {
        RayCone { spread: eta * self.spread + (eta - 1.0) * c * self.width.abs(), ..self }
    }
}

/// Mean normal curvature of triangle `tri` from its vertex normals,
/// Σ (n_i − n_j)·(p_i − p_j) / Σ |p_i − p_j|² over its edges (1/R on a
/// sphere of radius R with outward normals, 0 for flat shading), signed
/// positive where the surface bulges toward its geometric normal.
pub fn curvature(scene: &Scene, tri: u32) -> f32 {
    let t = &scene.geometry.triangles[tri as usize];
    if t.normals == u32::MAX {
        return 0.0;
    }
    let n = &scene.geometry.shading_normals[t.normals as usize];
    let p = t.corners();
    let (mut num, mut den) = (0.0f32, 0.0f32);
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let dp = p[i] - p[j];
        num += (n[i] - n[j]).dot(dp);
        den += dp.length_squared();
    }
    let c = if den > 0.0 { num / den } else { 0.0 };
    // Vertex normals may face against the winding; curvature is relative to ng.
    let agree = (n[0] + n[1] + n[2]).dot(t.ng);
    if agree < 0.0 { -c } else { c }
}

/// Angle a pixel subtends at the image centre (radians), the spread of the ray cones.
pub fn pixel_angle(camera: &Camera) -> f32 {
    let (_, _, _, _, sy) = camera.raster_basis();
    2.0 * sy / camera.resolution.1 as f32
}

/// Traces the eye path of pixel (`px`, `py`) in pass `pass`.
pub fn trace_eye(scene: &Scene, camera: &Camera, cfg: &ProgressiveConfig, pass: u64, px: u32, py: u32, spread: f32) -> EyePath {
    let pixel = py * camera.resolution.0 + px;
    let mut rng = stream(cfg.seed, pass, Purpose::PIXEL, pixel as u64);
    let (u, v) = rng.next_2d();
    let lens = rng.next_2d();
    let mut ray = camera.ray(px as f32 + u, py as f32 + v, lens);
    let eps = scene.epsilon();
    let mut beta = Vec3::ONE;
    let mut lambda = None;
    let mut direct = Vec3::ZERO;
    let mut cone = RayCone { width: 0.0, spread };
    let mut s = 0u32;
    loop {
        let Some(hit) = scene.intersect(&ray) else {
            // Leaving the scene (ES*L with the environment as L).
            if cfg.techniques.direct && s < cfg.max_depth {
                direct += beta * scene.environment_radiance(ray.d);
            }
            break;
        };
        cone = cone.travel(hit.t);
        let sp = hit.point;
        let wo = -ray.d;
        // ES*L: a path of s scattering vertices and s + 1 segments.
        if cfg.techniques.direct && s < cfg.max_depth {
            direct += beta * scene.emitted(&sp, wo);
        }
        // Vertex s + 1 scatters only if a path through it can still reach a light.
        if s + 1 > cfg.max_depth.saturating_sub(1) {
            break;
        }
        let Some(sc) = scatter(scene, sp, wo, cfg.spectral, &mut lambda, &mut beta, &mut rng) else { break };
        if sc.layer.is_diffuse() {
            let radius = (0.5 * cone.width.abs()).max(eps);
            let vertex = EyeVertex { pixel, x: sc.at, wo, beta, specular: s, radius, layer: sc.layer, eta: sc.eta };
            return EyePath { direct, vertex: Some(vertex) };
        }
        let Some(smp) = sc.layer.sample(&sc.at, wo, sc.eta, rng.next_2d()) else { break };
        beta *= smp.weight;
        // Curvature as the arriving ray sees it: positive where the surface bulges toward it.
        let c = curvature(scene, sp.triangle) * if wo.dot(sp.ng) >= 0.0 { 1.0 } else { -1.0 };
        cone = match sc.layer.kind {
            LayerKind::Transmission => cone.refract(if wo.dot(sp.ng) >= 0.0 { 1.0 / sc.eta } else { sc.eta }, c),
            _ => cone.reflect(c),
        };
        s += 1;
        if s >= cfg.rr_depth {
            let Some(q) = roulette(beta, &mut rng) else { break };
            beta /= q;
        }
        ray = Ray::new(sc.at.offset_toward(smp.w, eps), smp.w);
    }
    EyePath { direct, vertex: None }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::SceneSetup;

    /// On the glass scene's sphere (radius 0.8, outward normals) the
    /// curvature is 1/R; on its flat walls 0.
    #[test]
    fn curvature_of_a_sphere_is_one_over_r() {
        let setup = SceneSetup::builtin("glass").unwrap();
        let scene = &setup.scene;
        let glass = scene.materials.iter().position(|m| m.name == "glass").unwrap() as u32;
        let mut seen = 0;
        for (i, t) in scene.geometry.triangles.iter().enumerate() {
            let c = curvature(scene, i as u32);
            if t.material == glass {
                assert!((c - 1.0 / 0.8).abs() < 0.03 / 0.8, "triangle {i}: {c}");
                seen += 1;
            } else if t.normals == u32::MAX {
                assert_eq!(c, 0.0);
            }
        }
        assert!(seen > 100);
    }

    /// A convex mirror spreads a cone, a concave one focuses it; a convex
    /// glass surface entered from outside converges it (a lens).
    #[test]
    fn cones_bend_at_curved_surfaces() {
        let cone = RayCone { width: 0.01, spread: 0.001 };
        assert!(cone.reflect(1.25).spread > cone.spread);
        assert!(cone.reflect(-1.25).spread < cone.spread);
        assert_eq!(cone.reflect(0.0), cone);
        assert!(cone.refract(1.0 / 1.5, 1.25).spread < 0.0);
        // A flat interface only scales the spread by η (Snell's law for small angles).
        assert!((cone.refract(1.0 / 1.5, 0.0).spread - 0.001 / 1.5).abs() < 1e-9);
        // The width follows the spread, and a focused cone's radius is |width|.
        assert!((cone.travel(2.0).width - 0.012).abs() < 1e-7);
    }
}

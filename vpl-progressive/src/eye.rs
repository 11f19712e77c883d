//! Eye paths (§3.1, Fig. 3a): one per pixel and pass, through specular
//! vertices to the first diffuse one, with a ray cone that gives the caustic
//! bin radius (§5.3).

use crate::config::ProgressiveConfig;
use crate::vertex::{roulette, scatter};
use vpl_core::bsdf::Layer;
use vpl_core::glam::Vec3;
use vpl_core::{stream, Camera, Purpose, Ray, Scene, SurfacePoint};

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
    let mut length = 0.0f32;
    let mut s = 0u32;
    loop {
        let Some(hit) = scene.intersect(&ray) else { break };
        length += hit.t;
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
            let radius = (0.5 * spread * length).max(eps);
            let vertex = EyeVertex { pixel, x: sc.at, wo, beta, specular: s, radius, layer: sc.layer, eta: sc.eta };
            return EyePath { direct, vertex: Some(vertex) };
        }
        let Some(smp) = sc.layer.sample(&sc.at, wo, sc.eta, rng.next_2d()) else { break };
        beta *= smp.weight;
        s += 1;
        if s >= cfg.rr_depth {
            let Some(q) = roulette(beta, &mut rng) else { break };
            beta /= q;
        }
        ray = Ray::new(sc.at.offset_toward(smp.w, eps), smp.w);
    }
    EyePath { direct, vertex: None }
}

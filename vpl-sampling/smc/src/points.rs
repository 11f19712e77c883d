//! The camera points X (line 3 of Algorithm 1) and the candidate hits cast
//! from them (line 5, §3.2.1).

use rayon::prelude::*;
use vpl_core::glam::Vec3;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::{stream, Camera, LocalFrame, Purpose, Ray, Scene, SurfacePoint};

/// A camera-visible point that can reflect VPL light toward the camera,
/// normals turned toward the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPoint {
    /// Position.
    pub p: Vec3,
    /// Shading normal.
    pub n: Vec3,
    /// Geometric normal.
    pub ng: Vec3,
}

/// A surface point a candidate ray hit, normals turned toward the ray's
/// origin, and the camera point it came from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CandidateHit {
    /// The point (its normals face `origin`).
    pub y: SurfacePoint,
    /// Index of the camera point in X that cast the ray.
    pub origin: u32,
}

/// Casts `n` camera rays through uniformly random raster positions; keeps the
/// hits that reflect light toward the camera, in ray order. Ray j draws from
/// stream (seed, iteration, CAMERA_POINTS, j).
pub fn camera_points(scene: &Scene, camera: &Camera, n: usize, seed: u64, iteration: u64) -> Vec<CameraPoint> {
    let (w, h) = (camera.resolution.0 as f32, camera.resolution.1 as f32);
    let found: Vec<Option<CameraPoint>> = (0..n)
        .into_par_iter()
        .map(|j| {
            let mut rng = stream(seed, iteration, Purpose::CAMERA_POINTS, j as u64);
            let (u, v) = rng.next_2d();
            let ray = camera.ray(u * w, v * h, rng.next_2d());
            let (sp, _) = scene.reflecting_hit(&ray)?;
            Some(CameraPoint { p: sp.p, n: sp.n, ng: sp.ng })
        })
        .collect();
    found.into_iter().flatten().collect()
}

/// One cosine-distributed ray from every camera point; keeps the hits on
/// surfaces that reflect back toward the ray's origin, in ray order. Ray j
/// draws from stream (seed, iteration, CANDIDATE, j).
pub fn candidate_hits(scene: &Scene, xs: &[CameraPoint], seed: u64, iteration: u64) -> Vec<CandidateHit> {
    let eps = scene.epsilon();
    let found: Vec<Option<CandidateHit>> = xs
        .par_iter()
        .enumerate()
        .map(|(j, x)| {
            let mut rng = stream(seed, iteration, Purpose::CANDIDATE, j as u64);
            let (u, v) = rng.next_2d();
            let d = LocalFrame::from_normal(x.n).to_world(cosine_hemisphere(u, v));
            if d.dot(x.ng) <= 0.0 {
                return None;
            }
            let (y, _) = scene.reflecting_hit(&Ray::new(x.p + x.ng * eps, d))?;
            Some(CandidateHit { y, origin: j as u32 })
        })
        .collect();
    found.into_iter().flatten().collect()
}

/// Whether camera point `x` and a VPL at `y` with normal `n_y` see each
/// other with both cosines positive: the VPL can light x.
#[inline]
pub fn mutually_visible(scene: &Scene, x: &CameraPoint, y: Vec3, n_y: Vec3) -> bool {
    let d = y - x.p;
    if d.dot(x.ng) <= 0.0 || d.dot(x.n) <= 0.0 || d.dot(n_y) >= 0.0 {
        return false;
    }
    let eps = scene.epsilon();
    scene.visible(x.p + x.ng * eps, y + n_y * eps)
}

/// Whether the camera at `eye` still sees camera point `x` from the side it
/// was seen from, inside the image (the mailbox test of §3.2.2).
#[inline]
pub fn camera_sees(scene: &Scene, camera: &Camera, x: &CameraPoint) -> bool {
    let to_eye = camera.origin - x.p;
    if to_eye.dot(x.ng) <= 0.0 {
        return false;
    }
    let Some((px, py)) = camera.project(x.p) else { return false };
    let (w, h) = (camera.resolution.0 as f32, camera.resolution.1 as f32);
    if !(0.0..w).contains(&px) || !(0.0..h).contains(&py) {
        return false;
    }
    scene.visible(x.p + x.ng * scene.epsilon(), camera.origin)
}

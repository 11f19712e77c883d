//! Filling the G-buffer with one camera ray per pixel centre.

use rayon::prelude::*;
use vpl_core::bvh::FAN;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, GBuffer, GSample, Hit, Ray, Scene};

/// Side of the tiles of pixels whose rays a pinhole camera traces together
/// (one bundle of [`FAN`] rays from its centre of projection).
const TILE: usize = 8;
const _: () = assert!(TILE * TILE == FAN);

/// Traces one ray through the centre of every pixel and records what it
/// hits. A pinhole camera's rays, which share their origin, are traced a
/// tile of 8 × 8 pixels at a time ([`Scene::closest_fan`]); a thin lens's
/// one by one.
pub fn render_gbuffer(scene: &Scene, camera: &Camera) -> GBuffer {
    let (w, h) = camera.resolution;
    let (w, h) = (w as usize, h as usize);
    let mut samples = vec![GSample::MISS; w * h];
    let ray = |x: usize, y: usize| camera.ray(x as f32 + 0.5, y as f32 + 0.5, (0.5, 0.5));
    samples.par_chunks_mut(TILE * w).enumerate().for_each(|(band, rows)| {
        let (y0, rows_here) = (band * TILE, rows.len() / w);
        let mut rays = [Ray::new(Vec3::ZERO, Vec3::Z); FAN];
        let mut dirs = [Vec3::ZERO; FAN];
        let mut hits = [None; FAN];
        for x0 in (0..w).step_by(TILE) {
            let cols = TILE.min(w - x0);
            let n = cols * rows_here;
            for k in 0..n {
                rays[k] = ray(x0 + k % cols, y0 + k / cols);
                dirs[k] = rays[k].d;
            }
            if camera.lens_radius > 0.0 {
                for k in 0..n {
                    hits[k] = scene.intersect(&rays[k]).map(|h| (h.point.triangle, h.t));
                }
            } else {
                scene.closest_fan(camera.origin, &dirs[..n], &mut hits);
            }
            for k in 0..n {
                if let Some((tri, t)) = hits[k] {
                    rows[(k / cols) * w + x0 + k % cols] = sample(scene, &rays[k], scene.hit_at(&rays[k], tri, t));
                }
            }
        }
    });
    let c = camera.ray(w as f32 * 0.5, h as f32 * 0.5, (0.5, 0.5)).d;
    let r = camera.ray(w as f32 * 0.5 + 1.0, h as f32 * 0.5, (0.5, 0.5)).d;
    let mut g = GBuffer { width: w as u32, height: h as u32, samples, pixel_angle: c.dot(r).clamp(-1.0, 1.0).acos(), eye: camera.origin };
    environment_at_misses(&mut g, scene, camera);
    g
}

/// Gives the pixels of `g` whose camera ray (through the pixel centre, the
/// lens centre) leaves the scene the environment's radiance along that ray
/// as their emission: the sky seen directly. Nothing changes without an
/// environment light.
pub fn environment_at_misses(g: &mut GBuffer, scene: &Scene, camera: &Camera) {
    if scene.environment.is_none() {
        return;
    }
    let w = g.width.max(1) as usize;
    g.samples.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, s) in row.iter_mut().enumerate() {
            if !s.hit() {
                let d = camera.ray(x as f32 + 0.5, y as f32 + 0.5, (0.5, 0.5)).d;
                s.emitted = scene.environment_radiance(d);
            }
        }
    });
}

/// What the G-buffer records of `hit`, seen along `ray`.
fn sample(scene: &Scene, ray: &Ray, hit: Hit) -> GSample {
    let wo = -ray.d;
    let front = wo.dot(hit.point.ng) > 0.0;
    let sp = hit.point.facing(wo);
    let m = scene.material(&hit.point);
    GSample {
        p: sp.p,
        n: sp.n,
        ng: sp.ng,
        // A one-sided surface seen from behind reflects nothing.
        albedo: if front || scene.two_sided { m.albedo } else { Vec3::ZERO },
        emitted: scene.emitted(&hit.point, wo),
        material: hit.point.material,
        depth: hit.t,
    }
}

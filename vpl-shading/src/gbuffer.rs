//! Filling the G-buffer with one camera ray per pixel centre.

use rayon::prelude::*;
use vpl_core::{Camera, GBuffer, GSample, Scene};

/// Traces one ray through the centre of every pixel and records what it hits.
pub fn render_gbuffer(scene: &Scene, camera: &Camera) -> GBuffer {
    let (w, h) = camera.resolution;
    let mut samples = vec![GSample::MISS; w as usize * h as usize];
    samples.par_chunks_mut(w as usize).enumerate().for_each(|(y, row)| {
        for (x, s) in row.iter_mut().enumerate() {
            let ray = camera.ray(x as f32 + 0.5, y as f32 + 0.5, (0.5, 0.5));
            let Some(hit) = scene.intersect(&ray) else { continue };
            let wo = -ray.d;
            let front = wo.dot(hit.point.ng) > 0.0;
            let sp = hit.point.facing(wo);
            let m = scene.material(&hit.point);
            *s = GSample {
                p: sp.p,
                n: sp.n,
                ng: sp.ng,
                // A one-sided surface seen from behind reflects nothing.
                albedo: if front || scene.two_sided { m.albedo } else { vpl_core::glam::Vec3::ZERO },
                emitted: scene.emitted(&hit.point, wo),
                material: hit.point.material,
                depth: hit.t,
            };
        }
    });
    let c = camera.ray(w as f32 * 0.5, h as f32 * 0.5, (0.5, 0.5)).d;
    let r = camera.ray(w as f32 * 0.5 + 1.0, h as f32 * 0.5, (0.5, 0.5)).d;
    GBuffer { width: w, height: h, samples, pixel_angle: c.dot(r).clamp(-1.0, 1.0).acos(), eye: camera.origin }
}

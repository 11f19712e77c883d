//! Direct light at the G-buffer points: next-event estimation with shadow
//! rays, deterministic.

use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use vpl_core::glam::Vec3;
use vpl_core::{GBuffer, Image, Purpose, Scene, stream};

/// Light reflected once at every G-buffer point (single scattering, k = 1).
///
/// Each pixel takes `samples` light samples: the light chosen in proportion
/// to power with stratified numbers, a point on it, one shadow ray. The
/// numbers come from stream (seed, DIRECT, pixel), with no frame index in the
/// key, so the estimate is the same in every frame of a static view: the
/// direct light is noisy in space but never flickers. Delta lights (point,
/// spot, sun) are exact with one sample each.
pub fn direct_light(scene: &Scene, gbuf: &GBuffer, samples: u32, seed: u64) -> Image {
    let mut img = Image::new(gbuf.width, gbuf.height);
    let s = samples.max(1);
    img.data.par_chunks_mut(gbuf.width.max(1) as usize).enumerate().for_each(|(y, row)| {
        for (x, out) in row.iter_mut().enumerate() {
            let i = y * gbuf.width as usize + x;
            let g = &gbuf.samples[i];
            if !g.reflects() {
                continue;
            }
            let mut rng = stream(seed, 0, Purpose::DIRECT, i as u64);
            let mut sum = Vec3::ZERO;
            for k in 0..s {
                let u_sel = (k as f32 + rng.next_f32()) / s as f32;
                let Some((ls, p_sel)) = scene.sample_light(g.p, u_sel, rng.next_2d()) else { continue };
                let cos = g.n.dot(ls.wi);
                if cos <= 0.0 || ls.wi.dot(g.ng) <= 0.0 {
                    continue;
                }
                if !scene.light_unoccluded(g.p, g.ng, &ls) {
                    continue;
                }
                sum += ls.li * (cos / (p_sel * ls.pdf));
            }
            *out = g.albedo * FRAC_1_PI * sum / s as f32;
        }
    });
    img
}

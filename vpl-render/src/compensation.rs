//! Bias compensation of the geometry clamp (Kollig and Keller 2004, §3).
//!
//! VPL shading with G replaced by min(G, G_max) drops, at a receiver x, the
//! part of the reflected light that arrives from points y so close that
//! G(x, y) > G_max:
//!
//! ```text
//! ΔL(x) = ∫_Ω f(x) L(y(ω) → x) (1 − G_max / G(x, y(ω)))⁺ cos θ_x dω
//! ```
//!
//! with y(ω) the surface point seen from x in direction ω and L(y → x) the
//! light y reflects toward x. Kollig and Keller estimate ΔL with gather
//! rays: ω drawn from the BSDF (here cosine-weighted, so f cos θ_x / p = ρ),
//! traced only as far as G can exceed G_max (|x − y|² < cos θ_x / G_max,
//! since cos θ_y ≤ 1), and L(y → x) estimated where one lands. Kollig and
//! Keller estimate L(y → x) with the (clamped) VPLs at y; here it is a path
//! traced from y ([`PathTracer::reflected`]), which needs no second
//! compensation and is unbiased on its own. The sum of the clamped VPL image
//! and ΔL therefore converges to the unclamped image: the clamp keeps its
//! noise reduction where G is bounded and pays for the near field with a
//! little path-tracing noise in corners.
//!
//! Paths: x is the camera path's first scattering vertex and y its second,
//! so the path from y may scatter `max_k − 2` more times, max_k the largest
//! number of scattering vertices the frame's depth keeps.

use rayon::prelude::*;
use vpl_core::clamp::geometry_term;
use vpl_core::glam::Vec3;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::{GBuffer, GeometryClamp, Image, LocalFrame, Mode, Purpose, Ray, Scene, stream};
use vpl_pathtrace::PathTracer;

/// What bias compensation adds back: the light a clamp at `clamp` removed,
/// estimated with `gather_rays` rays per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compensation {
    /// The clamp the VPL shader applied.
    pub clamp: GeometryClamp,
    /// Gather rays per pixel (≥ 1).
    pub gather_rays: u32,
}

/// The light the clamp removed at each pixel of `gbuf` (module docs), for
/// frame `index` of streams seeded by `seed`, on paths of at most
/// `max_depth` segments. Zero at pixels that reflect nothing.
pub fn compensate(scene: &Scene, gbuf: &GBuffer, c: Compensation, max_depth: u32, seed: u64, index: u64) -> Image {
    let mut img = Image::new(gbuf.width, gbuf.height);
    let (_, max_k) = Mode::Indirect.k_range(max_depth);
    let g_max = c.clamp.g_max;
    if max_k < 2 || c.gather_rays == 0 || !(g_max.is_finite() && g_max > 0.0) {
        return img;
    }
    let pt = PathTracer::new(max_depth, Mode::Full);
    let eps = scene.epsilon();
    let n = c.gather_rays;
    let width = gbuf.width.max(1) as usize;
    img.data.par_chunks_mut(width).enumerate().for_each(|(row_index, row)| {
        for (col, out) in row.iter_mut().enumerate() {
            let i = row_index * width + col;
            let g = &gbuf.samples[i];
            if !g.reflects() {
                continue;
            }
            let mut rng = stream(seed, index, Purpose::COMPENSATION, i as u64);
            let frame = LocalFrame::from_normal(g.n);
            let mut sum = Vec3::ZERO;
            for k in 0..n {
                // Stratified in the first dimension across the pixel's rays.
                let u0 = (k as f32 + rng.next_f32()) / n as f32;
                let local = cosine_hemisphere(u0, rng.next_f32());
                let wi = frame.to_world(local);
                let cos_x = local.z;
                if cos_x <= 0.0 || wi.dot(g.ng) <= 0.0 {
                    continue;
                }
                // Beyond √(cos θ_x / G_max), G ≤ G_max whatever the slant of y.
                let reach = (cos_x / g_max).sqrt();
                let ray = Ray::segment(g.p + g.ng * eps, wi, reach);
                let Some(hit) = scene.intersect(&ray) else { continue };
                let y = hit.point;
                let big_g = geometry_term(cos_x, y.n.dot(-wi).abs(), hit.t * hit.t);
                if big_g <= g_max {
                    continue;
                }
                let removed = 1.0 - g_max / big_g;
                let l = pt.reflected(scene, &y, -wi, max_k - 2, &mut rng);
                // f cos θ_x / p(ω) = (ρ/π) cos θ_x / (cos θ_x / π) = ρ.
                sum += l * removed;
            }
            *out = g.albedo * sum / n as f32;
        }
    });
    img
}

//! Stochastic light culling (Tokuyoshi and Harada, *Stochastic Light
//! Culling*, JCGT 2016): every VPL at every pixel, as exhaustive shading,
//! but each VPL's reach cut by Russian roulette instead of a fixed range,
//! so that far receivers skip most VPLs (and their shadow rays) while the
//! image stays an unbiased estimate of the exhaustive one.
//!
//! VPL i of intensity I_i (its flux's luminance) draws one ξ_i ∈ (0, 1] a
//! frame. A receiver at distance l evaluates it with probability
//!
//! ```text
//! p_i(l) = min(1, I_i / (ε l²)),   evaluated iff l² < r_i² = I_i / (ε ξ_i),
//! ```
//!
//! and divides its term by p_i(l): E[1{ξ_i < p_i} / p_i] = 1, so each
//! term, and the image, is unbiased. Within √(I_i/ε) a VPL is always
//! evaluated; beyond, its term keeps its mean with a constant fall-off.
//! ε = `bound` · Ī / D², Ī the VPLs' mean intensity and D the diagonal of
//! the receivers' box, so `bound` is free of the scene's scale: the share
//! of the mean VPL's irradiance at distance D below which the roulette
//! starts. The range is one sphere a VPL, as the paper's tiled culling
//! needs.

use crate::gather::clamped_g;
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::sync::atomic::{AtomicU64, Ordering};
use vpl_core::glam::Vec3;
use vpl_core::image::luminance;
use vpl_core::rng::{Purpose, stream};
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, VplSet, VplVisibility};

/// Exhaustive shading with stochastic light culling: unbiased against
/// [`crate::ExhaustiveShader`] on the same set and visibility, with fewer
/// VPL terms (and visibility queries) far from the VPLs.
#[derive(Debug)]
pub struct CulledShader {
    /// Geometry-term clamp (`None`: off, the estimate of the unclamped sum).
    pub clamp: Option<GeometryClamp>,
    /// The roulette's threshold, relative to the mean VPL's irradiance at
    /// the receivers' diagonal (larger: more culled, more noise).
    pub bound: f32,
    /// Seed of the VPLs' ξ; each shade draws anew (its frame count).
    pub seed: u64,
    frame: u64,
    /// Terms evaluated and terms there were in the last shade.
    evaluated: (u64, u64),
}

impl CulledShader {
    /// A shader with `bound` (clamped to be positive), `clamp` and `seed`.
    pub fn new(bound: f32, clamp: Option<GeometryClamp>, seed: u64) -> CulledShader {
        let bound = if bound.is_finite() && bound > 0.0 { bound } else { 1.0 };
        CulledShader { clamp, bound, seed, frame: 0, evaluated: (0, 0) }
    }

    /// The share of (VPL, receiver) terms the last shade evaluated.
    pub fn evaluated_share(&self) -> f64 {
        self.evaluated.0 as f64 / self.evaluated.1.max(1) as f64
    }
}

impl IndirectShader for CulledShader {
    fn set_clamp(&mut self, clamp: Option<GeometryClamp>) {
        self.clamp = clamp;
    }

    fn name(&self) -> &'static str {
        "culled"
    }

    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        let frame = self.frame;
        self.frame += 1;
        let mut img = Image::new(gbuf.width, gbuf.height);
        let lights: Vec<(usize, f32, f32)> = vpls
            .slots()
            .iter()
            .enumerate()
            .filter_map(|(s, v)| {
                let v = v.as_ref()?;
                let i = luminance(v.flux);
                // ξ ∈ (0, 1]: one a VPL and frame, by its id.
                let xi = 1.0 - stream(self.seed, frame, Purpose::CULL, v.id).next_f32();
                (i.is_finite() && i > 0.0).then_some((s, i, xi))
            })
            .collect();
        // The receivers of exhaustive shading: points that reflect, with
        // their shading normals.
        let seen = |s: &vpl_core::GSample| s.reflects();
        let (lo, hi) =
            gbuf.samples.iter().filter(|s| seen(s)).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), s| (l.min(s.p), h.max(s.p)));
        let diag2 = (hi - lo).length_squared();
        if lights.is_empty() || !(diag2.is_finite() && diag2 > 0.0) {
            self.evaluated = (0, 0);
            return img;
        }
        let mean_i = lights.iter().map(|l| l.1 as f64).sum::<f64>() / lights.len() as f64;
        let eps = (self.bound as f64 * mean_i / diag2 as f64) as f32;
        let g_max = self.clamp.map_or(f32::INFINITY, |c| c.g_max);
        let (evaluated, total) = (AtomicU64::new(0), AtomicU64::new(0));
        img.data.par_iter_mut().enumerate().for_each(|(pixel, out)| {
            let s = &gbuf.samples[pixel];
            if !seen(s) {
                return;
            }
            let (x, n) = (s.p, s.n);
            let (mut sum, mut done, mut all) = (Vec3::ZERO, 0u64, 0u64);
            for &(slot, intensity, xi) in &lights {
                let Some(v) = vpls.get(slot) else { continue };
                let g = clamped_g(v, x, n, g_max);
                if g <= 0.0 {
                    continue;
                }
                all += 1;
                // The roulette: evaluated iff d² < I / (ε ξ), weighted 1 / p.
                let p = (intensity / (eps * (x - v.y).length_squared())).min(1.0);
                if xi >= p {
                    continue;
                }
                done += 1;
                let visible = vis.visible(slot, x, n);
                if visible > 0.0 {
                    sum += v.flux * (g * visible / p);
                }
            }
            evaluated.fetch_add(done, Ordering::Relaxed);
            total.fetch_add(all, Ordering::Relaxed);
            *out = s.albedo * FRAC_1_PI * sum;
        });
        self.evaluated = (evaluated.into_inner(), total.into_inner());
        img
    }
}

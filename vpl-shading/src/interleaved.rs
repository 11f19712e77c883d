//! Interleaved shading (Keller & Heidrich 2001; Segovia et al. 2006): each
//! pixel of a 4×4 tile shades with its own sixteenth of the VPLs, and a
//! cross-bilateral filter removes the structured noise (Hedman et al. 2017, §4).

use crate::filter::{CrossBilateral, Planes};
use crate::gather::{Sums, gather, slice};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, Purpose, VplSet, VplVisibility, stream};

/// Side of the interleaving tile: 4×4 pixels, 16 VPL subsets.
pub const TILE: u32 = 4;
/// Number of pixel classes and VPL subsets.
pub const CLASSES: usize = (TILE * TILE) as usize;
/// Receivers per parallel task.
const CHUNK: usize = 2048;

/// Milliseconds spent in the stages of the last [`InterleavedShader::shade`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShadeTimings {
    /// Gathering light from the VPLs.
    pub gather_ms: f64,
    /// The cross-bilateral filter.
    pub filter_ms: f64,
}

/// Interleaved shading with an optional cross-bilateral filter.
///
/// Pixel (x, y) belongs to class c = 4·(y mod 4) + (x mod 4) and sums only
/// the VPLs of subset c. The subsets partition the I slots at random (a
/// permutation drawn once from the seed), subset c holding n_c ≈ I/16
/// slots, and class-c sums are weighted by I / n_c. Each slot lies in subset
/// c with probability n_c / I, so the expected weighted sum is the sum over
/// all I VPLs: the estimator is the exhaustive one in expectation. Empty
/// slots count as VPLs of zero flux.
///
/// The loop is VPL-major: for one VPL, every receiver of its class is
/// visited before the next VPL, so the VPL's shadow map stays in cache.
#[derive(Clone, Debug)]
pub struct InterleavedShader {
    /// Geometry-term clamp (`None`: off).
    pub clamp: Option<GeometryClamp>,
    /// The filter applied to the interleaved result (`None`: raw).
    pub filter: Option<CrossBilateral>,
    /// Seed of the slot-to-subset assignment.
    pub seed: u64,
    subsets: Option<(usize, Vec<Vec<u32>>)>,
    timings: ShadeTimings,
    /// The filter's planes, reused from frame to frame.
    planes: Planes,
}

impl InterleavedShader {
    /// A shader with `clamp`, the default filter and `seed`.
    pub fn new(clamp: Option<GeometryClamp>, seed: u64) -> Self {
        InterleavedShader {
            clamp,
            filter: Some(CrossBilateral::default()),
            seed,
            subsets: None,
            timings: ShadeTimings::default(),
            planes: Planes::default(),
        }
    }

    /// Timings of the last shade.
    pub fn timings(&self) -> ShadeTimings {
        self.timings
    }

    /// The class of pixel (x, y).
    #[inline]
    pub fn class(x: u32, y: u32) -> usize {
        ((y % TILE) * TILE + x % TILE) as usize
    }

    /// The slots of each subset for a set of `slots` slots.
    pub fn subsets(&mut self, slots: usize) -> &[Vec<u32>] {
        if self.subsets.as_ref().is_none_or(|(n, _)| *n != slots) {
            let mut order: Vec<u32> = (0..slots as u32).collect();
            let mut rng = stream(self.seed, 0, Purpose::INTERLEAVE, 0);
            for i in (1..order.len()).rev() {
                order.swap(i, rng.below(i as u32 + 1) as usize);
            }
            let mut subsets: Vec<Vec<_>> = (0..CLASSES).map(|_| Vec::with_capacity(slots / CLASSES + 1)).collect();
            for (k, s) in order.into_iter().enumerate() {
                subsets[k % CLASSES].push(s);
            }
            subsets.iter_mut().for_each(|s| s.sort_unstable());
            self.subsets = Some((slots, subsets));
        }
        &self.subsets.as_ref().expect("just built").1
    }

    /// The weighted interleaved sums E(x) = (I / n_c) Σ_{v ∈ subset c} flux·min(G, G_max)·V,
    /// unfiltered: reflected radiance is ρ(x)/π · E(x).
    pub fn irradiance(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        let clamp = self.clamp;
        self.subsets(vpls.len());
        let subsets = &self.subsets.as_ref().expect("just built").1;
        let mut pixels: Vec<Vec<u32>> = vec![Vec::new(); CLASSES];
        for y in 0..gbuf.height {
            for x in 0..gbuf.width {
                pixels[Self::class(x, y)].push(y * gbuf.width + x);
            }
        }
        let classes: Vec<_> = pixels.into_iter().map(|p| gbuf.receivers(p)).collect();
        let tasks: Vec<(usize, usize)> =
            classes.iter().enumerate().flat_map(|(c, rx)| (0..rx.len()).step_by(CHUNK).map(move |s| (c, s))).collect();
        let parts: Vec<(usize, usize, Sums)> = tasks
            .into_par_iter()
            .map(|(c, s)| {
                let rx = &classes[c];
                let e = (s + CHUNK).min(rx.len());
                let part = slice(rx, s, e);
                let mut sums = Sums::zeros(e - s);
                gather(&part, vpls, &subsets[c], vis, clamp, &mut sums, &mut Vec::new());
                (c, s, sums)
            })
            .collect();
        let mut img = Image::new(gbuf.width, gbuf.height);
        for (c, s, sums) in parts {
            let weight = if subsets[c].is_empty() { 0.0 } else { vpls.len() as f32 / subsets[c].len() as f32 };
            for k in 0..sums.r.len() {
                img.data[classes[c].pixel[s + k] as usize] = weight * Vec3::new(sums.r[k], sums.g[k], sums.b[k]);
            }
        }
        img
    }
}

impl IndirectShader for InterleavedShader {
    fn set_clamp(&mut self, clamp: Option<GeometryClamp>) {
        self.clamp = clamp;
    }

    fn name(&self) -> &'static str {
        "interleaved"
    }

    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        let t0 = Instant::now();
        let e = self.irradiance(gbuf, vpls, vis);
        let t1 = Instant::now();
        // Filter the demodulated sums E, then multiply by ρ/π: the filter
        // never blurs albedo across edges.
        let mut e = match &self.filter {
            Some(f) => f.apply_with(gbuf, &e, &mut self.planes),
            None => e,
        };
        let t2 = Instant::now();
        for (o, g) in e.data.iter_mut().zip(&gbuf.samples) {
            *o *= g.albedo * FRAC_1_PI;
        }
        self.timings = ShadeTimings { gather_ms: (t1 - t0).as_secs_f64() * 1e3, filter_ms: (t2 - t1).as_secs_f64() * 1e3 };
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subsets_partition_the_slots_evenly() {
        let mut s = InterleavedShader::new(None, 4);
        let subsets = s.subsets(2050).to_vec();
        let mut all: Vec<u32> = subsets.iter().flatten().copied().collect();
        all.sort_unstable();
        assert_eq!(all, (0..2050).collect::<Vec<_>>());
        assert!(subsets.iter().all(|c| c.len() == 128 || c.len() == 129));
        assert_ne!(InterleavedShader::new(None, 5).subsets(2050)[0], subsets[0]);
        assert_eq!(InterleavedShader::class(5, 6), 9);
    }
}

//! Exhaustive shading: every VPL at every pixel.

use crate::gather::{Sums, gather, gather_free_and_clamped, slice};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use vpl_core::glam::Vec3;
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, Receivers, VplSet, VplVisibility};

/// Receivers per parallel task.
const CHUNK: usize = 1024;

/// All I VPLs at every pixel: the VPL estimator of eq. (2) with J = 1, the
/// quality bound for a given VPL set (the SMC paper's "All VPLs", Fig. 8).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExhaustiveShader {
    /// Geometry-term clamp (`None`: off).
    pub clamp: Option<GeometryClamp>,
}

impl ExhaustiveShader {
    /// The image without a clamp and the image under `clamp`, from one
    /// pass over the pairs: each visibility query serves both (half the
    /// shadow rays of shading twice). The first image is bit for bit
    /// [`ExhaustiveShader`] without a clamp; the second equals it under
    /// `clamp` within a rounding where a pair is clamped (min(G, G_max) · V
    /// is formed as G · V · G_max / G). `self.clamp` is not used.
    pub fn shade_free_and_clamped(&self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility, clamp: GeometryClamp) -> (Image, Image) {
        let rx = gbuf.receivers(0..gbuf.samples.len() as u32);
        let slots: Vec<u32> = (0..vpls.len() as u32).collect();
        let parts = per_chunk(&rx, |part| {
            let (mut free, mut clamped) = (Sums::zeros(part.len()), Sums::zeros(part.len()));
            gather_free_and_clamped(part, vpls, &slots, vis, clamp.g_max, &mut free, &mut clamped, (&mut Vec::new(), &mut Vec::new()));
            (free, clamped)
        });
        let mut images = (Image::new(gbuf.width, gbuf.height), Image::new(gbuf.width, gbuf.height));
        for (s, (free, clamped)) in parts {
            write_sums(&mut images.0, gbuf, &rx, s, &free);
            write_sums(&mut images.1, gbuf, &rx, s, &clamped);
        }
        images
    }
}

/// `work` on each run of [`CHUNK`] receivers of `rx`, in parallel, with
/// the index of the run's first receiver.
fn per_chunk<T: Send>(rx: &Receivers, work: impl Fn(&Receivers) -> T + Sync) -> Vec<(usize, T)> {
    let starts: Vec<usize> = (0..rx.len()).step_by(CHUNK).collect();
    starts.into_par_iter().map(|s| (s, work(&slice(rx, s, (s + CHUNK).min(rx.len()))))).collect()
}

/// The pixels of the receivers `s..` of `rx` that `sums` holds: albedo / π · Σ.
fn write_sums(img: &mut Image, gbuf: &GBuffer, rx: &Receivers, s: usize, sums: &Sums) {
    for k in 0..sums.r.len() {
        let p = rx.pixel[s + k] as usize;
        img.data[p] = gbuf.samples[p].albedo * FRAC_1_PI * Vec3::new(sums.r[k], sums.g[k], sums.b[k]);
    }
}

impl IndirectShader for ExhaustiveShader {
    fn set_clamp(&mut self, clamp: Option<vpl_core::GeometryClamp>) {
        self.clamp = clamp;
    }

    fn name(&self) -> &'static str {
        "exhaustive"
    }

    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        let rx = gbuf.receivers(0..gbuf.samples.len() as u32);
        let slots: Vec<u32> = (0..vpls.len() as u32).collect();
        let parts = per_chunk(&rx, |part| {
            let mut sums = Sums::zeros(part.len());
            gather(part, vpls, &slots, vis, self.clamp, &mut sums, &mut Vec::new());
            sums
        });
        let mut img = Image::new(gbuf.width, gbuf.height);
        for (s, sums) in parts {
            write_sums(&mut img, gbuf, &rx, s, &sums);
        }
        img
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::SceneSetup;
    use vpl_visibility::RayTraced;

    /// One pass gives both images: the unclamped one bit for bit, the
    /// clamped one within a rounding (f32: a few ulps a term, 10⁻⁵ of a
    /// pixel allows for 256 terms), on two scenes and at a G_max low
    /// enough that many pairs are clamped.
    #[test]
    fn one_pass_gives_the_free_and_the_clamped_images() {
        for name in ["cornell", "office"] {
            let setup = SceneSetup::builtin(name).unwrap();
            let camera = setup.camera.with_resolution((48, 36)).unwrap();
            let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 256, ..Default::default() })
                .unwrap()
                .sample(&setup.scene, 5)
                .clone();
            let gbuf = crate::render_gbuffer(&setup.scene, &camera);
            let mut vis = RayTraced::default();
            vis.update(&setup.scene, &set);
            // A tenth of the view's default: the clamp bites.
            let clamp = GeometryClamp::new(0.1 * GeometryClamp::for_view(256, &setup.scene, &camera).g_max);
            let (free, clamped) = ExhaustiveShader::default().shade_free_and_clamped(&gbuf, &set, &vis, clamp);
            let free_alone = ExhaustiveShader { clamp: None }.shade(&gbuf, &set, &vis);
            let clamped_alone = ExhaustiveShader { clamp: Some(clamp) }.shade(&gbuf, &set, &vis);
            assert!(free.data == free_alone.data, "{name}: the unclamped image differs");
            let sum = |img: &Image| img.data.iter().map(|c| c.element_sum() as f64).sum::<f64>();
            assert!(sum(&clamped) < 0.99 * sum(&free), "{name}: the clamp removed nothing, so the test shows nothing");
            for (a, b) in clamped.data.iter().zip(&clamped_alone.data) {
                assert!((*a - *b).abs().max_element() <= 1e-5 * b.max_element().max(1e-12), "{name}: clamped {a} against {b}");
            }
        }
    }
}

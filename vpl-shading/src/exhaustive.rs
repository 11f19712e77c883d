//! Exhaustive shading: every VPL at every pixel.

use crate::gather::{Sums, gather, slice};
use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use vpl_core::glam::Vec3;
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, VplSet, VplVisibility};

/// Receivers per parallel task.
const CHUNK: usize = 1024;

/// All I VPLs at every pixel: the VPL estimator of eq. (2) with J = 1, the
/// quality bound for a given VPL set (the SMC paper's "All VPLs", Fig. 8).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ExhaustiveShader {
    /// Geometry-term clamp (`None`: off).
    pub clamp: Option<GeometryClamp>,
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
        let starts: Vec<usize> = (0..rx.len()).step_by(CHUNK).collect();
        let parts: Vec<(usize, Sums)> = starts
            .into_par_iter()
            .map(|s| {
                let e = (s + CHUNK).min(rx.len());
                let part = slice(&rx, s, e);
                let mut sums = Sums::zeros(e - s);
                gather(&part, vpls, &slots, vis, self.clamp, &mut sums, &mut Vec::new());
                (s, sums)
            })
            .collect();
        let mut img = Image::new(gbuf.width, gbuf.height);
        for (s, sums) in parts {
            for k in 0..sums.r.len() {
                let p = rx.pixel[s + k] as usize;
                img.data[p] = gbuf.samples[p].albedo * FRAC_1_PI * Vec3::new(sums.r[k], sums.g[k], sums.b[k]);
            }
        }
        img
    }
}

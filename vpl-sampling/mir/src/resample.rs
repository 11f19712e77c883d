//! `mir-resample`: the stand-in for Metropolis IR that Hedman et al. (2017,
//! §5.1) used in their experiments. Camera paths from the path tracer are
//! resampled, ratio:1, in proportion to the light they bring the camera,
//! and their secondary vertices become the VPLs.

use crate::config::{MirError, MirResampleConfig};
use rayon::prelude::*;
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::image::luminance;
use vpl_core::resample::resample;
use vpl_core::rng::mix64;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::{Frame, LocalFrame, Mode, Purpose, RadiosityEstimator, Ray, Stats, SurfacePoint, Vpl, VplSampler, VplSet, stream};
use vpl_density::{rendering_k, set_densities};
use vpl_pathtrace::{PathRadiosity, PathTracer};

/// Counts of the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MirResampleStats {
    /// Camera paths traced (ratio·I).
    pub paths: usize,
    /// Paths whose secondary vertex brought light to the camera.
    pub useful: usize,
    /// VPLs stored.
    pub stored: usize,
    /// Milliseconds for the frame.
    pub ms: f64,
}

/// Resampled path-tracer secondary vertices as a [`VplSampler`]; it starts
/// afresh every frame.
#[derive(Debug)]
pub struct MirResampleSampler {
    config: MirResampleConfig,
    set: VplSet,
    stats: MirResampleStats,
}

/// A camera path's secondary vertex and the luminance the path brings.
#[derive(Clone, Copy)]
struct Candidate {
    y: SurfacePoint,
    weight: f32,
}

impl MirResampleSampler {
    /// A sampler with `config`.
    pub fn new(config: MirResampleConfig) -> Result<MirResampleSampler, MirError> {
        config.validate()?;
        Ok(MirResampleSampler { config, set: VplSet::new(config.vpls), stats: MirResampleStats::default() })
    }

    /// Counts of the last frame.
    pub fn stats(&self) -> MirResampleStats {
        self.stats
    }
}

impl VplSampler for MirResampleSampler {
    fn name(&self) -> &'static str {
        "mir-resample"
    }

    /// 1. ratio·I camera paths: a random raster position, its hit x, a
    ///    cosine-sampled direction to the secondary vertex y, and the path
    ///    tracer's estimate of L(y → x) with `radiosity_bounces` further
    ///    bounces; the path brings lum(ρ(x)·L(y → x)) to its pixel.
    /// 2. I of them, drawn without replacement in proportion to that.
    /// 3. Each chosen y is a VPL: L(y) from `radiosity_paths` NEE paths (new
    ///    ones, so the choice does not bias the estimate), p(y) the kNN area
    ///    density of the chosen set, flux = L / (I·p) (the SMC paper's eq. 5).
    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        let start = Instant::now();
        let c = self.config;
        let (seed, index, scene, camera) = (frame.seed, frame.index, frame.scene, frame.camera);
        let n = c.vpls * c.ratio;
        let (w, h) = (camera.resolution.0 as f32, camera.resolution.1 as f32);
        let pt = PathTracer::new(u32::MAX, Mode::Full);
        let eps = scene.epsilon();
        let cands: Vec<Option<Candidate>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let mut rng = stream(seed, index, Purpose::CAMERA_POINTS, j as u64);
                let (u, v) = rng.next_2d();
                let ray = camera.ray(u * w, v * h, rng.next_2d());
                let (x, rho) = scene.reflecting_hit(&ray)?;
                let d = LocalFrame::from_normal(x.n).to_world(cosine_hemisphere(rng.next_f32(), rng.next_f32()));
                if d.dot(x.ng) <= 0.0 {
                    return None;
                }
                let (y, _) = scene.reflecting_hit(&Ray::new(x.p + x.ng * eps, d))?;
                // Cosine sampling: f·cos/pdf = ρ(x).
                let l = pt.reflected(scene, &y, -d, c.radiosity_bounces, &mut rng);
                let weight = luminance(rho * l);
                (weight > 0.0 && weight.is_finite()).then_some(Candidate { y, weight })
            })
            .collect();
        let useful: Vec<Candidate> = cands.into_iter().flatten().collect();
        let weights: Vec<f32> = useful.iter().map(|k| k.weight).collect();
        let chosen = if weights.is_empty() { Vec::new() } else { resample(&weights, c.vpls, 8, seed, index) };

        let est = PathRadiosity { paths: c.radiosity_paths, max_bounces: c.radiosity_bounces };
        let radiance: Vec<Vec3> =
            chosen.par_iter().map(|&i| est.radiosity(scene, &useful[i].y, mix64(seed ^ mix64(index ^ (i as u64) << 20)))).collect();
        let m = chosen.len();
        let pts: Vec<Vec3> = chosen.iter().map(|&i| useful[i].y.p).collect();
        let dens = set_densities(&pts, c.knn_k.unwrap_or_else(|| rendering_k(c.vpls)), scene.surface_area());
        self.set.begin_frame();
        for s in 0..c.vpls {
            let v = (s < m).then(|| {
                let y = useful[chosen[s]].y;
                let flux = radiance[s] / (m as f32 * dens[s]);
                Vpl { y: y.p, n: y.n, flux: if flux.is_finite() { flux } else { Vec3::ZERO }, id: (index << 32) | s as u64, bounce: 0 }
            });
            self.set.set(s, v);
        }
        self.set.light_paths = n as u64;
        self.stats = MirResampleStats { paths: n, useful: useful.len(), stored: m, ms: start.elapsed().as_secs_f64() * 1e3 };
        &self.set
    }

    fn stats(&self) -> Stats {
        let s = self.stats;
        Stats::new().count("stored", s.stored).count("paths", s.paths).count("useful", s.useful).ms("ms", s.ms)
    }
}

//! The rendering pass (§3, Fig. 2) and the accumulation buffer.

use crate::config::{Culling, Gathering, ProgressiveConfig};
use crate::error::ProgressiveError;
use crate::eye::{EyePath, EyeVertex, pixel_angle, trace_eye};
use crate::gather::{contribution, sees};
use crate::histogram::{Bins, Photons, SourceResult, trace_photons};
use crate::light_paths::{Emitter, PassVpl, trace_light_path};
use crate::lightcut::PassTree;
use crate::projection::{SpecularBound, SpecularSet};
use rayon::prelude::*;
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, Halton, Image, Purpose, Scene, stream};

/// What one pass did and how long each step took.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PassStats {
    /// Eye paths that ended on a diffuse vertex.
    pub eye_vertices: u64,
    /// VPLs the light paths made (primary ones included).
    pub vpls: u64,
    /// VPLs stored after culling.
    pub stored: u64,
    /// Stored VPLs that no representative saw (kept by the unbiased culling's lottery).
    pub unseen_kept: u64,
    /// Caustic photons emitted.
    pub photons: u64,
    /// Photons whose first hit chose a specular layer.
    pub caustic_photons: u64,
    /// Photons that fell into a bin.
    pub deposits: u64,
    /// Mean projection-map coverage of the VPLs that emitted photons.
    pub map_coverage: f64,
    /// Eye paths (ms).
    pub eye_ms: f64,
    /// VPL light paths (ms).
    pub light_ms: f64,
    /// Stochastic culling (ms).
    pub cull_ms: f64,
    /// VPL gathering (ms).
    pub gather_ms: f64,
    /// Bins, projection maps and photons (ms).
    pub caustic_ms: f64,
    /// The whole pass (ms).
    pub total_ms: f64,
}

/// The progressive renderer: each [`Progressive::pass`] renders one
/// independent pass and adds it to an accumulation buffer of constant size.
pub struct Progressive<'s> {
    scene: &'s Scene,
    camera: Camera,
    config: ProgressiveConfig,
    bounds: SpecularSet,
    sum: Vec<[f64; 3]>,
    sum_sq: Vec<[f64; 3]>,
    passes: u64,
}

/// Bounding spheres of the triangles that have a specular layer (κ ≥ 0.2).
pub fn specular_bounds(scene: &Scene) -> Vec<SpecularBound> {
    scene
        .geometry
        .triangles
        .iter()
        .filter(|t| {
            scene.materials[t.material as usize].layered.as_ref().is_some_and(|l| !l.is_diffuse() && l.specular.max_element() > 0.0)
        })
        .map(|t| {
            let (p1, p2) = (t.p0 + t.e1, t.p0 + t.e2);
            let c = (t.p0 + p1 + p2) / 3.0;
            let r = (t.p0 - c).length().max((p1 - c).length()).max((p2 - c).length());
            SpecularBound { c, r: r * 1.001 + scene.epsilon() }
        })
        .collect()
}

impl<'s> Progressive<'s> {
    /// A renderer of `scene` through `camera`.
    pub fn new(scene: &'s Scene, camera: Camera, config: ProgressiveConfig) -> Result<Progressive<'s>, ProgressiveError> {
        config.validate()?;
        if scene.lights.is_empty() {
            return Err(ProgressiveError::NoLights(scene.name.clone()));
        }
        let n = camera.resolution.0 as usize * camera.resolution.1 as usize;
        Ok(Progressive {
            scene,
            camera,
            config,
            bounds: SpecularSet::new(specular_bounds(scene)),
            sum: vec![[0.0; 3]; n],
            sum_sq: vec![[0.0; 3]; n],
            passes: 0,
        })
    }

    /// The settings.
    pub fn config(&self) -> &ProgressiveConfig {
        &self.config
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }

    /// Passes accumulated so far.
    pub fn passes(&self) -> u64 {
        self.passes
    }

    /// Bytes held by the accumulation buffer (constant over passes).
    pub fn buffer_bytes(&self) -> usize {
        (self.sum.capacity() + self.sum_sq.capacity()) * std::mem::size_of::<[f64; 3]>()
    }

    /// Renders the next pass and adds it to the accumulation buffer.
    pub fn pass(&mut self) -> PassStats {
        let (img, stats) = self.render_pass(self.passes);
        for ((s, q), v) in self.sum.iter_mut().zip(self.sum_sq.iter_mut()).zip(&img) {
            for c in 0..3 {
                let x = v[c] as f64;
                s[c] += x;
                q[c] += x * x;
            }
        }
        self.passes += 1;
        stats
    }

    /// The mean of the passes so far.
    pub fn image(&self) -> Image {
        let (w, h) = self.camera.resolution;
        let mut img = Image::new(w, h);
        let n = self.passes.max(1) as f64;
        for (i, s) in self.sum.iter().enumerate() {
            img.set(i as u32 % w, i as u32 / w, Vec3::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32));
        }
        img
    }

    /// Standard error of the per-pixel mean over passes (passes are
    /// independent, so this is √(sample variance / passes)); zero before two passes.
    pub fn stderr(&self) -> Image {
        let (w, h) = self.camera.resolution;
        let mut img = Image::new(w, h);
        let n = self.passes as f64;
        if n < 2.0 {
            return img;
        }
        for (i, (s, q)) in self.sum.iter().zip(&self.sum_sq).enumerate() {
            let e = |c: usize| {
                let m = s[c] / n;
                (((q[c] / n - m * m).max(0.0) * n / (n - 1.0)) / n).sqrt() as f32
            };
            img.set(i as u32 % w, i as u32 / w, Vec3::new(e(0), e(1), e(2)));
        }
        img
    }

    /// Renders pass number `pass` alone (a pure function of the scene, the
    /// settings and `pass`): the pass image as row-major pixels, and statistics.
    pub fn render_pass(&self, pass: u64) -> (Vec<Vec3>, PassStats) {
        let start = Instant::now();
        let scene = self.scene;
        let cfg = &self.config;
        let (w, h) = self.camera.resolution;
        let mut st = PassStats::default();

        // 1. Eye paths (§3.1).
        let t = Instant::now();
        let spread = pixel_angle(&self.camera);
        let eye: Vec<EyePath> = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| trace_eye(scene, &self.camera, cfg, pass, x, y, spread))
            .collect();
        let mut image: Vec<Vec3> = eye.iter().map(|e| e.direct).collect();
        st.eye_vertices = eye.iter().filter(|e| e.vertex.is_some()).count() as u64;
        st.eye_ms = ms(t);

        // 2. VPL light paths (§5.1).
        let t = Instant::now();
        let vpls: Vec<PassVpl> = (0..cfg.vpl_paths as u32)
            .into_par_iter()
            .map(|i| {
                let mut v = Vec::new();
                trace_light_path(scene, cfg, pass, i, &mut v);
                v
            })
            .collect::<Vec<_>>()
            .concat();
        st.vpls = vpls.len() as u64;
        st.light_ms = ms(t);

        // 3. Stochastic culling (§5.1.1).
        let t = Instant::now();
        let gather_vpl = cfg.techniques.vpl || cfg.techniques.specular_gathering;
        let stored: Vec<PassVpl> = if !gather_vpl {
            Vec::new()
        } else {
            match cfg.culling {
                Culling::Off => vpls.clone(),
                culling => {
                    let reps = self.representatives(&eye, pass);
                    let decided: Vec<(Option<PassVpl>, bool)> = vpls
                        .par_iter()
                        .enumerate()
                        .map(|(i, v)| {
                            if reps.iter().any(|r| sees(scene, r, v)) {
                                return (Some(*v), false);
                            }
                            match culling {
                                Culling::Unbiased { accept } => {
                                    let mut rng = stream(cfg.seed, pass, Purpose::CULL, i as u64);
                                    if rng.next_f32() < accept { (Some(scaled(v, 1.0 / accept)), true) } else { (None, false) }
                                }
                                _ => (None, false),
                            }
                        })
                        .collect();
                    st.unseen_kept = decided.iter().filter(|d| d.1).count() as u64;
                    decided.into_iter().filter_map(|d| d.0).collect()
                }
            }
        };
        st.stored = stored.len() as u64;
        st.cull_ms = ms(t);

        // 4. VPL gathering (§5.1, Fig. 3c), directly and through specular vertices (§5.2).
        let t = Instant::now();
        let max_vertices = cfg.max_depth.saturating_sub(1);
        if !stored.is_empty() {
            let vpl_for = |v: &EyeVertex| if v.specular == 0 { cfg.techniques.vpl } else { cfg.techniques.specular_gathering };
            let tree = match cfg.gathering {
                Gathering::Lightcuts { cut } => Some((PassTree::build(scene, &stored), cut)),
                Gathering::Exhaustive => None,
            };
            let lit: Vec<Vec3> = eye
                .par_iter()
                .enumerate()
                .map(|(pixel, e)| match &e.vertex {
                    Some(v) if vpl_for(v) => {
                        let keep = |l: &PassVpl| v.specular + 1 + l.depth <= max_vertices;
                        match &tree {
                            Some((tree, cut)) => {
                                let mut rng = stream(cfg.seed, pass, Purpose::LIGHTCUT, pixel as u64);
                                tree.gather(scene, v, &stored, *cut, cfg.clamp, keep, &mut rng)
                            }
                            None => stored.iter().filter(|l| keep(l)).map(|l| contribution(scene, v, l, cfg.clamp)).sum(),
                        }
                    }
                    _ => Vec3::ZERO,
                })
                .collect();
            for (p, l) in image.iter_mut().zip(lit) {
                *p += l;
            }
        }
        st.gather_ms = ms(t);

        // 5. Caustic histograms (§5.3) with projection maps (§5.3.1).
        let t = Instant::now();
        if cfg.caustic_paths > 0 && !self.bounds.is_empty() && (cfg.techniques.caustics || cfg.techniques.specular_gathering) {
            let bins = Bins::new(eye.iter().filter_map(|e| e.vertex.as_ref()).collect());
            // A photon needs a specular vertex and a bin after its source.
            let sources: Vec<&PassVpl> =
                vpls.iter().filter(|v| (cfg.indirect_caustics || v.is_primary()) && v.depth + 2 <= max_vertices).collect();
            if !bins.is_empty() && !sources.is_empty() {
                let n = (cfg.caustic_paths as u64).div_ceil(sources.len() as u64);
                let results: Vec<SourceResult> = sources
                    .par_iter()
                    .enumerate()
                    .map(|(i, v)| trace_photons(scene, cfg, v, &self.bounds, Photons { pass, first: i as u64 * n, n }, &bins))
                    .collect();
                let mut coverage = 0.0f64;
                for r in &results {
                    st.photons += r.photons;
                    st.caustic_photons += r.caustic;
                    st.deposits += r.deposits.len() as u64;
                    coverage += r.coverage as f64;
                    for &(p, v) in &r.deposits {
                        image[p as usize] += v;
                    }
                }
                st.map_coverage = coverage / results.len() as f64;
            }
        }
        st.caustic_ms = ms(t);
        st.total_ms = ms(start);
        (image, st)
    }

    /// The eye vertices stochastic culling tests against: the pixels of
    /// `representatives` Halton points over the image, a new set each pass.
    fn representatives<'a>(&self, eye: &'a [EyePath], pass: u64) -> Vec<&'a EyeVertex> {
        let (w, h) = self.camera.resolution;
        let halton = Halton::new(2, self.config.seed);
        let r = self.config.representatives as u64;
        (0..r)
            .filter_map(|i| {
                let k = pass * r + i;
                let x = ((halton.sample(k, 0) * w as f32) as u32).min(w - 1);
                let y = ((halton.sample(k, 1) * h as f32) as u32).min(h - 1);
                eye[(y * w + x) as usize].vertex.as_ref()
            })
            .collect()
    }
}

/// A VPL with its power multiplied by `k`.
fn scaled(v: &PassVpl, k: f32) -> PassVpl {
    let emitter = match v.emitter {
        Emitter::Light { light, u_pos, scale } => Emitter::Light { light, u_pos, scale: scale * k },
        Emitter::Surface { y, w_in, flux, layer, eta } => Emitter::Surface { y, w_in, flux: flux * k, layer, eta },
    };
    PassVpl { emitter, ..*v }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

//! Algorithm 1 of Hedman et al. (2017), one iteration per frame.

use crate::config::{SmcConfig, SmcError};
use crate::flux::{AreaProbes, Cell, FluxEstimator, NEAR_BLEND, ProbeCandidate, ProbeHits, Site};
use crate::placement::{self, Placement, Shown};
use crate::points::{CameraPoint, CandidateHit, camera_points_of, camera_sees, candidate_hits_from, mutual_ray, resolve};
use crate::relight::{self, Relight};
use rayon::prelude::*;
use std::sync::Arc;
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::image::luminance;
use vpl_core::resample::resample_counted;
use vpl_core::rng::{mix64, stream_key};
use vpl_core::scene::LightingKey;
use vpl_core::{
    Camera, CameraRays, CpuRays, Frame, Purpose, RadiosityEstimator, RayCaster, Scene, Services, Stats, SurfacePoint, Vpl, VplSampler,
    VplSet, stream,
};
use vpl_density::{KnnDensity, set_densities};
use vpl_pathtrace::PathRadiosity;

/// A radiosity estimator the sampler can share between threads.
pub type Estimator = Box<dyn RadiosityEstimator + Send + Sync>;

/// One VPL of the set Y and what the sampler knows of it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Particle {
    /// The point y (normals toward the side it lights).
    pub y: SurfacePoint,
    /// Stable id: seeds its radiosity paths for its whole life.
    pub id: u64,
    /// Exitant radiance L(y) that the VPL's flux uses, from
    /// [`RadiosityEstimator`] with paths of its own: independent of
    /// `selection_radiance`, so choosing VPLs by intensity does not bias it.
    pub radiance: Vec3,
    /// The estimate of L(y) that intensities (eq. 6), and so every keep,
    /// remove and add decision, use: the candidate's estimate.
    pub selection_radiance: Vec3,
    /// Area density p(y) among the VPLs (eq. 7 with the rendering k).
    pub density: f32,
    /// The mailbox: a camera point that saw y (§3.2.2).
    pub anchor: CameraPoint,
}

impl Particle {
    /// Intensity I(y) = L(y) / p(y) (eq. 6), by luminance, with the
    /// selection estimate of L(y).
    pub fn intensity(&self) -> f32 {
        intensity(self.selection_radiance, self.density)
    }
}

#[inline]
fn intensity(l: Vec3, p: f32) -> f32 {
    let v = luminance(l) / p;
    if v.is_finite() { v.max(0.0) } else { 0.0 }
}

/// Milliseconds per step of the last iteration, in the columns of the
/// paper's Table 2.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SmcTimings {
    /// Camera points, candidate rays, counting undersampled regions and
    /// replacing VPLs ("Cand. sampling").
    pub candidates_ms: f64,
    /// Drawing candidates from the hits ("Cand. resampling").
    pub resampling_ms: f64,
    /// Mailbox tests and rays toward unverified VPLs ("Indirect visibility").
    pub visibility_ms: f64,
    /// Radiosity of candidates, and of the set when the lights changed ("Radiosity").
    pub radiosity_ms: f64,
    /// k-d tree builds and kNN queries: hit weights, candidate and VPL densities ("kNN").
    pub knn_ms: f64,
    /// The whole iteration.
    pub total_ms: f64,
}

/// Counts of the last iteration.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SmcStats {
    /// Iterations run so far (warm-up included).
    pub iterations: u64,
    /// Camera points X that reflect.
    pub camera_points: usize,
    /// Candidate rays that hit a reflecting surface.
    pub hits: usize,
    /// Candidates Ŷ after resampling.
    pub candidates: usize,
    /// VPLs whose mailbox point the camera still sees.
    pub mailbox_valid: usize,
    /// VPLs validated by visibility rays.
    pub ray_valid: usize,
    /// VPLs left unverified (INVALID after line 4).
    pub invalid: usize,
    /// M_strong of eq. (9).
    pub m_strong: usize,
    /// Valid VPLs invalidated as the weakest (lines 10–12).
    pub weakest: usize,
    /// VPLs removed (line 13).
    pub removed: usize,
    /// Slots filled with candidates (lines 14–17).
    pub added: usize,
    /// VPLs stored.
    pub stored: usize,
    /// Whether the lights changed, so every VPL's radiosity was estimated anew.
    pub relit: bool,
    /// Coefficient of variation (σ/μ) of the intensities I(y) of the set.
    pub intensity_cv: f32,
    /// Σ of the paper's kNN areas π r_k² / k over Σ of the Voronoi cells'
    /// areas (0 when the cells were not measured): how much more surface
    /// the paper's estimator gives the set.
    pub knn_area_ratio: f32,
    /// Shadow rays that gave probes their cells.
    pub probe_rays: usize,
    /// The light the candidates of the cells carry, by luminance
    /// ([`AreaProbes::candidate_light`]; 0 without probes).
    pub candidate_light: f64,
    /// Relighting estimates made ([`Relight::Candidates`]): D(t) of the
    /// candidates not relit before and D(now) of all held, at iterations
    /// whose lights changed; none where they stand still.
    pub relit_candidates: usize,
    /// The relit cells whose light fell below zero, and what became of it
    /// ([`relight::spread_deficits`]): taken from their neighbours, but
    /// for [`relight::Spread::unplaced`].
    pub negative_cells: relight::Spread,
}

impl SmcStats {
    /// The counts of Algorithm 1's last iteration as [`Stats`], in the
    /// order every SMC sampler reports them (the host's and a device's).
    pub fn counts(&self) -> Stats {
        Stats::new()
            .count("stored", self.stored)
            .count("iterations", self.iterations as usize)
            .count("hits", self.hits)
            .count("candidates", self.candidates)
            .count("mailbox_valid", self.mailbox_valid)
            .count("ray_valid", self.ray_valid)
            .count("invalid", self.invalid)
            .count("m_strong", self.m_strong)
            .count("removed", self.removed)
            .count("weakest", self.weakest)
            .count("added", self.added)
            .count("relit", self.relit as usize)
            .value("intensity_cv", self.intensity_cv as f64)
    }
}

impl SmcTimings {
    /// `stats` with the milliseconds of each step (Table 2's columns).
    pub fn steps(&self, stats: Stats) -> Stats {
        stats
            .ms("candidates_ms", self.candidates_ms)
            .ms("resampling_ms", self.resampling_ms)
            .ms("visibility_ms", self.visibility_ms)
            .ms("radiosity_ms", self.radiosity_ms)
            .ms("knn_ms", self.knn_ms)
    }
}

/// The Sequential Monte Carlo Instant Radiosity sampler (Algorithm 1).
pub struct SmcSampler {
    config: SmcConfig,
    estimator: Estimator,
    /// The candidates' short relighting estimates ([`Relight::Candidates`]).
    tracker: Estimator,
    rays: Arc<dyn RayCaster>,
    particles: Vec<Option<Particle>>,
    set: VplSet,
    next_id: u64,
    iterations: u64,
    lighting: Option<LightingKey>,
    /// The scene as it was when `lighting` was set, where candidates are
    /// relit ([`Relight::Candidates`]): the lights the candidates made
    /// since then were estimated under.
    lit: Option<Scene>,
    probes: AreaProbes,
    /// The point each slot's VPL shone from last ([`Placement::Centroid`]).
    shown: Vec<Option<Shown>>,
    /// Each slot's VPL and its blended near ratio ([`FluxEstimator::VoronoiNear`]).
    near: Vec<Option<(u64, f64)>>,
    /// Inside the warm-up: the flux is not looked at, so the cells are not measured.
    warming: bool,
    /// Whether this iteration's hits become area probes (all but the
    /// warm-up's early iterations, whose probes would expire unused).
    collect_probes: bool,
    stats: SmcStats,
    timings: SmcTimings,
}

impl std::fmt::Debug for SmcSampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SmcSampler").field("config", &self.config).field("stats", &self.stats).finish()
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Candidates of one iteration: hit, radiance, density against Y, intensity.
struct Candidate {
    hit: CandidateHit,
    id: u64,
    radiance: Vec3,
    intensity: f32,
}

impl SmcSampler {
    /// A sampler whose radiosities come from the path tracer with next-event
    /// estimation: `radiosity_paths` paths of at most `radiosity_bounces`
    /// bounces after y.
    pub fn new(config: SmcConfig) -> Result<SmcSampler, SmcError> {
        let pt = PathRadiosity { paths: config.radiosity_paths, max_bounces: config.radiosity_bounces };
        SmcSampler::with_estimator(config, Box::new(pt))
    }

    /// A sampler that casts its rays (camera points, candidate rays,
    /// mailbox and indirect-visibility rays) with `services.rays` and
    /// estimates radiosities with `services.radiosity` (its own path tracer
    /// when that is `None`): what a backend (a GPU) hands over.
    pub fn with_services(config: SmcConfig, services: &Services) -> Result<SmcSampler, SmcError> {
        let mut s = match &services.radiosity {
            Some(make) => {
                let mut s = SmcSampler::with_estimator(config, make.estimator(config.radiosity_paths, config.radiosity_bounces))?;
                s.tracker = make.estimator(config.relight_paths, config.relight_bounces());
                s
            }
            None => SmcSampler::new(config)?,
        };
        s.rays = services.rays.clone();
        Ok(s)
    }

    /// A sampler with another radiosity estimator.
    pub fn with_estimator(config: SmcConfig, estimator: Estimator) -> Result<SmcSampler, SmcError> {
        config.validate()?;
        Ok(SmcSampler {
            config,
            estimator,
            tracker: Box::new(PathRadiosity { paths: config.relight_paths, max_bounces: config.relight_bounces() }),
            rays: Arc::new(CpuRays),
            particles: vec![None; config.vpls],
            set: VplSet::new(config.vpls),
            next_id: 0,
            iterations: 0,
            lighting: None,
            lit: None,
            probes: AreaProbes::new(config.probe_iterations)
                .with_per_iteration(config.probes_per_iteration())
                .with_window(config.probe_window)
                .with_ball(config.probe_area),
            shown: vec![None; config.vpls],
            near: vec![None; config.vpls],
            warming: false,
            collect_probes: true,
            stats: SmcStats::default(),
            timings: SmcTimings::default(),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SmcConfig {
        &self.config
    }

    /// Counts of the last iteration.
    pub fn stats(&self) -> SmcStats {
        self.stats
    }

    /// Step timings of the last iteration.
    pub fn timings(&self) -> SmcTimings {
        self.timings
    }

    /// The VPLs after the last iteration.
    pub fn vpls(&self) -> &VplSet {
        &self.set
    }

    /// The particles behind the VPLs, by slot.
    pub fn particles(&self) -> &[Option<Particle>] {
        &self.particles
    }

    /// Whether the sampler has run (so the next frame needs no warm-up).
    pub fn started(&self) -> bool {
        self.iterations > 0
    }

    /// Forgets every VPL: the next frame starts afresh with a warm-up.
    pub fn reset(&mut self) {
        self.particles.iter_mut().for_each(|p| *p = None);
        self.iterations = 0;
        self.lighting = None;
        self.lit = None;
        self.probes.clear();
        self.shown.iter_mut().for_each(|s| *s = None);
        self.near.iter_mut().for_each(|s| *s = None);
    }

    /// The seed of VPL `id`'s radiosity paths.
    fn radiosity_seed(seed: u64, id: u64) -> u64 {
        mix64(seed ^ mix64(id.wrapping_add(0x5EC0_0001)))
    }

    /// The seed of VPL `id`'s second, rendering radiosity: independent of
    /// the one its selection used.
    ///
    /// Algorithm 1 keeps the candidates of largest estimated intensity and
    /// removes the VPLs of smallest, and the paper renders with those same
    /// 16-path estimates (re-estimated with the VPL's own seed, so unchanged).
    /// Selecting on a noisy estimate and then using it is the winner's curse:
    /// the kept VPLs are those whose noise came out high. Measured on
    /// `office` (frame 600, 2048 VPLs, exhaustive ray-traced shading, no
    /// clamp) the image was 67 % brighter than path tracing, and 56 % with
    /// k = 32, so the kNN densities were not the cause. A second estimate per
    /// VPL, seeded apart and made once when it joins Y (and again when the
    /// lights change), carries the flux; it is independent of every decision,
    /// so the flux is unbiased given the positions, and it stays fixed for
    /// the VPL's life, so it costs no temporal coherence.
    fn render_seed(seed: u64, id: u64) -> u64 {
        mix64(seed ^ mix64(id.wrapping_add(0x5EC0_0002)).rotate_left(17))
    }

    /// The seed of candidate `id`'s relighting estimates: the same at every
    /// iteration, so that their differences are quiet ([`Relight::Candidates`]).
    fn relight_seed(seed: u64, id: u64) -> u64 {
        mix64(seed ^ mix64(id.wrapping_add(0x5EC0_0003)).rotate_left(29))
    }

    /// One iteration of Algorithm 1 (lines 3–19) for `camera` over `scene`,
    /// step by step; the first call initialises Y from candidates (line 1).
    ///
    /// Each call is a frame: with [`Placement::Centroid`] the VPLs take
    /// their cells' probes at once in the first call, from cells measured
    /// by one iteration of probes, and later calls move at most M_max of
    /// them. [`VplSampler::next_frame`] runs the warm-up without placing
    /// anyone, so its first frame places every VPL from cells measured over
    /// all T iterations; drive the sampler through it to render.
    pub fn iterate(&mut self, scene: &Scene, camera: &Camera, seed: u64) -> &VplSet {
        let start = Instant::now();
        let mut st = SmcStats { iterations: self.iterations + 1, ..SmcStats::default() };
        let mut tm = SmcTimings::default();
        let (rays_x, xs, from) = self.draw_camera_points(scene, camera, seed, &mut st, &mut tm);
        let valid = self.verify_indirect_visibility(scene, camera, &xs, seed, &mut st, &mut tm);
        let candidates = self.draw_candidates(scene, &xs, (&rays_x, &from), seed, &mut st, &mut tm);
        let t0 = Instant::now();
        self.choose_removals(&candidates, &valid, &mut st);
        let added = self.fill_slots(candidates, &xs, &mut st);
        tm.candidates_ms += ms(t0);
        self.refresh_radiosities(scene, seed, &added, &mut st, &mut tm);
        let n = self.refresh_densities(scene, &mut tm);
        self.write_fluxes(scene, seed, n, &mut st, &mut tm);
        self.iterations += 1;
        tm.total_ms = ms(start);
        self.stats = st;
        self.timings = tm;
        &self.set
    }

    /// Line 3: camera points X, from random raster positions.
    /// The camera rays are kept with the index of the ray each point came
    /// from: the candidate rays leave those points (line 5).
    fn draw_camera_points<'c>(
        &self,
        scene: &Scene,
        camera: &'c Camera,
        seed: u64,
        st: &mut SmcStats,
        tm: &mut SmcTimings,
    ) -> (CameraRays<'c>, Vec<CameraPoint>, Vec<u32>) {
        let t0 = Instant::now();
        let n_rays = self.config.vpls * self.config.resample_ratio;
        let batch = CameraRays::new(camera, stream_key(seed, self.iterations, Purpose::CAMERA_POINTS), n_rays);
        let (xs, from) = camera_points_of(scene, self.rays.as_ref(), &batch);
        st.camera_points = xs.len();
        tm.candidates_ms += ms(t0);
        (batch, xs, from)
    }

    /// Line 4: INVALID ← Y \ indirectly visible VPLs. A VPL whose mailbox
    /// point the camera still sees stays valid (§3.2.2); for the others, up
    /// to V rays from random camera points try to see it, in rounds, and the
    /// first that does becomes its mailbox. Returns which slots are valid.
    fn verify_indirect_visibility(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        xs: &[CameraPoint],
        seed: u64,
        st: &mut SmcStats,
        tm: &mut SmcTimings,
    ) -> Vec<bool> {
        let t0 = Instant::now();
        let (c, it) = (self.config, self.iterations);
        let rays = self.rays.as_ref();
        let anchors: Vec<Option<CameraPoint>> = self.particles.iter().map(|p| p.map(|p| p.anchor)).collect();
        let mut valid: Vec<bool> = camera_sees(scene, camera, rays, &anchors);
        st.mailbox_valid = valid.iter().filter(|v| **v).count();
        if !xs.is_empty() {
            // A caster that speculates casts every round in one batch: a
            // slot's draws in round r come from its own stream (slot, r), so
            // the first that sees the VPL, in round order, is the same.
            let (rounds, per_batch) = if rays.speculates() { (1, c.visibility_iterations) } else { (c.visibility_iterations, 1) };
            for batch in 0..rounds {
                let unverified: Vec<usize> = (0..c.vpls).filter(|&s| self.particles[s].is_some() && !valid[s]).collect();
                if unverified.is_empty() {
                    break;
                }
                // Up to visibility_rays camera points per unverified VPL and
                // round, all drawn first; the first that sees the VPL
                // becomes its mailbox.
                let particles = &self.particles;
                let tries: Vec<(usize, CameraPoint, Result<vpl_core::Ray, bool>)> = unverified
                    .par_iter()
                    .flat_map_iter(|&s| {
                        let p = particles[s].expect("unverified slots hold a VPL");
                        let draws: Vec<CameraPoint> = (batch * per_batch..(batch + 1) * per_batch)
                            .flat_map(|round| {
                                let mut rng = stream(seed, it, Purpose::INDIRECT_VISIBILITY, (s as u64) << 8 | round as u64);
                                (0..c.visibility_rays).map(move |_| rng.below(xs.len() as u32) as usize).collect::<Vec<_>>()
                            })
                            .map(|j| xs[j])
                            .collect();
                        draws.into_iter().map(move |x| (s, x, mutual_ray(scene, &x, p.y.p, p.y.n)))
                    })
                    .collect();
                let seen = resolve(scene, rays, tries.iter().map(|(_, _, t)| *t).collect());
                for ((s, x, _), v) in tries.into_iter().zip(seen) {
                    if !v || valid[s] {
                        continue;
                    }
                    if let Some(p) = self.particles[s].as_mut() {
                        p.anchor = x;
                        valid[s] = true;
                        st.ray_valid += 1;
                    }
                }
            }
        }
        let occupied = self.particles.iter().filter(|p| p.is_some()).count();
        st.invalid = occupied - st.mailbox_valid - st.ray_valid;
        tm.visibility_ms = ms(t0);
        valid
    }

    /// Lines 5–8: candidates Ŷ. Rays from X hit the scene (line 5); the hits
    /// are resampled toward a uniform density over area (line 6); each
    /// candidate gets its radiosity, seeded by the id it keeps as a VPL
    /// (line 7), and its density against Y with k = 1 (line 8, §3.2.4).
    fn draw_candidates(
        &mut self,
        scene: &Scene,
        xs: &[CameraPoint],
        (rays_x, from): (&CameraRays, &[u32]),
        seed: u64,
        st: &mut SmcStats,
        tm: &mut SmcTimings,
    ) -> Vec<Candidate> {
        let (c, it) = (self.config, self.iterations);
        // Line 5: hits of rays from X.
        let t0 = Instant::now();
        let hits = candidate_hits_from(scene, self.rays.as_ref(), xs, rays_x, from, seed, it);
        st.hits = hits.len();
        tm.candidates_ms += ms(t0);

        // Line 6: weight 1/p_hit(y) ∝ r_1(y)², the squared distance to the nearest other hit.
        let t0 = Instant::now();
        let hit_points: Vec<Vec3> = hits.par_iter().map(|h| h.y.p).collect();
        let hit_tree = KnnDensity::new(&hit_points).ok();
        let nearest = hit_tree.as_ref().map(|d| d.member_nearest()).unwrap_or_default();
        let weights: Vec<f32> = if hits.len() > 1 && nearest.len() == hits.len() {
            nearest.par_iter().map(|n| n.map_or(f32::INFINITY, |(_, d2)| d2)).collect()
        } else {
            vec![1.0; hits.len()]
        };
        tm.knn_ms += ms(t0);
        let t0 = Instant::now();
        let drawn = resample_counted(&weights, c.vpls, c.max_retries, seed, it);
        let chosen = &drawn.taken;
        st.candidates = chosen.len();
        tm.resampling_ms = ms(t0);

        // Line 7: candidate radiosities, each seeded by the id it keeps as a VPL.
        let t0 = Instant::now();
        let first_id = self.next_id;
        self.next_id += chosen.len() as u64;
        let jobs: Vec<(SurfacePoint, u64)> =
            chosen.iter().enumerate().map(|(i, &h)| (hits[h].y, Self::radiosity_seed(seed, first_id + i as u64))).collect();
        let radiances: Vec<Vec3> = self.estimator.radiosity_many(scene, &jobs);
        tm.radiosity_ms += ms(t0);

        // The hits become area probes, the candidates among them with their radiance.
        if c.probes() && self.collect_probes {
            // Each candidate's point, where it is relit: its relighting
            // estimate under this iteration's lights is made if they change.
            let relit = c.relight == Relight::Candidates;
            let t0 = Instant::now();
            // Each candidate's first landings over its draw probability: with
            // its hit's area, its weight in its cell's mean radiance.
            let sampled: Vec<ProbeCandidate> = chosen
                .iter()
                .zip(drawn.first.iter().zip(&drawn.probability))
                .zip(&radiances)
                .enumerate()
                .map(|(i, ((&h, (&c, &p)), &l))| ProbeCandidate {
                    hit: h,
                    radiance: l,
                    draws: (c as f64 / p) as f32,
                    id: first_id + i as u64,
                    track: relit.then_some(hits[h].y),
                })
                .collect();
            let normals: Vec<Vec3> = hits.par_iter().map(|h| h.y.ng).collect();
            let shading: Vec<Vec3> = hits.par_iter().map(|h| h.y.n).collect();
            if let Some(tree) = hit_tree {
                self.probes.push(ProbeHits {
                    hits: &hit_points,
                    normals: &normals,
                    shading: &shading,
                    tree,
                    nearest: &nearest,
                    candidates: &sampled,
                    draw_scale: 1.0 / drawn.draws.max(1) as f64,
                    scene: Some(scene),
                });
            }
            tm.knn_ms += ms(t0);
        }

        // Line 8: candidate densities against Y with k = 1.
        let t0 = Instant::now();
        let current: Vec<Vec3> = self.particles.iter().flatten().map(|p| p.y.p).collect();
        let cand_points: Vec<Vec3> = chosen.iter().map(|&h| hits[h].y.p).collect();
        let cand_density = match KnnDensity::new(&current) {
            Ok(d) if !d.is_empty() => d.at_many(&cand_points, 1).unwrap_or_else(|_| vec![1.0; chosen.len()]),
            // Line 1: an empty Y takes candidates by radiosity alone.
            _ => vec![1.0; chosen.len()],
        };
        tm.knn_ms += ms(t0);
        chosen
            .iter()
            .enumerate()
            .map(|(i, &h)| Candidate {
                hit: hits[h],
                id: first_id + i as u64,
                radiance: radiances[i],
                intensity: intensity(radiances[i], cand_density[i]),
            })
            .collect()
    }

    /// Lines 9–13: which VPLs leave. M_strong counts the candidates stronger
    /// than the strong_quantile of the current intensities and M_min =
    /// min(M_max, M_strong) (eq. 9); while |INVALID| < M_min the weakest
    /// valid VPL is invalidated (lines 10–12); at most M_max of INVALID are
    /// removed, weakest first (line 13).
    fn choose_removals(&mut self, candidates: &[Candidate], valid: &[bool], st: &mut SmcStats) {
        let c = self.config;
        let mut current_i: Vec<f32> = self.particles.iter().flatten().map(|p| p.intensity()).collect();
        current_i.sort_by(f32::total_cmp);
        let threshold = quantile(&current_i, c.strong_quantile);
        st.m_strong = candidates.iter().filter(|k| threshold.is_none_or(|t| k.intensity > t)).count();
        let m_min = c.m_max.min(st.m_strong);

        // Each slot's intensity (0 where empty), weakest first, then by slot.
        let slot_i: Vec<f32> = self.particles.iter().map(|p| p.as_ref().map_or(0.0, Particle::intensity)).collect();
        let by_intensity = |a: &usize, b: &usize| slot_i[*a].total_cmp(&slot_i[*b]).then(a.cmp(b));
        let mut invalid: Vec<usize> = (0..c.vpls).filter(|&s| self.particles[s].is_some() && !valid[s]).collect();
        invalid.sort_by(by_intensity);
        if invalid.len() < m_min {
            let mut weak: Vec<usize> = (0..c.vpls).filter(|&s| valid[s]).collect();
            weak.sort_by(by_intensity);
            let extra = m_min - invalid.len();
            st.weakest = extra.min(weak.len());
            invalid.extend(weak.into_iter().take(extra));
        }
        invalid.truncate(c.m_max);
        for &s in &invalid {
            self.particles[s] = None;
        }
        st.removed = invalid.len();
    }

    /// Lines 14–17: the strongest candidates fill the empty slots; returns
    /// the slots filled.
    fn fill_slots(&mut self, mut candidates: Vec<Candidate>, xs: &[CameraPoint], st: &mut SmcStats) -> Vec<usize> {
        candidates.sort_by(|a, b| b.intensity.total_cmp(&a.intensity).then(a.id.cmp(&b.id)));
        let mut next = candidates.into_iter();
        let mut added = Vec::new();
        for s in 0..self.config.vpls {
            if self.particles[s].is_some() {
                continue;
            }
            let Some(k) = next.next() else { break };
            self.particles[s] = Some(Particle {
                y: k.hit.y,
                id: k.id,
                radiance: Vec3::ZERO,
                selection_radiance: k.radiance,
                density: 0.0,
                anchor: xs[k.hit.origin as usize],
            });
            added.push(s);
            st.added += 1;
        }
        added
    }

    /// Line 18: radiosities of the set, anew only when the lighting changed
    /// (otherwise the same seeds would give the same values); the rendering
    /// radiosity of each VPL that just joined Y ([`Self::render_seed`]).
    fn refresh_radiosities(&mut self, scene: &Scene, seed: u64, added: &[usize], st: &mut SmcStats, tm: &mut SmcTimings) {
        let t0 = Instant::now();
        let key = LightingKey::of(scene);
        if self.lighting.as_ref() != Some(&key) {
            st.relit = self.lighting.is_some();
            let slots: Vec<usize> = (0..self.config.vpls).filter(|&s| self.particles[s].is_some()).collect();
            let jobs: Vec<(SurfacePoint, u64)> = slots
                .iter()
                .flat_map(|&s| {
                    let p = self.particles[s].expect("occupied");
                    [(p.y, Self::radiosity_seed(seed, p.id)), (p.y, Self::render_seed(seed, p.id))]
                })
                .collect();
            let l = self.estimator.radiosity_many(scene, &jobs);
            for (k, &s) in slots.iter().enumerate() {
                if let Some(p) = self.particles[s].as_mut() {
                    p.selection_radiance = l[2 * k];
                    p.radiance = l[2 * k + 1];
                }
            }
            self.lighting = Some(key);
            // The candidates held, estimated under earlier lights, brought to
            // these: those not relit yet were made under the lights of the
            // last change, which `lit` holds (kept only where candidates are
            // relit).
            if self.config.relight == Relight::Candidates && self.config.probes() {
                if let Some(lit) = self.lit.replace(scene.clone()) {
                    let tracker = &self.tracker;
                    let estimate = |scene: &Scene, jobs: &[(SurfacePoint, u64)]| {
                        let jobs: Vec<(SurfacePoint, u64)> = jobs.iter().map(|&(y, id)| (y, Self::relight_seed(seed, id))).collect();
                        tracker.radiosity_many(scene, &jobs)
                    };
                    st.relit_candidates = self.probes.relight(&mut |jobs| estimate(&lit, jobs), &mut |jobs| estimate(scene, jobs));
                }
            }
        } else {
            let jobs: Vec<(SurfacePoint, u64)> =
                added.iter().filter_map(|&s| self.particles[s].map(|p| (p.y, Self::render_seed(seed, p.id)))).collect();
            let l = self.estimator.radiosity_many(scene, &jobs);
            let mut fresh = l.into_iter();
            for &s in added {
                if let Some(p) = self.particles[s].as_mut() {
                    p.radiance = fresh.next().expect("one estimate per added VPL");
                }
            }
        }
        tm.radiosity_ms += ms(t0);
    }

    /// Line 19: densities of the set with the rendering k (eq. 8), each point
    /// excluded from its own neighbours; a set too small for k uses k = n − 1,
    /// and a single VPL the scene's area. Returns the number n of VPLs.
    fn refresh_densities(&mut self, scene: &Scene, tm: &mut SmcTimings) -> usize {
        let t0 = Instant::now();
        let slots: Vec<usize> = (0..self.config.vpls).filter(|&s| self.particles[s].is_some()).collect();
        let pts: Vec<Vec3> = slots.iter().filter_map(|&s| self.particles[s].map(|p| p.y.p)).collect();
        let dens = set_densities(&pts, self.config.k(), scene.surface_area());
        for (&s, &p) in slots.iter().zip(&dens) {
            if let Some(q) = self.particles[s].as_mut() {
                q.density = p;
            }
        }
        tm.knn_ms += ms(t0);
        slots.len()
    }

    /// The occupied slots and their particles as the cells see them.
    fn sites(&self) -> (Vec<usize>, Vec<Site>) {
        (0..self.config.vpls).filter_map(|s| self.particles[s].map(|p| (s, Site { id: p.id, slot: s as u32, p: p.y.p, n: p.y.ng }))).unzip()
    }

    /// The last frame's cells cut into their probes, each a VPL with its
    /// share of its cell's flux ([`AreaProbes::pieces`]): the light the
    /// default flux gives each VPL, spread over its cell. Empty without
    /// measured cells.
    pub fn cell_pieces(&self) -> Vec<Vpl> {
        let (slots, sites) = self.sites();
        let Some(cells) = self.probes.cells(&sites) else { return Vec::new() };
        let (flux, _) = self.cell_fluxes(&slots, &sites, &cells);
        let radiance: Vec<Vec3> =
            flux.iter().zip(&cells).map(|(&f, c)| if c.area > 0.0 { f / c.area as f32 } else { Vec3::ZERO }).collect();
        self.probes
            .pieces(&sites, &radiance)
            .into_iter()
            .enumerate()
            .map(|(k, (_, y, n, flux))| Vpl { y, n, flux, id: k as u64, bounce: 0 })
            .collect()
    }

    /// Each cell's light Φ_i = L̄_now(V_i) · A(V_i) (the mean radiance as
    /// [`Relight`] brings it to the lights of now, the cell's VPL's own
    /// radiance where no candidate fell in it), `slots`, `sites` and
    /// `cells` in the same order, with the negative parts of relit cells
    /// taken from their neighbours' light ([`relight::spread_deficits`]);
    /// and what was spread.
    fn cell_fluxes(&self, slots: &[usize], sites: &[Site], cells: &[Cell]) -> (Vec<Vec3>, relight::Spread) {
        let mut flux: Vec<Vec3> = slots
            .iter()
            .zip(cells)
            .map(|(&s, c)| self.particles[s].map_or(Vec3::ZERO, |p| c.radiance(self.config.relight, p.radiance) * c.area as f32))
            .collect();
        let points: Vec<Vec3> = sites.iter().map(|s| s.p).collect();
        let normals: Vec<Vec3> = sites.iter().map(|s| s.n).collect();
        let spread = relight::spread_deficits(&points, &normals, &mut flux);
        (flux, spread)
    }

    /// The probes of the last frame's cells: point, shading normal and the
    /// area each stands for (weighted over the iterations held).
    pub fn cell_areas(&self) -> Vec<(usize, Vec3, Vec3, f32)> {
        let (_, sites) = self.sites();
        let ones = vec![Vec3::ONE; sites.len()];
        self.probes.pieces(&sites, &ones).into_iter().map(|(i, p, n, a)| (i, p, n, a.x)).collect()
    }

    /// The output: flux Φ (eq. 5 and the flux convention of vpl-core) as
    /// the configured [`FluxEstimator`] makes it. Until cells have been
    /// measured (and during the warm-up, whose flux nobody looks at) it is
    /// the paper's L / (n p). Each VPL shines from where the configured
    /// [`Placement`] puts it (the site until cells have been measured).
    fn write_fluxes(&mut self, scene: &Scene, seed: u64, n: usize, st: &mut SmcStats, tm: &mut SmcTimings) {
        let t0 = Instant::now();
        let slots: Vec<usize> = (0..self.config.vpls).filter(|&s| self.particles[s].is_some()).collect();
        let particle = |s: usize| self.particles[s].expect("occupied");
        // The flux of each slot (zero where it is empty), the paper's first.
        let mut flux = vec![Vec3::ZERO; self.config.vpls];
        for &s in &slots {
            let p = particle(s);
            flux[s] = p.radiance / (n as f32 * p.density);
        }
        let mut shown: Vec<Option<Shown>> = vec![None; self.config.vpls];
        let mut near_memory = std::mem::take(&mut self.near);
        if self.config.probes() {
            // Each VPL's radiance under this iteration's lights, beside this iteration's probes.
            let record: Vec<(u32, u64, Vec3)> = slots.iter().map(|&s| (s as u32, particle(s).id, particle(s).radiance)).collect();
            self.probes.record(&record);
        }
        if self.config.probes() && !self.warming {
            // The same occupied slots, in the same order, as `slots`.
            let (_, sites) = self.sites();
            st.probe_rays = self.probes.assign(scene, self.rays.as_ref(), &sites);
            st.candidate_light = self.probes.candidate_light();
            if let Some((cells, near_ratios)) = self.probes.cells_and(&sites, self.config.flux == FluxEstimator::VoronoiNear) {
                let knn_total: f64 = slots.iter().map(|&s| 1.0 / (n as f64 * particle(s).density as f64)).filter(|a| a.is_finite()).sum();
                let cell_total: f64 = cells.iter().map(|c| c.area).sum();
                st.knn_area_ratio = if cell_total > 0.0 { (knn_total / cell_total) as f32 } else { 0.0 };
                // Each cell's light under the lights of now ([`Relight`]), non-negative (eq. 2 of its module).
                let (by_cell, spread) = self.cell_fluxes(&slots, &sites, &cells);
                st.negative_cells = spread;
                match self.config.flux {
                    FluxEstimator::Voronoi => slots.iter().zip(by_cell).for_each(|(&s, f)| flux[s] = f),
                    FluxEstimator::VoronoiNear => {
                        let ratios = near_ratios.unwrap_or_else(|| vec![1.0; slots.len()]);
                        // Each VPL's ratio blended over its frames (NEAR_BLEND).
                        for ((&s, f), r) in slots.iter().zip(by_cell).zip(ratios) {
                            let id = particle(s).id;
                            let r = match near_memory[s] {
                                Some((was, prev)) if was == id => prev + NEAR_BLEND * (r - prev),
                                _ => r,
                            };
                            near_memory[s] = Some((id, r));
                            flux[s] = f * r as f32;
                        }
                    }
                    FluxEstimator::VoronoiSite => {
                        slots.iter().zip(&cells).for_each(|(&s, c)| flux[s] = particle(s).radiance * c.area as f32)
                    }
                    FluxEstimator::KnnCalibrated => {
                        // One factor: the cells' total flux over the kNN total, by luminance.
                        let total =
                            |f: &mut dyn Iterator<Item = Vec3>| f.map(|v| luminance(v) as f64).filter(|v| v.is_finite()).sum::<f64>();
                        let (by_cells, by_knn) = (total(&mut by_cell.iter().copied()), total(&mut slots.iter().map(|&s| flux[s])));
                        if by_knn > 0.0 {
                            let c = (by_cells / by_knn) as f32;
                            slots.iter().for_each(|&s| flux[s] *= c);
                        }
                    }
                    FluxEstimator::Knn => {}
                }
                if self.config.placement == Placement::Centroid {
                    let centroids: Vec<Vec3> = cells.iter().map(|c| c.centroid).collect();
                    let nearest = self.probes.nearest_probes(&sites, &centroids);
                    let mut choices = vec![None; self.config.vpls];
                    for ((&s, c), near) in slots.iter().zip(&cells).zip(nearest) {
                        let p = particle(s);
                        choices[s] = Some(placement::choose(p.id, (p.y.p, p.y.n), self.shown[s], c.centroid, c.area, near));
                    }
                    // Moves for placement share M_max with the slots Algorithm 1 replaced.
                    let budget = self.config.m_max.saturating_sub(st.removed.max(st.added));
                    shown = placement::settle(choices, &self.shown, budget);
                } else if self.config.placement == Placement::Random {
                    // A VPL new to its slot draws its point from its cell; the others keep theirs.
                    let kept = |s: usize| self.shown[s].filter(|at| at.id == particle(s).id);
                    let u: Vec<Option<f32>> = slots
                        .iter()
                        .map(|&s| kept(s).is_none().then(|| stream(seed, 0, Purpose::PLACEMENT, particle(s).id).next_f32()))
                        .collect();
                    let drawn = self.probes.drawn_probes(&sites, &cells, &u);
                    for (&s, d) in slots.iter().zip(drawn) {
                        let p = particle(s);
                        shown[s] = kept(s).or(Some(match d {
                            Some((at, n)) => Shown { id: p.id, p: at, n },
                            None => Shown { id: p.id, p: p.y.p, n: p.y.n },
                        }));
                    }
                }
            }
        }
        tm.knn_ms += ms(t0);
        self.set.begin_frame();
        for (s, f) in flux.into_iter().enumerate() {
            let v = self.particles[s].map(|p| {
                let (y, n) = shown[s].map_or((p.y.p, p.y.n), |at| (at.p, at.n));
                Vpl { y, n, flux: if f.is_finite() { f } else { Vec3::ZERO }, id: p.id, bounce: 0 }
            });
            self.set.set(s, v);
        }
        self.shown = shown;
        self.near = near_memory;
        st.stored = n;
        st.intensity_cv = coefficient_of_variation(self.particles.iter().flatten().map(|p| p.intensity()));
    }
}

/// The q-quantile of sorted values (nearest rank), `None` when empty.
fn quantile(sorted: &[f32], q: f32) -> Option<f32> {
    if sorted.is_empty() {
        return None;
    }
    let i = ((q * sorted.len() as f32).ceil() as usize).clamp(1, sorted.len()) - 1;
    Some(sorted[i])
}

/// σ/μ of the values (0 for fewer than two values or a zero mean).
fn coefficient_of_variation(v: impl Iterator<Item = f32>) -> f32 {
    let v: Vec<f64> = v.map(|x| x as f64).collect();
    if v.len() < 2 {
        return 0.0;
    }
    let m = v.iter().sum::<f64>() / v.len() as f64;
    if m <= 0.0 {
        return 0.0;
    }
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64;
    (var.sqrt() / m) as f32
}

impl VplSampler for SmcSampler {
    fn name(&self) -> &'static str {
        "smc"
    }

    /// The first frame initialises Y and runs the warm-up iterations on it;
    /// every frame then runs one iteration.
    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        if !self.started() {
            self.warming = true;
            let iterations = self.config.warmup as usize + 2;
            for w in 0..=self.config.warmup as usize {
                // The last T iterations (this loop's and the frame's own) collect probes.
                self.collect_probes = w + self.config.probe_iterations >= iterations;
                self.iterate(frame.scene, frame.camera, frame.seed);
            }
            self.warming = false;
            self.collect_probes = true;
        }
        self.iterate(frame.scene, frame.camera, frame.seed)
    }

    fn stats(&self) -> Stats {
        let s = self.stats;
        let stats = s
            .counts()
            .value("knn_area_ratio", s.knn_area_ratio as f64)
            .value("candidate_light", s.candidate_light)
            .count("probe_rays", s.probe_rays)
            .ms("ms", self.timings.total_ms);
        self.timings.steps(stats)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_and_cv() {
        let v = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0, 16.0, 17.0, 18.0, 19.0, 20.0];
        assert_eq!(quantile(&v, 0.95), Some(19.0));
        assert_eq!(quantile(&v, 1.0), Some(20.0));
        assert_eq!(quantile(&[], 0.5), None);
        assert_eq!(coefficient_of_variation([2.0, 2.0, 2.0].into_iter()), 0.0);
        assert!((coefficient_of_variation([1.0, 3.0].into_iter()) - 2f32.sqrt() / 2.0).abs() < 1e-6);
    }

    /// With the random placement every VPL shines from a point it drew
    /// when it joined and keeps it for its life: only replaced slots move,
    /// at most M_max a frame, and the same run gives the same points.
    #[test]
    fn random_placement_keeps_each_vpls_point_for_its_life() {
        let setup = vpl_core::SceneSetup::builtin("cornell").unwrap();
        let camera = setup.camera.with_resolution((32, 32)).unwrap();
        let gbuffer = vpl_core::GBuffer::empty();
        let config = SmcConfig { vpls: 128, warmup: 8, placement: Placement::Random, flux: FluxEstimator::Voronoi, ..SmcConfig::default() };
        let run = || {
            let mut smc = SmcSampler::new(config).unwrap();
            let mut frames = Vec::new();
            for index in 0..6 {
                let frame = Frame { scene: &setup.scene, camera: &camera, time: 0.0, index, seed: 3, gbuffer: &gbuffer, previous: None };
                let set = smc.next_frame(&frame);
                frames.push((0..128).map(|s| set.get(s).map(|v| (v.id, v.y, v.n))).collect::<Vec<_>>());
            }
            frames
        };
        let frames = run();
        assert_eq!(frames[0].iter().flatten().count(), 128);
        // Some VPLs shine from another point than their particle's.
        let mut smc = SmcSampler::new(config).unwrap();
        let frame = Frame { scene: &setup.scene, camera: &camera, time: 0.0, index: 0, seed: 3, gbuffer: &gbuffer, previous: None };
        let set = smc.next_frame(&frame).clone();
        let elsewhere =
            smc.particles().iter().enumerate().filter(|(s, p)| p.is_some_and(|p| set.get(*s).is_some_and(|v| v.y != p.y.p))).count();
        assert!(elsewhere > 64, "{elsewhere} of 128 moved into their cells");
        for pair in frames.windows(2) {
            let moved = pair[0].iter().zip(&pair[1]).filter(|(a, b)| a != b).count();
            assert!(moved <= config.m_max, "{moved} slots moved");
            for (a, b) in pair[0].iter().zip(&pair[1]) {
                if let (Some(a), Some(b)) = (a, b) {
                    assert!(a.0 != b.0 || a == b, "VPL {} moved", a.0);
                }
            }
        }
        assert_eq!(run(), frames);
    }
}

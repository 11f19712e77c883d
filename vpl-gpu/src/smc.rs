//! Sequential Monte Carlo Instant Radiosity on the device: Algorithm 1 of
//! Hedman et al. (2017), every line a kernel (`smc.wgsl`), one submission
//! an iteration; the twin of [`vpl_smc::SmcSampler`] with the paper's kNN
//! flux ([`FluxEstimator::Knn`], eqs. 5, 7, 8).
//!
//! | line | kernel | what differs from the CPU |
//! | --- | --- | --- |
//! | 3: camera points X | `camera_points`, `compact_x` | the same rays and streams |
//! | 4: indirect visibility | `visibility`: the mailbox, then V rays a round from random points of X, the first that sees the VPL its anchor | — |
//! | 5: candidate rays | `candidate_rays` | — |
//! | 6: weights r₁², resampling | a device grid ([`NeighbourSearch`]), `weights`, `scan_weights` (f32 running sums), `draw` (every attempt of every draw at once), `take` (one invocation keeps each draw's first attempt not taken) | f32 running sums and a 48-bit draw, not f64 and 53 bits: a draw that lands within rounding of a boundary may take the neighbouring hit |
//! | 7: candidate radiosities | the radiosity kernels on jobs written on the device, seeded by the ids the candidates keep | none: the same streams |
//! | 8: candidate densities (k = 1) | the grid over Y, `candidate_intensity` | — |
//! | 9–17: M_strong, removals, fills | `decide`: one workgroup, three bitonic sorts | — |
//! | 18: radiosities of the set | `added_jobs` / `relit_jobs`, the radiosity kernels | — |
//! | 19: densities (eq. 8), fluxes (eq. 5) | the grid over Y, `fluxes`, `stats` | — |
//!
//! Every kernel draws from the CPU's streams (the same keys and indices), so
//! the two samplers make the same choices until a resampling draw lands
//! within rounding of a boundary, or a ray grazes an edge; from there they
//! go apart as two seeds would.
//!
//! The statistics cross in the same read as the VPLs (48 B a slot and
//! 64 B), the only traffic of a steady iteration besides its 240 B of
//! parameters; the warm-up's iterations are submitted without waiting.

use crate::context::{GpuContext, GpuError};
use crate::device::Gpu;
use crate::kernel::{Binding, SAMPLING_WGSL, bind, dispatch, groups_1d, layout, pipeline, storage, uniform};
use crate::neighbours::{BoundSearch, NeighbourSearch, Rows};
use crate::radiosity::{self, path_params};
use crate::scene::{BVH_WGSL, scene_layout};
use std::time::Instant;
use vpl_core::glam::Vec4;
use vpl_core::rng::stream_key;
use vpl_core::scene::LightingKey;
use vpl_core::{Camera, Frame, Purpose, Scene, Stats, Vpl, VplSampler, VplSet};
use vpl_pathtrace::PathRadiosity;
use vpl_smc::{FluxEstimator, Placement, SmcConfig, SmcStats, SmcTimings};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct It {
    n: u32,
    c: u32,
    cs: u32,
    ns: u32,
    tries: u32,
    vis_rays: u32,
    vis_iters: u32,
    m_max: u32,
    row_c: u32,
    row_n: u32,
    np2: u32,
    two_sided: u32,
    paths: u32,
    row_d: u32,
    k: u32,
    pad0: u32,
    eps: f32,
    quantile: f32,
    area: f32,
    pad1: f32,
    key_cam: [u32; 2],
    key_cand: [u32; 2],
    key_res: [u32; 2],
    key_vis: [u32; 2],
    seed: [u32; 2],
    purpose_radiosity: [u32; 2],
    origin: [f32; 4],
    forward: [f32; 4],
    right: [f32; 4],
    up: [f32; 4],
    raster: [f32; 4],
}

fn words(v: u64) -> [u32; 2] {
    [v as u32, (v >> 32) as u32]
}

struct Kernels {
    layout: wgpu::BindGroupLayout,
    camera_points: wgpu::ComputePipeline,
    compact_x: wgpu::ComputePipeline,
    visibility: wgpu::ComputePipeline,
    candidate_rays: wgpu::ComputePipeline,
    weights: wgpu::ComputePipeline,
    scan_weights: wgpu::ComputePipeline,
    draw: wgpu::ComputePipeline,
    take: wgpu::ComputePipeline,
    candidate_jobs: wgpu::ComputePipeline,
    candidate_intensity: wgpu::ComputePipeline,
    decide: wgpu::ComputePipeline,
    added_jobs: wgpu::ComputePipeline,
    added_radiance: wgpu::ComputePipeline,
    relit_jobs: wgpu::ComputePipeline,
    relit_radiance: wgpu::ComputePipeline,
    fluxes: wgpu::ComputePipeline,
    stats: wgpu::ComputePipeline,
    radiosity: radiosity::Kernels,
}

impl Kernels {
    fn new(ctx: &GpuContext) -> Kernels {
        let (r, w) = (Binding::Read, Binding::ReadWrite);
        let layout = layout(ctx, "smc", &[Binding::Uniform, w, w, w, w, w, w, w, w, r, r]);
        let source = format!("{BVH_WGSL}\n{SAMPLING_WGSL}\n{}", include_str!("smc.wgsl"));
        let scene = scene_layout(ctx);
        let p = |entry: &str| pipeline(ctx, entry, &source, entry, &[&scene, &layout]);
        Kernels {
            camera_points: p("camera_points"),
            compact_x: p("compact_x"),
            visibility: p("visibility"),
            candidate_rays: p("candidate_rays"),
            weights: p("weights"),
            scan_weights: p("scan_weights"),
            draw: p("draw"),
            take: p("take"),
            candidate_jobs: p("candidate_jobs"),
            candidate_intensity: p("candidate_intensity"),
            decide: p("decide"),
            added_jobs: p("added_jobs"),
            added_radiance: p("added_radiance"),
            relit_jobs: p("relit_jobs"),
            relit_radiance: p("relit_radiance"),
            fluxes: p("fluxes"),
            stats: p("stats"),
            radiosity: radiosity::Kernels::new(ctx),
            layout,
        }
    }
}

/// The sampler's state on the device, sized by its configuration.
struct Buffers {
    it: wgpu::Buffer,
    state: wgpu::Buffer,
    group: wgpu::BindGroup,
    out: wgpu::Buffer,
    rjobs: wgpu::Buffer,
    rkeys: wgpu::Buffer,
    rpaths: wgpu::Buffer,
    rsum: wgpu::Buffer,
    search: NeighbourSearch,
    /// The hits' nearest other hit (line 6), the candidates' nearest VPL
    /// (line 8), the VPLs' k-th nearest (line 19).
    hits: BoundSearch,
    candidates: BoundSearch,
    set: BoundSearch,
}

/// Sizes and dispatch shapes of one configuration.
#[derive(Clone, Copy)]
struct Shape {
    n: u64,
    c: u64,
    cs: u64,
    ns: u64,
    tries: u64,
    np2: u64,
}

impl Shape {
    fn of(c: &SmcConfig) -> Shape {
        let n = c.vpls as u64;
        let rays = n * c.resample_ratio as u64;
        Shape {
            n,
            c: rays,
            cs: rays.next_multiple_of(16),
            ns: n.next_multiple_of(16),
            tries: c.max_retries as u64 + 1,
            np2: n.next_power_of_two(),
        }
    }
}

/// [`vpl_smc::SmcSampler`]'s Algorithm 1 with the paper's kNN flux, every
/// line on the device (see the module's table): the host writes 240 B of
/// parameters an iteration and reads the VPLs and the statistics back once
/// a frame. Its statistics are the CPU sampler's ([`SmcStats`]); the image
/// it gives is the CPU's within the twin test's tolerance
/// (`tests/smc_device.rs`), not bit for bit.
pub struct GpuSmcSampler {
    gpu: Gpu,
    config: SmcConfig,
    shape: Shape,
    kernels: Kernels,
    buffers: Buffers,
    iterations: u64,
    lighting: Option<LightingKey>,
    set: VplSet,
    stats: SmcStats,
    ms: f64,
    profile: Option<Profile>,
    timings: SmcTimings,
}

/// Timestamps written between the stages of the iteration that ends a frame.
struct Profile {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    /// Nanoseconds a tick.
    period: f64,
}

/// Timestamps an iteration writes: before it, and after each of its stages.
const STAMPS: u32 = 11;

/// Rows of 16 B the timestamps take after the statistics, so that they
/// come back in the same read.
const STAMP_ROWS: u64 = (STAMPS as u64 * 8).div_ceil(16);

impl std::fmt::Debug for GpuSmcSampler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuSmcSampler").field("config", &self.config).field("stats", &self.stats).finish()
    }
}

impl GpuSmcSampler {
    /// A sampler on `gpu` with `config`, which must ask for the paper's
    /// flux at the VPLs' own points ([`FluxEstimator::Knn`],
    /// [`Placement::Site`]) and at most 64 neighbours (eq. 8's k).
    pub fn new(gpu: Gpu, config: SmcConfig) -> Result<GpuSmcSampler, GpuError> {
        config.validate().map_err(|e| GpuError::Invalid(e.to_string()))?;
        if config.flux != FluxEstimator::Knn || config.placement != Placement::Site {
            return Err(GpuError::Invalid(format!(
                "the device's SMC has the paper's kNN flux at the VPLs' sites; asked for {:?} at {:?}",
                config.flux, config.placement
            )));
        }
        if config.k() > crate::MAX_K {
            return Err(GpuError::Invalid(format!("eq. 8's k = {} is over the device's {}", config.k(), crate::MAX_K)));
        }
        let shape = Shape::of(&config);
        let ctx = gpu.ctx();
        let kernels = Kernels::new(ctx);
        let s = shape;
        let it = uniform(ctx, "smc iteration", &<It as bytemuck::Zeroable>::zeroed());
        // The counters, and the indirect dispatch sizes `decide` writes.
        let state = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("smc state"),
            size: 32 * 4,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let u32s = storage(ctx, "smc words", (s.c + s.n * (s.tries + 2) + s.np2 + s.c) * 4)?;
        let pts = storage(ctx, "smc points", (6 * s.cs + s.ns) * 16)?;
        let f32s = storage(ctx, "smc floats", (s.c + s.n) * 4)?;
        let particles = storage(ctx, "smc particles", 9 * s.ns * 16)?;
        // The VPL rows, the statistics, and room for the stages' timestamps.
        let out = storage(ctx, "smc out", (3 * s.n + 4 + STAMP_ROWS) * 16)?;
        let rjobs = storage(ctx, "smc radiosity jobs", 2 * s.n * 48)?;
        let rkeys = storage(ctx, "smc radiosity keys", 2 * s.n * 8)?;
        let rpaths = storage(ctx, "smc radiosity paths", 2 * s.n * config.radiosity_paths.max(1) as u64 * 16)?;
        let rsum = storage(ctx, "smc radiosity sums", 2 * s.n * 16)?;
        let answers = storage(ctx, "smc neighbours", s.c.max(s.n) * 16)?;
        let group =
            bind(ctx, "smc", &kernels.layout, &[&it, &state, &u32s, &pts, &f32s, &particles, &out, &rjobs, &rkeys, &rsum, &answers]);
        let search = NeighbourSearch::new(ctx, s.c.max(s.n))?;
        let nk = gpu.neighbour_kernels();
        fn rows(buffer: &wgpu::Buffer, first: u64, count: u64) -> Rows<'_> {
            Rows { buffer, first, count }
        }
        let hits = search.bind(ctx, nk, rows(&pts, 3 * s.cs, s.c), None, 1, rows(&answers, 0, s.c));
        let candidates = search.bind(ctx, nk, rows(&particles, 0, s.n), Some(rows(&pts, 6 * s.cs, s.n)), 1, rows(&answers, 0, s.n));
        let set = search.bind(ctx, nk, rows(&particles, 0, s.n), None, config.k() as u32, rows(&answers, 0, s.n));
        let buffers = Buffers { it, state, group, out, rjobs, rkeys, rpaths, rsum, search, hits, candidates, set };
        Ok(GpuSmcSampler {
            gpu,
            config,
            shape,
            kernels,
            buffers,
            iterations: 0,
            lighting: None,
            set: VplSet::new(config.vpls),
            stats: SmcStats::default(),
            ms: 0.0,
            profile: None,
            timings: SmcTimings::default(),
        })
    }

    /// Times the stages of each frame's last iteration on the device, in
    /// the columns of the paper's Table 2 ([`GpuSmcSampler::timings`]): 88 B
    /// more in the frame's one read. Returns whether the stages are timed:
    /// `on`, where the device writes timestamps between passes (where it
    /// does not, only the step's wall time is known).
    pub fn profile(&mut self, on: bool) -> bool {
        let ctx = self.gpu.ctx();
        if !on || !ctx.has_timestamps() {
            self.profile = None;
            return false;
        }
        let queries = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("smc stages"),
            ty: wgpu::QueryType::Timestamp,
            count: STAMPS,
        });
        let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("smc stages"),
            size: STAMPS as u64 * 8,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        self.profile = Some(Profile { queries, resolved, period: ctx.queue.get_timestamp_period() as f64 });
        true
    }

    /// Milliseconds of the last frame's last iteration by stage, measured on
    /// the device when [`GpuSmcSampler::profile`] is on (else only
    /// `total_ms`, the frame's wall time, warm-up included on the first).
    /// Candidate sampling takes the camera points, the candidate rays and
    /// lines 9–17; kNN the three grids and their queries, the densities and
    /// the fluxes.
    pub fn timings(&self) -> SmcTimings {
        self.timings
    }

    /// The configuration.
    pub fn config(&self) -> &SmcConfig {
        &self.config
    }

    /// Counts of the last iteration read back (`probe_rays`,
    /// `knn_area_ratio` and `candidate_light` stay 0: no probes).
    pub fn stats(&self) -> SmcStats {
        self.stats
    }

    /// The VPLs after the last frame.
    pub fn vpls(&self) -> &VplSet {
        &self.set
    }

    /// Records and submits one iteration; reads the VPLs and statistics
    /// back when `read`.
    fn iterate(&mut self, scene: &Scene, camera: &Camera, seed: u64, read: bool) -> Result<(), GpuError> {
        let gpu = self.gpu.clone();
        let ctx = gpu.ctx();
        let s = self.shape;
        let c = self.config;
        let gs = self.gpu.scene(scene)?;
        let lights = self.gpu.lights(scene);
        let key = LightingKey::of(scene);
        let relit = self.lighting.as_ref().is_some_and(|k| *k != key);
        self.lighting = Some(key);
        let (f, right, up, sx, sy) = camera.raster_basis();
        let (w, h) = camera.resolution;
        let g_c = groups_1d(ctx, s.c, 64);
        let g_n = groups_1d(ctx, s.n, 64);
        let g_d = groups_1d(ctx, s.n * s.tries, 64);
        let k = |p: Purpose| words(stream_key(seed, self.iterations, p));
        let it = It {
            n: s.n as u32,
            c: s.c as u32,
            cs: s.cs as u32,
            ns: s.ns as u32,
            tries: s.tries as u32,
            vis_rays: c.visibility_rays as u32,
            vis_iters: c.visibility_iterations,
            m_max: c.m_max as u32,
            row_c: g_c.0 * 64,
            row_n: g_n.0 * 64,
            np2: s.np2 as u32,
            two_sided: scene.two_sided as u32,
            paths: c.radiosity_paths.max(1),
            row_d: g_d.0 * 64,
            k: c.k() as u32,
            pad0: 0,
            eps: scene.epsilon(),
            quantile: c.strong_quantile,
            area: scene.surface_area(),
            pad1: 0.0,
            key_cam: k(Purpose::CAMERA_POINTS),
            key_cand: k(Purpose::CANDIDATE),
            key_res: k(Purpose::RESAMPLE),
            key_vis: k(Purpose::INDIRECT_VISIBILITY),
            seed: words(seed),
            purpose_radiosity: words(Purpose::RADIOSITY.0.wrapping_mul(0xD1B5_4A32_D192_ED03)),
            origin: camera.origin.extend(0.0).into(),
            forward: f.extend(sx).into(),
            right: right.extend(sy).into(),
            up: up.extend(camera.focus_distance).into(),
            raster: [w as f32, h as f32, camera.lens_radius.max(0.0), 0.0],
        };
        ctx.write_buffer(&self.buffers.it, 0, bytemuck::bytes_of(&it));
        let b = &self.buffers;
        let kn = &self.kernels;
        let nk = self.gpu.neighbour_kernels();
        // A batch of radiosity jobs: `jobs` points from the jobs the SMC kernels wrote.
        let pr = PathRadiosity { paths: c.radiosity_paths.max(1), max_bounces: c.radiosity_bounces };
        let radiosity_group = |jobs: usize| {
            let (params, groups, sum_groups) = path_params(ctx, scene, pr, jobs);
            let p = uniform(ctx, "smc radiosity params", &params);
            let g = bind(
                ctx,
                "smc radiosity",
                &kn.radiosity.layout,
                &[&p, &b.rjobs, &b.rkeys, &lights.lights, &lights.cdf, &lights.pmf, &lights.tri_light, &b.rpaths, &b.rsum],
            );
            (g, groups, sum_groups)
        };
        let (g_cand, cand_paths, cand_sums) = radiosity_group(s.n as usize);
        let (g_set, set_paths, set_sums) = radiosity_group(if relit { 2 * s.n as usize } else { s.n as usize });
        let groups = [&gs.group, &b.group];
        let one = (1, 1, 1);
        let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("smc iteration") });
        let profile = self.profile.as_ref().filter(|_| read);
        let stamp = |enc: &mut wgpu::CommandEncoder, i: u32| {
            if let Some(p) = profile {
                enc.write_timestamp(&p.queries, i);
            }
        };
        stamp(&mut enc, 0);
        // Line 3.
        dispatch(&mut enc, &kn.camera_points, &groups, g_c);
        dispatch(&mut enc, &kn.compact_x, &groups, one);
        stamp(&mut enc, 1);
        // Line 4.
        dispatch(&mut enc, &kn.visibility, &groups, g_n);
        stamp(&mut enc, 2);
        // Lines 5 and 6.
        dispatch(&mut enc, &kn.candidate_rays, &groups, g_c);
        stamp(&mut enc, 3);
        b.search.record(&mut enc, nk, &b.hits);
        stamp(&mut enc, 4);
        dispatch(&mut enc, &kn.weights, &groups, g_c);
        dispatch(&mut enc, &kn.scan_weights, &groups, one);
        dispatch(&mut enc, &kn.draw, &groups, g_d);
        dispatch(&mut enc, &kn.take, &groups, one);
        stamp(&mut enc, 5);
        // Line 7.
        dispatch(&mut enc, &kn.candidate_jobs, &groups, g_n);
        dispatch(&mut enc, &kn.radiosity.paths, &[&gs.group, &g_cand], cand_paths);
        dispatch(&mut enc, &kn.radiosity.sum, &[&gs.group, &g_cand], cand_sums);
        stamp(&mut enc, 6);
        // Line 8.
        b.search.record(&mut enc, nk, &b.candidates);
        dispatch(&mut enc, &kn.candidate_intensity, &groups, g_n);
        stamp(&mut enc, 7);
        // Lines 9–17.
        dispatch(&mut enc, &kn.decide, &groups, one);
        stamp(&mut enc, 8);
        // Line 18.
        let (jobs, radiance) = if relit { (&kn.relit_jobs, &kn.relit_radiance) } else { (&kn.added_jobs, &kn.added_radiance) };
        dispatch(&mut enc, jobs, &groups, g_n);
        if relit || set_paths.1 > 1 {
            dispatch(&mut enc, &kn.radiosity.paths, &[&gs.group, &g_set], set_paths);
            dispatch(&mut enc, &kn.radiosity.sum, &[&gs.group, &g_set], set_sums);
        } else {
            // The new VPLs alone (at most M_max in a steady iteration), sized
            // on the device by `decide`.
            let mut pass =
                enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("smc new radiosity"), timestamp_writes: None });
            pass.set_bind_group(0, &gs.group, &[]);
            pass.set_bind_group(1, &g_set, &[]);
            pass.set_pipeline(&kn.radiosity.paths);
            pass.dispatch_workgroups_indirect(&b.state, 16 * 4);
            pass.set_pipeline(&kn.radiosity.sum);
            pass.dispatch_workgroups_indirect(&b.state, 20 * 4);
        }
        dispatch(&mut enc, radiance, &groups, g_n);
        stamp(&mut enc, 9);
        // Line 19 and the output.
        b.search.record(&mut enc, nk, &b.set);
        dispatch(&mut enc, &kn.fluxes, &groups, g_n);
        dispatch(&mut enc, &kn.stats, &groups, one);
        stamp(&mut enc, 10);
        if let Some(p) = profile {
            enc.resolve_query_set(&p.queries, 0..STAMPS, &p.resolved, 0);
            enc.copy_buffer_to_buffer(&p.resolved, 0, &b.out, (3 * s.n + 4) * 16, STAMPS as u64 * 8);
        }
        self.iterations += 1;
        if !read {
            ctx.submit([enc.finish()]);
            return Ok(());
        }
        let extra = if profile.is_some() { STAMP_ROWS as usize } else { 0 };
        let rows: Vec<Vec4> = crate::kernel::finish_read(ctx, enc, &b.out, 3 * s.n as usize + 4 + extra)?;
        if let Some(p) = profile {
            let words: Vec<u32> = rows[3 * s.n as usize + 4..].iter().flat_map(|r| r.to_array().map(f32::to_bits)).collect();
            let t: Vec<u64> = (0..STAMPS as usize).map(|i| words[2 * i] as u64 | (words[2 * i + 1] as u64) << 32).collect();
            let ms = |a: usize, b: usize| t[b].saturating_sub(t[a]) as f64 * p.period * 1e-6;
            self.timings = SmcTimings {
                candidates_ms: ms(0, 1) + ms(2, 3) + ms(7, 8),
                resampling_ms: ms(4, 5),
                visibility_ms: ms(1, 2),
                radiosity_ms: ms(5, 6) + ms(8, 9),
                knn_ms: ms(3, 4) + ms(6, 7) + ms(9, 10),
                total_ms: ms(0, 10),
            };
        }
        self.set.begin_frame();
        for slot in 0..s.n as usize {
            let (a, b2, f) = (rows[3 * slot], rows[3 * slot + 1], rows[3 * slot + 2]);
            let vpl = (f.w != 0.0).then(|| Vpl {
                y: a.truncate(),
                n: b2.truncate(),
                flux: f.truncate(),
                id: a.w.to_bits() as u64 | (b2.w.to_bits() as u64) << 32,
                bounce: 0,
            });
            self.set.set(slot, vpl);
        }
        let st: Vec<u32> = rows[3 * s.n as usize..3 * s.n as usize + 4].iter().flat_map(|r| r.to_array().map(f32::to_bits)).collect();
        if st[15] != 0 {
            return Err(GpuError::CutShort("SMC's neighbour searches"));
        }
        self.stats = SmcStats {
            iterations: self.iterations,
            camera_points: st[0] as usize,
            hits: st[5] as usize,
            candidates: st[1] as usize,
            mailbox_valid: st[6] as usize,
            ray_valid: st[7] as usize,
            invalid: st[8] as usize,
            m_strong: st[9] as usize,
            weakest: st[10] as usize,
            removed: st[11] as usize,
            added: st[12] as usize,
            stored: st[13] as usize,
            relit,
            intensity_cv: f32::from_bits(st[14]),
            ..SmcStats::default()
        };
        Ok(())
    }

    /// One frame: the first runs the warm-up's iterations before its own
    /// (submitted without waiting); each frame reads back once.
    pub fn frame(&mut self, scene: &Scene, camera: &Camera, seed: u64) -> Result<&VplSet, GpuError> {
        let t0 = Instant::now();
        if self.iterations == 0 {
            for _ in 0..=self.config.warmup {
                self.iterate(scene, camera, seed, false)?;
            }
        }
        self.iterate(scene, camera, seed, true)?;
        self.ms = t0.elapsed().as_secs_f64() * 1e3;
        if self.profile.is_none() {
            self.timings = SmcTimings { total_ms: self.ms, ..SmcTimings::default() };
        }
        Ok(&self.set)
    }
}

impl VplSampler for GpuSmcSampler {
    fn name(&self) -> &'static str {
        "smc"
    }

    /// # Panics
    /// When the device fails.
    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        if let Err(e) = self.frame(frame.scene, frame.camera, frame.seed) {
            panic!("GPU SMC: {e}");
        }
        &self.set
    }

    fn stats(&self) -> Stats {
        let stats = self.stats.counts().ms("ms", self.ms);
        if self.profile.is_none() {
            return stats;
        }
        // The stages as the device timed them.
        self.timings.steps(stats).ms("device_ms", self.timings.total_ms)
    }
}

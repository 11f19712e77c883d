//! Tracked pixels' ground truth on the device: twin of
//! [`vpl_pathtrace::track_chunk`], the papers' per-pixel reference
//! (hundreds of thousands of path-traced samples at a few pixels) spread
//! over the device's threads.

use crate::context::GpuError;
use crate::device::Gpu;
use crate::kernel::{bind, dispatch, finish_read, groups_1d, pipeline, storage, storage_init, uniform};
use crate::radiosity::{light_params, radiosity_layout, radiosity_source};
use crate::raycast::camera_rows;
use crate::scene::scene_layout;
use std::sync::OnceLock;
use std::sync::atomic::{AtomicBool, Ordering};
use vpl_core::glam::Vec4;
use vpl_core::rng::stream_key;
use vpl_core::{Camera, Purpose, Scene};
use vpl_pathtrace::{Accumulator, Footprint, PathTracer, TRACK_CHUNK, TrackRequest, TrackedPixel};

/// Most chunks one block adds up on the device (`track_sum` in
/// `radiosity.wgsl`); a pixel of fewer chunks gets blocks of the next power
/// of two of them, so that padding at most doubles a small request's work
/// and adds fewer than 64 chunks to a large one's.
const MAX_BLOCK: u64 = 64;

/// Chunks one submission samples at most, a whole number of blocks: a
/// bounded time on the device (a watchdog stops long submissions on some
/// systems) and at most 2 MiB of block sums back.
const CHUNKS_PER_SUBMISSION: u64 = 1 << 16;

/// [`vpl_pathtrace::track_with`]'s estimator on a [`Gpu`]: the camera ray
/// through the pixel (its centre or a uniform point of it) and the lens,
/// then [`PathTracer::li`] (next-event estimation with MIS, cosine-sampled
/// bounces, Russian roulette, the mode's path lengths, the clamp), over
/// diffuse materials.
///
/// The samples of a pixel are split into chunks of [`TRACK_CHUNK`]; one
/// invocation takes a chunk from its own stream
/// ([`vpl_pathtrace::track_chunk`]: the same draws in the same order). A
/// second kernel adds blocks of up to 64 chunks in chunk order (`f32`, 512
/// samples), and the host adds the blocks in order in `f64`: 32 B cross
/// back per 512 samples. So a result depends on the request alone,
/// not on the device's threads, and differs from `track_chunk`'s only by
/// float rounding and by rays that graze an edge; it is a different sample
/// from [`vpl_pathtrace::track_with`]'s (other streams), the same
/// estimator.
///
/// ```no_run
/// use vpl_core::{Mode, SceneSetup};
/// use vpl_gpu::{Gpu, GpuTracker};
/// use vpl_pathtrace::{Footprint, PathTracer, TrackRequest};
///
/// let setup = SceneSetup::builtin("cornell").unwrap();
/// let tracker = GpuTracker::new(Gpu::new().expect("a GPU adapter (lavapipe will do)"));
/// let pixels = [(128, 128), (40, 200)];
/// let request = TrackRequest { pixels: &pixels, spp: 65_536, seed: 1, frame: 0, footprint: Footprint::Centre };
/// let truth = tracker.track(&setup.scene, &setup.camera, &PathTracer::new(5, Mode::Indirect), &request).unwrap();
/// assert_eq!(truth[0].samples, 65_536);
/// ```
pub struct GpuTracker {
    gpu: Gpu,
    kernel: OnceLock<TrackKernels>,
}

/// The radiosity layout and the two entries of tracking over it.
struct TrackKernels {
    layout: wgpu::BindGroupLayout,
    track: wgpu::ComputePipeline,
    track_sum: wgpu::ComputePipeline,
}

impl TrackKernels {
    fn new(ctx: &crate::GpuContext) -> TrackKernels {
        let layout = radiosity_layout(ctx);
        let source = radiosity_source();
        let layouts = [&scene_layout(ctx), &layout];
        let track = pipeline(ctx, "track", &source, "track", &layouts);
        let track_sum = pipeline(ctx, "track sum", &source, "track_sum", &layouts);
        TrackKernels { layout, track, track_sum }
    }
}

impl GpuTracker {
    /// A tracker on `gpu` (its kernel compiled on first use).
    pub fn new(gpu: Gpu) -> GpuTracker {
        GpuTracker { gpu, kernel: OnceLock::new() }
    }

    /// The device it runs on.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    /// The estimate at each of `request`'s pixels, in order: mean, standard
    /// error and samples. Errs on a scene with layered materials (the
    /// device draws diffuse materials only: give the scene
    /// `with_material_policy(MaterialPolicy::Diffuse)`, as the VPL methods
    /// draw it) and when the device fails or cuts its loops short.
    pub fn track(&self, scene: &Scene, camera: &Camera, pt: &PathTracer, request: &TrackRequest) -> Result<Vec<TrackedPixel>, GpuError> {
        self.track_cancellable(scene, camera, pt, request, &|_, _| {}, &AtomicBool::new(false))
    }

    /// The chunks `request` takes, padding included: what the progress of
    /// [`GpuTracker::track_cancellable`] counts up to.
    pub fn chunks(request: &TrackRequest) -> u64 {
        request.pixels.len() as u64 * layout(request.spp).1
    }

    /// [`GpuTracker::track`] that reports `progress(chunks done, chunks)`
    /// after each submission (up to 65,536 chunks of [`TRACK_CHUNK`]
    /// samples, padding included) and stops before the next once `cancel`
    /// is set (from another thread), answering [`GpuError::Cancelled`]. An
    /// uncancelled run is [`GpuTracker::track`]'s result bit for bit.
    pub fn track_cancellable(
        &self,
        scene: &Scene,
        camera: &Camera,
        pt: &PathTracer,
        request: &TrackRequest,
        progress: &(dyn Fn(u64, u64) + Sync),
        cancel: &AtomicBool,
    ) -> Result<Vec<TrackedPixel>, GpuError> {
        if let Some(m) = scene.materials.iter().find(|m| m.layered.is_some()) {
            return Err(GpuError::Invalid(format!(
                "material '{}' is layered: the device path tracer draws diffuse materials only (draw the scene with MaterialPolicy::Diffuse)",
                m.name
            )));
        }
        let pixels = request.pixels;
        let (w, h) = camera.resolution;
        if let Some(&(x, y)) = pixels.iter().find(|&&(x, y)| x >= w || y >= h) {
            return Err(GpuError::Invalid(format!("tracked pixel ({x}, {y}) lies outside the {w}×{h} image")));
        }
        let spp = request.spp;
        let (min_k, max_k) = pt.mode.k_range(pt.max_depth);
        let (block, chunks) = layout(spp);
        let total = pixels.len() as u64 * chunks;
        if pt.max_depth == 0 || min_k > max_k || spp == 0 || pixels.is_empty() {
            // No path counts (the CPU's `li` is zero): every sample is zero.
            return Ok(pixels.iter().map(|&p| Accumulator::from_sums(spp as u64, [0.0; 3], [0.0; 3]).tracked(p)).collect());
        }
        if total > u32::MAX as u64 {
            return Err(GpuError::Invalid(format!("{} pixels of {spp} samples are more chunks than a device index holds", pixels.len())));
        }
        let ctx = self.gpu.ctx();
        let gs = self.gpu.scene(scene)?;
        let lb = self.gpu.lights(scene);
        let kernels = self.kernel.get_or_init(|| TrackKernels::new(ctx));
        // The camera, the footprint in the raster row's w (1: the box).
        let mut rows = camera_rows(camera).to_vec();
        rows[4].w = match request.footprint {
            Footprint::Box => 1.0,
            Footprint::Centre => 0.0,
        };
        rows.extend(pixels.iter().map(|&(x, y)| Vec4::new(x as f32, y as f32, 0.0, 0.0)));
        let limit = ctx.device.limits().max_storage_buffer_binding_size as u64;
        if rows.len() as u64 * 16 > limit {
            return Err(GpuError::Invalid(format!("{} pixels exceed the adapter's storage-buffer limit of {limit} bytes", pixels.len())));
        }
        let key = stream_key(request.seed, request.frame, Purpose::TRACKED_CHUNK);
        let b_rows = storage_init(ctx, "track jobs", &rows);
        let b_key = storage_init(ctx, "track key", &[key as u32, (key >> 32) as u32]);
        // Each pixel's blocks, added in order as their submissions come back
        // (so memory stays that of one submission, whatever the request).
        let mut accs = vec![Accumulator::default(); pixels.len()];
        let per_pixel = chunks / block;
        let block_samples = block * TRACK_CHUNK as u64;
        let mut first = 0u64;
        while first < total {
            if cancel.load(Ordering::Relaxed) {
                return Err(GpuError::Cancelled);
            }
            let n = (total - first).min(CHUNKS_PER_SUBMISSION);
            let groups = groups_1d(ctx, n, 64);
            let sum_groups = groups_1d(ctx, n / block, 64);
            let params = crate::radiosity::Params {
                jobs: n as u32,
                paths: spp,
                max_k,
                rr_depth: pt.rr_depth,
                row: groups.0 * 64,
                sum_row: sum_groups.0 * 64,
                min_k,
                g_max: pt.clamp.map_or(-1.0, |c| c.g_max),
                first: first as u32,
                chunks: chunks as u32,
                block: block as u32,
                ..light_params(scene)
            };
            let b_params = uniform(ctx, "track params", &params);
            let b_chunks = storage(ctx, "track chunks", n * 32)?;
            let b_blocks = storage(ctx, "track blocks", n / block * 32)?;
            let group = bind(
                ctx,
                "track",
                &kernels.layout,
                &[&b_params, &b_rows, &b_key, &lb.lights, &lb.cdf, &lb.pmf, &lb.tri_light, &b_chunks, &b_blocks],
            );
            let mut enc = ctx.device.create_command_encoder(&Default::default());
            dispatch(&mut enc, &kernels.track, &[&gs.group, &group], groups);
            dispatch(&mut enc, &kernels.track_sum, &[&gs.group, &group], sum_groups);
            let blocks = finish_read::<[Vec4; 2]>(ctx, enc, &b_blocks, (n / block) as usize)?;
            for (k, [s, s2]) in blocks.iter().enumerate() {
                let g = first / block + k as u64;
                let (p, b) = ((g / per_pixel) as usize, g % per_pixel);
                let expected = block_samples.min((spp as u64).saturating_sub(b * block_samples));
                // Fewer samples than asked: the device stopped its loops early.
                if s.w != expected as f32 {
                    return Err(GpuError::CutShort("the tracked pixels' paths"));
                }
                let wide = |v: Vec4| [v.x as f64, v.y as f64, v.z as f64];
                accs[p].merge(&Accumulator::from_sums(expected, wide(*s), wide(*s2)));
            }
            first += n;
            progress(first, total);
        }
        Ok(pixels.iter().zip(&accs).map(|(&pixel, acc)| acc.tracked(pixel)).collect())
    }
}

/// The block size of `spp` samples a pixel (a power of two, at most
/// [`MAX_BLOCK`] chunks), and the pixel's chunks padded to whole blocks.
fn layout(spp: u32) -> (u64, u64) {
    let chunks = spp.div_ceil(TRACK_CHUNK) as u64;
    let block = chunks.next_power_of_two().clamp(1, MAX_BLOCK);
    (block, chunks.next_multiple_of(block))
}

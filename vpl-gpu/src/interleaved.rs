//! Interleaved VPL shading on the device: twin of
//! [`vpl_shading::InterleavedShader`].

use crate::context::GpuError;
use crate::device::Gpu;
use crate::frame::{DeviceFrame, Frames};
use crate::kernel::{Binding, bind, dispatch, finish, groups_1d, layout, pipeline, read_back, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, scene_layout};
use crate::visibility::DeviceVisibility;
use std::time::Instant;
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, VplSet, VplVisibility};
use vpl_shading::{CLASSES, ExhaustiveShader, InterleavedShader, ShadeTimings};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GatherParams {
    width: u32,
    height: u32,
    slots: u32,
    mode: u32,
    res: u32,
    pad: [u32; 3],
    g_max: f32,
    eps2: f32,
    texel: f32,
    eps: f32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ModulateParams {
    count: u32,
    row: u32,
    pad: [u32; 2],
}

/// The albedo kernel every gather ends with: L = E · ρ / π
/// (`modulate.wgsl`), as the CPU shaders multiply after gathering.
pub(crate) struct Modulate {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl Modulate {
    pub(crate) fn new(ctx: &crate::GpuContext) -> Modulate {
        let r = Binding::Read;
        let layout = layout(ctx, "modulate", &[Binding::Uniform, r, r, Binding::ReadWrite]);
        let pipeline = pipeline(ctx, "modulate", include_str!("modulate.wgsl"), "main", &[&layout]);
        Modulate { layout, pipeline }
    }

    /// Encodes the radiance of the `n` pixels of `e` (sums, one vec4 a
    /// pixel) under `albedo` into a new buffer, which it returns.
    pub(crate) fn encode(
        &self,
        ctx: &crate::GpuContext,
        enc: &mut wgpu::CommandEncoder,
        e: &wgpu::Buffer,
        albedo: &wgpu::Buffer,
        n: usize,
    ) -> Result<wgpu::Buffer, GpuError> {
        let groups = groups_1d(ctx, n as u64, 64);
        let mp = uniform(ctx, "modulate params", &ModulateParams { count: n as u32, row: groups.0 * 64, pad: [0; 2] });
        let out = storage(ctx, "radiance", n as u64 * 16)?;
        let group = bind(ctx, "modulate", &self.layout, &[&mp, e, albedo, &out]);
        dispatch(enc, &self.pipeline, &[&group], groups);
        Ok(out)
    }
}

/// The slots of `vpls` as the gather kernels read them, three vec4 a slot:
/// [y, 1 if the slot holds a VPL], [n_y, 0], [flux, 0]; an empty slot is
/// zeros, and a set of no slots is one empty slot (a binding is never empty).
pub(crate) fn vpl_rows(vpls: &VplSet) -> Vec<Vec4> {
    let rows: Vec<Vec4> = vpls
        .slots()
        .iter()
        .flat_map(|v| match v {
            Some(v) => [v.y.extend(1.0), v.n.extend(0.0), v.flux.extend(0.0)],
            None => [Vec4::ZERO; 3],
        })
        .collect();
    if rows.is_empty() { vec![Vec4::ZERO; 3] } else { rows }
}

/// Milliseconds of the steps of the last [`GpuInterleavedShader`] shade,
/// each waited for on the device. The gather and the filter are apart only
/// under [`GpuInterleavedShader::profile`]; else `gather_ms` holds both.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuShadeTimings {
    /// Preparing and queueing the uploads of the VPLs (and the subsets or
    /// G-buffer when they changed); the transfer itself goes with the
    /// gather's submission, not in one of its own.
    pub upload_ms: f64,
    /// The gather kernel, the uploads' transfer included.
    pub gather_ms: f64,
    /// The filter and the albedo kernels.
    pub filter_ms: f64,
    /// Reading the image back.
    pub read_ms: f64,
}

struct Kernels {
    gather_layout: wgpu::BindGroupLayout,
    gather: wgpu::ComputePipeline,
    modulate: Modulate,
}

/// [`InterleavedShader`] on the device: the same 4×4 classes, the same
/// random subsets (drawn by the wrapped CPU shader from the same seed), the
/// same clamped geometry term and visibility test, then the cross-bilateral
/// filter and the albedo, all as WGSL kernels. The sums run over the same
/// slots in the same order; results differ from the CPU's by float rounding
/// and by the rare receiver whose shadow-map test lands on the other side of
/// its threshold.
///
/// Visibility must keep its structures on the same [`Gpu`] (a
/// [`crate::GpuShadowMaps`] or a [`crate::GpuRayTraced`] made on a clone of
/// it, found by its [`VplVisibility::device_key`]); with any other, `shade`
/// runs the wrapped CPU shader instead.
/// [`GpuInterleavedShader::exhaustive`] makes the exhaustive shader's twin.
pub struct GpuInterleavedShader {
    gpu: Gpu,
    /// The CPU twin: its clamp, filter and seed are the GPU shader's
    /// settings, and it shades when the visibility is not on the device.
    pub cpu: InterleavedShader,
    kernels: Option<Kernels>,
    /// (slots, subset slots, subset offsets) as uploaded.
    subsets: Option<(usize, wgpu::Buffer, wgpu::Buffer)>,
    timings: ShadeTimings,
    device_timings: GpuShadeTimings,
    exhaustive: bool,
    /// Leave images on the device ([`IndirectShader::keep_on_device`]).
    keep: bool,
    /// Whether the gather and the filter are submitted and waited for
    /// apart, so that [`GpuShadeTimings`] times each.
    profile: bool,
    /// The last image left on the device, and the G-buffer it was shaded over.
    kept: Option<DeviceFrame>,
    /// The kept image with the frame's emission and direct light added
    /// ([`IndirectShader::finish_on_device`]).
    finished: Option<DeviceFrame>,
    /// Where images left on the device are published, with their G-buffer.
    publish: Option<Frames>,
}

impl GpuInterleavedShader {
    /// A shader on `gpu` with `clamp`, the default filter and `seed`, as
    /// [`InterleavedShader::new`].
    pub fn new(gpu: Gpu, clamp: Option<GeometryClamp>, seed: u64) -> GpuInterleavedShader {
        GpuInterleavedShader {
            gpu,
            cpu: InterleavedShader::new(clamp, seed),
            kernels: None,
            subsets: None,
            timings: ShadeTimings::default(),
            device_timings: GpuShadeTimings::default(),
            exhaustive: false,
            keep: false,
            profile: false,
            kept: None,
            finished: None,
            publish: None,
        }
    }

    /// Publishes each image left on the device (under
    /// [`IndirectShader::keep_on_device`]) to `frames`, with the G-buffer
    /// it was shaded over, for a window on the same device to show; a
    /// frame read back publishes `None`.
    pub fn publish_to(&mut self, frames: Frames) {
        self.publish = Some(frames);
    }

    /// Submits and waits for the gather and the filter apart, so that
    /// [`GpuInterleavedShader::device_timings`] times each (one more
    /// submission a frame); by default they go in one.
    pub fn profile(&mut self, profile: bool) {
        self.profile = profile;
    }

    /// Every VPL at every pixel, unfiltered: twin of
    /// [`vpl_shading::ExhaustiveShader`] (one subset of all slots, weight 1).
    pub fn exhaustive(gpu: Gpu, clamp: Option<GeometryClamp>) -> GpuInterleavedShader {
        let mut s = GpuInterleavedShader::new(gpu, clamp, 0);
        s.cpu.filter = None;
        s.exhaustive = true;
        s
    }

    /// Timings of the last shade: gathering (uploads included), then
    /// filter, albedo and read-back.
    pub fn timings(&self) -> ShadeTimings {
        self.timings
    }

    /// The device steps of the last shade on the device.
    pub fn device_timings(&self) -> GpuShadeTimings {
        self.device_timings
    }

    fn kernels(&mut self) -> &Kernels {
        let ctx = self.gpu.ctx();
        self.kernels.get_or_insert_with(|| {
            let r = Binding::Read;
            let gather_layout = layout(ctx, "gather", &[Binding::Uniform, r, r, r, r, r, r, r, Binding::ReadWrite]);
            let source = format!("{BVH_WGSL}\n{}\n{}", include_str!("interleaved.wgsl"), include_str!("vpl_visible.wgsl"));
            let gather = pipeline(ctx, "gather", &source, "gather", &[&scene_layout(ctx), &gather_layout]);
            Kernels { gather_layout, gather, modulate: Modulate::new(ctx) }
        })
    }

    fn subset_buffers(&mut self, slots: usize) {
        if self.subsets.as_ref().is_some_and(|(n, _, _)| *n == slots) {
            return;
        }
        let all: Vec<Vec<u32>> = vec![(0..slots as u32).collect(); CLASSES];
        let subsets = if self.exhaustive { &all[..] } else { self.cpu.subsets(slots) };
        let mut offsets = vec![0u32];
        let mut flat = Vec::with_capacity(slots);
        for s in subsets {
            flat.extend_from_slice(s);
            offsets.push(flat.len() as u32);
        }
        debug_assert_eq!(offsets.len(), CLASSES + 1);
        let ctx = self.gpu.ctx();
        self.subsets = Some((slots, storage_init(ctx, "subset slots", &flat), storage_init(ctx, "subset offsets", &offsets)));
    }

    /// Whether `vis` is a visibility on this shader's device.
    fn device_visibility(&self, vis: &dyn VplVisibility) -> bool {
        vis.device_key().is_some_and(|k| self.gpu.holds_visibility(k))
    }

    fn shade_on_device(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Option<Result<Image, GpuError>> {
        let on_device = self.gpu.visibility(vis.device_key()?)?;
        Some(self.run(gbuf, vpls, &on_device))
    }

    fn run(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &DeviceVisibility) -> Result<Image, GpuError> {
        let DeviceVisibility { mode, ref scene, eps, res, bias, .. } = *vis;
        let t0 = Instant::now();
        self.subset_buffers(vpls.len());
        self.kernels();
        let gpu = self.gpu.clone();
        let ctx = gpu.ctx();
        let k = self.kernels.as_ref().expect("compiled");
        let (_, b_slots, b_offsets) = self.subsets.as_ref().expect("uploaded");
        let g = gpu.device_gbuffer(gbuf)?;
        let n = gbuf.width as usize * gbuf.height as usize;
        let b_vpls = storage_init(ctx, "vpls", &vpl_rows(vpls));
        let (atlas, headers) = vis.map_buffers(ctx)?;
        let params = GatherParams {
            width: gbuf.width,
            height: gbuf.height,
            slots: vpls.len() as u32,
            mode,
            res,
            pad: [0; 3],
            g_max: self.cpu.clamp.map_or(f32::MAX, |c| c.g_max),
            eps2: 2.0 * eps,
            texel: bias * 2.0 / res as f32,
            eps,
        };
        let b_params = uniform(ctx, "gather params", &params);
        let b_e = storage(ctx, "E", n as u64 * 16)?;
        let group =
            bind(ctx, "gather", &k.gather_layout, &[&b_params, &g.pos, &g.normal, &b_vpls, b_slots, b_offsets, &headers, &atlas, &b_e]);
        let t_up = Instant::now();
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(
            &mut enc,
            &k.gather,
            &[&scene.group, &group],
            (gbuf.width.div_ceil(4).div_ceil(8), gbuf.height.div_ceil(4).div_ceil(8), CLASSES as u32),
        );
        if self.profile {
            finish(ctx, std::mem::replace(&mut enc, ctx.device.create_command_encoder(&Default::default())))?;
        }
        let t1 = Instant::now();
        let filtered;
        let e = match &self.cpu.filter {
            Some(f) => {
                filtered = storage(ctx, "filtered E", n as u64 * 16)?;
                gpu.filter_kernel().encode(ctx, &mut enc, f, &g, &b_e, &filtered);
                &filtered
            }
            None => &b_e,
        };
        let b_out = k.modulate.encode(ctx, &mut enc, e, &g.albedo, n)?;
        finish(ctx, enc)?;
        let t2 = Instant::now();
        let out: Vec<Vec4> = if self.keep { Vec::new() } else { read_back(ctx, &b_out, n)? };
        let t3 = Instant::now();
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        self.timings = ShadeTimings { gather_ms: ms(t0, t1), filter_ms: ms(t1, t3) };
        self.device_timings =
            GpuShadeTimings { upload_ms: ms(t0, t_up), gather_ms: ms(t_up, t1), filter_ms: ms(t1, t2), read_ms: ms(t2, t3) };
        if self.keep {
            let frame = DeviceFrame::new(gbuf.width, gbuf.height, b_out, g.clone());
            if let Some(f) = &self.publish {
                f.publish(Some(frame.clone()));
            }
            self.kept = Some(frame);
            return Ok(Image::on_device(gbuf.width, gbuf.height));
        }
        self.kept = None;
        if let Some(f) = &self.publish {
            f.publish(None);
        }
        Ok(image_of(gbuf.width, gbuf.height, out))
    }
}

/// The image of `width` × `height` pixels read back as one vec4 a pixel.
pub(crate) fn image_of(width: u32, height: u32, rgba: Vec<Vec4>) -> Image {
    Image { width, height, data: rgba.into_iter().map(|v| Vec3::new(v.x, v.y, v.z)).collect() }
}

impl IndirectShader for GpuInterleavedShader {
    fn set_clamp(&mut self, clamp: Option<GeometryClamp>) {
        // The kernels read G_max from the CPU twin's clamp at each frame.
        self.cpu.clamp = clamp;
    }

    fn name(&self) -> &'static str {
        if self.exhaustive { "exhaustive" } else { "interleaved" }
    }

    fn on_device(&self, vis: &dyn VplVisibility) -> bool {
        self.device_visibility(vis)
    }

    fn keep_on_device(&mut self, keep: bool) {
        self.keep = keep;
    }

    /// # Panics
    /// When the device fails.
    fn read_image(&self) -> Option<Image> {
        let frame = self.finished.as_ref().or(self.kept.as_ref())?;
        Some(frame.read_image(self.gpu.ctx()).unwrap_or_else(|e| panic!("GPU image read-back: {e}")))
    }

    /// # Panics
    /// When the device fails.
    fn read_indirect(&self) -> Option<Image> {
        let frame = self.kept.as_ref()?;
        Some(frame.read_image(self.gpu.ctx()).unwrap_or_else(|e| panic!("GPU image read-back: {e}")))
    }

    /// The emission and the direct light are added by
    /// [`Gpu::finish_frame`] on the same device.
    fn finishes_on_device(&self) -> bool {
        true
    }

    /// # Panics
    /// When the device fails.
    fn finish_on_device(&mut self, scene: &vpl_core::Scene, emission: bool, direct: Option<(u32, u64)>) -> bool {
        let Some(frame) = &self.kept else { return false };
        let finished = self.gpu.finish_frame(scene, frame, emission, direct).unwrap_or_else(|e| panic!("GPU direct light: {e}"));
        if let Some(f) = &self.publish {
            f.publish(Some(finished.clone()));
        }
        self.finished = Some(finished);
        true
    }

    /// # Panics
    /// When the device fails.
    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        self.kept = None;
        self.finished = None;
        if let Some(f) = &self.publish {
            f.publish(None);
        }
        let host;
        let gbuf = match self.shade_on_device(gbuf, vpls, vis) {
            Some(Ok(img)) => return img,
            Some(Err(e)) => panic!("GPU interleaved shading: {e}"),
            // The CPU twin needs the samples on the host.
            None if !gbuf.on_host() => {
                host = self.gpu.read_gbuffer(gbuf.clone()).unwrap_or_else(|e| panic!("GPU G-buffer read-back: {e}"));
                &host
            }
            None => gbuf,
        };
        if self.exhaustive {
            return ExhaustiveShader { clamp: self.cpu.clamp }.shade(gbuf, vpls, vis);
        }
        let img = self.cpu.shade(gbuf, vpls, vis);
        self.timings = self.cpu.timings();
        img
    }
}

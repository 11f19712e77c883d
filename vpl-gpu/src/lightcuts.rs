//! Stochastic lightcuts on the device: twin of
//! [`vpl_shading::LightcutShader`].

use crate::context::GpuError;
use crate::device::Gpu;
use crate::interleaved::{Modulate, image_of, vpl_rows};
use crate::kernel::{Binding, SAMPLING_WGSL, bind, dispatch, finish, layout, pipeline, read_back, storage, storage_init, uniform};
use crate::scene::{BVH_WGSL, scene_layout};
use crate::visibility::DeviceVisibility;
use std::time::Instant;
use vpl_core::glam::Vec4;
use vpl_core::rng::{Purpose, stream_key};
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, VplSet, VplVisibility};
use vpl_lighttree::{Bounds, Child};
use vpl_shading::{LightcutShader, ShadeTimings};

/// The largest cut the kernel holds (its per-invocation arrays); a larger
/// one shades on the host.
pub const MAX_CUT: usize = 256;

/// High bit of a packed child: a slot (as the kernel reads it).
const SLOT: u32 = 1 << 31;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    slots: u32,
    mode: u32,
    res: u32,
    cut: u32,
    nodes: u32,
    root: u32,
    g_max: f32,
    eps2: f32,
    texel: f32,
    eps: f32,
    key: [u32; 2],
    pad: [u32; 2],
}

struct Kernels {
    gather_layout: wgpu::BindGroupLayout,
    gather: wgpu::ComputePipeline,
    modulate: Modulate,
}

/// [`LightcutShader`] on the device: the light tree is built on the host
/// (as the CPU shader builds it) and uploaded with the VPLs; a kernel
/// chooses each pixel's cut, walks down to one VPL a cut node with the CPU
/// shader's random streams, tests its visibility by the visibility's shadow
/// maps or shadow rays on the device, and sums; then the albedo. The cut,
/// the walk and the streams are the CPU shader's, so the images agree but
/// for float rounding (which may, rarely, tip an importance comparison and
/// so a choice) and the rare receiver whose shadow-map test lands on the
/// other side of its threshold.
///
/// Visibility must keep its structures on the same [`Gpu`] (as for
/// [`crate::GpuInterleavedShader`]); with any other, or a cut above
/// [`MAX_CUT`], `shade` runs the wrapped CPU shader instead, which draws
/// the same streams.
pub struct GpuLightcutShader {
    gpu: Gpu,
    /// The CPU twin: its cut, clamp, seed and frame count are the GPU
    /// shader's, and it shades when the work cannot run on the device.
    pub cpu: LightcutShader,
    kernels: Option<Kernels>,
    timings: ShadeTimings,
}

impl GpuLightcutShader {
    /// A shader on `gpu` sampling `cut` VPLs a pixel, as [`LightcutShader::new`].
    pub fn new(gpu: Gpu, cut: usize, clamp: Option<GeometryClamp>, seed: u64) -> GpuLightcutShader {
        GpuLightcutShader { gpu, cpu: LightcutShader::new(cut, clamp, seed), kernels: None, timings: ShadeTimings::default() }
    }

    /// Timings of the last shade: the tree, the uploads and the kernel, then
    /// the albedo and the read-back.
    pub fn timings(&self) -> ShadeTimings {
        self.timings
    }

    fn kernels(&mut self) -> &Kernels {
        let ctx = self.gpu.ctx();
        self.kernels.get_or_insert_with(|| {
            let r = Binding::Read;
            let gather_layout = layout(ctx, "lightcuts", &[Binding::Uniform, r, r, r, r, r, r, r, Binding::ReadWrite]);
            let source = format!("{BVH_WGSL}\n{SAMPLING_WGSL}\n{}\n{}", include_str!("lightcuts.wgsl"), include_str!("vpl_visible.wgsl"));
            let gather = pipeline(ctx, "lightcuts", &source, "gather", &[&scene_layout(ctx), &gather_layout]);
            Kernels { gather_layout, gather, modulate: Modulate::new(ctx) }
        })
    }

    fn run(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &DeviceVisibility, frame: u64) -> Result<Image, GpuError> {
        let DeviceVisibility { mode, ref scene, eps, res, bias, .. } = *vis;
        let t0 = Instant::now();
        self.kernels();
        let gpu = self.gpu.clone();
        let ctx = gpu.ctx();
        let k = self.kernels.as_ref().expect("compiled");
        let g = gpu.device_gbuffer(gbuf)?;
        let n = gbuf.width as usize * gbuf.height as usize;
        // The tree and its bounds: the inner nodes', then every slot's.
        let tree = LightcutShader::tree(vpls);
        let (mut bounds, mut children, mut root, mut nodes) = (Vec::new(), vec![0u32; 2], u32::MAX, 0u32);
        let row = |b: &Bounds| [b.lo.extend(b.power), b.hi.extend(b.cone.cos_theta), b.cone.axis.extend(0.0)];
        if let Some((tree, slots)) = &tree {
            let pack = |c: Child| match c {
                Child::Node(i) => i,
                Child::Slot(s) => s | SLOT,
            };
            nodes = tree.nodes().len() as u32;
            bounds = tree.nodes().iter().flat_map(|node| row(&node.bounds)).collect::<Vec<Vec4>>();
            bounds.extend(slots.iter().flat_map(|s| row(&Bounds::of(s.as_ref()))));
            children = tree.nodes().iter().flat_map(|node| node.children().map(pack)).collect();
            root = tree.root().map_or(u32::MAX, pack);
        }
        if bounds.is_empty() {
            bounds.push(Vec4::ZERO);
        }
        if children.is_empty() {
            children = vec![0; 2];
        }
        let b_vpls = storage_init(ctx, "vpls", &vpl_rows(vpls));
        let b_bounds = storage_init(ctx, "light tree bounds", &bounds);
        let b_children = storage_init(ctx, "light tree children", &children);
        let (atlas, headers) = vis.map_buffers(ctx)?;
        let key = stream_key(self.cpu.seed, frame, Purpose::LIGHTCUT);
        let params = Params {
            width: gbuf.width,
            height: gbuf.height,
            slots: vpls.len() as u32,
            mode,
            res,
            cut: self.cpu.cut.clamp(1, MAX_CUT) as u32,
            nodes,
            root,
            g_max: self.cpu.clamp.map_or(f32::MAX, |c| c.g_max),
            eps2: 2.0 * eps,
            texel: bias * 2.0 / res.max(1) as f32,
            eps,
            key: [key as u32, (key >> 32) as u32],
            pad: [0; 2],
        };
        let b_params = uniform(ctx, "lightcut params", &params);
        let b_e = storage(ctx, "E", n as u64 * 16)?;
        let group = bind(
            ctx,
            "lightcuts",
            &k.gather_layout,
            &[&b_params, &g.pos, &g.normal, &b_vpls, &b_bounds, &b_children, &headers, &atlas, &b_e],
        );
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &k.gather, &[&scene.group, &group], (gbuf.width.div_ceil(8), gbuf.height.div_ceil(8), 1));
        let b_out = k.modulate.encode(ctx, &mut enc, &b_e, &g.albedo, n)?;
        finish(ctx, enc)?;
        let out: Vec<Vec4> = read_back(ctx, &b_out, n)?;
        let t2 = Instant::now();
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        self.timings = ShadeTimings { gather_ms: ms(t0, t2), filter_ms: 0.0 };
        Ok(image_of(gbuf.width, gbuf.height, out))
    }
}

impl IndirectShader for GpuLightcutShader {
    fn set_clamp(&mut self, clamp: Option<GeometryClamp>) {
        self.cpu.clamp = clamp;
    }

    fn name(&self) -> &'static str {
        "lightcuts"
    }

    /// # Panics
    /// When the device fails.
    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image {
        let on_device = vis.device_key().and_then(|k| self.gpu.visibility(k));
        match on_device {
            Some(dv) if self.cpu.cut <= MAX_CUT => {
                let frame = self.cpu.take_frame();
                self.run(gbuf, vpls, &dv, frame).unwrap_or_else(|e| panic!("GPU lightcuts: {e}"))
            }
            _ => {
                // The CPU twin needs the samples on the host.
                let host;
                let gbuf = if gbuf.on_host() {
                    gbuf
                } else {
                    host = self.gpu.read_gbuffer(gbuf.clone()).unwrap_or_else(|e| panic!("GPU G-buffer read-back: {e}"));
                    &host
                };
                let t = Instant::now();
                let img = self.cpu.shade(gbuf, vpls, vis);
                self.timings = ShadeTimings { gather_ms: t.elapsed().as_secs_f64() * 1e3, filter_ms: 0.0 };
                img
            }
        }
    }
}

//! The end of a frame on the device: the G-buffer's emission and the direct
//! light added to the image the gather left there, twin of what the host
//! adds ([`vpl_shading::direct_light`] and the emission of
//! `vpl_render::render_frame`), with the same light samples from the same
//! streams.

use crate::context::{GpuContext, GpuError};
use crate::device::Gpu;
use crate::frame::DeviceFrame;
use crate::kernel::{Binding, bind, dispatch, finish, layout, pipeline, storage, uniform};
use crate::radiosity::{light_params, radiosity_source};
use crate::scene::scene_layout;
use vpl_core::rng::stream_key;
use vpl_core::{Purpose, Scene};

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct DirectParams {
    width: u32,
    height: u32,
    samples: u32,
    flags: u32,
    key: [u32; 2],
    pad: [u32; 2],
}

pub(crate) struct DirectKernel {
    lights_layout: wgpu::BindGroupLayout,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl DirectKernel {
    pub(crate) fn new(ctx: &GpuContext) -> DirectKernel {
        // Of radiosity.wgsl's group 1, what the light functions read: the
        // parameters (0), the lights and their distribution (3, 4, 5).
        let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
            count: None,
        };
        let read = wgpu::BufferBindingType::Storage { read_only: true };
        let lights_layout = ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("direct lights"),
            entries: &[entry(0, wgpu::BufferBindingType::Uniform), entry(3, read), entry(4, read), entry(5, read)],
        });
        let r = Binding::Read;
        let layout = layout(ctx, "direct", &[Binding::Uniform, r, r, r, r, r, Binding::ReadWrite]);
        let pipeline = pipeline(ctx, "direct", &radiosity_source(), "direct", &[&scene_layout(ctx), &lights_layout, &layout]);
        DirectKernel { lights_layout, layout, pipeline }
    }
}

impl Gpu {
    /// `frame` (its indirect light) with its G-buffer's emission added when
    /// `emission` (emitters and, at misses, the environment seen directly)
    /// and, when `direct` is `Some((samples, seed))`, the direct light:
    /// `samples` light samples a reflecting pixel, stratified in the light
    /// choice, from stream `(seed, 0, Purpose::DIRECT, pixel)` as the host's
    /// direct light draws them, each tested by a shadow ray. A new frame on
    /// the device (`frame` is left as it was); one submission, nothing
    /// crosses but the parameters (and the lights when they changed).
    pub fn finish_frame(
        &self,
        scene: &Scene,
        frame: &DeviceFrame,
        emission: bool,
        direct: Option<(u32, u64)>,
    ) -> Result<DeviceFrame, GpuError> {
        let ctx = self.ctx();
        let gs = self.scene(scene)?;
        let lights = self.lights(scene);
        let k = self.direct_kernel();
        let (samples, seed) = direct.unwrap_or((0, 0));
        let key = stream_key(seed, 0, Purpose::DIRECT);
        let params = DirectParams {
            width: frame.width,
            height: frame.height,
            samples,
            flags: emission as u32 | (direct.is_some() as u32) << 1,
            key: [key as u32, (key >> 32) as u32],
            pad: [0; 2],
        };
        let b_lp = uniform(ctx, "direct light params", &light_params(scene));
        let lights_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("direct lights"),
            layout: &k.lights_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: b_lp.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: lights.lights.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: lights.cdf.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: lights.pmf.as_entire_binding() },
            ],
        });
        let b_params = uniform(ctx, "direct params", &params);
        let g = frame.gbuffer();
        let bytes = frame.pixels() as u64 * 16;
        let image = storage(ctx, "finished image", bytes)?;
        let group = bind(ctx, "direct", &k.layout, &[&b_params, g.pos(), g.normal(), &g.ng, g.albedo(), &g.emitted, &image]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(frame.image(), 0, &image, 0, bytes);
        dispatch(&mut enc, &k.pipeline, &[&gs.group, &lights_group, &group], (g.width.div_ceil(8), g.height.div_ceil(8), 1));
        finish(ctx, enc)?;
        Ok(frame.with_image(image))
    }
}

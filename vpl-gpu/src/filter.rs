//! The cross-bilateral filter on the GPU: twin of [`vpl_shading::CrossBilateral`].

use crate::context::{GpuContext, GpuError};
use crate::gbuffer::DeviceGBuffer;
use crate::kernel::{Binding, bind, dispatch, finish_read, layout, pipeline, storage, storage_init, uniform};
use vpl_core::glam::{Vec3, Vec4};
use vpl_core::{GBuffer, Image};
use vpl_shading::CrossBilateral;

/// [`CrossBilateral`] as a WGSL compute kernel (`filter.wgsl`): the same
/// window and weights, with each pixel's σ_p computed on the device from
/// the G-buffer as [`CrossBilateral::guide`] does on the host.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GpuCrossBilateral {
    /// The filter's settings, shared with the CPU twin.
    pub filter: CrossBilateral,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Params {
    width: u32,
    height: u32,
    radius: i32,
    normal_power: u32,
    eye: [f32; 4],
    sigma: f32,
    pad: [f32; 3],
}

/// The compiled filter kernel.
pub(crate) struct FilterKernel {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl FilterKernel {
    pub fn new(ctx: &GpuContext) -> FilterKernel {
        let layout = layout(ctx, "filter", &[Binding::Uniform, Binding::Read, Binding::Read, Binding::Read, Binding::ReadWrite]);
        let pipeline = pipeline(ctx, "filter", include_str!("filter.wgsl"), "main", &[&layout]);
        FilterKernel { layout, pipeline }
    }

    /// Records the filter of `input` (one vec4 a pixel of `g`) into `output`.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        f: &CrossBilateral,
        g: &DeviceGBuffer,
        input: &wgpu::Buffer,
        output: &wgpu::Buffer,
    ) {
        let params = Params {
            width: g.width,
            height: g.height,
            radius: 2 * f.periods as i32,
            normal_power: f.normal_power,
            eye: g.eye.extend(g.pixel_angle).into(),
            sigma: f.sigma,
            pad: [0.0; 3],
        };
        let b_params = uniform(ctx, "filter params", &params);
        let group = bind(ctx, "filter", &self.layout, &[&b_params, &g.pos, &g.normal, input, output]);
        dispatch(enc, &self.pipeline, &[&group], (g.width.div_ceil(8), g.height.div_ceil(8), 1));
    }
}

impl GpuCrossBilateral {
    /// Filters `e` (one value per G-buffer pixel) on `ctx`'s device: uploads
    /// both, runs the kernel, reads the result back.
    pub fn apply(&self, ctx: &GpuContext, gbuf: &GBuffer, e: &Image) -> Result<Image, GpuError> {
        if e.width != gbuf.width || e.height != gbuf.height {
            return Err(GpuError::Invalid(format!("image {}x{} and G-buffer {}x{} differ", e.width, e.height, gbuf.width, gbuf.height)));
        }
        let n = e.data.len();
        if n == 0 {
            return Ok(e.clone());
        }
        let g = DeviceGBuffer::upload(ctx, gbuf);
        let input: Vec<Vec4> = e.data.iter().map(|c| c.extend(0.0)).collect();
        let b_in = storage_init(ctx, "filter input", &input);
        let b_out = storage(ctx, "filter output", n as u64 * 16)?;
        let kernel = FilterKernel::new(ctx);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        kernel.encode(ctx, &mut enc, &self.filter, &g, &b_in, &b_out);
        let out: Vec<Vec4> = finish_read(ctx, enc, &b_out, n)?;
        Ok(Image { width: e.width, height: e.height, data: out.into_iter().map(|v| Vec3::new(v.x, v.y, v.z)).collect() })
    }
}

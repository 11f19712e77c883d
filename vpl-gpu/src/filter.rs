//! The cross-bilateral filter on the GPU: twin of [`vpl_shading::CrossBilateral`].

use crate::context::{GpuContext, GpuError};
use vpl_core::glam::Vec3;
use vpl_core::{GBuffer, Image};
use vpl_shading::CrossBilateral;
use wgpu::util::DeviceExt;

/// [`CrossBilateral`] as a WGSL compute kernel (`filter.wgsl`): the same
/// window, weights and guide (computed on the CPU by [`CrossBilateral::guide`]).
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
}

fn vec4s(v: impl Iterator<Item = [f32; 4]>) -> Vec<[f32; 4]> {
    v.collect()
}

impl GpuCrossBilateral {
    /// Filters `e` (one value per G-buffer pixel) on `ctx`'s device.
    pub fn apply(&self, ctx: &GpuContext, gbuf: &GBuffer, e: &Image) -> Result<Image, GpuError> {
        if e.width != gbuf.width || e.height != gbuf.height {
            return Err(GpuError::Invalid(format!("image {}x{} and G-buffer {}x{} differ", e.width, e.height, gbuf.width, gbuf.height)));
        }
        let n = e.data.len();
        if n == 0 {
            return Ok(e.clone());
        }
        let guide = self.filter.guide(gbuf);
        let gp = vec4s(guide.iter().map(|(p, _, s)| [p.x, p.y, p.z, *s]));
        let gn = vec4s(guide.iter().map(|(_, n, _)| [n.x, n.y, n.z, 0.0]));
        let input = vec4s(e.data.iter().map(|c| [c.x, c.y, c.z, 0.0]));
        let params = Params { width: gbuf.width, height: gbuf.height, radius: 2 * self.filter.periods as i32, normal_power: self.filter.normal_power };
        let d = &ctx.device;
        let storage = |label: &str, data: &[[f32; 4]]| d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some(label), contents: bytemuck::cast_slice(data), usage: wgpu::BufferUsages::STORAGE });
        let b_params = d.create_buffer_init(&wgpu::util::BufferInitDescriptor { label: Some("params"), contents: bytemuck::bytes_of(&params), usage: wgpu::BufferUsages::UNIFORM });
        let (b_p, b_n, b_in) = (storage("guide_p", &gp), storage("guide_n", &gn), storage("input", &input));
        let size = (n * 16) as u64;
        let b_out = d.create_buffer(&wgpu::BufferDescriptor { label: Some("output"), size, usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC, mapped_at_creation: false });
        let b_read = d.create_buffer(&wgpu::BufferDescriptor { label: Some("read"), size, usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST, mapped_at_creation: false });
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some("filter"), source: wgpu::ShaderSource::Wgsl(include_str!("filter.wgsl").into()) });
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("filter"),
            layout: None,
            module: &module,
            entry_point: Some("main"),
            compilation_options: Default::default(),
            cache: None,
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("filter"),
            layout: &pipeline.get_bind_group_layout(0),
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: b_params.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: b_p.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: b_n.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 3, resource: b_in.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: b_out.as_entire_binding() },
            ],
        });
        let mut enc = d.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("filter") });
        {
            let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("filter"), timestamp_writes: None });
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, &bind, &[]);
            pass.dispatch_workgroups(gbuf.width.div_ceil(8), gbuf.height.div_ceil(8), 1);
        }
        enc.copy_buffer_to_buffer(&b_out, 0, &b_read, 0, size);
        ctx.queue.submit([enc.finish()]);
        let slice = b_read.slice(..);
        let (tx, rx) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        d.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::ReadBack(e.to_string()))?;
        rx.recv().map_err(|e| GpuError::ReadBack(e.to_string()))?.map_err(|e| GpuError::ReadBack(e.to_string()))?;
        let data: Vec<Vec3> = {
            let view = slice.get_mapped_range();
            bytemuck::cast_slice::<u8, [f32; 4]>(&view).iter().map(|v| Vec3::new(v[0], v[1], v[2])).collect()
        };
        b_read.unmap();
        Ok(Image { width: e.width, height: e.height, data })
    }
}

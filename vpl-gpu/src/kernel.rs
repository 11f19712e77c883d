//! What every kernel needs: explicit bind-group layouts, pipelines, buffers
//! and read-back, with the traffic counted on the [`GpuContext`]. Public so
//! that a program's own kernels (a viewer's compositing, say) run on the
//! toolkit's device the same way.

use crate::context::{GpuContext, GpuError};
use wgpu::util::DeviceExt;

/// WGSL of the PCG32 streams and samplings kernels draw with, prepended to
/// the kernels that draw.
pub(crate) const SAMPLING_WGSL: &str = include_str!("sampling.wgsl");

/// How a kernel binds one buffer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Binding {
    /// `var<uniform>`.
    Uniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
}

/// A bind-group layout whose binding `i` is `kinds[i]`, visible to compute.
pub fn layout(ctx: &GpuContext, label: &str, kinds: &[Binding]) -> wgpu::BindGroupLayout {
    let entries: Vec<wgpu::BindGroupLayoutEntry> = kinds
        .iter()
        .enumerate()
        .map(|(i, k)| wgpu::BindGroupLayoutEntry {
            binding: i as u32,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: match k {
                    Binding::Uniform => wgpu::BufferBindingType::Uniform,
                    Binding::Read => wgpu::BufferBindingType::Storage { read_only: true },
                    Binding::ReadWrite => wgpu::BufferBindingType::Storage { read_only: false },
                },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        })
        .collect();
    ctx.device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}

/// A bind group over `layout` binding `buffers[i]` at binding `i`.
pub fn bind(ctx: &GpuContext, label: &str, layout: &wgpu::BindGroupLayout, buffers: &[&wgpu::Buffer]) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> =
        buffers.iter().enumerate().map(|(i, b)| wgpu::BindGroupEntry { binding: i as u32, resource: b.as_entire_binding() }).collect();
    ctx.device.create_bind_group(&wgpu::BindGroupDescriptor { label: Some(label), layout, entries: &entries })
}

/// A compute pipeline: WGSL `source`, entry point `entry`, bind groups
/// `layouts` (group i is `layouts[i]`).
pub fn pipeline(ctx: &GpuContext, label: &str, source: &str, entry: &str, layouts: &[&wgpu::BindGroupLayout]) -> wgpu::ComputePipeline {
    let d = &ctx.device;
    let module =
        d.create_shader_module(wgpu::ShaderModuleDescriptor { label: Some(label), source: wgpu::ShaderSource::Wgsl(source.into()) });
    let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: layouts,
        push_constant_ranges: &[],
    });
    d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&pl),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// A storage buffer holding `data` (at least 16 bytes, so empty inputs bind).
pub fn storage_init<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, data: &[T]) -> wgpu::Buffer {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    let padded;
    let contents = if bytes.len() < 16 {
        padded = [bytes, &[0u8; 16][..16 - bytes.len()]].concat();
        &padded[..]
    } else {
        bytes
    };
    ctx.note_upload(contents.len() as u64);
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

/// A uniform buffer holding `value`.
pub fn uniform<T: bytemuck::Pod>(ctx: &GpuContext, label: &str, value: &T) -> wgpu::Buffer {
    ctx.note_upload(std::mem::size_of::<T>() as u64);
    ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::bytes_of(value),
        usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
    })
}

/// A zeroed storage buffer of `size` bytes (at least 16) that kernels write
/// and that can be copied out.
pub fn storage(ctx: &GpuContext, label: &str, size: u64) -> Result<wgpu::Buffer, GpuError> {
    let size = size.max(16).next_multiple_of(4);
    let limit = ctx.device.limits().max_storage_buffer_binding_size as u64;
    if size > limit {
        return Err(GpuError::Invalid(format!("{label}: {size} bytes exceed the adapter's storage-buffer limit of {limit}")));
    }
    Ok(ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// Records one dispatch of `pipeline` with bind groups `groups`.
pub fn dispatch(enc: &mut wgpu::CommandEncoder, pipeline: &wgpu::ComputePipeline, groups: &[&wgpu::BindGroup], size: (u32, u32, u32)) {
    if size.0 == 0 || size.1 == 0 || size.2 == 0 {
        return;
    }
    let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor { label: None, timestamp_writes: None });
    pass.set_pipeline(pipeline);
    for (i, g) in groups.iter().enumerate() {
        pass.set_bind_group(i as u32, *g, &[]);
    }
    pass.dispatch_workgroups(size.0, size.1, size.2);
}

/// Workgroups of `size` invocations that cover `n` items, laid out in 2D
/// when one dimension would exceed the adapter's limit. Kernels rebuild the
/// item index as `id.x + id.y * groups.0 * size`.
pub fn groups_1d(ctx: &GpuContext, n: u64, size: u32) -> (u32, u32, u32) {
    let groups = n.div_ceil(size as u64);
    let max = ctx.device.limits().max_compute_workgroups_per_dimension as u64;
    if groups <= max { (groups as u32, 1, 1) } else { (max as u32, groups.div_ceil(max) as u32, 1) }
}

/// Submits `enc` and waits for the device.
pub fn finish(ctx: &GpuContext, enc: wgpu::CommandEncoder) -> Result<(), GpuError> {
    ctx.submit([enc.finish()]);
    ctx.device.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::ReadBack(e.to_string()))?;
    Ok(())
}

/// Copies the first `count` elements of `buffer` back to the host.
pub fn read_back<T: bytemuck::Pod>(ctx: &GpuContext, buffer: &wgpu::Buffer, count: usize) -> Result<Vec<T>, GpuError> {
    finish_read(ctx, ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("read-back") }), buffer, count)
}

/// Ends `enc` with a copy of the first `count` elements of `buffer` to the
/// host, submits it and waits: the kernels `enc` recorded and their
/// read-back cross in one submission and one wait.
pub fn finish_read<T: bytemuck::Pod>(
    ctx: &GpuContext,
    mut enc: wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
    count: usize,
) -> Result<Vec<T>, GpuError> {
    let size = (count * std::mem::size_of::<T>()) as u64;
    if size == 0 {
        finish(ctx, enc)?;
        return Ok(Vec::new());
    }
    let d = &ctx.device;
    let staging = d.create_buffer(&wgpu::BufferDescriptor {
        label: Some("read-back"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
    ctx.submit([enc.finish()]);
    ctx.note_read(size);
    let slice = staging.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    d.poll(wgpu::PollType::wait_indefinitely()).map_err(|e| GpuError::ReadBack(e.to_string()))?;
    rx.recv().map_err(|e| GpuError::ReadBack(e.to_string()))?.map_err(|e| GpuError::ReadBack(e.to_string()))?;
    let out = bytemuck::cast_slice::<u8, T>(&slice.get_mapped_range()).to_vec();
    staging.unmap();
    Ok(out)
}

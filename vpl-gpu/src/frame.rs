//! A frame left on the device: its image and G-buffer, for whoever shows it
//! without reading it back (a window on the same device), and the
//! statistics a viewer wants of it, reduced on the device.

use crate::context::{GpuContext, GpuError};
use crate::device::Gpu;
use crate::gbuffer::DeviceGBuffer;
use crate::kernel::{Binding, bind, dispatch, finish_read, layout, pipeline, uniform};
use std::sync::{Arc, Mutex};
use vpl_core::glam::Vec4;
use vpl_core::{GBuffer, Image};

/// The image a GPU shader left on the device and the G-buffer it was shaded
/// over. Both are the frame's own buffers (a later frame writes new ones),
/// so a handle stays valid, and unchanged, for as long as it is held.
#[derive(Clone)]
pub struct DeviceFrame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    image: wgpu::Buffer,
    gbuffer: Arc<DeviceGBuffer>,
}

impl std::fmt::Debug for DeviceFrame {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DeviceFrame").field("width", &self.width).field("height", &self.height).finish()
    }
}

impl DeviceFrame {
    pub(crate) fn new(width: u32, height: u32, image: wgpu::Buffer, gbuffer: Arc<DeviceGBuffer>) -> DeviceFrame {
        DeviceFrame { width, height, image, gbuffer }
    }

    /// The same frame with another image.
    pub(crate) fn with_image(&self, image: wgpu::Buffer) -> DeviceFrame {
        DeviceFrame { image, ..self.clone() }
    }

    /// The radiance, one `vec4<f32>` a pixel (w unused), row-major.
    pub fn image(&self) -> &wgpu::Buffer {
        &self.image
    }

    /// The G-buffer the image was shaded over.
    pub fn gbuffer(&self) -> &DeviceGBuffer {
        &self.gbuffer
    }

    /// Pixels in the frame.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The image read back to the host (one read of 16 B a pixel).
    pub fn read_image(&self, ctx: &GpuContext) -> Result<Image, GpuError> {
        let rgba: Vec<Vec4> = crate::kernel::read_back(ctx, &self.image, self.pixels())?;
        Ok(Image { width: self.width, height: self.height, data: rgba.into_iter().map(|v| v.truncate()).collect() })
    }

    /// The G-buffer read back to the host ([`DeviceGBuffer::read`]).
    pub fn read_gbuffer(&self, ctx: &GpuContext) -> Result<GBuffer, GpuError> {
        self.gbuffer.read(ctx)
    }
}

/// Where the shaders of one [`crate::GpuBackend`] publish the frames they
/// leave on the device ([`crate::GpuBackend::frames`]): a cheap handle
/// (an `Arc`) that holds the latest.
#[derive(Clone, Default)]
pub struct Frames(Arc<Mutex<Option<DeviceFrame>>>);

impl std::fmt::Debug for Frames {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_tuple("Frames").field(&self.latest()).finish()
    }
}

impl Frames {
    /// The latest frame left on the device; `None` before the first and
    /// after a frame that was read back instead.
    pub fn latest(&self) -> Option<DeviceFrame> {
        self.0.lock().expect("frames lock").clone()
    }

    pub(crate) fn publish(&self, frame: Option<DeviceFrame>) {
        *self.0.lock().expect("frames lock") = frame;
    }
}

/// Workgroups of the change kernel, each summing a stride of the pixels:
/// the host reads back one pair of sums a workgroup (2 KiB).
const CHANGE_GROUPS: u32 = 256;

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct ChangeParams {
    count: u32,
    pad: [u32; 3],
}

pub(crate) struct ChangeKernel {
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl ChangeKernel {
    pub(crate) fn new(ctx: &GpuContext) -> ChangeKernel {
        let layout = layout(ctx, "change", &[Binding::Uniform, Binding::Read, Binding::Read, Binding::ReadWrite]);
        let pipeline = pipeline(ctx, "change", include_str!("change.wgsl"), "main", &[&layout]);
        ChangeKernel { layout, pipeline }
    }
}

impl Gpu {
    /// The frame-to-frame change Σ|ΔL| / ΣL over pixels and channels of
    /// `current` against `previous` (what the SMC paper's |E′| measures;
    /// twin of the host's sum, in f32 partial sums of at most a few dozen
    /// pixels each, added in f64): `None` for frames of different sizes or
    /// a black frame. One submission, 2 KiB read back.
    pub fn temporal_change(&self, previous: &DeviceFrame, current: &DeviceFrame) -> Result<Option<f64>, GpuError> {
        if (previous.width, previous.height) != (current.width, current.height) || current.pixels() == 0 {
            return Ok(None);
        }
        let ctx = self.ctx();
        let k = self.change_kernel();
        let params = uniform(ctx, "change params", &ChangeParams { count: current.pixels() as u32, pad: [0; 3] });
        let partial = crate::kernel::storage(ctx, "change sums", CHANGE_GROUPS as u64 * 8)?;
        let group = bind(ctx, "change", &k.layout, &[&params, &previous.image, &current.image, &partial]);
        let mut enc = ctx.device.create_command_encoder(&Default::default());
        dispatch(&mut enc, &k.pipeline, &[&group], (CHANGE_GROUPS, 1, 1));
        let sums: Vec<[f32; 2]> = finish_read(ctx, enc, &partial, CHANGE_GROUPS as usize)?;
        let (diff, sum) = sums.iter().fold((0.0f64, 0.0f64), |(d, s), p| (d + p[0] as f64, s + p[1] as f64));
        Ok((sum > 0.0).then_some(diff / sum))
    }
}

//! One device shared by the stages of a GPU frame: the context, the scene
//! upload, the compiled kernels and the G-buffer left on the device.

use crate::context::{GpuContext, GpuError};
use crate::filter::FilterKernel;
use crate::gbuffer::{DeviceGBuffer, GpuGBufferRenderer};
use crate::scene::{GpuScene, SceneCache};
use std::sync::{Arc, Mutex, OnceLock};
use vpl_core::{GBuffer, Scene};

/// A cheap handle (an `Arc`) to a device and what its stages share:
/// [`Gpu::render_gbuffer`], [`crate::GpuShadowMaps`],
/// [`crate::GpuRayTraced`] and [`crate::GpuInterleavedShader`] built on
/// clones of one `Gpu` reuse one scene upload, and the shader reads the
/// G-buffer the G-buffer stage left on the device instead of uploading it.
#[derive(Clone)]
pub struct Gpu(Arc<Inner>);

struct Inner {
    ctx: GpuContext,
    scene: Mutex<SceneCache>,
    gbuffer_kernel: OnceLock<GpuGBufferRenderer>,
    filter_kernel: OnceLock<FilterKernel>,
    resident: Mutex<Option<Resident>>,
    gbuffer_ms: Mutex<(f64, f64)>,
}

/// The device G-buffer and the host copy it was read into, recognised by
/// the address and size of the host copy's samples and by its first and
/// last samples.
struct Resident {
    key: (usize, usize, u32, u32),
    ends: Option<(vpl_core::GSample, vpl_core::GSample)>,
    buffer: Arc<DeviceGBuffer>,
}

fn key_of(g: &GBuffer) -> (usize, usize, u32, u32) {
    (g.samples.as_ptr() as usize, g.samples.len(), g.width, g.height)
}

fn ends_of(g: &GBuffer) -> Option<(vpl_core::GSample, vpl_core::GSample)> {
    Some((*g.samples.first()?, *g.samples.last()?))
}

impl Gpu {
    /// Opens the default adapter ([`GpuContext::new`]).
    pub fn new() -> Result<Gpu, GpuError> {
        Ok(Gpu::from_context(GpuContext::new()?))
    }

    /// Shares an open context.
    pub fn from_context(ctx: GpuContext) -> Gpu {
        Gpu(Arc::new(Inner {
            ctx,
            scene: Mutex::new(SceneCache::default()),
            gbuffer_kernel: OnceLock::new(),
            filter_kernel: OnceLock::new(),
            resident: Mutex::new(None),
            gbuffer_ms: Mutex::new((0.0, 0.0)),
        }))
    }

    /// The context.
    pub fn ctx(&self) -> &GpuContext {
        &self.0.ctx
    }

    /// The upload of `scene`, made on first use and when its geometry or
    /// materials change.
    pub fn scene(&self, scene: &Scene) -> Result<Arc<GpuScene>, GpuError> {
        self.0.scene.lock().expect("scene cache lock").get(&self.0.ctx, scene)
    }

    pub(crate) fn gbuffer_kernel(&self) -> &GpuGBufferRenderer {
        self.0.gbuffer_kernel.get_or_init(|| GpuGBufferRenderer::new(&self.0.ctx))
    }

    pub(crate) fn filter_kernel(&self) -> &FilterKernel {
        self.0.filter_kernel.get_or_init(|| FilterKernel::new(&self.0.ctx))
    }

    /// Records that `host` is the read-back of `device`.
    pub(crate) fn set_resident(&self, host: &GBuffer, device: Arc<DeviceGBuffer>) {
        *self.0.resident.lock().expect("resident lock") = Some(Resident { key: key_of(host), ends: ends_of(host), buffer: device });
    }

    /// The device copy of `host`: the resident G-buffer when `host` is its
    /// read-back, else an upload.
    pub(crate) fn device_gbuffer(&self, host: &GBuffer) -> Arc<DeviceGBuffer> {
        if let Some(r) = self.0.resident.lock().expect("resident lock").as_ref()
            && r.key == key_of(host)
            && r.ends == ends_of(host)
        {
            return r.buffer.clone();
        }
        Arc::new(DeviceGBuffer::upload(&self.0.ctx, host))
    }
}

impl Gpu {
    /// Renders the G-buffer of `scene` seen by `camera` on the device
    /// ([`GpuGBufferRenderer`]), reads it back, and keeps the device copy
    /// for the shader of the same frame.
    pub fn render_gbuffer(&self, scene: &Scene, camera: &vpl_core::Camera) -> Result<GBuffer, GpuError> {
        let gs = self.scene(scene)?;
        let t0 = std::time::Instant::now();
        let device = self.gbuffer_kernel().render(&self.0.ctx, &gs, scene, camera)?;
        let t1 = std::time::Instant::now();
        let host = device.read(&self.0.ctx)?;
        *self.0.gbuffer_ms.lock().expect("timings lock") = ((t1 - t0).as_secs_f64() * 1e3, t1.elapsed().as_secs_f64() * 1e3);
        self.set_resident(&host, Arc::new(device));
        Ok(host)
    }

    /// Milliseconds of the last [`Gpu::render_gbuffer`]: (kernel, read-back).
    pub fn gbuffer_timings(&self) -> (f64, f64) {
        *self.0.gbuffer_ms.lock().expect("timings lock")
    }
}

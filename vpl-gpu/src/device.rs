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
    change_kernel: OnceLock<crate::frame::ChangeKernel>,
    direct_kernel: OnceLock<crate::direct::DirectKernel>,
    neighbour_kernels: OnceLock<crate::neighbours::Kernels>,
    lights: Mutex<Option<Arc<crate::radiosity::LightBuffers>>>,
    resident: Mutex<Option<Resident>>,
    gbuffer_ms: Mutex<(f64, f64)>,
    visibilities: crate::visibility::Visibilities,
}

/// The device G-buffer of the last frame, and what the host holds of it:
/// the copy it was read into, recognised by the address and size of its
/// samples and by its first and last samples; or no samples
/// ([`GBuffer::on_device`]), recognised by size, pixel angle and eye.
struct Resident {
    host: Option<(HostKey, Ends)>,
    buffer: Arc<DeviceGBuffer>,
}

/// Address and length of a host G-buffer's samples, and its size.
type HostKey = (usize, usize, u32, u32);
/// First and last samples of a host G-buffer (none when it is empty).
type Ends = Option<(vpl_core::GSample, vpl_core::GSample)>;

fn key_of(g: &GBuffer) -> HostKey {
    (g.samples.as_ptr() as usize, g.samples.len(), g.width, g.height)
}

fn ends_of(g: &GBuffer) -> Ends {
    Some((*g.samples.first()?, *g.samples.last()?))
}

impl Resident {
    fn is(&self, g: &GBuffer) -> bool {
        match &self.host {
            Some((key, ends)) => *key == key_of(g) && *ends == ends_of(g),
            None => {
                let b = &self.buffer;
                !g.on_host() && (b.width, b.height, b.pixel_angle, b.eye) == (g.width, g.height, g.pixel_angle, g.eye)
            }
        }
    }
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
            change_kernel: OnceLock::new(),
            direct_kernel: OnceLock::new(),
            neighbour_kernels: OnceLock::new(),
            lights: Mutex::new(None),
            resident: Mutex::new(None),
            gbuffer_ms: Mutex::new((0.0, 0.0)),
            visibilities: Default::default(),
        }))
    }

    pub(crate) fn visibilities(&self) -> &crate::visibility::Visibilities {
        &self.0.visibilities
    }

    /// Whether `other` is a handle to the same device.
    pub fn same(&self, other: &Gpu) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
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

    pub(crate) fn direct_kernel(&self) -> &crate::direct::DirectKernel {
        self.0.direct_kernel.get_or_init(|| crate::direct::DirectKernel::new(&self.0.ctx))
    }

    pub(crate) fn neighbour_kernels(&self) -> &crate::neighbours::Kernels {
        self.0.neighbour_kernels.get_or_init(|| crate::neighbours::Kernels::new(&self.0.ctx))
    }

    pub(crate) fn light_cache(&self) -> &Mutex<Option<Arc<crate::radiosity::LightBuffers>>> {
        &self.0.lights
    }

    pub(crate) fn change_kernel(&self) -> &crate::frame::ChangeKernel {
        self.0.change_kernel.get_or_init(|| crate::frame::ChangeKernel::new(&self.0.ctx))
    }

    /// Records that `host` is the read-back of `device`, or (`None`) that
    /// the host holds none of its samples.
    fn set_resident(&self, host: Option<&GBuffer>, device: Arc<DeviceGBuffer>) {
        let host = host.map(|h| (key_of(h), ends_of(h)));
        *self.0.resident.lock().expect("resident lock") = Some(Resident { host, buffer: device });
    }

    /// The device copy of `g`: the resident G-buffer when `g` is its
    /// read-back or its [`GBuffer::on_device`] stand-in, else an upload of
    /// `g`'s samples. A stand-in of no resident G-buffer is an error.
    pub(crate) fn device_gbuffer(&self, g: &GBuffer) -> Result<Arc<DeviceGBuffer>, GpuError> {
        if let Some(r) = self.0.resident.lock().expect("resident lock").as_ref()
            && r.is(g)
        {
            return Ok(r.buffer.clone());
        }
        if !g.on_host() {
            return Err(GpuError::Invalid(format!(
                "a {}x{} G-buffer without samples that is not this device's last one",
                g.width, g.height
            )));
        }
        Ok(Arc::new(DeviceGBuffer::upload(&self.0.ctx, g)))
    }

    /// What has crossed between host and device so far
    /// ([`GpuContext::traffic`]).
    pub fn traffic(&self) -> crate::Traffic {
        self.0.ctx.traffic()
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
        self.set_resident(Some(&host), Arc::new(device));
        Ok(host)
    }

    /// Renders the G-buffer of `scene` seen by `camera` and leaves it on the
    /// device: the answer is its [`GBuffer::on_device`] stand-in, which the
    /// shader of the same frame reads through, and
    /// [`Gpu::read_gbuffer`] reads back on request. Nothing crosses but the
    /// camera's parameters.
    pub fn render_gbuffer_on_device(&self, scene: &Scene, camera: &vpl_core::Camera) -> Result<GBuffer, GpuError> {
        let gs = self.scene(scene)?;
        let t0 = std::time::Instant::now();
        let device = self.gbuffer_kernel().render(&self.0.ctx, &gs, scene, camera)?;
        *self.0.gbuffer_ms.lock().expect("timings lock") = (t0.elapsed().as_secs_f64() * 1e3, 0.0);
        let g = GBuffer::on_device(device.width, device.height, device.pixel_angle, device.eye);
        self.set_resident(None, Arc::new(device));
        Ok(g)
    }

    /// The samples of `g`: `g` itself when they are on the host, else those
    /// of the G-buffer [`Gpu::render_gbuffer_on_device`] left on the device
    /// for it, read back (and remembered as its host copy).
    pub fn read_gbuffer(&self, g: GBuffer) -> Result<GBuffer, GpuError> {
        if g.on_host() {
            return Ok(g);
        }
        let device = self.device_gbuffer(&g)?;
        let host = device.read(&self.0.ctx)?;
        self.set_resident(Some(&host), device);
        Ok(host)
    }

    /// Milliseconds of the last [`Gpu::render_gbuffer`]: (kernel, read-back).
    pub fn gbuffer_timings(&self) -> (f64, f64) {
        *self.0.gbuffer_ms.lock().expect("timings lock")
    }
}

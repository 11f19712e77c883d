//! The GPU as a [`vpl_render::Backend`]: the G-buffer, shadow maps or
//! shadow rays, interleaved or exhaustive shading and the filter as wgpu
//! kernels; SMC with the paper's kNN flux wholly on the device
//! ([`GpuSmcSampler`], built in the registry's place), and the rays and
//! radiosity estimates of the samplers that take them (SMC with the other
//! fluxes). The rest of sampling stays on the CPU.

use crate::{Frames, Gpu, GpuError, GpuInterleavedShader, GpuRadiosity, GpuRayTraced, GpuRays, GpuShadowMaps, GpuSmcSampler};
use std::sync::Arc;
use vpl_core::{
    Budget, Camera, DeviceError, DeviceSamplers, GBuffer, GeometryClamp, IndirectShader, Params, Scene, Services, SharedEstimator,
    VplSampler, VplVisibility,
};
use vpl_pathtrace::PathRadiosity;
use vpl_render::{Backend, RenderError, ShadingSpec, VisibilitySpec};
use vpl_smc::{FluxEstimator, Placement, SmcConfig};

/// The GPU backend on one device.
#[derive(Clone)]
pub struct GpuBackend {
    gpu: Gpu,
    frames: Frames,
}

impl std::fmt::Debug for GpuBackend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuBackend").field("adapter", &self.gpu.ctx().describe()).finish()
    }
}

/// The GPU backend on the first adapter found (Vulkan, Metal or DX12 first,
/// GL as the fallback; `WGPU_BACKEND` selects).
pub fn backend() -> Result<GpuBackend, GpuError> {
    Ok(GpuBackend::new(Gpu::new()?))
}

/// The name this backend is registered and reported under.
pub const NAME: &str = "gpu";

/// Registers this backend as [`NAME`] ([`backend`]: the first adapter
/// found), so that an application finds it by name
/// ([`vpl_render::Backends`]).
pub fn register(backends: &mut vpl_render::Backends) {
    backends.register(NAME, "wgpu kernels: G-buffer, shadow maps or shadow rays, shading, filter, SMC's rays and radiosity", || {
        Ok(Box::new(backend().map_err(err)?))
    });
}

fn err(e: impl std::fmt::Display) -> RenderError {
    RenderError::backend(NAME, e)
}

impl GpuBackend {
    /// The backend on `gpu`.
    pub fn new(gpu: Gpu) -> GpuBackend {
        GpuBackend { gpu, frames: Frames::default() }
    }

    /// Where the shaders this backend makes publish the frames they leave
    /// on the device (`vpl_render::ReadBack::Nothing`): a window on the
    /// same device shows them from there, with no read-back.
    pub fn frames(&self) -> Frames {
        self.frames.clone()
    }

    /// The device handle.
    pub fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    fn storage_limit(&self) -> u64 {
        self.gpu.ctx().device.limits().max_storage_buffer_binding_size as u64
    }
}

/// The samplers this backend runs wholly on the device: SMC with the
/// paper's kNN flux at the VPLs' sites ([`GpuSmcSampler`]). Other settings
/// (the Voronoi flux, the centroid placement) run on the host with the
/// device's rays and radiosities.
struct DeviceTwins(Gpu);

impl DeviceSamplers for DeviceTwins {
    fn twin(&self, name: &str, budget: &Budget, params: &Params) -> Option<Result<Box<dyn VplSampler>, DeviceError>> {
        let config = match name {
            "smc" => SmcConfig::from_params(budget, params).ok()?,
            "smc-knn" => SmcConfig::paper_from_params(budget, params).ok()?,
            _ => return None,
        };
        let runs = config.flux == FluxEstimator::Knn && config.placement == Placement::Site && config.k() <= crate::MAX_K;
        runs.then(|| GpuSmcSampler::new(self.0.clone(), config).map(|s| Box::new(s) as Box<dyn VplSampler>).map_err(DeviceError::from))
    }
}

impl Backend for GpuBackend {
    fn name(&self) -> &str {
        NAME
    }

    fn device(&self) -> Option<String> {
        Some(self.gpu.ctx().describe())
    }

    fn services(&self) -> Services {
        let g = self.gpu.clone();
        let make = move |paths: u32, max_bounces: u32| -> SharedEstimator {
            Box::new(GpuRadiosity::new(g.clone(), PathRadiosity { paths, max_bounces }))
        };
        Services {
            rays: Arc::new(GpuRays::new(self.gpu.clone())),
            radiosity: Some(Arc::new(make)),
            samplers: Some(Arc::new(DeviceTwins(self.gpu.clone()))),
        }
    }

    fn gbuffer(&self, scene: &Scene, camera: &Camera) -> Result<GBuffer, RenderError> {
        let mut g = self.gpu.render_gbuffer(scene, camera).map_err(err)?;
        vpl_shading::environment_at_misses(&mut g, scene, camera);
        Ok(g)
    }

    fn device_gbuffer(&self, scene: &Scene, camera: &Camera) -> Result<Option<GBuffer>, RenderError> {
        self.gpu.render_gbuffer_on_device(scene, camera).map(Some).map_err(err)
    }

    fn host_gbuffer(&self, g: GBuffer, scene: &Scene, camera: &Camera) -> Result<GBuffer, RenderError> {
        if g.on_host() {
            return Ok(g);
        }
        let mut g = self.gpu.read_gbuffer(g).map_err(err)?;
        vpl_shading::environment_at_misses(&mut g, scene, camera);
        Ok(g)
    }

    /// Each per-pixel buffer (16 bytes a pixel) must fit the adapter's
    /// storage-buffer limit.
    fn check_size(&self, size: (u32, u32)) -> Result<(), RenderError> {
        let bytes = size.0 as u64 * size.1 as u64 * 16;
        let limit = self.storage_limit();
        if bytes > limit {
            return Err(err(format!(
                "{}x{} needs {} MiB per image buffer, over the adapter's {} MiB",
                size.0,
                size.1,
                bytes >> 20,
                limit >> 20
            )));
        }
        Ok(())
    }

    fn visibility(&self, spec: VisibilitySpec, budget: &Budget) -> Result<Box<dyn VplVisibility>, RenderError> {
        Ok(match spec {
            VisibilitySpec::RayTraced => Box::new(GpuRayTraced::new(self.gpu.clone())),
            VisibilitySpec::ShadowMaps(res) => {
                let bytes = GpuShadowMaps::atlas_bytes(res, budget.vpls);
                let limit = self.storage_limit();
                if bytes > limit {
                    return Err(err(format!(
                        "{} shadow maps of {res}² texels need {} MiB, over the adapter's {} MiB per buffer",
                        budget.vpls,
                        bytes >> 20,
                        limit >> 20
                    )));
                }
                Box::new(GpuShadowMaps::new(self.gpu.clone(), res).map_err(|e| RenderError::Invalid(format!("shadow maps: {e}")))?)
            }
        })
    }

    fn shader(&self, spec: ShadingSpec, clamp: Option<GeometryClamp>, seed: u64) -> Result<Box<dyn IndirectShader>, RenderError> {
        Ok(match spec {
            ShadingSpec::Exhaustive => {
                let mut s = GpuInterleavedShader::exhaustive(self.gpu.clone(), clamp);
                s.publish_to(self.frames.clone());
                Box::new(s)
            }
            ShadingSpec::Interleaved { filter } => {
                let mut s = GpuInterleavedShader::new(self.gpu.clone(), clamp, seed);
                if !filter {
                    s.cpu.filter = None;
                }
                s.publish_to(self.frames.clone());
                Box::new(s)
            }
            // No device twin yet: the host's, over a G-buffer read back.
            ShadingSpec::Lightcuts { cut } => Box::new(crate::GpuLightcutShader::new(self.gpu.clone(), cut as usize, clamp, seed)),
            ShadingSpec::Culled { bound } => Box::new(vpl_shading::CulledShader::new(bound, clamp, seed)),
        })
    }
}

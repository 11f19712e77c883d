//! Where a renderer's stages run: the G-buffer, visibility, shading and
//! the services samplers use. [`CpuBackend`] is the CPU (rayon); the crate
//! `vpl-gpu` implements the same trait on wgpu (`vpl_gpu::backend()`).

use crate::error::RenderError;
use crate::spec::{ShadingSpec, VisibilitySpec};
use vpl_core::{Budget, Camera, GBuffer, GeometryClamp, IndirectShader, Scene, Services, VplVisibility};
use vpl_shading::{CulledShader, ExhaustiveShader, InterleavedShader, LightcutShader};
use vpl_visibility::{RayTraced, ShadowMaps};

/// A place the stages of a VPL frame run.
pub trait Backend: Send {
    /// Short name (`cpu`, `gpu`).
    fn name(&self) -> &str;

    /// The device in words (the GPU adapter), `None` for the CPU.
    fn device(&self) -> Option<String> {
        None
    }

    /// What samplers built for this backend use: its ray caster and
    /// radiosity estimators.
    fn services(&self) -> Services {
        Services::cpu()
    }

    /// The G-buffer of `scene` seen by `camera`, on the host.
    fn gbuffer(&self, scene: &Scene, camera: &Camera) -> Result<GBuffer, RenderError>;

    /// The G-buffer of `scene` seen by `camera` left on the backend's device
    /// ([`GBuffer::on_device`]: no samples on the host), for a frame whose
    /// stages all run there; `None` (the default, and the CPU's answer)
    /// where the backend has no device to keep it on.
    fn device_gbuffer(&self, scene: &Scene, camera: &Camera) -> Result<Option<GBuffer>, RenderError> {
        let _ = (scene, camera);
        Ok(None)
    }

    /// The host copy of `g`, the G-buffer of `scene` seen by `camera`: `g`
    /// itself when its samples are on the host; the samples of the last
    /// G-buffer this backend left on its device, read back, when `g` is
    /// that one (as [`Backend::gbuffer`] would have made them). Anything
    /// else is an error.
    fn host_gbuffer(&self, g: GBuffer, scene: &Scene, camera: &Camera) -> Result<GBuffer, RenderError> {
        let _ = (scene, camera);
        if g.on_host() {
            Ok(g)
        } else {
            Err(RenderError::Invalid(format!("the {} backend holds no device G-buffer of {}x{}", self.name(), g.width, g.height)))
        }
    }

    /// Whether images of `size` fit the backend (a GPU's buffer limits).
    fn check_size(&self, size: (u32, u32)) -> Result<(), RenderError> {
        let _ = size;
        Ok(())
    }

    /// The visibility structure for sets of `budget.vpls` slots.
    fn visibility(&self, spec: VisibilitySpec, budget: &Budget) -> Result<Box<dyn VplVisibility>, RenderError>;

    /// The indirect shader.
    fn shader(&self, spec: ShadingSpec, clamp: Option<GeometryClamp>, seed: u64) -> Result<Box<dyn IndirectShader>, RenderError>;
}

/// The CPU stages of `vpl-shading` and `vpl-visibility`.
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuBackend;

impl Backend for CpuBackend {
    fn name(&self) -> &str {
        "cpu"
    }

    fn gbuffer(&self, scene: &Scene, camera: &Camera) -> Result<GBuffer, RenderError> {
        Ok(vpl_shading::render_gbuffer(scene, camera))
    }

    fn visibility(&self, spec: VisibilitySpec, _budget: &Budget) -> Result<Box<dyn VplVisibility>, RenderError> {
        Ok(match spec {
            VisibilitySpec::RayTraced => Box::new(RayTraced::default()),
            VisibilitySpec::ShadowMaps(res) => {
                Box::new(ShadowMaps::new(res).map_err(|e| RenderError::Invalid(format!("shadow maps: {e}")))?)
            }
        })
    }

    fn shader(&self, spec: ShadingSpec, clamp: Option<GeometryClamp>, seed: u64) -> Result<Box<dyn IndirectShader>, RenderError> {
        Ok(match spec {
            ShadingSpec::Exhaustive => Box::new(ExhaustiveShader { clamp }),
            ShadingSpec::Lightcuts { cut } => Box::new(LightcutShader::new(cut as usize, clamp, seed)),
            ShadingSpec::Culled { bound } => Box::new(CulledShader::new(bound, clamp, seed)),
            ShadingSpec::Interleaved { filter } => {
                let mut s = InterleavedShader::new(clamp, seed);
                if !filter {
                    s.filter = None;
                }
                Box::new(s)
            }
        })
    }
}

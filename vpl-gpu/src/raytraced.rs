//! Exact visibility by shadow rays on the device: twin of
//! [`vpl_visibility::RayTraced`].

use crate::device::Gpu;
use crate::scene::GpuScene;
use std::sync::Arc;
use vpl_core::glam::Vec3;
use vpl_core::{Receivers, Scene, VisibilityUpdate, VplSet, VplVisibility};
use vpl_visibility::RayTraced;

/// One shadow ray per (receiver, VPL) pair, traced by
/// [`crate::GpuInterleavedShader`] over the device BVH. `update` uploads the
/// scene when it changed; host queries answer with the CPU BVH
/// ([`RayTraced`]), which tests the same triangles.
pub struct GpuRayTraced {
    gpu: Gpu,
    host: RayTraced,
    scene: Option<(Arc<GpuScene>, f32)>,
}

impl GpuRayTraced {
    /// Shadow rays on `gpu`.
    pub fn new(gpu: Gpu) -> GpuRayTraced {
        GpuRayTraced { gpu, host: RayTraced::default(), scene: None }
    }

    /// The device scene and its ray offset ε, after the first update.
    pub(crate) fn gpu(&self) -> &Gpu {
        &self.gpu
    }

    pub(crate) fn device_scene(&self) -> Option<&(Arc<GpuScene>, f32)> {
        self.scene.as_ref()
    }
}

impl VplVisibility for GpuRayTraced {
    fn name(&self) -> &'static str {
        "raytrace"
    }

    /// # Panics
    /// When the device fails to take the scene.
    fn update(&mut self, scene: &Scene, vpls: &VplSet) -> VisibilityUpdate {
        let gs = self.gpu.scene(scene).unwrap_or_else(|e| panic!("GPU scene upload: {e}"));
        self.scene = Some((gs, scene.epsilon()));
        self.host.update(scene, vpls)
    }

    fn visible(&self, slot: usize, x: Vec3, n_x: Vec3) -> f32 {
        self.host.visible(slot, x, n_x)
    }

    fn attenuate(&self, slot: usize, rx: &Receivers, w: &mut [f32]) {
        self.host.attenuate(slot, rx, w)
    }

    fn memory_bytes(&self) -> usize {
        self.host.memory_bytes()
    }

    fn as_any(&self) -> &dyn std::any::Any {
        self
    }
}

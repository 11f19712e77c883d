//! Exact visibility by shadow rays on the device: twin of
//! [`vpl_visibility::RayTraced`].

use crate::device::Gpu;
use crate::visibility::DeviceVisibility;
use vpl_core::glam::Vec3;
use vpl_core::{DeviceKey, Receivers, Scene, VisibilityUpdate, VplSet, VplVisibility};
use vpl_visibility::RayTraced;

/// One shadow ray per (receiver, VPL) pair, traced by
/// [`crate::GpuInterleavedShader`] over the device BVH. `update` uploads the
/// scene when it changed; host queries answer with the CPU BVH
/// ([`RayTraced`]), which tests the same triangles.
pub struct GpuRayTraced {
    gpu: Gpu,
    host: RayTraced,
    /// Where shaders on the same device find the device scene.
    key: DeviceKey,
}

impl GpuRayTraced {
    /// Shadow rays on `gpu`.
    pub fn new(gpu: Gpu) -> GpuRayTraced {
        GpuRayTraced { key: gpu.register_visibility(), gpu, host: RayTraced::default() }
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
        let eps = scene.epsilon();
        self.gpu.publish_visibility(self.key, DeviceVisibility { mode: 1, scene: gs, eps, res: 1, bias: 0.0, maps: None });
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

    fn device_key(&self) -> Option<DeviceKey> {
        Some(self.key)
    }
}

impl Drop for GpuRayTraced {
    fn drop(&mut self) {
        self.gpu.forget_visibility(self.key);
    }
}

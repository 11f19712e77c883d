//! Exact visibility by BVH shadow rays.

use vpl_core::glam::Vec3;
use vpl_core::{Scene, VisibilityUpdate, VplSet, VplVisibility};

/// One shadow ray per (receiver, VPL) query: exact, the visibility every
/// approximation is measured against.
#[derive(Clone, Debug, Default)]
pub struct RayTraced {
    scene: Option<Scene>,
    /// VPL positions stepped off their surfaces, by slot.
    origins: Vec<Option<Vec3>>,
}

impl VplVisibility for RayTraced {
    fn name(&self) -> &'static str {
        "raytrace"
    }

    fn update(&mut self, scene: &Scene, vpls: &VplSet) -> VisibilityUpdate {
        let eps = scene.epsilon();
        self.origins = vpls.slots().iter().map(|v| v.map(|v| v.y + v.n * eps)).collect();
        self.scene = Some(scene.clone());
        VisibilityUpdate { rebuilt: 0, memory_bytes: self.memory_bytes() }
    }

    #[inline]
    fn visible(&self, slot: usize, x: Vec3, n_x: Vec3) -> f32 {
        let (Some(scene), Some(Some(y))) = (&self.scene, self.origins.get(slot)) else { return 0.0 };
        if scene.visible(x + n_x * scene.epsilon(), *y) { 1.0 } else { 0.0 }
    }

    fn memory_bytes(&self) -> usize {
        // The BVH is the scene's own; this holds one offset point per slot.
        self.origins.len() * std::mem::size_of::<Option<Vec3>>()
    }
}

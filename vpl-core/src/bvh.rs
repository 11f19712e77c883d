//! The BVH: obvhs's compressed wide BVH8 (CWBVH) over the scene's triangles.

use crate::ray::Ray;
use crate::scene::TriangleData;
use glam::Vec3A;
use obvhs::{cwbvh::CwBvh, ray::RayHit, triangle::Triangle, BvhBuildParams};
use std::time::Duration;

/// A CWBVH with the triangles laid out in its primitive order, so traversal
/// reads them without an indirection.
#[derive(Debug)]
pub struct Bvh {
    cwbvh: CwBvh,
    /// Triangles in BVH primitive order.
    tris: Vec<Triangle>,
    /// `order[k]` is the scene triangle index of BVH primitive `k`.
    order: Vec<u32>,
}

impl Bvh {
    /// Builds the BVH (PLOC + reinsertion, obvhs's "medium" preset).
    pub fn build(triangles: &[TriangleData]) -> Bvh {
        let tris: Vec<Triangle> = triangles
            .iter()
            .map(|t| Triangle { v0: t.p0.into(), v1: (t.p0 + t.e1).into(), v2: (t.p0 + t.e2).into() })
            .collect();
        let cwbvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(&tris, BvhBuildParams::medium_build(), &mut Duration::default());
        let order: Vec<u32> = cwbvh.primitive_indices.clone();
        let tris = order.iter().map(|&i| tris[i as usize]).collect();
        Bvh { cwbvh, tris, order }
    }

    #[inline]
    fn obvhs_ray(ray: &Ray) -> obvhs::ray::Ray {
        obvhs::ray::Ray::new(Vec3A::from(ray.o), Vec3A::from(ray.d), 0.0, ray.t_max)
    }

    /// Closest hit: (scene triangle, t).
    #[inline]
    pub fn closest(&self, ray: &Ray) -> Option<(u32, f32)> {
        let r = Self::obvhs_ray(ray);
        let mut hit = RayHit::none();
        let tris = &self.tris;
        if !self.cwbvh.ray_traverse(r, &mut hit, |r, id| tris[id].intersect(r)) {
            return None;
        }
        Some((self.order[hit.primitive_id as usize], hit.t))
    }

    /// Early-exit occlusion test (obvhs's `ray_traverse_miss`).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let r = Self::obvhs_ray(ray);
        let tris = &self.tris;
        !self.cwbvh.ray_traverse_miss(r, |r, id| tris[id].intersect(r))
    }
}


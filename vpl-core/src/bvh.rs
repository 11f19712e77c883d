//! The BVH: obvhs's compressed wide BVH8 (CWBVH) over the scene's triangles,
//! with triangle tests by precomputed affine transforms.

use crate::ray::Ray;
use crate::triangle::TriangleData;
use glam::{Vec3A, Vec4};
use obvhs::{BvhBuildParams, cwbvh::CwBvh, ray::RayHit, triangle::Triangle};
use std::time::Duration;

/// A triangle prepared for ray tests (Baldwin & Weber, "Fast Ray-Triangle
/// Intersections by Coordinate Transformation", JCGT 2016): the rows of an
/// affine map that sends the triangle to (0,0,0), (1,0,0), (0,1,0) and its
/// normal to +Z. A test costs four dot products and one division.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
struct PreparedTriangle {
    row0: Vec4,
    row1: Vec4,
    row2: Vec4,
}

/// The three rows of the affine map [`Bvh`] tests a triangle with: a point p
/// lies at barycentrics (u, v) = (row0·(p, 1), row1·(p, 1)) and height
/// row2·(p, 1) above the triangle's plane (in units of its normal e1 × e2).
/// The GPU twin of the BVH uploads these rows.
pub fn prepared_rows(t: &TriangleData) -> [Vec4; 3] {
    let p = PreparedTriangle::new(t);
    [p.row0, p.row1, p.row2]
}

impl PreparedTriangle {
    fn new(t: &TriangleData) -> Self {
        let (p0, e1, e2) = (t.p0, t.e1, t.e2);
        let n = e1.cross(e2);
        // Columns (e1, e2, n) form a basis; invert it and fold in the translation.
        let m = glam::Mat3::from_cols(e1, e2, n);
        let inv = m.inverse();
        let r0 = inv.row(0);
        let r1 = inv.row(1);
        let r2 = inv.row(2);
        PreparedTriangle { row0: r0.extend(-r0.dot(p0)), row1: r1.extend(-r1.dot(p0)), row2: r2.extend(-r2.dot(p0)) }
    }

    /// Ray parameter of the hit in `[0, t_max]`, or infinity.
    #[inline(always)]
    fn intersect(&self, o: Vec3A, d: Vec3A, t_max: f32) -> f32 {
        let oz = Vec3A::from(self.row2.truncate()).dot(o) + self.row2.w;
        let dz = Vec3A::from(self.row2.truncate()).dot(d);
        let t = -oz / dz;
        if !(t >= 0.0 && t <= t_max) {
            return f32::INFINITY;
        }
        let p = o + d * t;
        let u = Vec3A::from(self.row0.truncate()).dot(p) + self.row0.w;
        let v = Vec3A::from(self.row1.truncate()).dot(p) + self.row1.w;
        if u >= 0.0 && v >= 0.0 && u + v <= 1.0 { t } else { f32::INFINITY }
    }
}

/// How far behind its origin a ray's box traversal starts (see `Bvh::prepare`).
const BACKSTEP: f32 = 2e-4;

/// A CWBVH with the triangles laid out in its primitive order, so traversal
/// reads them without an indirection.
#[derive(Debug)]
pub struct Bvh {
    cwbvh: CwBvh,
    /// Prepared triangles in BVH primitive order.
    tris: Vec<PreparedTriangle>,
    /// `order[k]` is the scene triangle index of BVH primitive `k`.
    order: Vec<u32>,
}

impl Bvh {
    /// Builds the BVH: PLOC with spatial pre-splits of large triangles and
    /// reinsertion (obvhs's "slow" preset; measured fastest to trace on the
    /// Cornell box), at most 3 triangles per leaf.
    pub fn build(triangles: &[TriangleData]) -> Bvh {
        let tris: Vec<Triangle> =
            triangles.iter().map(|t| Triangle { v0: t.p0.into(), v1: (t.p0 + t.e1).into(), v2: (t.p0 + t.e2).into() }).collect();
        let mut params = BvhBuildParams::slow_build();
        params.max_prims_per_leaf = 3;
        let cwbvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(&tris, params, &mut Duration::default());
        let order: Vec<u32> = cwbvh.primitive_indices.clone();
        let tris = order.iter().map(|&i| PreparedTriangle::new(&triangles[i as usize])).collect();
        Bvh { cwbvh, tris, order }
    }

    /// Triangle references in the leaves (a triangle split by the builder's
    /// spatial splits is referenced more than once).
    pub fn primitive_count(&self) -> usize {
        self.tris.len()
    }

    /// Nodes of the tree.
    pub fn node_count(&self) -> usize {
        self.cwbvh.nodes.len()
    }

    /// Bytes the BVH holds: its nodes, the prepared triangles and the two
    /// index tables (capacity not counted).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.cwbvh.nodes.len() * size_of::<obvhs::cwbvh::node::CwBvhNode>()
            + self.cwbvh.primitive_indices.len() * size_of::<u32>()
            + self.tris.len() * size_of::<PreparedTriangle>()
            + self.order.len() * size_of::<u32>()
    }

    /// Origin, direction and the obvhs ray of `ray`.
    ///
    /// - A component of −0.0 becomes +0.0: obvhs takes the traversal octant
    ///   from `d < 0` (false for −0.0) but the inverse direction from the
    ///   sign bit (−1/ε), and a ray whose two disagree misses everything.
    ///   `-direction` of an axis-aligned sun or a cosine sample about an
    ///   axis-aligned normal makes such rays.
    /// - The traversal ray starts [`BACKSTEP`] behind the origin: obvhs's
    ///   box test enters a child no earlier than t = 10⁻⁴, so a box the ray
    ///   leaves before that (a wall or ceiling a ray from the edge of the
    ///   adjacent surface meets at t < 10⁻⁴) would be skipped. Triangles are
    ///   still tested from the true origin; only the boxes see the shift.
    #[inline(always)]
    fn prepare(ray: &Ray) -> (Vec3A, Vec3A, obvhs::ray::Ray) {
        let (o, d) = (Vec3A::from(ray.o), Vec3A::from(ray.d) + Vec3A::ZERO);
        (o, d, obvhs::ray::Ray::new(o - d * BACKSTEP, d, 0.0, ray.t_max + BACKSTEP))
    }

    /// Closest hit: (scene triangle, t).
    #[inline]
    pub fn closest(&self, ray: &Ray) -> Option<(u32, f32)> {
        let (o, d, r) = Self::prepare(ray);
        let mut hit = RayHit::none();
        let tris = &self.tris;
        // The best hit in the ray's own parameter; obvhs sees t + BACKSTEP.
        let mut best = (ray.t_max, u32::MAX);
        self.cwbvh.ray_traverse(r, &mut hit, |_, id| {
            let t = tris[id].intersect(o, d, best.0);
            if t < best.0 {
                best = (t, id as u32);
                t + BACKSTEP
            } else {
                f32::INFINITY
            }
        });
        (best.1 != u32::MAX).then(|| (self.order[best.1 as usize], best.0))
    }

    /// Early-exit occlusion test (obvhs's `ray_traverse_miss`).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let (o, d, r) = Self::prepare(ray);
        let tris = &self.tris;
        !self.cwbvh.ray_traverse_miss(r, |_, id| tris[id].intersect(o, d, ray.t_max) + BACKSTEP)
    }

    /// The parameter at which `ray` meets scene triangle `tri` within
    /// `[0, t_max]`, by the same test as [`Bvh::closest`], so a hit found
    /// elsewhere (a GPU) gets the t this BVH would report.
    pub fn triangle_t(&self, triangles: &[TriangleData], ray: &Ray, tri: u32) -> Option<f32> {
        let (o, d, _) = Self::prepare(ray);
        let t = PreparedTriangle::new(triangles.get(tri as usize)?).intersect(o, d, ray.t_max);
        t.is_finite().then_some(t)
    }
}

#[cfg(test)]
mod tests {
    use crate::material::Material;
    use crate::mesh::Mesh;
    use crate::ray::Ray;
    use crate::scene::Scene;
    use glam::Vec3;

    /// A roof over the origin: rays straight up hit it whatever the sign of
    /// their zero components, and a sun straight overhead is shadowed.
    #[test]
    fn negative_zero_directions_and_near_hits_traverse() {
        let mut mesh = Mesh::default();
        mesh.push_quad(Vec3::new(-1.0, 1.0, -1.0), Vec3::new(1.0, 1.0, -1.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(-1.0, 1.0, 1.0), 0);
        mesh.push_quad(Vec3::new(-5.0, 0.0, -5.0), Vec3::new(-5.0, 0.0, 5.0), Vec3::new(5.0, 0.0, 5.0), Vec3::new(5.0, 0.0, -5.0), 0);
        let sun = crate::light::Light::Directional { direction: Vec3::new(0.0, -1.0, 0.0), irradiance: Vec3::ONE };
        let s = Scene::new("roof", &mesh, vec![Material::diffuse("m", Vec3::splat(0.5))], vec![sun], true).unwrap();
        let o = Vec3::new(0.2, 0.01, 0.3);
        for d in [Vec3::new(0.0, 1.0, 0.0), Vec3::new(-0.0, 1.0, -0.0), Vec3::new(-0.0, 1.0, 0.0)] {
            assert!(s.occluded(&Ray::new(o, d)), "{d:?}");
            let t = s.intersect(&Ray::new(o, d)).map(|h| h.t);
            assert!(t.is_some_and(|t| (t - 0.99).abs() < 1e-4), "{d:?}: {t:?}");
        }
        // Hits nearer than obvhs's box epsilon (10⁻⁴) are found: a ray from
        // just under the roof meets it at t = 5·10⁻⁵.
        let near = Vec3::new(0.2, 1.0 - 5e-5, 0.3);
        let t = s.intersect(&Ray::new(near, Vec3::new(0.3, 0.9, -0.3).normalize())).map(|h| h.t);
        assert!(t.is_some_and(|t| t > 0.0 && t < 1e-4), "{t:?}");
        assert!(s.occluded(&Ray::new(near, Vec3::Y)));
        let (ls, _) = s.sample_light(o, 0.5, (0.5, 0.5)).unwrap();
        assert!(ls.wi.x.is_sign_negative(), "the test needs −0.0 in the light direction");
        assert!(!s.light_unoccluded(Vec3::new(0.2, 0.0, 0.3), Vec3::Y, &ls));
    }
}

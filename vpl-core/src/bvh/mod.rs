//! The BVH: an 8-wide tree with its children's boxes side by side, traversed
//! one ray at a time with all eight boxes tested together, and the
//! watertight triangle test of Woop et al. (2013) in its leaves.
//!
//! The tree is built by obvhs (PLOC with spatial pre-splits of large
//! triangles and reinsertion, its "slow" preset, leaves of at most 4
//! triangles by its SAH collapse) as a binary tree, which [`Bvh::build`]
//! folds into 8-wide nodes by opening, at each node, the child of largest
//! surface area until eight are gathered. Traversal visits the children a
//! ray enters nearest first and skips those beyond the best hit so far
//! (closest hit), or stops at the first hit (occlusion).
//!
//! The slab test is written over fixed arrays of eight lanes, and once more
//! with AVX intrinsics (one 8-wide step and one mask move); the whole
//! traversal is compiled twice, for the x86-64 baseline (SSE2: the lanes in
//! two 4-wide halves) and for AVX2 with FMA, and the build picks the second
//! where the CPU has it (`is_x86_feature_detected!`). Both give the same
//! hits bit for bit: the lanes are independent and the arithmetic is the
//! same (no fused multiply-add is written; the compiler may not fuse).

mod fan;
mod node;
mod watertight;

pub use fan::FAN;

use crate::error::{CoreError, Result};
use crate::ray::Ray;
use crate::triangle::TriangleData;
use glam::Vec3;
use node::{BoxRay, COUNT_SHIFT, LEAF, MAX_SLOTS, Node8, SLOT_MASK, WIDTH};
use obvhs::{BvhBuildParams, bvh2::Bvh2, triangle::Triangle};
use std::time::Duration;
use watertight::ShearedRay;

/// How far behind its origin a ray enters boxes: a ray that leaves a
/// surface at its edge may meet the adjacent wall at t ≈ 0 inside a flat
/// box it is, by rounding, already past. Triangles are still tested from
/// t = 0.
const BACKSTEP: f32 = 2e-4;

/// Triangles per leaf at most.
const LEAF_SIZE: u32 = 4;

/// Entries of the traversal stack kept on the call stack; it is filled
/// anew for every ray, so it is kept small, and entries beyond it (trees
/// deeper than about 9 levels of 8-wide nodes, and only on the rays that
/// enter many children on the way) spill to the heap.
const STACK: usize = 64;

/// A traversal stack: [`STACK`] entries in place, the rest on the heap
/// (allocated only if ever needed).
struct Stack<E> {
    items: [E; STACK],
    top: usize,
    spill: Vec<E>,
}

impl<E: Copy> Stack<E> {
    #[inline(always)]
    fn new(fill: E) -> Self {
        Stack { items: [fill; STACK], top: 0, spill: Vec::new() }
    }

    #[inline(always)]
    fn push(&mut self, e: E) {
        if self.top < STACK {
            self.items[self.top] = e;
            self.top += 1;
        } else {
            self.spill.push(e);
        }
    }

    /// Pushes at most [`WIDTH`] entries (a node's entered children) so that
    /// the one of least `dist` is popped first.
    #[inline(always)]
    fn push_nearest_last(&mut self, entries: impl Iterator<Item = E>, dist: impl Fn(&E) -> f32)
    where
        E: Default,
    {
        let mut sorted = [E::default(); WIDTH];
        let mut k = 0;
        for e in entries {
            let mut j = k;
            while j > 0 && dist(&sorted[j - 1]) < dist(&e) {
                sorted[j] = sorted[j - 1];
                j -= 1;
            }
            sorted[j] = e;
            k += 1;
        }
        for e in &sorted[..k] {
            self.push(*e);
        }
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<E> {
        if let Some(e) = self.spill.pop() {
            return Some(e);
        }
        self.top = self.top.checked_sub(1)?;
        Some(self.items[self.top])
    }
}

/// The scene's triangles in an 8-wide BVH.
#[derive(Debug)]
pub struct Bvh {
    nodes: Vec<Node8>,
    /// Triangle vertices by slot (a leaf's triangles are consecutive slots).
    tris: Vec<[Vec3; 3]>,
    /// `order[k]` is the scene triangle in slot `k` (a triangle split by
    /// the builder fills several slots).
    order: Vec<u32>,
    /// A slot of each scene triangle (`u32::MAX` where none).
    slot_of: Vec<u32>,
    /// Whether the traversal compiled for AVX2 and FMA runs.
    avx2: bool,
    /// The largest magnitude of any vertex coordinate.
    extent: f32,
}

impl Bvh {
    /// Builds the BVH over triangles given by their three vertices, in the
    /// scene's order. Triangles that share an edge must share its vertices'
    /// coordinates bit for bit for the test to be watertight (as a mesh's
    /// indexed vertices do).
    ///
    /// Errors: more triangle references than a leaf can address (2²⁸,
    /// about 268 million, splits included).
    pub fn build(vertices: &[[Vec3; 3]]) -> Result<Bvh> {
        let avx2 = crate::cpu::has_avx2_fma();
        let mut bvh =
            Bvh { nodes: Vec::new(), tris: Vec::new(), order: Vec::new(), slot_of: vec![u32::MAX; vertices.len()], avx2, extent: 0.0 };
        if vertices.is_empty() {
            return Ok(bvh);
        }
        let input: Vec<Triangle> = vertices.iter().map(|v| Triangle { v0: v[0].into(), v1: v[1].into(), v2: v[2].into() }).collect();
        let mut params = BvhBuildParams::slow_build();
        params.max_prims_per_leaf = LEAF_SIZE;
        let b2 = obvhs::bvh2::builder::build_bvh2_from_tris(&input, params, &mut Duration::default());
        if b2.primitive_indices.len() >= MAX_SLOTS {
            return Err(CoreError::Invalid(format!(
                "{} triangles make {} BVH references, more than the {MAX_SLOTS} a BVH can address",
                vertices.len(),
                b2.primitive_indices.len()
            )));
        }
        bvh.order = b2.primitive_indices.clone();
        bvh.tris = bvh.order.iter().map(|&i| vertices[i as usize]).collect();
        for (k, &i) in bvh.order.iter().enumerate().rev() {
            bvh.slot_of[i as usize] = k as u32;
        }
        bvh.nodes = fold(&b2);
        bvh.extent = vertices.iter().flatten().fold(0f32, |m, v| m.max(v.abs().max_element()));
        Ok(bvh)
    }

    /// Builds the BVH over a scene's triangles as [`TriangleData`]
    /// (vertices p0, p0 + e1, p0 + e2: watertight only where those sums
    /// reproduce shared vertices exactly; scenes build from their meshes'
    /// vertices instead).
    pub fn from_triangles(triangles: &[TriangleData]) -> Result<Bvh> {
        let vertices: Vec<[Vec3; 3]> = triangles.iter().map(TriangleData::corners).collect();
        Bvh::build(&vertices)
    }

    /// Triangle references in the leaves (a triangle split by the builder's
    /// spatial splits is referenced more than once).
    pub fn primitive_count(&self) -> usize {
        self.tris.len()
    }

    /// Nodes of the tree.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes the BVH holds: its nodes, the triangles' vertices and the
    /// index tables (capacity not counted).
    pub fn memory_bytes(&self) -> usize {
        use std::mem::size_of;
        self.nodes.len() * size_of::<Node8>()
            + self.tris.len() * size_of::<[Vec3; 3]>()
            + (self.order.len() + self.slot_of.len()) * size_of::<u32>()
    }

    /// Whether rays run through the traversal compiled for AVX2 and FMA.
    pub fn uses_avx2(&self) -> bool {
        self.avx2
    }

    /// Closest hit: (scene triangle, t).
    #[inline]
    pub fn closest(&self, ray: &Ray) -> Option<(u32, f32)> {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            return self.closest_avx2(ray);
        }
        self.closest_in(ray)
    }

    /// Whether anything lies on `ray` within `[0, t_max]`.
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        #[cfg(target_arch = "x86_64")]
        if self.avx2 {
            return self.occluded_avx2(ray);
        }
        self.occluded_in(ray)
    }

    /// [`Bvh::closest_in`] compiled for AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)] // the call of a function compiled for AVX2 and FMA, made only where the CPU has them
    fn closest_avx2(&self, ray: &Ray) -> Option<(u32, f32)> {
        #[target_feature(enable = "avx2,fma")]
        fn run(bvh: &Bvh, ray: &Ray) -> Option<(u32, f32)> {
            bvh.closest_in(ray)
        }
        // SAFETY: `avx2` is set only where `is_x86_feature_detected!` found AVX2 and FMA.
        unsafe { run(self, ray) }
    }

    /// [`Bvh::occluded_in`] compiled for AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)] // as `closest_avx2`
    fn occluded_avx2(&self, ray: &Ray) -> bool {
        #[target_feature(enable = "avx2,fma")]
        fn run(bvh: &Bvh, ray: &Ray) -> bool {
            bvh.occluded_in(ray)
        }
        // SAFETY: as in `closest_avx2`.
        unsafe { run(self, ray) }
    }

    /// The closest-hit traversal.
    #[inline(always)]
    fn closest_in(&self, ray: &Ray) -> Option<(u32, f32)> {
        self.closest_on(ray, &mut Stack::new((0, 0.0)))
    }

    /// The occlusion traversal.
    #[inline(always)]
    fn occluded_in(&self, ray: &Ray) -> bool {
        self.occluded_on(ray, &mut Stack::new(0))
    }

    /// The closest-hit traversal: children entered nearest first, those
    /// beyond the best hit skipped.
    #[inline(always)]
    fn closest_on(&self, ray: &Ray, stack: &mut Stack<(u32, f32)>) -> Option<(u32, f32)> {
        // A non-finite ray would enter every box (NaN compares false).
        if self.nodes.is_empty() || !(ray.o.is_finite() && ray.d.is_finite()) {
            return None;
        }
        let (o, d) = (ray.o, ray.d);
        let (boxes, tri_ray) = (BoxRay::new(o, d), ShearedRay::new(o, d));
        let (mut best_t, mut best) = (ray.t_max, u32::MAX);
        let mut node = 0usize;
        let mut t_near = [0f32; WIDTH];
        loop {
            let n = &self.nodes[node];
            let mut mask = boxes.children_on(self.avx2, n, -BACKSTEP, best_t, &mut t_near);
            let entered = std::iter::from_fn(|| {
                let i = (mask != 0).then(|| mask.trailing_zeros() as usize)?;
                mask &= mask - 1;
                Some((n.child[i], t_near[i]))
            });
            stack.push_nearest_last(entered, |e| e.1);
            // The next inner node; leaves on the way are tested.
            loop {
                let Some((child, t)) = stack.pop() else {
                    return (best != u32::MAX).then(|| (self.order[best as usize], best_t));
                };
                if t > best_t {
                    continue;
                }
                if child & LEAF == 0 {
                    node = child as usize;
                    break;
                }
                let (first, count) = leaf_range(child);
                for s in first..first + count {
                    // Every hit is within [0, best_t]; the first of equals wins.
                    if let Some(t) = tri_ray.hit(&self.tris[s], best_t) {
                        if t < best_t || best == u32::MAX {
                            best_t = t;
                            best = s as u32;
                        }
                    }
                }
            }
        }
    }

    /// The occlusion traversal: the first hit ends it.
    #[inline(always)]
    fn occluded_on(&self, ray: &Ray, stack: &mut Stack<u32>) -> bool {
        if self.nodes.is_empty() || !(ray.o.is_finite() && ray.d.is_finite()) {
            return false;
        }
        let (o, d) = (ray.o, ray.d);
        let (boxes, tri_ray) = (BoxRay::new(o, d), ShearedRay::new(o, d));
        let t_max = ray.t_max;
        let mut node = 0usize;
        let mut t_near = [0f32; WIDTH];
        loop {
            let n = &self.nodes[node];
            let mut mask = boxes.children_on(self.avx2, n, -BACKSTEP, t_max, &mut t_near);
            while mask != 0 {
                let i = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                let child = n.child[i];
                if child & LEAF != 0 {
                    let (first, count) = leaf_range(child);
                    for s in first..first + count {
                        if tri_ray.hit(&self.tris[s], t_max).is_some() {
                            return true;
                        }
                    }
                } else {
                    stack.push(child);
                }
            }
            let Some(next) = stack.pop() else { return false };
            node = next as usize;
        }
    }

    /// The scene triangles in the leaves whose boxes overlap the box
    /// [`lo`, `hi`], each once and in ascending order, into `out` (cleared
    /// first). A leaf's box bounds all its triangles, so the caller tests
    /// each triangle itself; none that touches the box is left out.
    pub fn triangles_in_box(&self, lo: Vec3, hi: Vec3, out: &mut Vec<u32>) {
        out.clear();
        if self.nodes.is_empty() || !(lo.is_finite() && hi.is_finite()) {
            return;
        }
        let mut stack = vec![0u32];
        while let Some(node) = stack.pop() {
            let n = &self.nodes[node as usize];
            for i in 0..WIDTH {
                // An unused lane's empty box (lo +∞, hi −∞) overlaps nothing.
                let apart = (0..3).any(|a| n.lo[a][i] > hi[a] || n.hi[a][i] < lo[a]);
                if apart {
                    continue;
                }
                let child = n.child[i];
                if child & LEAF != 0 {
                    let (first, count) = leaf_range(child);
                    out.extend(self.order[first..first + count].iter().copied());
                } else {
                    stack.push(child);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    /// The vertices of scene triangle `tri` as the BVH tests them (`None`
    /// for a triangle it does not hold).
    pub fn vertices(&self, tri: u32) -> Option<[Vec3; 3]> {
        self.tris.get(*self.slot_of.get(tri as usize)? as usize).copied()
    }

    /// The parameter at which `ray` meets scene triangle `tri` within
    /// `[0, t_max]`, by the same test as [`Bvh::closest`], so a hit found
    /// elsewhere (a GPU) gets the t this BVH would report.
    pub fn triangle_t(&self, ray: &Ray, tri: u32) -> Option<f32> {
        ShearedRay::new(ray.o, ray.d).hit(&self.vertices(tri)?, ray.t_max)
    }
}

/// The first slot and the number of triangles of a leaf reference.
#[inline(always)]
fn leaf_range(child: u32) -> (usize, usize) {
    ((child & SLOT_MASK) as usize, ((child >> COUNT_SHIFT) & 7) as usize + 1)
}

/// Folds obvhs's binary tree into 8-wide nodes, depth first (a subtree's
/// nodes stay together). Each node gathers the children of a binary node
/// and keeps opening the inner one of largest surface area until it holds
/// eight or only leaves.
fn fold(b2: &Bvh2) -> Vec<Node8> {
    let is_leaf = |i: usize| b2.nodes[i].prim_count > 0;
    let area = |i: usize| b2.nodes[i].aabb.half_area();
    let mut nodes = vec![Node8::EMPTY];
    let mut todo = vec![(0usize, 0usize)];
    while let Some((at, root)) = todo.pop() {
        let mut set: Vec<usize> = if is_leaf(root) {
            vec![root]
        } else {
            let f = b2.nodes[root].first_index as usize;
            vec![f, f + 1]
        };
        while set.len() < WIDTH {
            let Some((k, _)) = set.iter().enumerate().filter(|(_, i)| !is_leaf(**i)).max_by(|a, b| area(*a.1).total_cmp(&area(*b.1)))
            else {
                break;
            };
            let f = b2.nodes[set[k]].first_index as usize;
            set[k] = f;
            set.insert(k + 1, f + 1);
        }
        let mut node = Node8::EMPTY;
        let mut inner = Vec::new();
        for (lane, &i) in set.iter().enumerate() {
            let b = &b2.nodes[i];
            let (lo, hi) = (Vec3::from(b.aabb.min), Vec3::from(b.aabb.max));
            if is_leaf(i) {
                node.set(lane, lo, hi, LEAF | (b.prim_count - 1) << COUNT_SHIFT | b.first_index);
            } else {
                let k = nodes.len() as u32;
                nodes.push(Node8::EMPTY);
                node.set(lane, lo, hi, k);
                inner.push((k as usize, i));
            }
        }
        nodes[at] = node;
        // Depth first: the last pushed is folded next.
        todo.extend(inner.into_iter().rev());
    }
    nodes
}

#[cfg(test)]
mod tests {
    use super::*;
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

    /// Boxes through `office`: the query returns every triangle whose own
    /// bounding box overlaps the box (testing every triangle), and only
    /// triangles in leaves that overlap it.
    #[test]
    fn a_box_query_finds_every_triangle_that_touches_the_box() {
        let s = crate::SceneSetup::builtin("office").unwrap().scene;
        let bvh = &s.geometry.bvh;
        let (lo, hi) = s.geometry.bounds;
        let mut rng = crate::rng::stream(3, 0, crate::rng::Purpose::TEST, 0);
        let mut out = Vec::new();
        for _ in 0..200 {
            let c = lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            let h = (hi - lo) * 0.05 * rng.next_f32();
            bvh.triangles_in_box(c - h, c + h, &mut out);
            assert!(out.windows(2).all(|w| w[0] < w[1]), "ascending, each once");
            for (t, tri) in s.geometry.triangles.iter().enumerate() {
                let v = [tri.p0, tri.p0 + tri.e1, tri.p0 + tri.e2];
                let (tlo, thi) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
                let touches = (tlo.cmple(c + h) & thi.cmpge(c - h)).all();
                if touches && tri.area > 0.0 {
                    assert!(out.binary_search(&(t as u32)).is_ok(), "triangle {t} touches the box and was left out");
                }
            }
        }
        bvh.triangles_in_box(Vec3::splat(1e6), Vec3::splat(1e6 + 1.0), &mut out);
        assert!(out.is_empty());
        bvh.triangles_in_box(lo, hi, &mut out);
        assert_eq!(out.len(), s.geometry.triangles.iter().filter(|t| t.area > 0.0).count(), "the scene's box holds them all");
    }

    /// Random rays through `office` (its 8-wide tree has several levels):
    /// the traversal finds what testing every triangle finds, the closest
    /// hit and whether a segment is blocked, and the AVX2 and baseline
    /// traversals agree bit for bit.
    #[test]
    fn traversal_finds_what_testing_every_triangle_finds() {
        let setup = crate::SceneSetup::builtin("office").unwrap();
        let scene = &setup.scene;
        let bvh = &scene.geometry.bvh;
        assert!(bvh.node_count() > 8, "{}", bvh.node_count());
        let tris: Vec<[Vec3; 3]> = scene.geometry.triangles.iter().map(TriangleData::corners).collect();
        let exact = Bvh::build(&tris).unwrap();
        let baseline = Bvh { avx2: false, ..Bvh::build(&tris).unwrap() };
        let (lo, hi) = scene.geometry.bounds;
        let mut rng = crate::rng::stream(3, 0, crate::rng::Purpose::TEST, 0);
        let mut point = || {
            let (u, v) = rng.next_2d();
            let w = rng.next_f32();
            lo + (hi - lo) * Vec3::new(u, v, w)
        };
        let (mut hits, mut blocked) = (0, 0);
        for n in 0..3000 {
            let (o, target) = (point(), point());
            let ray = if n % 2 == 0 {
                Ray::new(o, (target - o).normalize())
            } else {
                Ray::segment(o, (target - o).normalize(), (target - o).length())
            };
            let brute = tris
                .iter()
                .enumerate()
                .filter_map(|(i, v)| ShearedRay::new(ray.o, ray.d).hit(v, ray.t_max).map(|t| (i as u32, t)))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            let got = exact.closest(&ray);
            assert_eq!(got.map(|h| h.1), brute.map(|h| h.1), "ray {n}");
            assert_eq!(exact.occluded(&ray), brute.is_some(), "ray {n}");
            assert_eq!(baseline.closest(&ray), got, "ray {n}");
            assert_eq!(baseline.occluded(&ray), exact.occluded(&ray), "ray {n}");
            hits += got.is_some() as usize;
            blocked += (n % 2 == 1 && got.is_some()) as usize;
        }
        assert!(hits > 1000 && blocked > 300, "{hits} {blocked}");
        assert_eq!(bvh.closest(&Ray::new(Vec3::ZERO, Vec3::NAN)), None);
        assert!(!bvh.occluded(&Ray::new(Vec3::NAN, Vec3::Y)));
        let empty = Bvh::build(&[]).unwrap();
        assert_eq!((empty.closest(&Ray::new(Vec3::ZERO, Vec3::Y)), empty.occluded(&Ray::new(Vec3::ZERO, Vec3::Y))), (None, false));
    }
}

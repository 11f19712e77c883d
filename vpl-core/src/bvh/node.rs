//! An 8-wide BVH node with its children's boxes in structure-of-arrays
//! order, and the slab test of a ray against all eight at once.
//!
//! The test is written twice: with AVX intrinsics (one 8-wide step and one
//! mask move) for CPUs with AVX2 and FMA, and lane by lane over fixed
//! arrays of eight, which the compiler turns into two 4-wide SSE operations
//! per step, for the others; [`BoxRay::children_on`] picks one.

use glam::Vec3;

/// Children per node.
pub(crate) const WIDTH: usize = 8;

/// High bit of a child reference: the child is a leaf; bits 28–30 hold its
/// triangle count less one, bits 0–27 its first triangle slot.
pub(crate) const LEAF: u32 = 1 << 31;

/// Where a leaf reference's count starts.
pub(crate) const COUNT_SHIFT: u32 = 28;

/// The first-slot bits of a leaf reference.
pub(crate) const SLOT_MASK: u32 = (1 << COUNT_SHIFT) - 1;

/// Triangle slots a BVH can address.
pub(crate) const MAX_SLOTS: usize = 1 << COUNT_SHIFT;

/// Eight children: boxes (min and max per axis, one lane per child) and
/// references (an inner node's index, or a leaf: [`LEAF`], count and first
/// slot). An unused lane has an empty box (min +∞,
/// max −∞), which no ray enters.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct Node8 {
    pub lo: [[f32; WIDTH]; 3],
    pub hi: [[f32; WIDTH]; 3],
    pub child: [u32; WIDTH],
}

impl Node8 {
    /// A node with no children.
    pub(crate) const EMPTY: Node8 = Node8 { lo: [[f32::INFINITY; WIDTH]; 3], hi: [[f32::NEG_INFINITY; WIDTH]; 3], child: [0; WIDTH] };

    /// Puts a child with box (`lo`, `hi`) in lane `i`.
    pub(crate) fn set(&mut self, i: usize, lo: Vec3, hi: Vec3, child: u32) {
        for a in 0..3 {
            self.lo[a][i] = lo[a];
            self.hi[a][i] = hi[a];
        }
        self.child[i] = child;
    }
}

/// Smallest magnitude of a direction component in the slab test: a zero
/// component would give 0 · ∞ = NaN where a box face passes through the
/// origin; ±10⁻³⁰ keeps every product finite and the sign (so the near and
/// far faces) of the component.
pub(crate) const TINY: f32 = 1e-30;

/// Relative widening of the far distance, so that rounding never drops a
/// box the ray touches (Ize, "Robust BVH Ray Traversal", JCGT 2013: 1 + 2γ₃
/// for a subtraction and a multiplication; a little more here).
pub(crate) const FAR_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

/// A ray prepared for the slab test: inverse direction, origin times it,
/// and which face of each axis it meets first.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BoxRay {
    inv: [f32; 3],
    o_inv: [f32; 3],
    negative: [bool; 3],
}

impl BoxRay {
    #[inline(always)]
    pub(crate) fn new(o: Vec3, d: Vec3) -> BoxRay {
        let safe = |x: f32| if x.abs() < TINY { TINY.copysign(x) } else { x };
        let inv = [1.0 / safe(d.x), 1.0 / safe(d.y), 1.0 / safe(d.z)];
        BoxRay { inv, o_inv: [o.x * inv[0], o.y * inv[1], o.z * inv[2]], negative: [inv[0] < 0.0, inv[1] < 0.0, inv[2] < 0.0] }
    }

    /// The near and far faces of `n`'s boxes on each axis, as the ray meets them.
    #[inline(always)]
    fn faces<'n>(&self, n: &'n Node8) -> [(&'n [f32; WIDTH], &'n [f32; WIDTH]); 3] {
        let face = |a: usize| if self.negative[a] { (&n.hi[a], &n.lo[a]) } else { (&n.lo[a], &n.hi[a]) };
        [face(0), face(1), face(2)]
    }

    /// [`BoxRay::children`] with AVX: the same operations in the same order
    /// (multiply, subtract, max, min, an ordered ≤), so the same bits, with
    /// the hit mask taken by one `vmovmskps` (the lane loop's mask compiles
    /// to shuffles and ors, and cost up to 40 % of a shadow ray).
    ///
    /// # Safety
    /// The CPU must have AVX2 and FMA (`is_x86_feature_detected!`).
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)] // unaligned loads and a store through the nodes' and `t_near`'s own arrays
    #[target_feature(enable = "avx2,fma")]
    #[inline]
    pub(crate) unsafe fn children_avx2(&self, n: &Node8, t_min: f32, t_max: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        use std::arch::x86_64::*;
        let [(nx, fx), (ny, fy), (nz, fz)] = self.faces(n);
        // SAFETY: each load reads the 8 floats of a `[f32; 8]`.
        let load = |a: &[f32; WIDTH]| unsafe { _mm256_loadu_ps(a.as_ptr()) };
        let axis = |a: usize| (_mm256_set1_ps(self.inv[a]), _mm256_set1_ps(self.o_inv[a]));
        let ((ix, ox), (iy, oy), (iz, oz)) = (axis(0), axis(1), axis(2));
        let slab = |p: &[f32; WIDTH], i: __m256, o: __m256| _mm256_sub_ps(_mm256_mul_ps(load(p), i), o);
        let tn = _mm256_max_ps(_mm256_max_ps(slab(nx, ix, ox), slab(ny, iy, oy)), _mm256_max_ps(slab(nz, iz, oz), _mm256_set1_ps(t_min)));
        let tf = _mm256_min_ps(_mm256_min_ps(slab(fx, ix, ox), slab(fy, iy, oy)), _mm256_min_ps(slab(fz, iz, oz), _mm256_set1_ps(t_max)));
        let tf = _mm256_mul_ps(tf, _mm256_set1_ps(FAR_SCALE));
        // SAFETY: the store writes the 8 floats of `t_near`.
        unsafe { _mm256_storeu_ps(t_near.as_mut_ptr(), tn) };
        _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OQ>(tn, tf)) as u32
    }

    /// The children test on this CPU: [`BoxRay::children_avx2`] where
    /// `avx2` (set only where the CPU has AVX2 and FMA), else the lanes.
    #[inline(always)]
    #[allow(unsafe_code)] // the call of `children_avx2`, guarded by `avx2`
    pub(crate) fn children_on(&self, avx2: bool, n: &Node8, t_min: f32, t_max: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        #[cfg(target_arch = "x86_64")]
        if avx2 {
            // SAFETY: `avx2` is true only where `is_x86_feature_detected!` found AVX2 and FMA.
            return unsafe { self.children_avx2(n, t_min, t_max, t_near) };
        }
        let _ = avx2;
        self.children(n, t_min, t_max, t_near)
    }

    /// Which of `n`'s children the ray enters within `[t_min, t_max]`, as a
    /// bit mask, and each child's entry distance in `t_near`.
    #[inline(always)]
    pub(crate) fn children(&self, n: &Node8, t_min: f32, t_max: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        let [(nx, fx), (ny, fy), (nz, fz)] = self.faces(n);
        let [ix, iy, iz] = self.inv;
        let [ox, oy, oz] = self.o_inv;
        let mut mask = 0u32;
        for i in 0..WIDTH {
            // max/min as selects: no NaN can occur (see TINY), and the
            // selects compile to single max/min instructions.
            let max = |a: f32, b: f32| if a > b { a } else { b };
            let min = |a: f32, b: f32| if a < b { a } else { b };
            let tn = max(max(nx[i] * ix - ox, ny[i] * iy - oy), max(nz[i] * iz - oz, t_min));
            let tf = min(min(fx[i] * ix - ox, fy[i] * iy - oy), min(fz[i] * iz - oz, t_max)) * FAR_SCALE;
            t_near[i] = tn;
            mask |= ((tn <= tf) as u32) << i;
        }
        mask
    }
}

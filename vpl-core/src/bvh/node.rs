//! An 8-wide BVH node with its children's boxes in structure-of-arrays
//! order, and the slab test of a ray against all eight at once.
//!
//! The test is written lane by lane over fixed arrays of eight, which the
//! compiler turns into two 4-wide SSE operations per step, or one 8-wide
//! AVX2 operation in the traversal compiled for AVX2 (see `super`).

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
const TINY: f32 = 1e-30;

/// Relative widening of the far distance, so that rounding never drops a
/// box the ray touches (Ize, "Robust BVH Ray Traversal", JCGT 2013: 1 + 2γ₃
/// for a subtraction and a multiplication; a little more here).
const FAR_SCALE: f32 = 1.0 + 4.0 * f32::EPSILON;

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

    /// Which of `n`'s children the ray enters within `[t_min, t_max]`, as a
    /// bit mask, and each child's entry distance in `t_near`.
    #[inline(always)]
    pub(crate) fn children(&self, n: &Node8, t_min: f32, t_max: f32, t_near: &mut [f32; WIDTH]) -> u32 {
        let face = |a: usize| if self.negative[a] { (&n.hi[a], &n.lo[a]) } else { (&n.lo[a], &n.hi[a]) };
        let ((nx, fx), (ny, fy), (nz, fz)) = (face(0), face(1), face(2));
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

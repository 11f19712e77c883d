//! What eye paths, VPL paths and photons share at a scattering vertex
//! besides [`vpl_core::bsdf::scatter`]: Russian roulette on a relative
//! throughput.

use vpl_core::RngStream;
use vpl_core::glam::Vec3;

/// Russian roulette on a throughput `t` (relative to the path's start):
/// survival probability min(max channel, 0.95). Returns the factor to
/// divide by, or `None` when the path ends.
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
pub fn roulette(t: Vec3, rng: &mut RngStream) -> Option<f32> {
    let q = t.max_element().min(0.95);
    if !(q > 0.0) || rng.next_f32() >= q {
        return None;
    }
    Some(q)
}

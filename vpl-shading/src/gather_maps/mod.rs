//! The gather with shadow-map visibility, fused into one pass per VPL and
//! eight receivers wide: the geometry term and the test of
//! [`vpl_core::MapView::visible`] lane by lane, without the weight
//! array and the per-VPL dynamic call of the generic gather.
//!
//! Two implementations compute the same lanes with the same operations in
//! the same order: one with AVX2 intrinsics (one 256-bit register per step,
//! the map's texels fetched by one `vgatherdps`), chosen at
//! run time where the CPU has AVX2 and FMA, and one over `wide`'s 8-lane
//! type (two SSE halves) elsewhere. No fused multiply-add is written, so
//! both give the same bits.
//!
//! ## Approximations
//!
//! The exact loop spent most of its time in three divisions and two square
//! roots per lane. They are replaced by the processor's reciprocal and
//! reciprocal-square-root estimates (relative error at most 1.5 · 2⁻¹² on
//! x86) refined by one Newton step,
//!
//! ```text
//! 1/x  ≈ r (2 − x r),            r ≈ 1/x,
//! 1/√x ≈ r (3/2 − (x/2) r r),    r ≈ 1/√x,
//! ```
//!
//! which squares the estimate's error: at most (1.5 · 2⁻¹²)² ≈ 1.3 · 10⁻⁷
//! for the reciprocal and 3/2 of that for the square root, plus four
//! roundings of 2⁻²⁴: below 5 · 10⁻⁷ relative each. The geometry term takes
//! one reciprocal (G = cos θ_y cos θ_x · 1/d⁴) and the visibility test's
//! distance, texel and bias take two reciprocal square roots and two
//! reciprocals, so a receiver's weight is within about 10⁻⁶ relative of the
//! exact one, and a visibility decision can differ only where |x − y| − b
//! lies within about 10⁻⁶ of the texel's depth. The tests bound both.
//! √s for the bias's tan φ is s · 1/√s (0 at s = 0).

use crate::gather::Sums;
use vpl_core::glam::Vec3;
use vpl_core::{Receivers, ShadowMapSource, VplSet};

#[cfg(target_arch = "x86_64")]
mod avx2;
mod lanes;

/// Receivers per step.
const LANES: usize = 8;

/// Smallest argument of the reciprocal square root in the bias's √s, so
/// that s = 0 gives 0 · finite.
const TINY: f32 = 1e-30;

/// What the kernel needs of one VPL and its map.
#[derive(Clone, Copy)]
struct Light<'a> {
    /// Position and normal.
    y: Vec3,
    n_y: Vec3,
    /// The map's origin and frame (+Z along the normal).
    o: Vec3,
    s: Vec3,
    t: Vec3,
    n: Vec3,
    flux: Vec3,
    /// Half the map's side (texel coordinate = (u + 1) · half) and its last texel.
    half: f32,
    max: f32,
    /// The bias terms 2ε and k · 2/res.
    eps2: f32,
    texel: f32,
    g_max: f32,
    depth: &'a [f32],
    res: usize,
}

/// The VPLs of `slots` that have a map.
fn lights<'a>(vpls: &'a VplSet, slots: &'a [u32], sm: &'a dyn ShadowMapSource, g_max: f32) -> impl Iterator<Item = Light<'a>> + 'a {
    slots.iter().filter_map(move |&slot| {
        let v = vpls.get(slot as usize)?;
        let view = sm.map(slot as usize)?;
        let f = view.frame();
        let (eps2, texel) = view.bias_terms();
        let (depth, res) = view.depths();
        Some(Light {
            y: v.y,
            n_y: v.n,
            o: view.origin,
            s: f.s,
            t: f.t,
            n: f.n,
            flux: v.flux,
            half: view.half(),
            max: (res - 1) as f32,
            eps2,
            texel,
            g_max,
            depth,
            res,
        })
    })
}

/// Receivers `i..` (fewer than eight) in eight lanes: positions, then
/// normals; the lanes past the end sit at `pad` with a zero normal, which
/// no VPL at `pad` lights (d = 0).
fn tail(rx: &Receivers, i: usize, pad: Vec3) -> [[f32; LANES]; 6] {
    let mut c = [[0f32; LANES]; 6];
    for a in 0..3 {
        c[a] = [pad[a]; LANES];
    }
    let sources = [&rx.px, &rx.py, &rx.pz, &rx.nx, &rx.ny, &rx.nz];
    for (lanes, src) in c.iter_mut().zip(sources) {
        for (lane, v) in lanes.iter_mut().zip(&src[i.min(src.len())..]) {
            *lane = *v;
        }
    }
    c
}

/// Adds flux · w to the receivers `i..` (fewer than eight: the lanes of
/// `w` past the end are dropped), as the full steps add: the sum of a lane
/// and the product of flux and weight.
fn add_tail(sums: &mut Sums, i: usize, flux: Vec3, w: &[f32; LANES]) {
    for (a, f) in [(&mut sums.r, flux.x), (&mut sums.g, flux.y), (&mut sums.b, flux.z)] {
        for (s, w) in a[i..].iter_mut().zip(w) {
            *s += f * w;
        }
    }
}

/// Adds Σ flux · min(G, G_max) · V over the VPLs of `slots` to `sums`,
/// with visibility from `sm`'s maps.
pub(crate) fn gather_shadow_maps(rx: &Receivers, vpls: &VplSet, slots: &[u32], sm: &dyn ShadowMapSource, g_max: f32, sums: &mut Sums) {
    #[cfg(target_arch = "x86_64")]
    if avx2::gather(rx, lights(vpls, slots, sm, g_max), sums) {
        return;
    }
    lanes::gather(rx, lights(vpls, slots, sm, g_max), sums)
}

/// [`gather_shadow_maps`] on the portable lanes whatever the CPU (for
/// tests that compare the two implementations).
#[cfg(test)]
pub(crate) fn gather_shadow_maps_portable(
    rx: &Receivers,
    vpls: &VplSet,
    slots: &[u32],
    sm: &dyn ShadowMapSource,
    g_max: f32,
    sums: &mut Sums,
) {
    lanes::gather(rx, lights(vpls, slots, sm, g_max), sums)
}

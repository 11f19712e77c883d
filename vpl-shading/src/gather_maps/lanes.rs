//! The shadow-map gather over `wide`'s 8-lane type (two SSE halves on the
//! x86-64 baseline).

use super::{LANES, Light, TINY, add_tail, tail};
use crate::gather::Sums;
use vpl_core::Receivers;
use wide::{CmpGt, CmpLe, f32x8};

#[inline(always)]
fn s8(x: f32) -> f32x8 {
    f32x8::splat(x)
}

/// 1/x: the estimate and one Newton step, r (2 − x r).
#[inline(always)]
fn rcp(x: f32x8) -> f32x8 {
    let r = x.recip();
    r * (s8(2.0) - x * r)
}

/// 1/√x: the estimate and one Newton step, r (3/2 − (x/2) r r).
#[inline(always)]
fn rsqrt(x: f32x8) -> f32x8 {
    let r = x.recip_sqrt();
    r * (s8(1.5) - (s8(0.5) * x) * (r * r))
}

/// The weight flux-free min(G, G_max) · V of eight receivers (positions
/// `p`, normals `n`) from light `l`.
#[inline(always)]
fn weights(l: &Light, p: [f32x8; 3], n: [f32x8; 3]) -> Option<f32x8> {
    let zero = f32x8::ZERO;
    let one = f32x8::ONE;
    let [px, py, pz] = p;
    let [nx, ny, nz] = n;
    let (dx, dy, dz) = (px - s8(l.y.x), py - s8(l.y.y), pz - s8(l.y.z));
    let d2 = (dx * dx + dy * dy) + dz * dz;
    let cos_y = (s8(l.n_y.x) * dx + s8(l.n_y.y) * dy) + s8(l.n_y.z) * dz;
    let cos_x = -((nx * dx + ny * dy) + nz * dz);
    let lit = cos_y.cmp_gt(zero) & cos_x.cmp_gt(zero) & d2.cmp_gt(zero);
    if lit.none() {
        return None;
    }
    let gt = ((cos_y * cos_x) * rcp(d2 * d2)).fast_min(s8(l.g_max));
    // Visibility, as MapView::visible.
    let (ex, ey, ez) = (px - s8(l.o.x), py - s8(l.o.y), pz - s8(l.o.z));
    let e2 = (ex * ex + ey * ey) + ez * ez;
    let cos_xo = -((nx * ex + ny * ey) + nz * ez);
    let inv = rsqrt(e2);
    let dist = e2 * inv;
    let lz = ((ex * s8(l.n.x) + ey * s8(l.n.y)) + ez * s8(l.n.z)) * inv;
    let k = inv * rcp(one + lz);
    let half = s8(l.half);
    let u = (((ex * s8(l.s.x) + ey * s8(l.s.y)) + ez * s8(l.s.z)) * k + one) * half;
    let w = (((ex * s8(l.t.x) + ey * s8(l.t.y)) + ez * s8(l.t.z)) * k + one) * half;
    // Texel indices clamped into the map (max and min as x86's: a NaN
    // coordinate takes the second operand, texel 0).
    let (ua, wa) = (u.fast_max(zero).fast_min(s8(l.max)).to_array(), w.fast_max(zero).fast_min(s8(l.max)).to_array());
    let mut depth = [0.0f32; LANES];
    for k in 0..LANES {
        depth[k] = l.depth[wa[k] as usize * l.res + ua[k] as usize];
    }
    let cos_r = (cos_xo * inv).abs();
    let s2 = (one - cos_r * cos_r).fast_max(zero);
    let tan = ((s2 * rsqrt(s2.fast_max(s8(TINY)))) * rcp(cos_r.fast_max(s8(0.1)))).fast_min(s8(10.0));
    let bias = s8(l.eps2) + ((s8(l.texel) * dist) * (one + lz)) * (s8(0.5) + tan);
    let seen = ((dist - bias).cmp_le(f32x8::from(depth)) & lz.cmp_gt(zero)) | e2.cmp_le(zero);
    let m = lit & seen;
    (!m.none()).then(|| m.blend(gt, zero))
}

/// Adds each light's flux times the weights to `sums`.
pub(super) fn gather<'a>(rx: &Receivers, lights: impl Iterator<Item = Light<'a>>, sums: &mut Sums) {
    let n = rx.len();
    let full = n / LANES * LANES;
    let load = |a: &[f32], i: usize| f32x8::from(<[f32; LANES]>::try_from(&a[i..i + LANES]).expect("eight lanes"));
    for l in lights {
        // Adds flux · weight to the eight receivers i..i + 8.
        let acc = |sums: &mut Sums, i: usize, wgt: f32x8| {
            for (a, f) in [(&mut sums.r, l.flux.x), (&mut sums.g, l.flux.y), (&mut sums.b, l.flux.z)] {
                let v = (load(a, i) + s8(f) * wgt).to_array();
                a[i..i + LANES].copy_from_slice(&v);
            }
        };
        for i in (0..full).step_by(LANES) {
            let p = [load(&rx.px, i), load(&rx.py, i), load(&rx.pz, i)];
            let nn = [load(&rx.nx, i), load(&rx.ny, i), load(&rx.nz, i)];
            if let Some(wgt) = weights(&l, p, nn) {
                acc(sums, i, wgt);
            }
        }
        if full < n {
            let c = tail(rx, full, l.y).map(f32x8::from);
            if let Some(wgt) = weights(&l, [c[0], c[1], c[2]], [c[3], c[4], c[5]]) {
                add_tail(sums, full, l.flux, &wgt.to_array());
            }
        }
    }
}

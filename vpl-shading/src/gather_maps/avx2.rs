//! The shadow-map gather with AVX2 intrinsics: the operations of
//! [`super::lanes`] in the same order on 256-bit registers, and the map's
//! texels fetched with one gather instruction per eight receivers.

use super::{LANES, Light, TINY, add_tail, tail};
use crate::gather::Sums;
use std::arch::x86_64::*;
use vpl_core::Receivers;

/// Adds each light's flux times the weights to `sums`; false (and nothing
/// added) where the CPU lacks AVX2 or FMA.
#[allow(unsafe_code)] // the call of a function compiled for AVX2 and FMA, made only where the CPU has them
pub(super) fn gather<'a>(rx: &Receivers, lights: impl Iterator<Item = Light<'a>>, sums: &mut Sums) -> bool {
    if !vpl_core::cpu::has_avx2_fma() {
        return false;
    }
    // SAFETY: the CPU has AVX2 and FMA (checked above).
    unsafe { run(rx, lights, sums) };
    true
}

/// The kernel.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[allow(unsafe_code)] // loads and stores through the receivers' and sums' own slices, and the texel gather
#[target_feature(enable = "avx2,fma")]
unsafe fn run<'a>(rx: &Receivers, lights: impl Iterator<Item = Light<'a>>, sums: &mut Sums) {
    let n = rx.len();
    let full = n / LANES * LANES;
    let s8 = |x: f32| _mm256_set1_ps(x);
    // SAFETY: each load reads the eight floats of a `[f32; 8]`.
    let load = |a: &[f32; LANES]| unsafe { _mm256_loadu_ps(a.as_ptr()) };
    let at = |a: &[f32], i: usize| load(a[i..i + LANES].try_into().expect("eight lanes"));
    let (zero, one) = (_mm256_setzero_ps(), s8(1.0));
    // 1/x and 1/√x: the estimates and one Newton step (see the module notes of `gather_maps`).
    let rcp = |x: __m256| {
        let r = _mm256_rcp_ps(x);
        _mm256_mul_ps(r, _mm256_sub_ps(s8(2.0), _mm256_mul_ps(x, r)))
    };
    let rsqrt = |x: __m256| {
        let r = _mm256_rsqrt_ps(x);
        _mm256_mul_ps(r, _mm256_sub_ps(s8(1.5), _mm256_mul_ps(_mm256_mul_ps(s8(0.5), x), _mm256_mul_ps(r, r))))
    };
    let (add, sub, mul) = (|a, b| _mm256_add_ps(a, b), |a, b| _mm256_sub_ps(a, b), |a, b| _mm256_mul_ps(a, b));
    let dot = |a: [__m256; 3], b: [__m256; 3]| add(add(mul(a[0], b[0]), mul(a[1], b[1])), mul(a[2], b[2]));
    let neg = |a: __m256| _mm256_xor_ps(a, s8(-0.0));
    let gt = |a, b| _mm256_cmp_ps::<_CMP_GT_OQ>(a, b);
    let le = |a, b| _mm256_cmp_ps::<_CMP_LE_OQ>(a, b);
    let none = |m: __m256| _mm256_movemask_ps(m) == 0;
    for l in lights {
        let y = [s8(l.y.x), s8(l.y.y), s8(l.y.z)];
        let n_y = [s8(l.n_y.x), s8(l.n_y.y), s8(l.n_y.z)];
        let o = [s8(l.o.x), s8(l.o.y), s8(l.o.z)];
        let (fs, ft, fnn) = ([s8(l.s.x), s8(l.s.y), s8(l.s.z)], [s8(l.t.x), s8(l.t.y), s8(l.t.z)], [s8(l.n.x), s8(l.n.y), s8(l.n.z)]);
        let (half, max, g_max) = (s8(l.half), s8(l.max), s8(l.g_max));
        let res = _mm256_set1_epi32(l.res as i32);
        // The weight min(G, G_max) · V of eight receivers, as `lanes::weights`.
        let weights = |p: [__m256; 3], nn: [__m256; 3]| -> Option<__m256> {
            let d = [sub(p[0], y[0]), sub(p[1], y[1]), sub(p[2], y[2])];
            let d2 = dot(d, d);
            let cos_y = dot(n_y, d);
            let cos_x = neg(dot(nn, d));
            let lit = _mm256_and_ps(_mm256_and_ps(gt(cos_y, zero), gt(cos_x, zero)), gt(d2, zero));
            if none(lit) {
                return None;
            }
            let g = _mm256_min_ps(mul(mul(cos_y, cos_x), rcp(mul(d2, d2))), g_max);
            let e = [sub(p[0], o[0]), sub(p[1], o[1]), sub(p[2], o[2])];
            let e2 = dot(e, e);
            let cos_xo = neg(dot(nn, e));
            let inv = rsqrt(e2);
            let dist = mul(e2, inv);
            let lz = mul(dot(e, fnn), inv);
            let k = mul(inv, rcp(add(one, lz)));
            let u = mul(add(mul(dot(e, fs), k), one), half);
            let w = mul(add(mul(dot(e, ft), k), one), half);
            // Texel indices clamped into the map (a NaN coordinate takes texel 0).
            let clamp = |x| _mm256_cvttps_epi32(_mm256_min_ps(_mm256_max_ps(x, zero), max));
            let idx = _mm256_add_epi32(_mm256_mullo_epi32(clamp(w), res), clamp(u));
            // SAFETY: every index is j · res + i with i, j in 0..res, inside
            // the map's res² texels (MapView checks the slice's length).
            let depth = unsafe { _mm256_i32gather_ps::<4>(l.depth.as_ptr(), idx) };
            let cos_r = _mm256_andnot_ps(s8(-0.0), mul(cos_xo, inv));
            let s2 = _mm256_max_ps(sub(one, mul(cos_r, cos_r)), zero);
            let tan = _mm256_min_ps(mul(mul(s2, rsqrt(_mm256_max_ps(s2, s8(TINY)))), rcp(_mm256_max_ps(cos_r, s8(0.1)))), s8(10.0));
            let bias = add(s8(l.eps2), mul(mul(mul(s8(l.texel), dist), add(one, lz)), add(s8(0.5), tan)));
            let seen = _mm256_or_ps(_mm256_and_ps(le(sub(dist, bias), depth), gt(lz, zero)), le(e2, zero));
            let m = _mm256_and_ps(lit, seen);
            (!none(m)).then(|| _mm256_blendv_ps(zero, g, m))
        };
        // Adds flux · weight to the eight receivers i..i + 8.
        let acc = |sums: &mut Sums, i: usize, wgt: __m256| {
            for (a, f) in [(&mut sums.r, l.flux.x), (&mut sums.g, l.flux.y), (&mut sums.b, l.flux.z)] {
                let a: &mut [f32; LANES] = (&mut a[i..i + LANES]).try_into().expect("eight lanes");
                // SAFETY: the load and the store read and write the eight floats of `a`.
                unsafe { _mm256_storeu_ps(a.as_mut_ptr(), add(_mm256_loadu_ps(a.as_ptr()), mul(s8(f), wgt))) };
            }
        };
        for i in (0..full).step_by(LANES) {
            let p = [at(&rx.px, i), at(&rx.py, i), at(&rx.pz, i)];
            let nn = [at(&rx.nx, i), at(&rx.ny, i), at(&rx.nz, i)];
            if let Some(wgt) = weights(p, nn) {
                acc(sums, i, wgt);
            }
        }
        if full < n {
            let c = tail(rx, full, l.y);
            if let Some(wgt) = weights([load(&c[0]), load(&c[1]), load(&c[2])], [load(&c[3]), load(&c[4]), load(&c[5])]) {
                let mut w = [0f32; LANES];
                // SAFETY: the store writes the eight floats of `w`.
                unsafe { _mm256_storeu_ps(w.as_mut_ptr(), wgt) };
                add_tail(sums, full, l.flux, &w);
            }
        }
    }
}

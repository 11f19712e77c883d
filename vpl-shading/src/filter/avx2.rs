//! The filter's rows with AVX2 intrinsics: the operations of
//! [`super::lanes`] in the same order on 256-bit registers.

use super::{E, EXP_MIN, EXP_ROUND, EXP_TAYLOR, K, LANES, N, P, Planes};
use std::arch::x86_64::*;
use vpl_core::glam::Vec3;

/// Filters row `y` of `pl` into `out`; false (and nothing written) where
/// the CPU lacks AVX2 or FMA.
#[allow(unsafe_code)] // the call of a function compiled for AVX2 and FMA, made only where the CPU has them
pub(super) fn row(pl: &Planes, alpha: u32, y: usize, out: &mut [Vec3]) -> bool {
    if !vpl_core::cpu::has_avx2_fma() {
        return false;
    }
    // SAFETY: the CPU has AVX2 and FMA (checked above).
    unsafe { run(pl, alpha, y, out) };
    true
}

/// The kernel.
///
/// # Safety
/// The CPU must have AVX2 and FMA.
#[allow(unsafe_code)] // loads and stores through the planes' own slices and local arrays
#[target_feature(enable = "avx2,fma")]
unsafe fn run(pl: &Planes, alpha: u32, y: usize, out: &mut [Vec3]) {
    let s8 = |x: f32| _mm256_set1_ps(x);
    // SAFETY: each load reads the eight floats of a `[f32; 8]`.
    let at = |c: usize, row: usize, col: usize| unsafe { _mm256_loadu_ps(pl.lanes(c, row, col).as_ptr()) };
    let store = |v: __m256| {
        let mut a = [0f32; LANES];
        // SAFETY: the store writes the eight floats of `a`.
        unsafe { _mm256_storeu_ps(a.as_mut_ptr(), v) };
        a
    };
    let (add, sub, mul) = (|a, b| _mm256_add_ps(a, b), |a, b| _mm256_sub_ps(a, b), |a, b| _mm256_mul_ps(a, b));
    let (zero, one) = (_mm256_setzero_ps(), s8(1.0));
    let [c2, c3, c4, c5, c6] = EXP_TAYLOR.map(s8);
    // eˣ for x ≤ 0, as `lanes::exp_neg`.
    let exp_neg = |x: __m256| {
        let valid = _mm256_cmp_ps::<_CMP_GE_OQ>(x, s8(EXP_MIN));
        let x = _mm256_blendv_ps(zero, x, valid);
        let y = mul(x, s8(std::f32::consts::LOG2_E));
        let rounded = add(y, s8(EXP_ROUND));
        let n = sub(rounded, s8(EXP_ROUND));
        let g = mul(sub(y, n), s8(std::f32::consts::LN_2));
        let p = add(one, mul(g, add(one, mul(g, add(c2, mul(g, add(c3, mul(g, add(c4, mul(g, add(c5, mul(g, c6))))))))))));
        let n = _mm256_sub_epi32(_mm256_castps_si256(rounded), _mm256_set1_epi32(EXP_ROUND.to_bits() as i32));
        let scale = _mm256_castsi256_ps(_mm256_slli_epi32::<23>(_mm256_add_epi32(n, _mm256_set1_epi32(127))));
        _mm256_blendv_ps(zero, mul(p, scale), valid)
    };
    for x0 in (0..pl.width).step_by(LANES) {
        let (row, col) = (y + pl.r, x0 + pl.r);
        let p = [at(P, row, col), at(P + 1, row, col), at(P + 2, row, col)];
        let n = [at(N, row, col), at(N + 1, row, col), at(N + 2, row, col)];
        let kp = at(K, row, col);
        let mut sum = [zero; 3];
        let mut wsum = zero;
        for &(dy, dx, t) in &pl.taps {
            let (qr, qc) = (y + dy, x0 + dx);
            let dot = add(add(mul(n[0], at(N, qr, qc)), mul(n[1], at(N + 1, qr, qc))), mul(n[2], at(N + 2, qr, qc)));
            let mut base = _mm256_blendv_ps(zero, dot, _mm256_cmp_ps::<_CMP_GT_OQ>(dot, zero));
            let (mut wn, mut k) = (one, alpha);
            while k > 0 {
                if k & 1 == 1 {
                    wn = mul(wn, base);
                }
                base = mul(base, base);
                k >>= 1;
            }
            let d = [sub(p[0], at(P, qr, qc)), sub(p[1], at(P + 1, qr, qc)), sub(p[2], at(P + 2, qr, qc))];
            let d2 = add(add(mul(d[0], d[0]), mul(d[1], d[1])), mul(d[2], d[2]));
            let wd = exp_neg(mul(_mm256_xor_ps(d2, s8(-0.0)), kp));
            let empty = _mm256_cmp_ps::<_CMP_EQ_OQ>(at(K, qr, qc), zero);
            let wt = _mm256_blendv_ps(mul(mul(s8(t), wn), wd), zero, empty);
            for (a, sum) in sum.iter_mut().enumerate() {
                *sum = add(*sum, mul(at(E + a, qr, qc), wt));
            }
            wsum = add(wsum, wt);
        }
        pl.finish(y, x0, sum.map(store), store(wsum), out);
    }
}

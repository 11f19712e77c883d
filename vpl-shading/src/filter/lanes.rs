//! The filter's rows on `wide`'s 8-lane type (two SSE halves on the x86-64
//! baseline).

use super::{E, EXP_MIN, EXP_ROUND, EXP_TAYLOR, K, LANES, N, P, Planes};
use vpl_core::glam::Vec3;
use wide::{CmpEq, CmpGe, CmpGt, f32x8, i32x8};

#[inline(always)]
fn s8(x: f32) -> f32x8 {
    f32x8::splat(x)
}

/// eˣ for x ≤ 0, lane by lane: the steps of `exp_neg`.
#[inline(always)]
fn exp_neg(x: f32x8) -> f32x8 {
    let valid = x.cmp_ge(s8(EXP_MIN));
    let x = valid.blend(x, f32x8::ZERO);
    let y = x * s8(std::f32::consts::LOG2_E);
    let rounded = y + s8(EXP_ROUND);
    let n = rounded - s8(EXP_ROUND);
    let g = (y - n) * s8(std::f32::consts::LN_2);
    let [c2, c3, c4, c5, c6] = EXP_TAYLOR.map(s8);
    let one = f32x8::ONE;
    let p = one + g * (one + g * (c2 + g * (c3 + g * (c4 + g * (c5 + g * c6)))));
    let n: i32x8 = bytemuck::cast::<f32x8, i32x8>(rounded) - i32x8::splat(EXP_ROUND.to_bits() as i32);
    let scale: f32x8 = bytemuck::cast((n + i32x8::splat(127)) << 23);
    valid.blend(p * scale, f32x8::ZERO)
}

/// Filters row `y` of `pl` into `out`.
pub(super) fn row(pl: &Planes, alpha: u32, y: usize, out: &mut [Vec3]) {
    let at = |c: usize, row: usize, col: usize| f32x8::from(*pl.lanes(c, row, col));
    let zero = f32x8::ZERO;
    for x0 in (0..pl.width).step_by(LANES) {
        let (row, col) = (y + pl.r, x0 + pl.r);
        let p = [at(P, row, col), at(P + 1, row, col), at(P + 2, row, col)];
        let n = [at(N, row, col), at(N + 1, row, col), at(N + 2, row, col)];
        let kp = at(K, row, col);
        let mut sum = [zero; 3];
        let mut wsum = zero;
        for &(dy, dx, t) in &pl.taps {
            let (qr, qc) = (y + dy, x0 + dx);
            let dot = n[0] * at(N, qr, qc) + n[1] * at(N + 1, qr, qc) + n[2] * at(N + 2, qr, qc);
            // max(0, n_p · n_q)^α by squaring, as `pow_u`.
            let mut base = dot.cmp_gt(zero).blend(dot, zero);
            let (mut wn, mut k) = (f32x8::ONE, alpha);
            while k > 0 {
                if k & 1 == 1 {
                    wn *= base;
                }
                base *= base;
                k >>= 1;
            }
            let d = [p[0] - at(P, qr, qc), p[1] - at(P + 1, qr, qc), p[2] - at(P + 2, qr, qc)];
            let wd = exp_neg(-(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * kp);
            // A pixel that reflects nothing gives no weight.
            let wt = at(K, qr, qc).cmp_eq(zero).blend(zero, s8(t) * wn * wd);
            for (a, sum) in sum.iter_mut().enumerate() {
                *sum += at(E + a, qr, qc) * wt;
            }
            wsum += wt;
        }
        pl.finish(y, x0, sum.map(|v| v.to_array()), wsum.to_array(), out);
    }
}

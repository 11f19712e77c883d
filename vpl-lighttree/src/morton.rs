//! Morton codes: 21 bits a coordinate, interleaved into 63, so that sorting
//! by code puts nearby lights next to each other (the order the tree is
//! built in).

use glam::Vec3;

/// The 63-bit Morton code of `p` in the box [`lo`, `lo + extent`].
pub(crate) fn code(p: Vec3, lo: Vec3, extent: Vec3) -> u64 {
    let scale = (1u32 << 21) as f32;
    let q = |a: usize| {
        let e = extent[a];
        let t = if e > 0.0 { (p[a] - lo[a]) / e } else { 0.0 };
        ((t * scale) as i64).clamp(0, (1 << 21) - 1) as u64
    };
    spread(q(0)) | (spread(q(1)) << 1) | (spread(q(2)) << 2)
}

/// The 21 low bits of `v`, each moved to every third bit.
fn spread(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_interleave_x_first() {
        assert_eq!(spread(0b111), 0b1001001);
        assert_eq!(spread((1 << 21) - 1).count_ones(), 21);
        let (lo, e) = (Vec3::ZERO, Vec3::ONE);
        assert_eq!(code(Vec3::ZERO, lo, e), 0);
        assert!(code(Vec3::new(0.6, 0.0, 0.0), lo, e) & 1 << 62 == 0 && code(Vec3::new(0.0, 0.0, 0.6), lo, e) >> 62 == 1);
        assert_eq!(code(Vec3::ONE, lo, e), (1 << 63) - 1, "the far corner saturates every bit");
    }
}

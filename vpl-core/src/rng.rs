//! Seeded random streams keyed by (seed, frame, purpose, index).
//!
//! Every random decision in the toolkit draws from a [`RngStream`] made by
//! [`stream`]: the key names *why* numbers are drawn ([`Purpose`]) and for
//! *which* item (a pixel, a light path, a VPL id), so results do not depend on
//! thread count or on the order in which work is scheduled.

use rand_core::Rng;
use rand_pcg::Pcg32;

/// Why random numbers are drawn; one value per use, so two uses never share numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Purpose(pub u64);

impl Purpose {
    /// Camera paths of a pixel (index = pixel index y·w + x).
    pub const PIXEL: Purpose = Purpose(1);
    /// Light paths (index = path index).
    pub const LIGHT_PATH: Purpose = Purpose(2);
    /// Radiosity estimates of a VPL (index = VPL id).
    pub const RADIOSITY: Purpose = Purpose(3);
    /// Tracked-pixel ground truth (index = tracked pixel number).
    pub const TRACKED: Purpose = Purpose(4);
    /// Scene generation (procedural layouts).
    pub const SCENE: Purpose = Purpose(5);
    /// Tests and benchmarks.
    pub const TEST: Purpose = Purpose(6);
    /// Scrambles of low-discrepancy sequences (index = dimension).
    pub const SCRAMBLE: Purpose = Purpose(7);
    /// Assignment of VPL slots to interleaved-shading subsets (index 0).
    pub const INTERLEAVE: Purpose = Purpose(8);
    /// Light samples of deterministic direct lighting (index = pixel index).
    pub const DIRECT: Purpose = Purpose(9);
    /// Camera points a VPL sampler casts (index = point number).
    pub const CAMERA_POINTS: Purpose = Purpose(10);
    /// Candidate rays of the SMC sampler (index = candidate ray).
    pub const CANDIDATE: Purpose = Purpose(11);
    /// Weighted resampling of candidates (index = draw).
    pub const RESAMPLE: Purpose = Purpose(12);
    /// Indirect-visibility rays toward a VPL (index = VPL slot).
    pub const INDIRECT_VISIBILITY: Purpose = Purpose(13);
    /// Russian-roulette acceptance of VPL candidates (index = candidate).
    pub const ACCEPT: Purpose = Purpose(14);
    /// Markov chains of Metropolis samplers (index = chain).
    pub const CHAIN: Purpose = Purpose(15);
    /// Independent (bootstrap or large-step) samples of a Metropolis sampler (index = sample).
    pub const BOOTSTRAP: Purpose = Purpose(16);
    /// Thinning a VPL set down to its budget (index 0).
    pub const THIN: Purpose = Purpose(17);
    /// Caustic photons of the progressive renderer (index = photon number in the pass).
    pub const PHOTON: Purpose = Purpose(18);
    /// Stochastic VPL culling decisions (index = VPL number in the pass).
    pub const CULL: Purpose = Purpose(19);
    /// Gather rays of the clamp's bias compensation (index = pixel).
    pub const COMPENSATION: Purpose = Purpose(20);
    /// Bootstrap draws of a table's confidence intervals (index = table row).
    pub const CONFIDENCE: Purpose = Purpose(21);
    /// Light samples of the check of what a camera sees (index = grid ray).
    pub const VIEW: Purpose = Purpose(22);
    /// The point of its cell a VPL shines from (index = the VPL's id).
    pub const PLACEMENT: Purpose = Purpose(23);
    /// The lights a stochastic lightcut samples (index = pixel).
    pub const LIGHTCUT: Purpose = Purpose(24);
    /// Tracked-pixel ground truth on a device, in chunks of samples small
    /// enough to spread over its threads (index = tracked pixel number · 2³²
    /// + chunk number).
    pub const TRACKED_CHUNK: Purpose = Purpose(25);
}

/// SplitMix64 finaliser: a bijective 64-bit mix.
#[inline]
pub fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The key the streams (seed, frame, purpose, ·) share: [`stream`] and
/// [`stream_state`] of index i are [`keyed_state`]`(key, i)`'s, so a kernel
/// given one key per (seed, frame, purpose) derives every index's stream
/// itself.
#[inline]
pub fn stream_key(seed: u64, frame: u64, purpose: Purpose) -> u64 {
    mix64(mix64(mix64(seed) ^ frame) ^ purpose.0.wrapping_mul(0xD1B5_4A32_D192_ED03))
}

/// rand_pcg's `Pcg32::new` arguments (state, stream) of index `index` under `key`.
#[inline]
fn keyed_seed(key: u64, index: u64) -> (u64, u64) {
    (mix64(key ^ index), mix64(key.rotate_left(17) ^ index.wrapping_mul(0x9E37_79B9_7F4A_7C15)))
}

/// The stream for (seed, frame, purpose, index).
#[inline]
pub fn stream(seed: u64, frame: u64, purpose: Purpose, index: u64) -> RngStream {
    keyed_stream(stream_key(seed, frame, purpose), index)
}

/// Stream `index` under a [`stream_key`]: `stream(seed, frame, purpose, i)`
/// is `keyed_stream(stream_key(seed, frame, purpose), i)`.
#[inline]
pub fn keyed_stream(key: u64, index: u64) -> RngStream {
    let (state, sequence) = keyed_seed(key, index);
    RngStream { pcg: Pcg32::new(state, sequence) }
}

/// The PCG32 (XSH RR 64/32) state and increment of [`stream`]`(seed, frame,
/// purpose, index)` before its first draw, for kernels that run the same
/// stream elsewhere (a GPU): draw k outputs XSH RR of the state, then the
/// state becomes state · 6364136223846793005 + increment (mod 2⁶⁴).
pub fn stream_state(seed: u64, frame: u64, purpose: Purpose, index: u64) -> (u64, u64) {
    keyed_state(stream_key(seed, frame, purpose), index)
}

/// [`stream_state`] of index `index` under a [`stream_key`].
pub fn keyed_state(key: u64, index: u64) -> (u64, u64) {
    let (state, sequence) = keyed_seed(key, index);
    // As rand_pcg's Pcg32::new: an odd increment, one step away from the seed.
    let increment = (sequence << 1) | 1;
    (state.wrapping_add(increment).wrapping_mul(PCG_MULTIPLIER).wrapping_add(increment), increment)
}

/// The LCG multiplier of PCG32.
pub const PCG_MULTIPLIER: u64 = 6_364_136_223_846_793_005;

/// A PCG32 stream with the few draws a renderer needs.
#[derive(Clone, Debug)]
pub struct RngStream {
    pcg: Pcg32,
}

impl RngStream {
    /// Uniform in [0, 1), 24 bits of precision (never returns 1.0).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.pcg.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniforms in [0, 1).
    #[inline]
    pub fn next_2d(&mut self) -> (f32, f32) {
        (self.next_f32(), self.next_f32())
    }

    /// Uniform 32-bit integer.
    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        self.pcg.next_u32()
    }

    /// Uniform integer in `0..n` (n > 0), by Lemire's multiply-shift (bias < n / 2³²).
    #[inline]
    pub fn below(&mut self, n: u32) -> u32 {
        ((self.pcg.next_u32() as u64 * n as u64) >> 32) as u32
    }

    /// The underlying generator, for use with the `rand` API (`RngExt`).
    pub fn pcg(&mut self) -> &mut Pcg32 {
        &mut self.pcg
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn stream_state_runs_the_same_stream() {
        for (seed, index) in [(0u64, 0u64), (7, 3), (u64::MAX, 1 << 40)] {
            let (mut state, inc) = super::stream_state(seed, 5, Purpose::RADIOSITY, index);
            let mut rng = super::stream(seed, 5, Purpose::RADIOSITY, index);
            for _ in 0..20 {
                let rot = (state >> 59) as u32;
                let xsh = (((state >> 18) ^ state) >> 27) as u32;
                assert_eq!(xsh.rotate_right(rot), rng.next_u32());
                state = state.wrapping_mul(super::PCG_MULTIPLIER).wrapping_add(inc);
            }
        }
    }

    use super::*;

    #[test]
    fn same_key_same_numbers_different_key_different_numbers() {
        let a: Vec<u32> = (0..8).map(|_| 0).scan(stream(1, 2, Purpose::PIXEL, 3), |s, _| Some(s.next_u32())).collect();
        let b: Vec<u32> = (0..8).map(|_| 0).scan(stream(1, 2, Purpose::PIXEL, 3), |s, _| Some(s.next_u32())).collect();
        assert_eq!(a, b);
        for other in [
            stream(2, 2, Purpose::PIXEL, 3),
            stream(1, 3, Purpose::PIXEL, 3),
            stream(1, 2, Purpose::LIGHT_PATH, 3),
            stream(1, 2, Purpose::PIXEL, 4),
        ] {
            let c: Vec<u32> = (0..8).map(|_| 0).scan(other, |s, _| Some(s.next_u32())).collect();
            assert_ne!(a, c);
        }
    }

    #[test]
    fn uniforms_are_in_range_with_the_right_mean() {
        let mut s = stream(7, 0, Purpose::TEST, 0);
        let n = 100_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let u = s.next_f32();
            assert!((0.0..1.0).contains(&u));
            sum += u as f64;
        }
        // mean of U(0,1): 0.5, standard error 1/sqrt(12 n) ≈ 0.00091; 5 σ.
        assert!((sum / n as f64 - 0.5).abs() < 5.0 * (1.0 / (12.0 * n as f64)).sqrt());
    }
}

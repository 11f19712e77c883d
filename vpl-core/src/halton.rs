//! The Halton sequence with a Cranley–Patterson rotation per dimension.

use crate::rng::{Purpose, stream};
use crate::sampling::radical_inverse;

/// Halton points in `dims` dimensions (prime bases 2, 3, 5, …), each
/// dimension shifted modulo 1 by a random offset drawn from the seed, so
/// different seeds give different, equally well-spread point sets.
#[derive(Clone, Debug)]
pub struct Halton {
    bases: Vec<u64>,
    shifts: Vec<f64>,
}

impl Halton {
    /// The first `dims` dimensions, rotated by offsets from `seed`.
    pub fn new(dims: usize, seed: u64) -> Halton {
        let bases = primes(dims);
        let shifts = (0..dims).map(|d| stream(seed, 0, Purpose::SCRAMBLE, d as u64).next_f32() as f64).collect();
        Halton { bases, shifts }
    }

    /// Number of dimensions.
    pub fn dims(&self) -> usize {
        self.bases.len()
    }

    /// Coordinate `dim` of point `index`, in [0, 1).
    #[inline]
    pub fn sample(&self, index: u64, dim: usize) -> f32 {
        let v = radical_inverse(index, self.bases[dim]) + self.shifts[dim];
        let v = if v >= 1.0 { v - 1.0 } else { v };
        (v as f32).min(1.0 - f32::EPSILON / 2.0)
    }
}

/// The first `n` primes.
fn primes(n: usize) -> Vec<u64> {
    let mut p: Vec<u64> = Vec::with_capacity(n);
    let mut c = 2u64;
    while p.len() < n {
        if p.iter().take_while(|&&q| q * q <= c).all(|&q| c % q != 0) {
            p.push(c);
        }
        c += 1;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bases_are_primes_and_points_are_stratified() {
        assert_eq!(primes(6), vec![2, 3, 5, 7, 11, 13]);
        let h = Halton::new(2, 3);
        // 2^k points of the base-2 dimension fall one into each of 2^k strata.
        let mut strata = [0u32; 16];
        for i in 0..16 {
            strata[(h.sample(i, 0) * 16.0) as usize] += 1;
        }
        assert!(strata.iter().all(|&c| c == 1), "{strata:?}");
    }
}

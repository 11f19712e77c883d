//! Weighted resampling without replacement (§3.2.1): `count` draws from a
//! discrete distribution with weights `w`, each draw retried while it lands
//! on an element already taken, at most `max_retries` times; a draw that runs
//! out of retries takes nothing, as the paper's parallel version does.

use crate::rng::{Purpose, stream};

/// Indices of the elements taken, in draw order. Draw d uses stream
/// (seed, iteration, RESAMPLE, d). Non-finite or negative weights count as
/// zero; when every weight is zero, the elements are drawn uniformly.
pub fn resample(weights: &[f32], count: usize, max_retries: u32, seed: u64, iteration: u64) -> Vec<usize> {
    let n = weights.len();
    if n == 0 || count == 0 {
        return Vec::new();
    }
    let clean = |w: f32| if w.is_finite() && w > 0.0 { w as f64 } else { 0.0 };
    let mut cdf = Vec::with_capacity(n);
    let mut total = 0.0f64;
    for &w in weights {
        total += clean(w);
        cdf.push(total);
    }
    let uniform = total <= 0.0;
    let mut taken = vec![false; n];
    let mut out = Vec::with_capacity(count.min(n));
    for d in 0..count.min(n) {
        let mut rng = stream(seed, iteration, Purpose::RESAMPLE, d as u64);
        for _ in 0..=max_retries {
            let i = if uniform {
                rng.below(n as u32) as usize
            } else {
                // 53-bit uniform in [0, total): the first CDF entry above it.
                let u = ((rng.next_u32() as u64) << 21 ^ (rng.next_u32() as u64 >> 11)) as f64 / (1u64 << 53) as f64 * total;
                cdf.partition_point(|&c| c <= u).min(n - 1)
            };
            if !taken[i] {
                taken[i] = true;
                out.push(i);
                break;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn takes_each_element_at_most_once_and_never_zero_weights() {
        let w = [1.0, 0.0, 2.0, f32::NAN, 3.0, -1.0];
        let got = resample(&w, 10, 8, 1, 0);
        assert!(got.len() <= 3);
        let mut s = got.clone();
        s.sort();
        s.dedup();
        assert_eq!(s.len(), got.len());
        assert!(got.iter().all(|&i| i == 0 || i == 2 || i == 4));
        assert!(resample(&[], 3, 8, 1, 0).is_empty());
        assert_eq!(resample(&[0.0, 0.0], 2, 64, 1, 0).len(), 2);
    }

    /// The first draw follows the weights: over 20 000 seeds, element i is
    /// drawn first with frequency w_i / Σw within 5 binomial standard errors.
    #[test]
    fn first_draw_is_proportional_to_weight() {
        let w = [1.0f32, 3.0, 0.5, 5.5];
        let n = 20_000;
        let mut counts = [0usize; 4];
        for seed in 0..n {
            counts[resample(&w, 1, 0, seed, 0)[0]] += 1;
        }
        for (i, &c) in counts.iter().enumerate() {
            let p = w[i] as f64 / 10.0;
            let se = (p * (1.0 - p) / n as f64).sqrt();
            assert!((c as f64 / n as f64 - p).abs() < 5.0 * se, "element {i}: {c} of {n}");
        }
    }
}

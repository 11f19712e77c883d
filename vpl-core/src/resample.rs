//! Weighted resampling without replacement (§3.2.1): `count` draws from a
//! discrete distribution with weights `w`, each draw retried while it lands
//! on an element already taken, at most `max_retries` times; a draw that runs
//! out of retries takes nothing, as the paper's parallel version does.

use crate::rng::{Purpose, stream};

/// Indices of the elements taken, in draw order. Draw d uses stream
/// (seed, iteration, RESAMPLE, d). Non-finite or negative weights count as
/// zero; when every weight is zero, the elements are drawn uniformly.
pub fn resample(weights: &[f32], count: usize, max_retries: u32, seed: u64, iteration: u64) -> Vec<usize> {
    resample_counted(weights, count, max_retries, seed, iteration).taken
}

/// What [`resample_counted`] took, and how the draws found it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Resampled {
    /// The elements taken, in draw order ([`resample`]'s answer).
    pub taken: Vec<usize>,
    /// For each element taken, how many draws *first* landed on it.
    pub first: Vec<u32>,
    /// For each element taken, the probability p_i of one draw landing on
    /// it: w_i / Σw, or 1 / n where the draws were uniform.
    pub probability: Vec<f64>,
    /// The draws made: min(count, n).
    pub draws: usize,
}

/// [`resample`] (the same elements, in the same order), with each element's
/// first landings and draw probability ([`Resampled`]).
///
/// The first landings of the draws, before any retry, are independent
/// draws with probabilities p_i, and each lands on an element that is taken
/// (by that draw or an earlier one). So while the elements taken are not
/// drawn in proportion to w (a heavy element is taken once however often it
/// is hit, and the retries move its share to lighter ones),
/// Σ_i c_i g_i / (draws · p_i) over the taken elements, c_i their first
/// landings, is an unbiased estimate of Σ_i g_i over all elements, for any
/// g (Horvitz–Thompson with replacement).
pub fn resample_counted(weights: &[f32], count: usize, max_retries: u32, seed: u64, iteration: u64) -> Resampled {
    let n = weights.len();
    if n == 0 || count == 0 {
        return Resampled::default();
    }
    let clean = |w: f32| if w.is_finite() && w > 0.0 { w as f64 } else { 0.0 };
    let mut cdf = Vec::with_capacity(n);
    let mut total = 0.0f64;
    for &w in weights {
        total += clean(w);
        cdf.push(total);
    }
    let uniform = total <= 0.0;
    let draws = count.min(n);
    // For each element, its place in `taken` once taken.
    let mut place = vec![u32::MAX; n];
    let mut r =
        Resampled { taken: Vec::with_capacity(draws), first: Vec::with_capacity(draws), probability: Vec::with_capacity(draws), draws };
    for d in 0..draws {
        let mut rng = stream(seed, iteration, Purpose::RESAMPLE, d as u64);
        for attempt in 0..=max_retries {
            let i = if uniform {
                rng.below(n as u32) as usize
            } else {
                // 53-bit uniform in [0, total): the first CDF entry above it.
                let u = ((rng.next_u32() as u64) << 21 ^ (rng.next_u32() as u64 >> 11)) as f64 / (1u64 << 53) as f64 * total;
                cdf.partition_point(|&c| c <= u).min(n - 1)
            };
            let fresh = place[i] == u32::MAX;
            if fresh {
                place[i] = r.taken.len() as u32;
                r.taken.push(i);
                r.first.push(0);
                r.probability.push(if uniform { 1.0 / n as f64 } else { clean(weights[i]) / total });
            }
            if attempt == 0 {
                r.first[place[i] as usize] += 1;
            }
            if fresh {
                break;
            }
        }
    }
    r
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

    /// The first landings are draws in proportion to the weights, every
    /// one on an element taken: they count `count` in all, and the
    /// Horvitz–Thompson sum Σ c_i g_i Σw / (count w_i) estimates Σ g_i
    /// without bias where the plain mean of the taken elements does not
    /// (one heavy element among light ones). Over 4000 seeds, within 5
    /// standard errors of the seeds' mean.
    #[test]
    fn first_landings_give_an_unbiased_sum() {
        let w: Vec<f32> = (0..40).map(|i| if i == 0 { 40.0 } else { 1.0 }).collect();
        let g: Vec<f64> = (0..40).map(|i| if i == 0 { 10.0 } else { 1.0 }).collect();
        let truth: f64 = g.iter().sum();
        let total: f64 = w.iter().map(|&x| x as f64).sum();
        let count = 20;
        let runs = 4000;
        let (mut ht, mut plain) = (Vec::new(), Vec::new());
        for seed in 0..runs {
            let r = resample_counted(&w, count, 8, seed, 0);
            let taken = &r.taken;
            assert_eq!(*taken, resample(&w, count, 8, seed, 0));
            assert_eq!((r.first.iter().sum::<u32>() as usize, r.draws), (count, count));
            for (&i, &p) in taken.iter().zip(&r.probability) {
                assert_eq!(p, w[i] as f64 / total);
            }
            ht.push(taken.iter().zip(&r.first).zip(&r.probability).map(|((&i, &c), &p)| c as f64 * g[i] / (count as f64 * p)).sum::<f64>());
            // The plain mean of the taken elements, times the count of elements.
            plain.push(taken.iter().map(|&i| g[i]).sum::<f64>() / taken.len() as f64 * 40.0);
        }
        let mean_se = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64;
            (m, (var / v.len() as f64).sqrt())
        };
        let (m, se) = mean_se(&ht);
        assert!((m - truth).abs() < 5.0 * se, "Horvitz–Thompson {m} ± {se} against {truth}");
        let (p, pse) = mean_se(&plain);
        assert!((p - truth).abs() > 5.0 * pse, "the plain mean {p} ± {pse} should miss {truth}");
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

//! Confidence intervals for Table 1: a two-way bootstrap over seeds and
//! tracked pixels, paired comparisons between methods, and the split of
//! the error into bias and noise.
//!
//! A method's errors on a row form an array E\[s\]\[f\]\[p\] (seed s, frame f,
//! tracked pixel p) of tone-mapped estimate − truth. The measures are means
//! over it: |E| of |E|, |E′| of |E\[s\]\[f\]\[p\] − E\[s\]\[f−1\]\[p\]|, the bias of E.
//!
//! **Resampling units.** Seeds are independent runs; pixels are a sample of
//! the image's content (the paper's eight). Frames are not resampled: the
//! error of one pixel is strongly correlated from frame to frame (a VPL set
//! changes a few slots per frame), so frames do not carry independent
//! information, and |E′| needs consecutive frames. Each replicate draws S
//! seeds and P pixels with replacement, independently, and keeps each drawn
//! (seed, pixel) series whole: a two-way (crossed) bootstrap. With S = 3
//! seeds the seed dimension is coarse; the pixel dimension carries most of
//! the spread. 95 % intervals are the 2.5 and 97.5 percentiles of
//! [`REPLICATES`] replicates (percentile bootstrap).
//!
//! **Paired comparisons.** Two methods on one row share the draws (the same
//! seed indices and the same pixels in every replicate), so the interval of
//! a difference of means keeps the pixels' shared difficulty out of it: a
//! difference is significant when its interval excludes zero.
//!
//! **Bias and noise.** Per frame and pixel, the mean over seeds ē and the
//! sample variance v of E\[·\]\[f\]\[p\] estimate the bias b and the noise
//! variance σ²: E\[ē²\] = b² + σ²/S and E\[v\] = σ², so the mean squared error
//! mean(E²) = b² + σ² splits into noise mean(v) and bias² mean(ē²) − mean(v)/S.

use serde::{Deserialize, Serialize};
use vpl_core::{Purpose, stream};

/// Bootstrap replicates per interval.
pub const REPLICATES: usize = 2000;

/// A 95 % confidence interval.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    /// 2.5 percentile.
    pub lo: f64,
    /// 97.5 percentile.
    pub hi: f64,
}

impl Interval {
    /// The percentile interval of `values` (sorted here).
    fn of(mut values: Vec<f64>) -> Interval {
        if values.is_empty() {
            return Interval::default();
        }
        values.sort_by(|a, b| a.total_cmp(b));
        Interval { lo: percentile(&values, 0.025), hi: percentile(&values, 0.975) }
    }

    /// Whether the interval lies wholly below zero, above it, or holds it.
    pub fn sign(&self) -> Verdict {
        if self.hi < 0.0 {
            Verdict::Lower
        } else if self.lo > 0.0 {
            Verdict::Higher
        } else {
            Verdict::NotDistinguishable
        }
    }
}

/// Linear interpolation between order statistics of sorted `v` at quantile `q`.
fn percentile(v: &[f64], q: f64) -> f64 {
    let x = q * (v.len() - 1) as f64;
    let (i, t) = (x.floor() as usize, x - x.floor());
    if i + 1 < v.len() { v[i] * (1.0 - t) + v[i + 1] * t } else { v[i] }
}

/// How a difference of means compares with zero at 95 %.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Verdict {
    /// Significantly lower.
    Lower,
    /// Significantly higher.
    Higher,
    /// The interval holds zero.
    NotDistinguishable,
}

impl Verdict {
    /// Words for a report.
    pub fn words(self) -> &'static str {
        match self {
            Verdict::Lower => "significantly lower",
            Verdict::Higher => "significantly higher",
            Verdict::NotDistinguishable => "not distinguishable",
        }
    }
}

/// The three measures of one method on one row.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Measures {
    /// |E|.
    pub e: f64,
    /// |E′|.
    pub e_prime: f64,
    /// Mean signed error.
    pub bias: f64,
}

/// Intervals of [`Measures`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Intervals {
    /// Of |E|.
    pub e: Interval,
    /// Of |E′|.
    pub e_prime: Interval,
    /// Of the bias.
    pub bias: Interval,
}

/// Per (seed, pixel) sums over frames of one method's errors: all a
/// replicate needs.
#[derive(Clone, Debug, PartialEq)]
pub struct SeriesSums {
    seeds: usize,
    pixels: usize,
    frames: usize,
    /// Σ_f |E|, Σ_f≥1 |ΔE|, Σ_f E, index s·pixels + p.
    sums: Vec<[f64; 3]>,
}

impl SeriesSums {
    /// The sums of `err[s][f][p]`; `None` when it is empty or ragged.
    pub fn new(err: &[Vec<Vec<f64>>]) -> Option<SeriesSums> {
        let seeds = err.len();
        let frames = err.first()?.len();
        let pixels = err.first()?.first()?.len();
        if seeds == 0 || frames == 0 || pixels == 0 || err.iter().any(|s| s.len() != frames || s.iter().any(|f| f.len() != pixels)) {
            return None;
        }
        let mut sums = vec![[0.0; 3]; seeds * pixels];
        for (s, series) in err.iter().enumerate() {
            for (f, row) in series.iter().enumerate() {
                for (p, e) in row.iter().enumerate() {
                    let c = &mut sums[s * pixels + p];
                    c[0] += e.abs();
                    c[2] += e;
                    if f > 0 {
                        c[1] += (e - series[f - 1][p]).abs();
                    }
                }
            }
        }
        Some(SeriesSums { seeds, pixels, frames, sums })
    }

    /// The measures over the drawn seeds and pixels (each as often as drawn).
    fn measures(&self, seeds: &[usize], pixels: &[usize]) -> Measures {
        let mut t = [0.0; 3];
        for &s in seeds {
            for &p in pixels {
                let c = self.sums[s * self.pixels + p];
                t[0] += c[0];
                t[1] += c[1];
                t[2] += c[2];
            }
        }
        let n = (seeds.len() * pixels.len()) as f64;
        let prime = if self.frames > 1 { t[1] / (n * (self.frames - 1) as f64) } else { 0.0 };
        Measures { e: t[0] / (n * self.frames as f64), e_prime: prime, bias: t[2] / (n * self.frames as f64) }
    }

    /// The measures over every seed and pixel.
    pub fn point(&self) -> Measures {
        self.measures(&(0..self.seeds).collect::<Vec<_>>(), &(0..self.pixels).collect::<Vec<_>>())
    }

    /// The measures of seed `s` alone, over every pixel.
    pub fn seed(&self, s: usize) -> Measures {
        self.measures(&[s], &(0..self.pixels).collect::<Vec<_>>())
    }

    /// Number of seeds.
    pub fn seeds(&self) -> usize {
        self.seeds
    }
}

/// The seeds and pixels each replicate draws, shared by the methods of a
/// row so that their comparisons are paired.
#[derive(Clone, Debug, PartialEq)]
pub struct Draws {
    draws: Vec<(Vec<usize>, Vec<usize>)>,
}

impl Draws {
    /// [`REPLICATES`] draws of `seeds` seed and `pixels` pixel indices, from
    /// the stream of `seed` keyed by the row's number `row`.
    pub fn new(seeds: usize, pixels: usize, seed: u64, row: u64) -> Draws {
        let mut rng = stream(seed, 0, Purpose::CONFIDENCE, row);
        let mut pick = |n: usize| -> Vec<usize> { (0..n).map(|_| rng.below(n as u32) as usize).collect() };
        let draws = (0..REPLICATES).map(|_| (pick(seeds), pick(pixels))).collect();
        Draws { draws }
    }

    /// The 95 % intervals of a method's measures.
    pub fn intervals(&self, m: &SeriesSums) -> Intervals {
        let reps: Vec<Measures> = self.draws.iter().map(|(s, p)| m.measures(s, p)).collect();
        Intervals {
            e: Interval::of(reps.iter().map(|r| r.e).collect()),
            e_prime: Interval::of(reps.iter().map(|r| r.e_prime).collect()),
            bias: Interval::of(reps.iter().map(|r| r.bias).collect()),
        }
    }

    /// The 95 % intervals of the differences a − b of two methods' measures
    /// on the same row (paired draws).
    pub fn differences(&self, a: &SeriesSums, b: &SeriesSums) -> Intervals {
        let reps: Vec<(Measures, Measures)> = self.draws.iter().map(|(s, p)| (a.measures(s, p), b.measures(s, p))).collect();
        Intervals {
            e: Interval::of(reps.iter().map(|(x, y)| x.e - y.e).collect()),
            e_prime: Interval::of(reps.iter().map(|(x, y)| x.e_prime - y.e_prime).collect()),
            bias: Interval::of(reps.iter().map(|(x, y)| x.bias - y.bias).collect()),
        }
    }
}

/// The mean squared error of a method on a row, split into bias² and noise.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ErrorSplit {
    /// mean(E²) over seeds, frames and pixels.
    pub mse: f64,
    /// Noise variance σ²: the mean over frames and pixels of the variance across seeds.
    pub noise: f64,
    /// Bias²: mean(ē²) − noise / S (can come out slightly negative when there is no bias; kept as estimated).
    pub bias2: f64,
}

impl ErrorSplit {
    /// The split of `err[s][f][p]`; `None` with fewer than two seeds or ragged input.
    pub fn new(err: &[Vec<Vec<f64>>]) -> Option<ErrorSplit> {
        let seeds = err.len();
        if seeds < 2 {
            return None;
        }
        SeriesSums::new(err)?;
        let (frames, pixels) = (err[0].len(), err[0][0].len());
        let (mut sq, mut noise, mut mean_sq) = (0.0, 0.0, 0.0);
        for f in 0..frames {
            for p in 0..pixels {
                let xs: Vec<f64> = err.iter().map(|s| s[f][p]).collect();
                let m = xs.iter().sum::<f64>() / seeds as f64;
                let v = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (seeds - 1) as f64;
                sq += xs.iter().map(|x| x * x).sum::<f64>() / seeds as f64;
                noise += v;
                mean_sq += m * m;
            }
        }
        let n = (frames * pixels) as f64;
        let (mse, noise, mean_sq) = (sq / n, noise / n, mean_sq / n);
        Some(ErrorSplit { mse, noise, bias2: mean_sq - noise / seeds as f64 })
    }

    /// The share of the mean squared error that is noise, in [0, 1].
    pub fn noise_share(&self) -> f64 {
        if self.mse > 0.0 { (self.noise / self.mse).clamp(0.0, 1.0) } else { 0.0 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// err[s][f][p] = bias + noise, with a fixed bias per pixel.
    fn synthetic(seeds: usize, frames: usize, pixels: usize, bias: f64, noise: f64, key: u64) -> Vec<Vec<Vec<f64>>> {
        let mut rng = stream(key, 0, Purpose::TEST, 0);
        let mut gauss = || {
            let (u, v) = rng.next_2d();
            (-2.0 * (u.max(1e-7) as f64).ln()).sqrt() * (std::f64::consts::TAU * v as f64).cos()
        };
        (0..seeds).map(|_| (0..frames).map(|_| (0..pixels).map(|_| bias + noise * gauss()).collect()).collect()).collect()
    }

    #[test]
    fn measures_match_the_definitions() {
        // Two seeds, two frames, one pixel.
        let err = vec![vec![vec![0.1], vec![-0.1]], vec![vec![0.3], vec![0.3]]];
        let sums = SeriesSums::new(&err).unwrap();
        let m = sums.point();
        assert!((m.e - 0.2).abs() < 1e-12 && (m.bias - 0.15).abs() < 1e-12);
        // |ΔE|: 0.2 on seed 0, 0 on seed 1.
        assert!((m.e_prime - 0.1).abs() < 1e-12, "{m:?}");
        // One seed alone is the paper's measure of that run (`temporal_error`).
        let truth = vec![vec![0.0]; 2];
        let t = crate::metrics::temporal_error(&err[0], &truth).unwrap();
        let s0 = sums.seed(0);
        assert!((s0.e - t.e).abs() < 1e-12 && (s0.e_prime - t.e_prime).abs() < 1e-12 && (s0.bias - t.bias).abs() < 1e-12);
        assert!(SeriesSums::new(&[vec![vec![0.1], vec![0.1, 0.2]]]).is_none());
        assert!(SeriesSums::new(&[]).is_none());
    }

    #[test]
    fn the_split_finds_the_bias_and_the_noise() {
        // Bias 0.02, noise σ = 0.05: bias² 4e-4, noise 2.5e-3. 8 seeds × 50 frames × 8 pixels.
        // Bounds at three standard deviations of the estimators: the noise's relative
        // error is √(2 / (7·400)) = 2.7 % (bound 8 %); bias² = mean(ē²) − σ²/S has
        // standard deviation √(2(σ²/S)² + 4b²σ²/S) / √400 = 4.2e-5, 10 % of it (bound 30 %).
        let err = synthetic(8, 50, 8, 0.02, 0.05, 1);
        let s = ErrorSplit::new(&err).unwrap();
        assert!((s.noise / 2.5e-3 - 1.0).abs() < 0.08, "{s:?}");
        assert!((s.bias2 / 4e-4 - 1.0).abs() < 0.3, "{s:?}");
        assert!((s.mse - (s.noise + s.bias2)).abs() < 0.05 * s.mse);
        assert!(ErrorSplit::new(&err[..1]).is_none());
    }

    #[test]
    fn intervals_cover_the_truth_and_paired_differences_are_found() {
        // 95 % intervals of the bias over 40 independent data sets: the true
        // bias 0.01 lies inside in most of them (binomial: ≥ 34 of 40 is the
        // 1 % lower tail of a 95 % coverage). The data have no pixel effect,
        // so the bootstrap over pixels and seeds is exact up to its percentile
        // approximation.
        let mut covered = 0;
        for key in 0..40 {
            let err = synthetic(3, 8, 8, 0.01, 0.02, 100 + key);
            let m = SeriesSums::new(&err).unwrap();
            let ci = Draws::new(3, 8, key, 0).intervals(&m);
            assert!(ci.e.lo <= m.point().e && m.point().e <= ci.e.hi);
            covered += (ci.bias.lo <= 0.01 && 0.01 <= ci.bias.hi) as usize;
        }
        eprintln!("the bias interval covered the truth in {covered} of 40 data sets");
        assert!(covered >= 34, "{covered} of 40");
        // A method 0.02 worse at every pixel is significantly higher; a copy is not distinguishable.
        let a = synthetic(3, 8, 8, 0.0, 0.01, 7);
        let b: Vec<Vec<Vec<f64>>> = a.iter().map(|s| s.iter().map(|f| f.iter().map(|e| e + 0.02).collect()).collect()).collect();
        let d = Draws::new(3, 8, 0, 0);
        let (sa, sb) = (SeriesSums::new(&a).unwrap(), SeriesSums::new(&b).unwrap());
        assert_eq!(d.differences(&sb, &sa).bias.sign(), Verdict::Higher);
        assert_eq!(d.differences(&sa, &sb).e.sign(), Verdict::Lower);
        assert_eq!(d.differences(&sa, &sa).e.sign(), Verdict::NotDistinguishable);
        // The same draws from the same seed: deterministic.
        assert_eq!(Draws::new(3, 8, 5, 2), Draws::new(3, 8, 5, 2));
    }
}

//! A discrete distribution sampled by binary search over its CDF.

/// Discrete distribution over `0..n` proportional to non-negative weights.
#[derive(Clone, Debug, Default)]
pub struct Distribution1D {
    cdf: Vec<f32>,
    pmf: Vec<f32>,
    total: f64,
}

impl Distribution1D {
    /// Builds from weights; negative or non-finite weights count as zero.
    /// Returns `None` when every weight is zero.
    pub fn new(weights: &[f32]) -> Option<Self> {
        let total: f64 = weights.iter().map(|&w| if w.is_finite() && w > 0.0 { w as f64 } else { 0.0 }).sum();
        if total <= 0.0 {
            return None;
        }
        let mut acc = 0.0f64;
        let mut cdf = Vec::with_capacity(weights.len());
        let mut pmf = Vec::with_capacity(weights.len());
        for &w in weights {
            let w = if w.is_finite() && w > 0.0 { w as f64 } else { 0.0 };
            acc += w;
            cdf.push((acc / total) as f32);
            pmf.push((w / total) as f32);
        }
        if let Some(last) = cdf.last_mut() {
            *last = 1.0;
        }
        Some(Self { cdf, pmf, total })
    }

    /// Number of entries.
    pub fn len(&self) -> usize {
        self.pmf.len()
    }

    /// True when there are no entries.
    pub fn is_empty(&self) -> bool {
        self.pmf.is_empty()
    }

    /// Sum of the weights.
    pub fn total(&self) -> f64 {
        self.total
    }

    /// The cumulative distribution (last entry 1), for kernels that sample
    /// it elsewhere the way [`Distribution1D::sample`] does.
    pub fn cdf(&self) -> &[f32] {
        &self.cdf
    }

    /// The probabilities of all entries.
    pub fn pmfs(&self) -> &[f32] {
        &self.pmf
    }

    /// Probability of entry `i`.
    #[inline]
    pub fn pmf(&self, i: usize) -> f32 {
        self.pmf[i]
    }

    /// Samples an index from `u ∈ [0,1)`; returns (index, probability).
    /// Entries of zero probability are never returned.
    #[inline]
    pub fn sample(&self, u: f32) -> (usize, f32) {
        let mut i = self.cdf.partition_point(|&c| c <= u).min(self.cdf.len() - 1);
        while self.pmf[i] == 0.0 && i + 1 < self.pmf.len() {
            i += 1;
        }
        (i, self.pmf[i])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frequencies_follow_weights() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]).unwrap();
        let mut counts = [0u32; 3];
        let n = 40_000;
        for k in 0..n {
            let (i, p) = d.sample((k as f32 + 0.5) / n as f32);
            counts[i] += 1;
            assert!(p > 0.0);
        }
        assert_eq!(counts[1], 0);
        assert!((counts[0] as f32 / n as f32 - 0.25).abs() < 1e-3);
        assert!(Distribution1D::new(&[0.0, 0.0]).is_none());
    }
}

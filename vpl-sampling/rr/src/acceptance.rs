//! The acceptance probability of eq. (3).

/// p_i = min(Φ̃_i / Φ̃_v + ε, 1) (Georgiev & Slusallek 2010, eq. 3): a
/// candidate bringing the desired average Φ̃_v (or more) to the camera is
/// always kept; a weaker one survives with a probability that falls with its
/// contribution but never below ε. Φ̃_v = 0 (nothing known of the image yet)
/// gives p = 1: plain Instant Radiosity.
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
pub fn acceptance(phi_i: f32, phi_v: f32, epsilon: f32) -> f32 {
    if !(phi_v > 0.0) {
        return 1.0;
    }
    let p = phi_i.max(0.0) / phi_v + epsilon;
    if p.is_nan() { 1.0 } else { p.clamp(0.0, 1.0) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equation_three() {
        assert_eq!(acceptance(0.0, 0.0, 0.05), 1.0);
        assert!((acceptance(0.0, 2.0, 0.05) - 0.05).abs() < 1e-7);
        assert!((acceptance(1.0, 2.0, 0.05) - 0.55).abs() < 1e-6);
        assert_eq!(acceptance(2.0, 2.0, 0.05), 1.0);
        assert_eq!(acceptance(f32::INFINITY, 2.0, 0.05), 1.0);
        assert_eq!(acceptance(1.0, 2.0, 1.0), 1.0);
    }
}

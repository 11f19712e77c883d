//! What the processor offers the hand-vectorised kernels.

/// Whether this CPU has AVX2 and FMA, the features every AVX2 kernel of the
/// toolkit (BVH traversal, shadow-map gather, filter) is compiled for.
/// `is_x86_feature_detected!` caches its answer, so this is cheap to call
/// per batch; false on other architectures.
pub fn has_avx2_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::is_x86_feature_detected!("avx2") && std::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

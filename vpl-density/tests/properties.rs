//! Property tests of the kNN density (eq. 7): uniform points on a plane or on
//! a box surface give the true density within a stated tolerance, and the
//! estimate does not depend on the order of the points.
//!
//! Tolerance. For N uniform points on an area A and a query farther than r_k
//! from any edge, the count in a disc of area π r² is binomial ≈ Poisson, so
//! X = N π r_k² / A is Gamma(k, 1)-distributed and the estimate
//! p̂ = k / (N π r_k²) = (k / X) / A has E[p̂·A] = k/(k−1) and
//! Var[p̂·A] = k² / ((k−1)²(k−2)). The tests average (k−1)/k · p̂ · A over Q
//! queries spaced farther apart than 2 r_k (their discs are nearly disjoint,
//! so nearly independent) and require it to be within 4 standard errors,
//! 4 / √((k−2)·Q), of 1. Fixed proptest seeds make every run the same.

use glam::{Quat, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vpl_core::{Purpose, stream};
use vpl_density::KnnDensity;

const K: usize = 16;

fn config() -> Config {
    Config { cases: 24, rng_seed: RngSeed::Fixed(0x5eed_0007), failure_persistence: None, ..Config::default() }
}

/// Mean of (k−1)/k · p̂ · A over the queries, and its 4-standard-error bound.
fn normalised_mean(d: &KnnDensity, queries: &[Vec3], area: f32) -> (f32, f32) {
    let m: f32 = queries.iter().map(|&q| d.at(q, K).unwrap() * area * (K - 1) as f32 / K as f32).sum::<f32>() / queries.len() as f32;
    (m, 4.0 / (((K - 2) * queries.len()) as f32).sqrt())
}

proptest! {
    #![proptest_config(config())]

    /// Uniform points on a square of side s in any plane: density 1/s².
    #[test]
    fn uniform_points_on_a_plane(seed in 0u64..1_000_000, s in 0.5f32..4.0,
                                 ax in -1.0f32..1.0, ay in -1.0f32..1.0, az in -1.0f32..1.0, angle in 0.0f32..std::f32::consts::TAU,
                                 ox in -10.0f32..10.0, oy in -10.0f32..10.0, oz in -10.0f32..10.0) {
        let axis = Vec3::new(ax, ay, az);
        prop_assume!(axis.length() > 1e-2);
        let rot = Quat::from_axis_angle(axis.normalize(), angle);
        let place = |u: f32, v: f32| rot * Vec3::new(u * s, v * s, 0.0) + Vec3::new(ox, oy, oz);
        let n = 4096;
        let mut rng = stream(seed, 0, Purpose::TEST, 0);
        let pts: Vec<Vec3> = (0..n).map(|_| { let (u, v) = rng.next_2d(); place(u, v) }).collect();
        let d = KnnDensity::new(&pts).unwrap();
        // 8×8 queries from 0.15 to 0.85 of the side: 0.1·s apart, while
        // r_16 ≈ s·√(16 / (4096 π)) = 0.035·s.
        let queries: Vec<Vec3> = (0..64).map(|i| place(0.15 + 0.1 * (i % 8) as f32, 0.15 + 0.1 * (i / 8) as f32)).collect();
        let (m, tol) = normalised_mean(&d, &queries, s * s);
        prop_assert!((m - 1.0).abs() < tol, "normalised mean {m}, tolerance {tol}");
    }

    /// Uniform points on the surface of a w×h×d box: density 1/area, checked
    /// near the middle of each face (farther than r_k from its edges).
    #[test]
    fn uniform_points_on_a_box_surface(seed in 0u64..1_000_000, w in 1.0f32..3.0, h in 1.0f32..3.0, dpt in 1.0f32..3.0) {
        let size = Vec3::new(w, h, dpt);
        let faces = [(0usize, 1usize, 2usize, 0.0f32), (0, 1, 2, 1.0), (1, 2, 0, 0.0), (1, 2, 0, 1.0), (2, 0, 1, 0.0), (2, 0, 1, 1.0)];
        let face_area = |f: &(usize, usize, usize, f32)| size[f.0] * size[f.1];
        let area: f32 = faces.iter().map(face_area).sum();
        let on_face = |f: &(usize, usize, usize, f32), u: f32, v: f32| {
            let mut p = Vec3::ZERO;
            p[f.0] = u * size[f.0];
            p[f.1] = v * size[f.1];
            p[f.2] = f.3 * size[f.2];
            p
        };
        let n = 16384;
        let mut rng = stream(seed, 0, Purpose::TEST, 1);
        let pts: Vec<Vec3> = (0..n).map(|_| {
            // A face in proportion to its area, then a uniform point on it.
            let mut t = rng.next_f32() * area;
            let mut face = &faces[5];
            for f in &faces {
                if t < face_area(f) { face = f; break; }
                t -= face_area(f);
            }
            let (u, v) = rng.next_2d();
            on_face(face, u, v)
        }).collect();
        let d = KnnDensity::new(&pts).unwrap();
        // r_16 ≈ √(16 · area / (16384 π)) ≤ 0.13 m for the largest box; a 3×3
        // grid from 0.3 to 0.7 of each face keeps ≥ 0.3 m from its edges.
        let queries: Vec<Vec3> = faces.iter().flat_map(|f| (0..9).map(move |i| (f, 0.3 + 0.2 * (i % 3) as f32, 0.3 + 0.2 * (i / 3) as f32)))
            .map(|(f, u, v)| on_face(f, u, v)).collect();
        let (m, tol) = normalised_mean(&d, &queries, area);
        prop_assert!((m - 1.0).abs() < tol, "normalised mean {m}, tolerance {tol}");
    }

    /// Shuffling the points changes no estimate: not at a query point, not at a member.
    #[test]
    fn the_estimate_ignores_point_order(seed in 0u64..1_000_000, n in 20usize..400, k in 1usize..10) {
        let mut rng = stream(seed, 0, Purpose::TEST, 2);
        let pts: Vec<Vec3> = (0..n).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), 0.2 * rng.next_f32())).collect();
        let mut order: Vec<usize> = (0..n).collect();
        for i in (1..n).rev() {
            order.swap(i, rng.below(i as u32 + 1) as usize);
        }
        let shuffled: Vec<Vec3> = order.iter().map(|&i| pts[i]).collect();
        let (a, b) = (KnnDensity::new(&pts).unwrap(), KnnDensity::new(&shuffled).unwrap());
        let queries: Vec<Vec3> = (0..32).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), 0.1)).collect();
        prop_assert_eq!(a.at_many(&queries, k).unwrap(), b.at_many(&queries, k).unwrap());
        let (ma, mb) = (a.members(k), b.members(k));
        for (j, &i) in order.iter().enumerate() {
            prop_assert_eq!(ma[i], mb[j]);
        }
    }
}

//! Property tests of vpl-core's invariants.

use proptest::prelude::*;
use vpl_core::distribution::Distribution1D;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, FovAxis, LocalFrame};

proptest! {
    /// A point on a primary ray projects back to the raster position the ray came from.
    #[test]
    fn camera_project_inverts_ray(px in 0.0f32..320.0, py in 0.0f32..240.0, t in 0.5f32..50.0,
                                  ox in -5.0f32..5.0, oz in -5.0f32..5.0, fov in 10.0f32..120.0,
                                  axis in prop_oneof![Just(FovAxis::X), Just(FovAxis::Y), Just(FovAxis::Smaller)]) {
        let cam = Camera::new(Vec3::new(ox, 1.0, oz), Vec3::new(0.3, 0.8, -7.0), Vec3::Y, fov, axis, (320, 240)).unwrap();
        let r = cam.ray(px, py, (0.5, 0.5));
        let (qx, qy) = cam.project(r.at(t)).unwrap();
        prop_assert!((qx - px).abs() < 2e-2 && (qy - py).abs() < 2e-2, "({px},{py}) -> ({qx},{qy})");
    }

    /// Frames built from any unit normal are orthonormal and round-trip vectors.
    #[test]
    fn local_frames_are_orthonormal(x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0) {
        let n = Vec3::new(x, y, z);
        prop_assume!(n.length() > 1e-3);
        let n = n.normalize();
        let f = LocalFrame::from_normal(n);
        prop_assert!(f.s.dot(f.t).abs() < 1e-4 && f.s.dot(n).abs() < 1e-4 && f.t.dot(n).abs() < 1e-4);
        prop_assert!((f.s.length() - 1.0).abs() < 1e-4 && (f.t.length() - 1.0).abs() < 1e-4);
        let v = Vec3::new(0.2, -0.7, 0.4);
        prop_assert!((f.to_world(f.to_local(v)) - v).length() < 1e-4);
    }

    /// Probabilities sum to one and sampling never returns an entry of zero weight.
    #[test]
    fn distribution_is_normalised(w in prop::collection::vec(0.0f32..10.0, 1..40), u in 0.0f32..1.0) {
        prop_assume!(w.iter().any(|&x| x > 0.0));
        let d = Distribution1D::new(&w).unwrap();
        let sum: f32 = (0..d.len()).map(|i| d.pmf(i)).sum();
        prop_assert!((sum - 1.0).abs() < 1e-4);
        let (i, p) = d.sample(u);
        prop_assert!(w[i] > 0.0 && p == d.pmf(i));
    }
}

#[test]
fn thin_lens_focuses_the_focus_plane() {
    // Rays through one raster position meet at the focus distance whatever the lens sample.
    let cam = Camera::new(Vec3::ZERO, -Vec3::Z, Vec3::Y, 40.0, FovAxis::Smaller, (100, 100)).unwrap().with_lens(0.2, 5.0).unwrap();
    let a = cam.ray(30.0, 70.0, (0.1, 0.9));
    let b = cam.ray(30.0, 70.0, (0.8, 0.2));
    assert!((a.o - b.o).length() > 0.05, "different lens positions");
    let plane = |r: vpl_core::Ray| r.at((-5.0 - r.o.z) / r.d.z);
    assert!((plane(a) - plane(b)).length() < 1e-4, "{} {}", plane(a), plane(b));
}

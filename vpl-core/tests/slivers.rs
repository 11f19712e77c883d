//! Long thin, huge and tiny triangles with shading normals: every hit the
//! scene reports, every light sample toward it and every ray it emits is
//! finite, or the triangle was skipped at load with a counted warning. (A sliver of the Cornell box's tall block stretched to
//! y = 4000 once made the barycentrics NaN and `clamp` panic.)

use proptest::prelude::*;
use vpl_core::glam::Vec3;
use vpl_core::{Light, Material, Mesh, Ray, Scene, TriangleDesc};

/// One triangle with tilted shading normals, lit by a point light (or
/// emitting itself, `emissive`); `None` when the scene skips it as
/// degenerate (and says so).
fn scene_of(a: Vec3, b: Vec3, c: Vec3) -> Option<Scene> {
    scene_with(a, b, c, false)
}

fn scene_with(a: Vec3, b: Vec3, c: Vec3, emissive: bool) -> Option<Scene> {
    let ng = (b - a).cross(c - a).normalize_or_zero();
    let tilt = |v: Vec3| (ng + v).normalize_or(ng);
    let mesh = Mesh {
        positions: vec![a, b, c],
        normals: vec![tilt(Vec3::new(0.3, 0.0, 0.0)), tilt(Vec3::new(0.0, 0.3, 0.0)), tilt(Vec3::new(0.0, 0.0, 0.3))],
        triangles: vec![TriangleDesc { v: [0, 1, 2], n: Some([0, 1, 2]), material: 0 }],
    };
    let light = Light::Point { position: (a + b + c) / 3.0 + Vec3::ONE, intensity: Vec3::ONE };
    let (material, lights) = if emissive {
        (Material::emissive("lamp", Vec3::splat(0.5), Vec3::ONE), vec![])
    } else {
        (Material::diffuse("grey", Vec3::splat(0.5)), vec![light])
    };
    match Scene::new("sliver", &mesh, vec![material], lights, true) {
        Ok(s) => Some(s),
        Err(e) => {
            assert!(e.to_string().contains("triangle"), "a scene of one triangle fails only for want of triangles: {e}");
            None
        }
    }
}

/// Points on the triangle (barycentrics `u`), hit from above by the BVH and
/// by `hit_at` (what a GPU caster calls with a (triangle, t) found elsewhere):
/// every hit finite, with unit normals.
fn check(a: Vec3, b: Vec3, c: Vec3, us: &[(f32, f32)]) -> Result<(), TestCaseError> {
    let Some(scene) = scene_of(a, b, c) else { return Ok(()) };
    let ng = (b - a).cross(c - a).normalize();
    for &(u, v) in us {
        let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
        let q = a + (b - a) * u + (c - a) * v;
        let d = 1.0 + q.abs().max_element() * 1e-3;
        let ray = Ray::new(q + ng * d, -ng);
        let hits = [scene.intersect(&ray), Some(scene.hit_at(&ray, 0, d)), Some(scene.hit_at(&ray, 0, 2.0 * d))];
        for h in hits.into_iter().flatten() {
            let p = h.point;
            prop_assert!(h.t.is_finite() && p.p.is_finite(), "{a} {b} {c}: hit {p:?}");
            prop_assert!(p.n.is_normalized() && p.ng.is_normalized(), "{a} {b} {c}: normals {p:?}");
        }
    }
    // The same triangle as an area light: light samples toward points above
    // it and emitted rays are finite (or absent).
    let Some(lamp) = scene_with(a, b, c, true) else { return Ok(()) };
    for &(u, v) in us {
        let q = a + (b - a) * u.min(1.0 - v) + (c - a) * v;
        let x = q + ng * (1.0 + q.abs().max_element() * 1e-3);
        if let Some((ls, p)) = lamp.sample_light(x, u, (u, v)) {
            prop_assert!(
                ls.wi.is_normalized() && ls.li.is_finite() && ls.pdf.is_finite() && ls.pdf >= 0.0 && p.is_finite(),
                "{a} {b} {c}: {ls:?}"
            );
        }
        if let Some(e) = lamp.sample_emission(u, (v, u), (u, v)) {
            prop_assert!(e.beta.is_finite() && e.ray.o.is_finite() && e.ray.d.is_normalized(), "{a} {b} {c}: {e:?}");
        }
    }
    Ok(())
}

#[test]
fn a_long_thin_triangle_hit_at_its_sharp_corner_is_finite() {
    // Found by the property test below: legs of 20 km and 9 cm; the f32
    // barycentrics' denominator cancels to zero at the far corner.
    let (a, b, c) = (Vec3::new(19988.531, 0.0, 0.0), Vec3::ZERO, Vec3::new(0.0, 0.0, 0.09337675));
    check(a, b, c, &[(0.0, 0.0), (0.5, 0.25), (0.999, 0.0)]).unwrap();
}

#[test]
fn the_tall_block_stretched_to_4000_gives_finite_hits() {
    // A face of the Cornell box's tall block with one vertex moved to y = 4000.
    let (a, b, c) = (Vec3::new(0.423, 0.0, 0.247), Vec3::new(0.265, 0.0, 0.296), Vec3::new(0.265, 4000.0, 0.296001));
    let us: Vec<(f32, f32)> = (0..64).map(|i| ((i % 8) as f32 / 8.0 + 0.01, (i / 8) as f32 / 8.0 + 0.01)).collect();
    check(a, b, c, &us).unwrap();
    check(a, c, b, &us).unwrap();
}

fn coordinate() -> impl Strategy<Value = f32> {
    (-1.0f32..1.0, -6i32..7).prop_map(|(m, e)| m * 10f32.powi(e))
}

fn point() -> impl Strategy<Value = Vec3> {
    (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    /// Any triangle of extreme size or shape: finite hits or skipped.
    #[test]
    fn extreme_triangles_give_finite_hits_or_are_skipped(a in point(), b in point(), c in point(),
                                                         us in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 8)) {
        check(a, b, c, &us)?;
    }

    /// Slivers: the third vertex a tiny offset from the line through the first two.
    #[test]
    fn slivers_give_finite_hits_or_are_skipped(a in point(), b in point(), t in -2.0f32..3.0, off in point(),
                                               e in -12i32..-2, us in prop::collection::vec((0.0f32..1.0, 0.0f32..1.0), 8)) {
        let c = a + (b - a) * t + off * 10f32.powi(e);
        check(a, b, c, &us)?;
    }
}

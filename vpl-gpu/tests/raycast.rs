//! GPU ray casting against the CPU BVH (`Scene::intersect`, `Scene::occluded`).
//!
//! The two traverse different trees (binary on the GPU, 8-wide on the CPU)
//! and test triangles with the same watertight test on the same vertices, so
//! a ray finds the same triangle at the same t up to rounding (the GPU may
//! fuse multiply-adds). Rays through a
//! shared edge or onto coplanar faces (cornell's camera rays meet the box
//! corners exactly; the tall box stands on the floor's plane) tie, and the
//! two may pick different triangles at the same t. Tolerances: hit or miss
//! the same for at least 99.9 % of rays; t within 1e-5 relative (plus 1e-6 of the scene's extent) on every ray
//! both hit; the same triangle on at least 99 % of those; occlusion
//! identical for at least 99.9 % of segments.

mod common;

use common::context;
use vpl_core::glam::Vec3;
use vpl_core::sampling::uniform_sphere;
use vpl_core::{CameraRays, Purpose, Ray, Scene, SceneSetup, stream};
use vpl_gpu::{GpuRayCaster, GpuScene};

/// Camera rays over a 96×64 image and rays in random directions from random
/// points inside the scene's bounds and on its surfaces.
fn rays(scene: &Scene, setup: &SceneSetup) -> Vec<Ray> {
    let cam = setup.camera.with_resolution((96, 64)).unwrap();
    let mut out: Vec<Ray> = (0..96 * 64).map(|i| cam.ray((i % 96) as f32 + 0.5, (i / 96) as f32 + 0.5, (0.5, 0.5))).collect();
    let (lo, hi) = scene.geometry.bounds;
    let mut rng = stream(7, 0, Purpose::TEST, 0);
    for k in 0..6000 {
        let d = uniform_sphere(rng.next_f32(), rng.next_f32());
        let o = if k % 2 == 0 {
            lo + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())
        } else {
            let t = &scene.geometry.triangles
                [(rng.next_f32() * scene.geometry.triangles.len() as f32) as usize % scene.geometry.triangles.len()];
            let (u, v) = (rng.next_f32() * 0.5, rng.next_f32() * 0.5);
            let p = t.p0 + t.e1 * u + t.e2 * v;
            let n = if d.dot(t.ng) > 0.0 { t.ng } else { -t.ng };
            p + n * scene.epsilon()
        };
        // Axis-aligned directions with −0.0 components test the traversal's
        // handling of zero slopes.
        let d = if k % 97 == 0 { Vec3::new(-0.0, 1.0, -0.0) } else { d };
        out.push(Ray::new(o, d));
    }
    out
}

fn check(name: &str) {
    let Some(ctx) = context() else { return };
    let setup = vpl_core::SceneSetup::builtin(name).unwrap();
    let scene = &setup.scene;
    let gpu_scene = GpuScene::new(&ctx, scene).unwrap();
    let caster = GpuRayCaster::new(&ctx);
    let rays = rays(scene, &setup);
    // Rounding of t near an origin is absolute, of the order of the
    // coordinates' ulps: 1e-6 of the scene's extent.
    let extent = (scene.geometry.bounds.1 - scene.geometry.bounds.0).max_element();
    let gpu = caster.closest(&ctx, &gpu_scene, &rays).unwrap();
    // same: both miss or both hit the same triangle; hits: both hit.
    let (mut same, mut hits, mut both_miss) = (0usize, 0usize, 0usize);
    for (k, (r, g)) in rays.iter().zip(&gpu).enumerate() {
        let c = scene.intersect(r).map(|h| (h.point.triangle, h.t));
        match (c, g) {
            (None, None) => both_miss += 1,
            (Some((ct, tc)), Some((gt, tg))) => {
                hits += 1;
                assert!((tc - tg).abs() <= 1e-5 * tc + 1e-6 * extent, "{name} ray {k}: CPU t {tc} (tri {ct}), GPU t {tg} (tri {gt})");
                same += (ct == *gt) as usize;
            }
            _ => {}
        }
    }
    let n = rays.len();
    eprintln!("{name}: {n} rays, {hits} hit on both (same triangle: {same}), {both_miss} miss on both");
    assert!(hits > n / 2, "{name}: too few hits to test");
    assert!((hits + both_miss) as f64 >= 0.999 * n as f64, "{name}: hit and miss agree on {} of {n} rays", hits + both_miss);
    assert!(same as f64 >= 0.99 * hits as f64, "{name}: the same triangle on {same} of {hits} hits");
    // Occlusion: segments to a point at 30–90 % of each closest hit (or of a
    // unit length for misses), so both outcomes occur.
    let mut rng = stream(8, 0, Purpose::TEST, 0);
    let segs: Vec<Ray> = rays
        .iter()
        .map(|r| {
            let t = scene.intersect(r).map_or(1.0, |h| h.t);
            Ray::segment(r.o, r.d, t * (0.3 + 1.2 * rng.next_f32()))
        })
        .collect();
    let occ = caster.occluded(&ctx, &gpu_scene, &segs).unwrap();
    let agree = segs.iter().zip(&occ).filter(|(r, o)| scene.occluded(r) == **o).count();
    let blocked = occ.iter().filter(|o| **o).count();
    eprintln!("{name}: occlusion agrees on {agree} of {n} ({blocked} blocked)");
    assert!(blocked > n / 10 && blocked < n * 9 / 10);
    assert!(agree as f64 >= 0.999 * n as f64, "{name}: occlusion agrees on {agree} of {n}");
}

#[test]
fn gpu_rays_match_the_cpu_bvh_on_cornell() {
    check("cornell");
}

#[test]
fn gpu_rays_match_the_cpu_bvh_on_office() {
    check("office");
}

/// Camera rays made on the device ([`GpuRayCaster::closest_camera`]) against
/// the host's [`CameraRays`] cast on the CPU BVH, for a pinhole and a thin
/// lens: the device's rays differ from the host's by rounding only, so the
/// tolerances are those above (hit or miss and the triangle as the CPU's on
/// at least 99.9 % and 99 % of rays; t within 1e-5 relative plus 1e-6 of
/// the extent where both hit the same triangle).
#[test]
fn camera_rays_made_on_the_device_hit_what_the_host_rays_hit() {
    let Some(ctx) = context() else { return };
    let setup = SceneSetup::builtin("office").unwrap();
    let scene = &setup.scene;
    let gs = GpuScene::new(&ctx, scene).unwrap();
    let caster = GpuRayCaster::new(&ctx);
    let c = setup.camera.with_resolution((320, 180)).unwrap();
    let focus = (c.target - c.origin).length();
    let lens = c.with_lens(0.05 * focus, focus).unwrap();
    let extent = (scene.geometry.bounds.1 - scene.geometry.bounds.0).length();
    for (name, camera) in [("pinhole", &c), ("thin lens", &lens)] {
        let batch = CameraRays::new(camera, 0x5EED_0001, 20_000);
        let cpu: Vec<_> = batch.rays.iter().map(|r| scene.intersect(r)).collect();
        let gpu = caster.closest_camera(&ctx, &gs, camera, batch.key, batch.rays.len()).unwrap();
        let (mut agree, mut same, mut hits) = (0, 0, 0);
        for (k, (c, g)) in cpu.iter().zip(&gpu).enumerate() {
            match (c, g) {
                (Some(c), Some((tri, t))) => {
                    agree += 1;
                    hits += 1;
                    if c.point.triangle == *tri {
                        same += 1;
                        assert!((c.t - t).abs() <= 1e-5 * c.t + 1e-6 * extent, "{name} ray {k}: CPU t {}, GPU t {t}", c.t);
                    }
                }
                (None, None) => agree += 1,
                _ => {}
            }
        }
        let n = batch.rays.len();
        eprintln!("{name}: {agree} of {n} agree on hit or miss, {same} of {hits} hits on the same triangle");
        assert!(hits > n / 2, "{name}: too few hits to test");
        assert!(agree as f64 >= 0.999 * n as f64, "{name}: hit and miss agree on {agree} of {n}");
        assert!(same as f64 >= 0.99 * hits as f64, "{name}: the same triangle on {same} of {hits} hits");
    }
}

/// Candidate rays made on the device from the hits of a camera batch it
/// still holds ([`vpl_core::BounceRays`] through [`GpuRays`]) against the
/// host's rays cast on the CPU BVH: the device's rays differ from the
/// host's by rounding (its camera points come from its own camera rays), so
/// the tolerance is the one above: the same hit on at least 99.9 % of rays.
#[test]
fn bounce_rays_made_on_the_device_hit_what_the_host_rays_hit() {
    use vpl_core::sampling::cosine_hemisphere;
    use vpl_core::{BounceRays, CpuRays, LocalFrame, RayCaster};
    let Some(ctx) = context() else { return };
    let setup = SceneSetup::builtin("office").unwrap();
    let scene = &setup.scene;
    let gpu = vpl_gpu::Gpu::from_context(ctx);
    let rays = vpl_gpu::GpuRays::new(gpu.clone());
    let camera = setup.camera.with_resolution((320, 180)).unwrap();
    let batch = CameraRays::new(&camera, 0x5EED_0002, 20_000);
    let hits = rays.intersect_camera(scene, &batch);
    let key = 0x5EED_0003;
    let eps = scene.epsilon();
    let (mut origins, mut cast) = (Vec::new(), Vec::new());
    for (i, (r, h)) in batch.rays.iter().zip(&hits).enumerate() {
        let Some((x, _)) = h.and_then(|h| scene.reflecting(r, h)) else { continue };
        let j = origins.len() as u32;
        let (u, v) = vpl_core::rng::keyed_stream(key, j as u64).next_2d();
        let d = LocalFrame::from_normal(x.n).to_world(cosine_hemisphere(u, v));
        if d.dot(x.ng) > 0.0 {
            origins.push((i as u32, j));
            cast.push(Ray::new(x.p + x.ng * eps, d));
        }
    }
    let bounce = BounceRays { camera: &batch, key, origins, rays: cast };
    let before = gpu.traffic();
    let gpu_hits = rays.intersect_bounce(scene, &bounce);
    let moved = gpu.traffic() - before;
    let cpu = CpuRays.intersect(scene, &bounce.rays);
    let n = bounce.rays.len();
    // Made on the device: 8 B a ray up (not the 24 B of the rays), 4 B back.
    assert!(moved.bytes_up <= 8 * n as u64 + 256 && moved.bytes_down == 4 * n as u64, "{moved}");
    let same = cpu.iter().zip(&gpu_hits).filter(|(a, b)| a == b).count();
    let hit = cpu.iter().filter(|h| h.is_some()).count();
    eprintln!("{same} of {n} bounce rays hit as on the CPU ({hit} hit)");
    assert!(n > 10_000 && hit > n / 2);
    assert!(same as f64 >= 0.999 * n as f64, "{same} of {n}");
}

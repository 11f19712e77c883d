//! The G-buffer kernel against `vpl_shading::render_gbuffer`.
//!
//! Both shoot the same camera ray through each pixel centre and test the
//! same prepared triangles; they differ in rounding (fused multiply-adds,
//! normalisation) and in which of two tied triangles a ray through a shared
//! edge reports. Tolerances: hit or miss the same on at least 99.9 % of
//! pixels; positions within 1e-5 of the depth plus 1e-6 of the scene's
//! extent on every pixel both hit; the same material on at least 99 % of
//! them, and there normals within 1e-4 and albedo and emission bit-equal.

mod common;

use common::context;
use vpl_gpu::{GpuGBufferRenderer, GpuScene};

fn check(name: &str, res: (u32, u32)) {
    let Some(ctx) = context() else { return };
    let setup = vpl_core::SceneSetup::builtin(name).unwrap();
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution(res).unwrap();
    let cpu = vpl_shading::render_gbuffer(scene, &camera);
    let gpu_scene = GpuScene::new(&ctx, scene).unwrap();
    let gpu = GpuGBufferRenderer::new(&ctx).render(&ctx, &gpu_scene, scene, &camera).unwrap().read(&ctx).unwrap();
    assert_eq!((gpu.width, gpu.height, gpu.pixel_angle, gpu.eye), (cpu.width, cpu.height, cpu.pixel_angle, cpu.eye));
    let extent = (scene.geometry.bounds.1 - scene.geometry.bounds.0).max_element();
    let (mut agree, mut hits, mut same_material) = (0usize, 0usize, 0usize);
    for (i, (c, g)) in cpu.samples.iter().zip(&gpu.samples).enumerate() {
        if c.hit() != g.hit() {
            continue;
        }
        agree += 1;
        if !c.hit() {
            continue;
        }
        hits += 1;
        assert!((c.p - g.p).length() <= 1e-5 * c.depth + 1e-6 * extent, "{name} pixel {i}: p {} vs {}", c.p, g.p);
        assert!((c.depth - g.depth).abs() <= 1e-5 * c.depth + 1e-6 * extent, "{name} pixel {i}: depth {} vs {}", c.depth, g.depth);
        if c.material == g.material {
            same_material += 1;
            assert!((c.n - g.n).abs().max_element() <= 1e-4, "{name} pixel {i}: n {} vs {}", c.n, g.n);
            assert!((c.ng - g.ng).abs().max_element() <= 1e-4, "{name} pixel {i}: ng {} vs {}", c.ng, g.ng);
            assert_eq!((c.albedo, c.emitted), (g.albedo, g.emitted), "{name} pixel {i}");
        }
    }
    let n = cpu.samples.len();
    eprintln!("{name}: {n} pixels, hit/miss agree on {agree}, {hits} hits, same material on {same_material}");
    assert!(agree as f64 >= 0.999 * n as f64);
    assert!(hits > n / 2);
    assert!(same_material as f64 >= 0.99 * hits as f64);
}

#[test]
fn gpu_gbuffer_matches_the_cpu_gbuffer_on_cornell() {
    check("cornell", (96, 64));
}

/// Larger scenes with many materials: office (one-sided) and atrium.
#[test]
fn gpu_gbuffer_matches_the_cpu_gbuffer_on_office_and_atrium() {
    check("office", (160, 90));
    check("atrium", (160, 90));
}

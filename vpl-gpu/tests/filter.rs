//! The GPU filter against its CPU twin. Without an adapter the test says it
//! skipped, unless VPL_REQUIRE_GPU=1 (CI), where a missing adapter fails.

mod common;

use common::context;
use vpl_core::glam::Vec3;
use vpl_core::{Image, SceneSetup};
use vpl_gpu::GpuCrossBilateral;
use vpl_shading::CrossBilateral;

/// On `cornell` (64×48) with an interleaving-like pattern: every pixel
/// within 1e-4 relative (plus 1e-6 absolute) of the CPU filter. The two
/// differ only in exp() and the order of float additions.
#[test]
fn gpu_filter_matches_the_cpu_filter() {
    let Some(ctx) = context() else { return };
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((64, 48)).unwrap();
    let gbuf = vpl_shading::render_gbuffer(&setup.scene, &camera);
    let mut e = Image::new(64, 48);
    for (i, c) in e.data.iter_mut().enumerate() {
        let (x, y) = (i % 64, i / 64);
        *c = Vec3::new(((x * 7 + y * 3) % 16) as f32, (x % 4) as f32 * 0.5, (y % 4) as f32 * 0.25);
    }
    let f = CrossBilateral::default();
    let cpu = f.apply(&gbuf, &e);
    let gpu = GpuCrossBilateral { filter: f }.apply(&ctx, &gbuf, &e).unwrap();
    let mut worst = 0.0f32;
    for (a, b) in cpu.data.iter().zip(&gpu.data) {
        for c in 0..3 {
            let err = (a[c] - b[c]).abs() / (a[c].abs() * 1e-4 + 1e-6);
            worst = worst.max(err);
        }
    }
    assert!(worst <= 1.0, "GPU and CPU filters differ by {worst} tolerances");
    assert!(cpu.data.iter().any(|c| c.x > 0.0));
}

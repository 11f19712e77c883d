//! GPU interleaved shading against `vpl_shading::InterleavedShader`, with
//! shadow maps and with shadow rays, filtered and raw.
//!
//! Both sum the same slots in the same order per pixel; they differ by
//! float rounding (~1e-7 relative) and where a receiver sits on the
//! threshold of a shadow-map test or a shadow ray grazes an edge, which
//! flips one VPL's term at one pixel. Tolerance: relative squared error
//! Σ|gpu − cpu|² / Σ|cpu|² ≤ 1e-6 over the image, and at least 99 % of
//! pixels within 1e-4 relative (plus 1e-6 of the mean) of the CPU's.

mod common;

use common::context;
use vpl_core::{GeometryClamp, Image, IndirectShader, SceneSetup, VplVisibility};
use vpl_gpu::{Gpu, GpuInterleavedShader, GpuRayTraced, GpuShadowMaps};
use vpl_shading::{ExhaustiveShader, InterleavedShader};
use vpl_visibility::{RayTraced, ShadowMaps};

fn compare(label: &str, cpu: &Image, gpu: &Image) {
    let mean = cpu.data.iter().map(|c| c.element_sum()).sum::<f32>() / cpu.data.len() as f32;
    assert!(mean > 0.0, "{label}: a black image tests nothing");
    let (mut num, mut den, mut close) = (0.0f64, 0.0f64, 0usize);
    for (c, g) in cpu.data.iter().zip(&gpu.data) {
        num += (*c - *g).length_squared() as f64;
        den += c.length_squared() as f64;
        close += ((*c - *g).abs().max_element() <= 1e-4 * c.abs().max_element() + 1e-6 * mean) as usize;
    }
    let rel = num / den;
    eprintln!("{label}: relative squared error {rel:.3e}, {close} of {} pixels close", cpu.data.len());
    assert!(rel <= 1e-6, "{label}: relative squared error {rel:e}");
    assert!(close as f64 >= 0.99 * cpu.data.len() as f64, "{label}: {close} pixels close");
}

#[test]
fn gpu_interleaved_shading_matches_the_cpu_shader() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution((96, 54)).unwrap();
    let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 256, ..Default::default() }).unwrap().sample(scene, 5).clone();
    let clamp = Some(GeometryClamp::new(50.0));
    // The G-buffer rendered on the device, so the shader reads it in place.
    let gbuf = gpu.render_gbuffer(scene, &camera).unwrap();
    for filter in [true, false] {
        let mut cpu_shader = InterleavedShader::new(clamp, 9);
        let mut gpu_shader = GpuInterleavedShader::new(gpu.clone(), clamp, 9);
        if !filter {
            cpu_shader.filter = None;
            gpu_shader.cpu.filter = None;
        }
        let mut sm = ShadowMaps::new(64).unwrap();
        let mut gsm = GpuShadowMaps::new(gpu.clone(), 64).unwrap();
        sm.update(scene, &set);
        gsm.update(scene, &set);
        let a = cpu_shader.shade(&gbuf, &set, &sm);
        let b = gpu_shader.shade(&gbuf, &set, &gsm);
        compare(&format!("shadow maps, filter {filter}"), &a, &b);
        let mut rt = RayTraced::default();
        let mut grt = GpuRayTraced::new(gpu.clone());
        rt.update(scene, &set);
        grt.update(scene, &set);
        let a = cpu_shader.shade(&gbuf, &set, &rt);
        let b = gpu_shader.shade(&gbuf, &set, &grt);
        compare(&format!("shadow rays, filter {filter}"), &a, &b);
    }
    // Exhaustive shading: every VPL at every pixel.
    let mut sm = ShadowMaps::new(64).unwrap();
    let mut gsm = GpuShadowMaps::new(gpu.clone(), 64).unwrap();
    sm.update(scene, &set);
    gsm.update(scene, &set);
    let a = ExhaustiveShader { clamp }.shade(&gbuf, &set, &sm);
    let b = GpuInterleavedShader::exhaustive(gpu.clone(), clamp).shade(&gbuf, &set, &gsm);
    compare("exhaustive, shadow maps", &a, &b);
}

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

/// A shader finds a visibility's device structures by its
/// [`VplVisibility::device_key`], on its own device only: maps on another
/// device, or a visibility on the host, make it shade on the host. A depth
/// bias set after the maps' update reaches the device gather (checked
/// against the CPU maps with the same bias, which must differ from the
/// default's image for the check to tell).
#[test]
fn the_shader_reads_only_visibilities_of_its_own_device() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    // A second device where the driver gives one (GL may not); without it
    // the shader's own table is tested against host visibility alone.
    let other = match vpl_gpu::GpuContext::new() {
        Ok(c) => Some(Gpu::from_context(c)),
        Err(e) => {
            eprintln!("no second device ({e}): maps on another device are not tested");
            None
        }
    };
    let setup = SceneSetup::builtin("cornell").unwrap();
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution((48, 48)).unwrap();
    let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 64, ..Default::default() }).unwrap().sample(scene, 5).clone();
    let clamp = Some(GeometryClamp::new(50.0));
    let gbuf = gpu.render_gbuffer(scene, &camera).unwrap();
    let mut shader = GpuInterleavedShader::exhaustive(gpu.clone(), clamp);

    let mut mine = GpuShadowMaps::new(gpu.clone(), 16).unwrap();
    mine.update(scene, &set);
    let mut host = RayTraced::default();
    host.update(scene, &set);
    let mut second = GpuShadowMaps::new(gpu.clone(), 16).unwrap();
    second.update(scene, &set);
    assert!(mine.device_key().is_some() && host.device_key().is_none());
    assert_ne!(mine.device_key(), second.device_key(), "every visibility has its own key");
    assert!(shader.on_device(&mine) && shader.on_device(&second));
    assert!(!shader.on_device(&host), "a visibility on the host");
    let device_maps = shader.shade(&gbuf, &set, &mine);
    // Another device's maps shade on the host, through the same answers.
    if let Some(other) = other {
        let mut theirs = GpuShadowMaps::new(other, 16).unwrap();
        theirs.update(scene, &set);
        assert!(!shader.on_device(&theirs), "maps on another device");
        let host_maps = shader.shade(&gbuf, &set, &theirs);
        compare("another device's maps, on the host", &device_maps, &host_maps);
    }

    // Coarse 16² maps show the bias: k = 4 against the default k = 1.
    let mut cpu = ShadowMaps::new(16).unwrap();
    cpu.bias_scale = 4.0;
    cpu.update(scene, &set);
    mine.set_bias_scale(4.0);
    let biased = shader.shade(&gbuf, &set, &mine);
    compare("bias 4, set after the update", &ExhaustiveShader { clamp }.shade(&gbuf, &set, &cpu), &biased);
    let changed =
        biased.data.iter().zip(&device_maps.data).filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3 * b.max_element()).count();
    assert!(changed > 0, "the bias must change the image for this check to tell");
}

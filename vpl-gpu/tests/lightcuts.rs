//! GPU stochastic lightcuts against `vpl_shading::LightcutShader` (the same
//! cut, walk and streams) and against exhaustive gathering (unbiasedness).
//!
//! Twin: both shaders choose each pixel's cut by the same importance and
//! draw from the same PCG32 streams, so a pixel differs by float rounding
//! (~1e-6 relative) unless rounding tips an importance comparison or a
//! visibility test at a threshold, which changes one sampled VPL at that
//! pixel. Tolerance: at least 99 % of pixels within 1e-4 relative (plus
//! 1e-6 of the mean) of the CPU's, and image means within 1e-3 relative.
//!
//! Unbiasedness, on cornell, office and Dabrovic's Sponza (where its model
//! is present): the mean of 24 GPU frames (fresh streams each) against
//! the exhaustive sum over the same VPLs and visibility, which has no noise:
//! the image mean and the means of 8×8-pixel blocks within 4 standard
//! errors of the frames' spread (p ≈ 6e-5 each).

mod common;

use common::context;
use vpl_core::{GeometryClamp, Image, IndirectShader, SceneSetup, VplVisibility};
use vpl_gpu::{Gpu, GpuLightcutShader, GpuRayTraced, GpuShadowMaps};
use vpl_shading::{ExhaustiveShader, LightcutShader};
use vpl_visibility::{RayTraced, ShadowMaps};

fn mean(img: &Image) -> f64 {
    img.data.iter().map(|c| c.element_sum() as f64).sum::<f64>() / img.data.len() as f64
}

fn twin(label: &str, cpu: &Image, gpu: &Image) {
    let m = mean(cpu) as f32;
    assert!(m > 0.0, "{label}: a black image tests nothing");
    let close =
        cpu.data.iter().zip(&gpu.data).filter(|(c, g)| (**c - **g).abs().max_element() <= 1e-4 * c.abs().max_element() + 1e-6 * m).count();
    let rel = (mean(gpu) - mean(cpu)).abs() / mean(cpu);
    eprintln!("{label}: {close} of {} pixels close, means differ by {rel:.2e} relative", cpu.data.len());
    assert!(close as f64 >= 0.99 * cpu.data.len() as f64, "{label}: {close} of {} pixels close", cpu.data.len());
    assert!(rel <= 1e-3, "{label}: image means differ by {rel:e} relative");
}

#[test]
fn gpu_lightcuts_draw_the_cpu_shaders_cuts() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("office").unwrap();
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution((96, 54)).unwrap();
    let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 512, ..Default::default() }).unwrap().sample(scene, 5).clone();
    let gbuf = gpu.render_gbuffer(scene, &camera).unwrap();
    let mut rt = RayTraced::default();
    let mut grt = GpuRayTraced::new(gpu.clone());
    rt.update(scene, &set);
    grt.update(scene, &set);
    let mut sm = ShadowMaps::new(64).unwrap();
    let mut gsm = GpuShadowMaps::new(gpu.clone(), 64).unwrap();
    sm.update(scene, &set);
    gsm.update(scene, &set);
    for (cut, clamp) in [(4, None), (32, Some(GeometryClamp::new(50.0)))] {
        let mut cpu = LightcutShader::new(cut, clamp, 7);
        let mut dev = GpuLightcutShader::new(gpu.clone(), cut, clamp, 7);
        // Two frames each: the second draws new streams on both.
        for frame in 0..2 {
            let a = cpu.shade(&gbuf, &set, &rt);
            let b = dev.shade(&gbuf, &set, &grt);
            twin(&format!("cut {cut}, shadow rays, frame {frame}"), &a, &b);
        }
        let a = cpu.shade(&gbuf, &set, &sm);
        let b = dev.shade(&gbuf, &set, &gsm);
        twin(&format!("cut {cut}, shadow maps"), &a, &b);
        // A host visibility: the GPU shader runs its CPU twin, which draws the same streams.
        let a = cpu.shade(&gbuf, &set, &rt);
        let b = dev.shade(&gbuf, &set, &rt);
        assert_eq!(a.data, b.data, "cut {cut}: host visibility");
    }
}

#[test]
fn gpu_lightcuts_are_unbiased_against_exhaustive_gathering() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    // The built-ins, and Dabrovic's Sponza (66K triangles) where its model is in ../shared/scenes.
    let sponza = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/sponza-dabrovic.toml");
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes/sponza-dabrovic/sponza.obj");
    let mut scenes = vec![("cornell", SceneSetup::builtin("cornell").unwrap()), ("office", SceneSetup::builtin("office").unwrap())];
    if model.is_file() {
        scenes.push(("sponza-dabrovic", vpl_scene_io::load(&sponza.to_string_lossy()).unwrap()));
    } else {
        eprintln!("skipped sponza-dabrovic: {} is not there", model.display());
    }
    for (name, setup) in scenes {
        let scene = &setup.scene;
        let (w, h) = (64u32, 48u32);
        let camera = setup.camera.with_resolution((w, h)).unwrap();
        let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 1024, ..Default::default() }).unwrap().sample(scene, 3).clone();
        let gbuf = gpu.render_gbuffer(scene, &camera).unwrap();
        let mut grt = GpuRayTraced::new(gpu.clone());
        grt.update(scene, &set);
        let mut rt = RayTraced::default();
        rt.update(scene, &set);
        let exact = ExhaustiveShader { clamp: None }.shade(&gbuf, &set, &rt);
        let mut dev = GpuLightcutShader::new(gpu.clone(), 8, None, 11);
        let frames: Vec<Image> = (0..24).map(|_| dev.shade(&gbuf, &set, &grt)).collect();
        // Regions: the image, and 8×8 blocks.
        let mut regions: Vec<Vec<usize>> = vec![(0..(w * h) as usize).collect()];
        for by in 0..h / 8 {
            for bx in 0..w / 8 {
                regions.push((0..(w * h) as usize).filter(|i| (*i as u32 % w) / 8 == bx && (*i as u32 / w) / 8 == by).collect());
            }
        }
        let region_mean = |img: &Image, r: &[usize]| r.iter().map(|&i| img.data[i].element_sum() as f64).sum::<f64>() / r.len() as f64;
        let mut worst = 0.0f64;
        for (k, r) in regions.iter().enumerate() {
            let target = region_mean(&exact, r);
            let xs: Vec<f64> = frames.iter().map(|f| region_mean(f, r)).collect();
            let n = xs.len() as f64;
            let m = xs.iter().sum::<f64>() / n;
            let se = (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
            if target <= 0.0 && m <= 0.0 {
                continue;
            }
            let z = (m - target).abs() / se.max(1e-6 * target.abs().max(1e-12));
            worst = worst.max(z);
            assert!(z <= 4.0, "{name} region {k}: lightcuts {m} ± {se}, exhaustive {target} ({z:.1} s.e.)");
        }
        eprintln!("{name}: worst of {} regions {worst:.2} s.e.", regions.len());
    }
}

//! Stochastic lightcuts on the real scenes of `../shared/scenes` (Dabrovic's
//! Sponza, 66K triangles, and the Munich blocks), where their models are
//! present: the same z-test as vpl-shading's on the built-ins, against
//! exhaustive gathering of the same VPL set (the mean of 32 frames' image
//! means within 4 standard errors of the exhaustive image mean; seeds fixed).

use vpl_core::image::luminance;
use vpl_core::{IndirectShader, VplVisibility};
use vpl_shading::{ExhaustiveShader, LightcutShader, render_gbuffer};
use vpl_visibility::RayTraced;

#[test]
fn stochastic_lightcuts_are_unbiased_on_the_real_scenes() {
    let mut ran = 0;
    for file in ["sponza-dabrovic.toml", "city-munich.toml"] {
        let Some(path) = vpl_tests::real_scene(file) else {
            eprintln!("skipped {file}: its model is not in ../shared/scenes");
            continue;
        };
        let setup = vpl_scene_io::load(&path.to_string_lossy()).unwrap();
        let scene = &setup.scene;
        let (w, h) = setup.camera.resolution;
        let camera = setup.camera.with_resolution((40, (40 * h / w).max(1))).unwrap();
        let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 256, ..Default::default() }).unwrap().sample(scene, 5).clone();
        let gbuf = render_gbuffer(scene, &camera);
        let mut vis = RayTraced::default();
        vis.update(scene, &set);
        let mean = |img: &vpl_core::Image| img.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.data.len() as f64;
        let truth = mean(&ExhaustiveShader { clamp: None }.shade(&gbuf, &set, &vis));
        assert!(truth > 0.0, "{file}: a black image tests nothing");
        let mut shader = LightcutShader::new(8, None, 5);
        let xs: Vec<f64> = (0..32).map(|_| mean(&shader.shade(&gbuf, &set, &vis))).collect();
        let n = xs.len() as f64;
        let m = xs.iter().sum::<f64>() / n;
        let se = (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let z = (m - truth) / se;
        eprintln!("{file}: lightcuts (cut 8 of 256) {m:.5} ± {se:.5} against exhaustive {truth:.5}, z {z:+.2}");
        assert!(se > 0.0 && z.abs() <= 4.0, "{file}: {m} ± {se} against {truth}, z = {z:.2}");
        ran += 1;
    }
    eprintln!("{ran} real scenes tested");
}

//! glTF scenes render with the light they carry: the VPL renderer (IR, an
//! unbiased sampler, unclamped) against the path tracer on the same scene.
//! Fixed seeds; the bound says why.

use std::path::{Path, PathBuf};
use vpl_core::image::luminance;
use vpl_core::{Image, SceneSetup};
use vpl_pathtrace::{Footprint, Mode, PathTracer, track_with};
use vpl_render::{Clamp, Renderer, ShadingSpec, VisibilitySpec};
use vpl_tests::mean_se;

fn gltf_data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../vpl-core/tests/data/gltf").join(p)
}

/// Mean luminance of an image and, from per-pixel standard errors, its
/// standard error (pixels independent; the luminance of the channels'
/// errors bounds the luminance's, so the error is conservative).
fn mean_and_se(img: &Image, se: &Image) -> (f64, f64) {
    let n = img.data.len() as f64;
    let m = img.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / n;
    let v = se.data.iter().map(|&c| (luminance(c) as f64).powi(2)).sum::<f64>();
    (m, v.sqrt() / n)
}

/// `Sundial.glb` (its sun, its camera, at 48×36, its materials' albedo) and `Box.gltf` under a
/// scene file's point light and a camera of its own: full light (direct
/// and indirect, depth 5). The VPL image mean over 8 seeds (1024 VPLs each,
/// ray-traced, exhaustive) must lie within 4 standard errors of the path
/// tracer's (256 paths through each pixel centre, the point the G-buffer
/// shades), the error combining the spread over
/// seeds (7 degrees of freedom: P(|t| > 4) ≈ 0.5 % per scene) and the path
/// tracer's own, plus 1e-5 of the mean for rounding.
#[test]
fn gltf_scenes_render_with_their_light_as_the_path_tracer_does() {
    let dir = vpl_tests::scratch_dir("gltf-render");
    let box_toml = dir.join("box.toml");
    std::fs::write(
        &box_toml,
        format!(
            "[geometry]\ngltf = \"{}\"\n[camera]\norigin = [1.5, 1.2, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 45.0\n\
             [[lights]]\ntype = \"point\"\nposition = [0.8, 1.5, 0.6]\nintensity = [2.0, 2.0, 2.0]\n",
            gltf_data("Box/Box.gltf").display()
        ),
    )
    .unwrap();
    let scenes = [("Sundial", gltf_data("Sundial-KHR_lights_punctual/Sundial.glb")), ("Box", box_toml)];
    for (name, path) in scenes {
        let setup = SceneSetup::load(path.to_str().unwrap()).unwrap();
        // The VPL pipeline reads the albedo only; Sundial's one smooth metal
        // ("Material", κ 0.58) would be black there and glossy in the path
        // tracer (3.6 % of the image). Both render the albedo-only scene, so
        // what is compared is the geometry and light the file carries.
        let mut scene = setup.scene.clone();
        for m in scene.materials.iter_mut() {
            m.layered = None;
        }
        let scene = &scene;
        assert!(!scene.lights.is_empty(), "{name}");
        let camera = setup.camera.with_resolution((48, 36)).unwrap();
        // Through each pixel's centre, the point the G-buffer shades.
        let (w, h) = camera.resolution;
        let pixels: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
        let tracked = track_with(scene, &camera, &PathTracer::new(5, Mode::Full), &pixels, 256, 3, 0, Footprint::Centre);
        let (mut img, mut err) = (Image::new(w, h), Image::new(w, h));
        for t in tracked {
            img.set(t.pixel.0, t.pixel.1, t.mean);
            err.set(t.pixel.0, t.pixel.1, t.stderr);
        }
        let (m_pt, se_pt) = mean_and_se(&img, &err);
        let means: Vec<f64> = (0..8)
            .map(|seed| {
                let mut r = Renderer::builder(scene)
                    .sampler("ir")
                    .vpls(1024)
                    .seed(seed)
                    .visibility(VisibilitySpec::RayTraced)
                    .shader(ShadingSpec::Exhaustive)
                    .mode(vpl_core::Mode::Full)
                    .clamp(Clamp::Off)
                    .build()
                    .unwrap();
                let out = r.render(scene, &camera, 0, 0.0).unwrap();
                out.image.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / out.image.data.len() as f64
            })
            .collect();
        let (m, se) = mean_se(&means);
        // A lone convex box has no indirect light: both images are direct
        // light only, equal up to rounding (1e-5 relative).
        let z = (m - m_pt) / ((se * se + se_pt * se_pt).sqrt() + 1e-5 * m_pt);
        eprintln!("{name}: path tracer {m_pt:.5} ± {se_pt:.5}, VPL {m:.5} ± {se:.5}, z = {z:.2}");
        assert!(m_pt > 1e-3, "{name}: the scene is dark ({m_pt})");
        assert!(z.abs() <= 4.0, "{name}: VPL {m} vs path tracer {m_pt}, z = {z:.2}");
    }
}

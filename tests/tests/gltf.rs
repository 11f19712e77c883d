//! glTF scenes render with the light they carry: the VPL renderer (IR, an
//! unbiased sampler, unclamped) against the path tracer on the same scene.
//! Fixed seeds; the bound says why.

use std::path::{Path, PathBuf};
use vpl_tests::vpl_against_path_tracer;

fn gltf_data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../vpl-scene-io/tests/data/gltf").join(p)
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
            "[geometry]\ngltf = \"{}\"\nallow_outside = [\"{}\"]\n[camera]\norigin = [1.5, 1.2, 2.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 45.0\n\
             [[lights]]\ntype = \"point\"\nposition = [0.8, 1.5, 0.6]\nintensity = [2.0, 2.0, 2.0]\n",
            gltf_data("Box/Box.gltf").display(),
            gltf_data("Box").display()
        ),
    )
    .unwrap();
    let scenes = [("Sundial", gltf_data("Sundial-KHR_lights_punctual/Sundial.glb")), ("Box", box_toml)];
    for (name, path) in scenes {
        let setup = vpl_scene_io::load(path.to_str().unwrap()).unwrap();
        // The VPL pipeline reads the albedo only; Sundial's one smooth metal
        // ("Material", κ 0.58) would be black there and glossy in the path
        // tracer (3.6 % of the image). Both render the albedo-only scene, so
        // what is compared is the geometry and light the file carries.
        let scene = &setup.scene.with_material_policy(vpl_core::MaterialPolicy::Diffuse);
        assert!(!scene.lights.is_empty(), "{name}");
        let camera = setup.camera.with_resolution((48, 36)).unwrap();
        // Through each pixel's centre, the point the G-buffer shades.
        let c = vpl_against_path_tracer(scene, &camera, 1024, 8, 256);
        let z = c.z(1e-5);
        let ((m_pt, se_pt), (m, se)) = (c.path, c.vpl);
        eprintln!("{name}: path tracer {m_pt:.5} ± {se_pt:.5}, VPL {m:.5} ± {se:.5}, z = {z:.2}");
        assert!(m_pt > 1e-3, "{name}: the scene is dark ({m_pt})");
        assert!(z.abs() <= 4.0, "{name}: VPL {m} vs path tracer {m_pt}, z = {z:.2}");
    }
}

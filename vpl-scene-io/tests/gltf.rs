//! glTF 2.0 loading on the samples in `tests/data/gltf` (copies of
//! `../shared/scenes/gltf-samples`).
#![cfg(feature = "gltf")]

use std::path::{Path, PathBuf};
use vpl_core::Light;
use vpl_core::glam::Vec3;
use vpl_core::scene_file::LightSpec;
use vpl_scene_io::SceneIoError;
use vpl_scene_io::gltf::{average_colour, kappa_from_roughness, load_gltf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf").join(p)
}

fn bounds(ps: &[Vec3]) -> (Vec3, Vec3) {
    ps.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

#[test]
fn box_has_twelve_triangles_a_rotated_unit_cube_and_a_red_rough_metal_drawn_as_lambertian() {
    let d = load_gltf(&data("Box/Box.gltf"), None).unwrap();
    assert_eq!(d.mesh.triangles.len(), 12);
    // The node's matrix turns the ±0.5 cube by 90° about x: still ±0.5.
    let (lo, hi) = bounds(&d.mesh.positions);
    assert!(close(lo, Vec3::splat(-0.5), 1e-6) && close(hi, Vec3::splat(0.5), 1e-6), "{lo} {hi}");
    // Normals follow the rotation: each triangle's shading normal agrees with its winding.
    for t in &d.mesh.triangles {
        let [a, b, c] = t.v.map(|i| d.mesh.positions[i as usize]);
        let ng = (b - a).cross(c - a).normalize();
        let ns = d.mesh.normals[t.n.unwrap()[0] as usize];
        assert!(ng.dot(ns) > 0.999, "{ng} {ns}");
    }
    // baseColorFactor (0.8, 0, 0); metallic and roughness default to 1: a rough metal, Lambertian here.
    assert_eq!(d.materials.len(), 1);
    assert!(close(d.materials[0].albedo, Vec3::new(0.8, 0.0, 0.0), 1e-6));
    assert!(d.materials[0].layered.is_none());
    assert!(d.lights.is_empty() && d.camera.is_none());
}

#[test]
fn a_buffer_that_does_not_match_its_accessors_is_refused_by_name() {
    let e = load_gltf(&data("BoxTextured/BoxTextured.gltf"), None).unwrap_err();
    assert!(matches!(e, SceneIoError::Gltf { .. }));
    let m = e.to_string();
    assert!(m.contains("accessor 2") && m.contains("does not match"), "{m}");
}

#[test]
fn the_texture_average_is_taken_in_linear_light() {
    let d = load_gltf(&data("BoxTextured/BoxTextured-matching.gltf"), None).unwrap();
    assert_eq!(d.mesh.triangles.len(), 12);
    // The average over the PNG's texels, decoded here independently with the png crate.
    let mut decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(data("BoxTextured/CesiumLogoFlat.png")).unwrap()));
    decoder.set_transformations(png::Transformations::EXPAND);
    let mut r = decoder.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.bit_depth, png::BitDepth::Eight);
    let ch = info.color_type.samples();
    let lin = |v: u8| {
        let c = v as f64 / 255.0;
        if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
    };
    let mut sum = [0.0f64; 3];
    let px = buf[..info.buffer_size()].chunks_exact(ch);
    let n = px.len() as f64;
    for p in px {
        for k in 0..3 {
            sum[k] += lin(p[k.min(ch - 1)]);
        }
    }
    let want = Vec3::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32);
    assert!(close(d.materials[0].albedo, want, 1e-4), "{} vs {want}", d.materials[0].albedo);
    // Not the sRGB-encoded mean (which is brighter).
    assert!(want.max_element() < 0.9);
}

#[test]
fn alpha_masked_texels_are_left_out_and_blended_ones_count_by_alpha() {
    let img = vpl_scene_io::gltf::gltf::image::Data {
        pixels: vec![255, 255, 255, 255, 0, 0, 0, 0, 188, 188, 188, 128],
        format: vpl_scene_io::gltf::gltf::image::Format::R8G8B8A8,
        width: 3,
        height: 1,
    };
    let opaque = average_colour(&img, None, false).unwrap();
    let masked = average_colour(&img, Some(0.6), false).unwrap();
    let blended = average_colour(&img, None, true).unwrap();
    let g = {
        let c: f32 = 188.0 / 255.0;
        ((c + 0.055) / 1.055).powf(2.4)
    };
    assert!(close(opaque, Vec3::splat((1.0 + g) / 3.0), 1e-5), "{opaque}");
    assert!(close(masked, Vec3::ONE, 1e-6), "{masked}");
    let a = 128.0 / 255.0;
    assert!(close(blended, Vec3::splat((1.0 + a * g) / (1.0 + a)), 1e-5), "{blended}");
    let clear = vpl_scene_io::gltf::gltf::image::Data {
        pixels: vec![9, 9, 9, 0],
        format: vpl_scene_io::gltf::gltf::image::Format::R8G8B8A8,
        width: 1,
        height: 1,
    };
    assert!(average_colour(&clear, Some(0.5), false).is_none());
}

#[test]
fn cameras_takes_the_perspective_camera_and_skips_the_orthographic_one() {
    let d = load_gltf(&data("Cameras/Cameras.gltf"), None).unwrap();
    assert_eq!(d.mesh.triangles.len(), 2);
    let c = d.camera.unwrap();
    assert_eq!(c.origin, [0.5, 0.5, 3.0]);
    assert!(close(Vec3::from(c.target) - Vec3::from(c.origin), -Vec3::Z, 1e-6));
    assert!((c.fov - 0.7f32.to_degrees()).abs() < 1e-4 && c.fov_axis == vpl_core::FovAxis::Y);
    assert_eq!(c.resolution, [480, 480]);
    assert!(d.warnings.iter().any(|w| w.contains("orthographic")), "{:?}", d.warnings);
    let e = load_gltf(&data("Cameras/Cameras.gltf"), Some("nope")).unwrap_err().to_string();
    assert!(e.contains("no perspective camera named 'nope'"), "{e}");
}

#[test]
fn sundial_has_its_sun_camera_and_hidden_nodes_left_out() {
    let d = load_gltf(&data("Sundial-KHR_lights_punctual/Sundial.glb"), None).unwrap();
    assert_eq!(d.lights.len(), 1);
    let LightSpec::Directional { direction, irradiance } = d.lights[0] else { panic!("{:?}", d.lights[0]) };
    // intensity π times the light's colour; the sun shines down.
    assert!(Vec3::from(irradiance).max_element() <= std::f32::consts::PI + 1e-5 && Vec3::from(irradiance).max_element() > 1.0);
    assert!(direction[1] < 0.0, "{direction:?}");
    assert!(d.camera.is_some());
    let n = d.mesh.triangles.len();
    // The file has 10,134 triangles in all; the two nodes KHR_node_visibility hides are left out.
    assert!(n > 0 && n < 10_134, "{n}");
    // The whole file renders: lights, camera and geometry make a scene.
    let s = vpl_scene_io::load(data("Sundial-KHR_lights_punctual/Sundial.glb").to_str().unwrap()).unwrap();
    assert!(matches!(s.scene.lights[0], Light::Directional { .. }));
    assert_eq!(s.camera.resolution.1, 480);
}

#[test]
fn punctual_light_snippets_become_lights_or_clear_errors() {
    let d = load_gltf(&data("khr-extension-snippets/KHR_lights_punctual/node_point_valid.gltf"), None).unwrap();
    // A point light with the defaults (white, intensity 1) on a node without a transform.
    assert_eq!(d.lights, vec![LightSpec::Point { position: [0.0; 3], intensity: [1.0; 3] }]);
    // A light no node carries is not in the scene.
    let d = load_gltf(&data("khr-extension-snippets/KHR_lights_punctual/light_spot_valid.gltf"), None).unwrap();
    assert!(d.lights.is_empty());
    let e = load_gltf(&data("khr-extension-snippets/KHR_lights_punctual/light_spot_invalid_angles.gltf"), None);
    // The light is on no node, so the file loads; the angles are checked when a node carries it (below).
    assert!(e.is_ok());
}

#[test]
fn a_spot_on_a_node_gets_its_cone_and_bad_angles_are_an_error() {
    let text = |inner: f32, outer: f32| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_lights_punctual"],
            "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"spot","intensity":2.0,"color":[1,0.5,0.25],
            "spot":{{"innerConeAngle":{inner},"outerConeAngle":{outer}}}}}]}}}},
            "nodes":[{{"translation":[1,2,3],"rotation":[-0.7071068,0,0,0.7071068],"extensions":{{"KHR_lights_punctual":{{"light":0}}}}}}]}}"#
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("spot.gltf");
    std::fs::write(&p, text(0.2, 0.5)).unwrap();
    let d = load_gltf(&p, None).unwrap();
    let LightSpec::Spot { position, direction, intensity, angle, falloff_start } = d.lights[0].clone() else { panic!() };
    assert_eq!(position, [1.0, 2.0, 3.0]);
    // −90° about x turns the node's −Z to −Y.
    assert!(close(Vec3::from(direction), -Vec3::Y, 1e-5), "{direction:?}");
    assert_eq!(intensity, [2.0, 1.0, 0.5]);
    assert!((angle - 0.5f32.to_degrees()).abs() < 1e-4 && (falloff_start.unwrap() - 0.2f32.to_degrees()).abs() < 1e-4);
    std::fs::write(&p, text(0.2, 0.1)).unwrap();
    let e = load_gltf(&p, None).unwrap_err().to_string();
    assert!(e.contains("innerConeAngle") && e.contains("spot.gltf"), "{e}");
}

#[test]
fn emissive_strength_scales_the_emission_and_a_negative_one_is_an_error() {
    let d = load_gltf(&data("khr-extension-snippets/KHR_materials_emissive_strength/material_valid.gltf"), None).unwrap();
    let e: Vec<Vec3> = d.materials.iter().map(|m| m.emission).collect();
    assert_eq!(e, vec![Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO]);
    let r = load_gltf(&data("khr-extension-snippets/KHR_materials_emissive_strength/material_out_of_range.gltf"), None);
    let m = r.unwrap_err().to_string();
    assert!(m.contains("emissiveStrength") && m.contains("-0.5"), "{m}");
}

#[test]
fn roughness_maps_onto_kappa() {
    assert_eq!(kappa_from_roughness(1.0), 0.0);
    assert_eq!(kappa_from_roughness(0.0), 1.0);
    // r = 0.3: α = 0.09, n = 2/α² − 2 ≈ 244.9, κ = (n − 1)/1024 ≈ 0.238.
    assert!((kappa_from_roughness(0.3) - 0.2382).abs() < 1e-3);
    let mut last = 2.0;
    for i in 0..=100 {
        let k = kappa_from_roughness(i as f32 / 100.0);
        assert!(k <= last);
        last = k;
    }
}

#[test]
fn garbage_and_missing_files_are_errors_not_panics() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in [
        ("a.gltf", &b"{not json"[..]),
        ("b.glb", &b"glTF\x02\x00\x00\x00\xff\xff\xff\xff"[..]),
        ("c.gltf", &br#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":12,"uri":"missing.bin"}]}"#[..]),
        (
            "d.gltf",
            &br#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"],"extensionsUsed":["KHR_draco_mesh_compression"]}"#[..],
        ),
    ] {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        let e = load_gltf(&p, None).unwrap_err();
        assert!(matches!(e, SceneIoError::Gltf { .. }), "{name}: {e}");
    }
    let p = dir.path().join("d.gltf");
    assert!(load_gltf(&p, None).unwrap_err().to_string().contains("KHR_draco_mesh_compression"));
    assert!(load_gltf(&dir.path().join("none.glb"), None).is_err());
}

/// A node hierarchy that is no set of disjoint trees is refused before the
/// walk: a chain of 64 nodes each listing the next twice would otherwise
/// be walked 2⁶⁴ times. A proper tree with the same lights loads, each
/// light once.
#[test]
fn node_graphs_that_are_no_forest_are_refused_before_the_walk() {
    let file = |nodes: &str, scene: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_lights_punctual"],
            "extensions":{{"KHR_lights_punctual":{{"lights":[{{"type":"point","intensity":1.0}}]}}}},
            {scene}"nodes":[{nodes}]}}"#
        )
    };
    let light = r#""extensions":{"KHR_lights_punctual":{"light":0}}"#;
    let chain = |twice: bool| {
        (0..64)
            .map(|i| match (i, twice) {
                (63, _) => format!("{{{light}}}"),
                (_, true) => format!("{{\"children\":[{0},{0}],{light}}}", i + 1),
                (_, false) => format!("{{\"children\":[{}],{light}}}", i + 1),
            })
            .collect::<Vec<_>>()
            .join(",")
    };
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("g.gltf");
    std::fs::write(&p, file(&chain(false), r#""scene":0,"scenes":[{"nodes":[0]}],"#)).unwrap();
    assert_eq!(load_gltf(&p, None).unwrap().lights.len(), 64);
    for (nodes, scene, says) in [
        (chain(true), r#""scene":0,"scenes":[{"nodes":[0]}],"#.to_string(), "node 1 is a child twice"),
        (chain(true), String::new(), "node 1 is a child twice"),
        (
            format!(r#"{{"children":[2]}},{{"children":[2]}},{{{light}}}"#),
            String::new(),
            "node 2 is a child twice (of node 0 and of node 1)",
        ),
        (format!(r#"{{{light}}}"#), r#""scenes":[{"nodes":[0,0]}],"#.to_string(), "lists node 0 twice"),
        (
            format!(r#"{{"children":[1]}},{{{light}}}"#),
            r#""scenes":[{"nodes":[0,1]}],"#.to_string(),
            "node 1 is a root of the scene and a child of node 0",
        ),
    ] {
        std::fs::write(&p, file(&nodes, &scene)).unwrap();
        let e = load_gltf(&p, None).unwrap_err().to_string();
        assert!(e.contains(says), "{e}");
    }
}

//! Mitsuba 3 XML loading on the samples in `tests/data/mitsuba` (copies of
//! `../shared/scenes/mitsuba-xml`), and the errors outside the subset.
#![cfg(all(feature = "mitsuba", feature = "toml"))]

use std::path::{Path, PathBuf};
use vpl_core::camera::FovAxis;
use vpl_core::glam::Vec3;
use vpl_core::scene_file::LightSpec;
use vpl_scene_io::SceneIoError;
use vpl_scene_io::mitsuba::{MitsubaData, load_mitsuba};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mitsuba").join(p)
}

fn load(p: &str) -> MitsubaData {
    load_mitsuba(&data(p), &[]).unwrap()
}

fn bounds(ps: &[Vec3]) -> (Vec3, Vec3) {
    ps.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

/// Triangles of a tessellated sphere (48 rings × 96 segments, one triangle
/// per segment at each pole).
const SPHERE_TRIANGLES: usize = 2 * 48 * 96 - 2 * 96;

fn emissive_triangles(d: &MitsubaData) -> usize {
    d.mesh.triangles.iter().filter(|t| d.materials[t.material as usize].is_emissive()).count()
}

#[test]
fn cornell_box_three_ways_loads_the_same_geometry() {
    // cbox.xml is self-contained; cbox-rgb.xml and cbox-spectral.xml are
    // built from <include>d fragments, with the emitter defined after the
    // shape that <ref>s it.
    let whole = load("cbox-mitsuba-data/cbox.xml");
    let rgb = load("cbox-mitsuba-data/cbox-rgb.xml");
    let spectral = load("cbox-mitsuba-data/cbox-spectral.xml");
    for d in [&whole, &rgb, &spectral] {
        // 38 triangles: the OBJ quads split in two (counted from the files' face lines).
        assert_eq!(d.mesh.triangles.len(), 38);
        let (lo, hi) = bounds(&d.mesh.positions);
        assert!(close(lo, Vec3::ZERO, 1e-4) && close(hi, Vec3::new(556.0, 548.8, 559.2), 1e-3), "{lo} {hi}");
        // The luminaire's quad, moved 0.5 down by its translate.
        assert_eq!(emissive_triangles(d), 2);
        let lum_y: Vec<f32> = d
            .mesh
            .triangles
            .iter()
            .filter(|t| d.materials[t.material as usize].is_emissive())
            .flat_map(|t| t.v.map(|i| d.mesh.positions[i as usize].y))
            .collect();
        assert!(lum_y.iter().all(|y| (y - 548.3).abs() < 1e-3), "{lum_y:?}");
        assert!(d.lights.is_empty());
        assert!(!d.two_sided, "bare diffuse BSDFs are one-sided in Mitsuba");
        let c = d.camera.as_ref().unwrap();
        assert_eq!((c.origin, c.target), ([278.0, 273.0, -800.0], [278.0, 273.0, -799.0]));
        assert_eq!((c.fov, c.fov_axis, c.resolution), (39.3077, FovAxis::Smaller, [256, 256]));
    }
    // Same spectra, same materials.
    assert_eq!(whole.materials, spectral.materials);
    assert_eq!(whole.mesh, spectral.mesh);
    let by_name = |d: &MitsubaData, n: &str| d.materials.iter().find(|m| m.name == n).unwrap().clone();
    assert_eq!(by_name(&rgb, "box").albedo, Vec3::new(0.45, 0.30, 0.90));
    assert_eq!(by_name(&rgb, "light+emitter").emission, Vec3::new(18.387, 10.9873, 2.75357));
    // The spectral red wall is red, the white wall grey (a flat-ish spectrum near 0.74).
    let red = by_name(&spectral, "red").albedo;
    assert!(red.x > 0.4 && red.y < 0.1 && red.z < 0.1, "{red}");
    let white = by_name(&spectral, "white").albedo;
    assert!(close(white, Vec3::splat(0.737), 0.01), "{white}");
    // The light's spectrum 400:0, 500:8, 600:15.6, 700:18.4 rises to the red.
    let le = by_name(&spectral, "light+emitter").emission;
    assert!(le.x > le.y && le.y > le.z && le.z > 0.0, "{le}");
}

#[test]
fn defaults_yield_to_given_parameters() {
    let d = load_mitsuba(&data("cbox-mitsuba-data/cbox.xml"), &[("res".into(), "64".into())]).unwrap();
    assert_eq!(d.camera.unwrap().resolution, [64, 64]);
}

#[test]
fn tutorial_box_has_a_mirror_and_a_glass_sphere() {
    let d = load("cbox-tutorials/cbox.xml");
    assert_eq!(d.mesh.triangles.len(), 12 + 2 * SPHERE_TRIANGLES);
    let (lo, hi) = bounds(&d.mesh.positions);
    assert!(close(lo, Vec3::splat(-1.0), 1e-5) && close(hi, Vec3::splat(1.0), 1e-5), "{lo} {hi}");
    assert_eq!(emissive_triangles(&d), 2);
    let mirror = d.materials.iter().find(|m| m.name == "mirror").unwrap();
    let l = mirror.layered.as_ref().unwrap();
    assert_eq!((l.kappa, l.transmission, l.specular, mirror.albedo), (1.0, 0.0, Vec3::ONE, Vec3::ZERO));
    let glass = d.materials.iter().find(|m| m.name == "glass").unwrap();
    let l = glass.layered.as_ref().unwrap();
    // bk7 in air.
    assert!((l.ior - 1.5046 / 1.000277).abs() < 1e-5 && l.transmission == 1.0);
    // The mirror sphere: radius 0.5 (scale) at (-0.3, -0.5, 0.2) (translate after it).
    let on_mirror: Vec<Vec3> = d
        .mesh
        .triangles
        .iter()
        .filter(|t| d.materials[t.material as usize].name == "mirror")
        .flat_map(|t| t.v.map(|i| d.mesh.positions[i as usize]))
        .collect();
    assert!(on_mirror.iter().all(|p| ((*p - Vec3::new(-0.3, -0.5, 0.2)).length() - 0.5).abs() < 1e-5));
    assert_eq!(d.camera.unwrap().origin, [0.0, 0.0, 4.0]);
}

#[test]
fn veach_mis_scenes_load_their_plates_and_spheres() {
    let m = load("veach-mis-mitsuba-data/veach_mis.xml");
    assert_eq!(m.mesh.triangles.len(), 12 + 5 * SPHERE_TRIANGLES);
    // Five emitting spheres.
    assert_eq!(emissive_triangles(&m), 5 * SPHERE_TRIANGLES);
    let c = m.camera.as_ref().unwrap();
    // The two scale x = -1 cancel: the look-at alone.
    assert_eq!((c.origin, c.resolution, c.fov, c.fov_axis), ([0.0, 2.0, 15.0], [768, 512], 28.0, FovAxis::Smaller));
    // α 0.005 and 0.02 are mirrors, 0.05 glossy, 0.1 Lambertian.
    let kappas: Vec<Option<f32>> =
        m.materials.iter().filter(|x| x.name.starts_with("roughplastic")).map(|x| x.layered.as_ref().map(|l| l.kappa)).collect();
    assert_eq!(kappas.len(), 4);
    assert_eq!(&kappas[..2], &[Some(1.0), Some(1.0)]);
    assert!(kappas[2].is_some_and(|k| k > 0.7 && k < 0.8) && kappas[3].is_none(), "{kappas:?}");

    let b = load("veach-mis-bitterli/scene.xml");
    // Four cubes, two rectangles, three spheres; its integrator ($integrator,
    // a plugin of its own) is ignored.
    assert_eq!(b.mesh.triangles.len(), 4 * 12 + 2 * 2 + 3 * SPHERE_TRIANGLES);
    assert_eq!(emissive_triangles(&b), 3 * SPHERE_TRIANGLES);
    assert!(b.two_sided, "every BSDF is wrapped in twosided");
    let c = b.camera.as_ref().unwrap();
    assert_eq!((c.resolution, c.fov, c.fov_axis), ([1280, 720], 35.0, FovAxis::X));
    // The matrix puts the camera at (28.28, 3.5, 0) looking along −X.
    let o = Vec3::from(c.origin);
    assert!(close(o, Vec3::new(28.2792, 3.5, 0.0), 1e-4), "{o}");
    assert!(close(Vec3::from(c.target) - o, Vec3::NEG_X, 1e-5));
    let (lo, hi) = bounds(&b.mesh.positions);
    assert!((lo.z + 23.76).abs() < 1e-3 && (hi.z - 23.76).abs() < 1e-3, "{lo} {hi}");
}

#[test]
fn samples_load_as_scenes() {
    for p in
        ["cbox-mitsuba-data/cbox.xml", "cbox-tutorials/cbox.xml", "veach-mis-mitsuba-data/veach_mis.xml", "veach-mis-bitterli/scene.xml"]
    {
        let s = vpl_scene_io::load(data(p).to_str().unwrap()).unwrap();
        assert!(!s.scene.lights.is_empty(), "{p}");
        assert!(s.warnings.is_empty(), "{p}: {:?}", s.warnings);
    }
}

/// Writes `body` inside a `<scene>` to a file in `dir` and loads it.
fn try_scene(dir: &Path, name: &str, body: &str) -> Result<MitsubaData, SceneIoError> {
    let p = dir.join(name);
    std::fs::write(&p, format!("<scene version=\"3.0.0\">\n{body}\n</scene>\n")).unwrap();
    load_mitsuba(&p, &[])
}

const LIGHT: &str = "<shape type=\"rectangle\"><emitter type=\"area\"><rgb name=\"radiance\" value=\"1\"/></emitter></shape>";

#[test]
fn outside_the_subset_is_one_error_naming_element_and_line() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("<shape type=\"cylinder\"/>", "x.xml:2: <shape type=\"cylinder\"> is not supported"),
        ("\n<bsdf type=\"principled\" id=\"p\"/>\n<shape type=\"cube\"><ref id=\"p\"/></shape>", "x.xml:3: <bsdf type=\"principled\""),
        (
            "<emitter type=\"envmap\"><string name=\"filename\" value=\"sky.exr\"/></emitter>",
            "x.xml:2: <emitter type=\"envmap\"> is not supported",
        ),
        ("<shape type=\"cube\"><ref id=\"nope\"/></shape>", "<ref id=\"nope\">: no object has this id"),
        ("<shape type=\"sphere\"><float name=\"radius\" value=\"$r\"/></shape>", "parameter $r has no value"),
        ("<medium type=\"homogeneous\"/>", "<medium type=\"homogeneous\"> is not supported"),
        ("<shape type=\"cube\"><float name=\"radius\" value=\"x\"/></shape>", "'x' is not a number"),
        ("<shape type=\"cube\"><transform name=\"to_world\"><shear x=\"1\"/></transform></shape>", "<shear> in <transform"),
        ("<sensor type=\"orthographic\"/>", "<sensor type=\"orthographic\"> is not supported"),
        ("<shape type=\"obj\"><string name=\"filename\" value=\"missing.obj\"/></shape>", "missing.obj"),
        ("<include filename=\"x.xml\"/>", "include"),
        ("<shape type=\"cube\"><bsdf type=\"bumpmap\"/></shape>", "<bsdf type=\"bumpmap\"> is not supported"),
        ("<shape type=\"cube\"><texture type=\"bitmap\" name=\"x\"/></shape>", "inside <shape type=\"cube\"> is not supported"),
        (
            "<shape type=\"cube\"><bsdf type=\"diffuse\"><texture type=\"noise\" name=\"reflectance\"/></bsdf></shape>",
            "<texture type=\"noise\"> is not supported",
        ),
        (
            "<shape type=\"cube\"><bsdf type=\"conductor\"><string name=\"material\" value=\"Unobtainium\"/></bsdf></shape>",
            "'Unobtainium' is not known",
        ),
        (
            "<shape type=\"cube\"><bsdf type=\"dielectric\"><string name=\"int_ior\" value=\"kryptonite\"/></bsdf></shape>",
            "'kryptonite' is not a known medium",
        ),
        ("<shape type=\"cube\"", "not well-formed XML"),
    ];
    for (body, want) in cases {
        let e = try_scene(dir.path(), "x.xml", body).unwrap_err().to_string();
        assert!(e.contains(want), "{body}\n  gave: {e}\n  want: {want}");
    }
    assert!(try_scene(dir.path(), "ok.xml", LIGHT).is_ok());
}

#[test]
fn emitters_textures_and_sidedness() {
    let dir = tempfile::tempdir().unwrap();
    let d = try_scene(
        dir.path(),
        "e.xml",
        &format!(
            "{LIGHT}\n<emitter type=\"point\"><point name=\"position\" x=\"1\" y=\"2\" z=\"3\"/><rgb name=\"intensity\" value=\"5\"/></emitter>\n\
             <emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"0,4,0\" target=\"0,0,0\" up=\"0,0,1\"/></transform>\
             <float name=\"cutoff_angle\" value=\"30\"/></emitter>\n\
             <emitter type=\"directional\"><vector name=\"direction\" x=\"0\" y=\"-2\" z=\"0\"/><spectrum name=\"irradiance\" value=\"3\"/></emitter>\n\
             <emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.5, 0.6, 0.7\"/></emitter>\n\
             <shape type=\"cube\"><bsdf type=\"twosided\"><bsdf type=\"diffuse\">\
             <texture type=\"checkerboard\" name=\"reflectance\"><rgb name=\"color0\" value=\"0.6\"/></texture></bsdf></bsdf></shape>"
        ),
    )
    .unwrap();
    assert_eq!(d.lights.len(), 4);
    assert_eq!(d.lights[3], LightSpec::Environment { radiance: [0.5, 0.6, 0.7], horizon: None, ground: None });
    assert_eq!(d.lights[0], LightSpec::Point { position: [1.0, 2.0, 3.0], intensity: [5.0; 3] });
    let LightSpec::Spot { position, direction, angle, falloff_start, .. } = &d.lights[1] else { panic!() };
    assert_eq!((*position, *angle, *falloff_start), ([0.0, 4.0, 0.0], 30.0, Some(22.5)));
    assert!(close(Vec3::from(*direction), Vec3::NEG_Y, 1e-6));
    let LightSpec::Directional { direction, irradiance } = &d.lights[2] else { panic!() };
    assert_eq!(*direction, [0.0, -1.0, 0.0]);
    // A flat emitted spectrum is the equal-energy white: luminance 3, a little pink in sRGB.
    let e = Vec3::from(*irradiance);
    let y = 0.2126 * e.x + 0.7152 * e.y + 0.0722 * e.z;
    assert!((y - 3.0).abs() < 0.03 && e.x > e.y && e.y > e.z, "{e}");
    // The checkerboard's mean: (0.6 + 0.2) / 2.
    let cube = d.materials.iter().find(|m| m.name.starts_with("diffuse")).unwrap();
    assert!(close(cube.albedo, Vec3::splat(0.4), 1e-6));
    // One bare (the light's default BSDF) and one twosided: drawn one-sided, with a warning.
    assert!(!d.two_sided);
    assert!(d.warnings.iter().any(|w| w.contains("some BSDFs are twosided")), "{:?}", d.warnings);
}

#[test]
fn bitmap_textures_give_their_average_linear_colour() {
    let dir = tempfile::tempdir().unwrap();
    // A 2×1 sRGB PNG: texels 255 and 0 (linear 1 and 0): mean 0.5 in red.
    let png = dir.path().join("t.png");
    let mut buf = Vec::new();
    {
        let mut enc = png::Encoder::new(&mut buf, 2, 1);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        enc.write_header().unwrap().write_image_data(&[255, 0, 0, 0, 0, 0]).unwrap();
    }
    std::fs::write(&png, buf).unwrap();
    let body = format!(
        "{LIGHT}<texture type=\"bitmap\" id=\"t\"><string name=\"filename\" value=\"t.png\"/></texture>\
         <shape type=\"cube\"><bsdf type=\"diffuse\"><ref name=\"reflectance\" id=\"t\"/></bsdf></shape>"
    );
    let d = try_scene(dir.path(), "b.xml", &body).unwrap();
    let m = d.materials.iter().find(|m| m.name.starts_with("diffuse")).unwrap();
    assert!(close(m.albedo, Vec3::new(0.5, 0.0, 0.0), 1e-3), "{}", m.albedo);
}

#[test]
fn include_cycles_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("a.xml"), "<scene version=\"3.0.0\"><include filename=\"b.xml\"/></scene>").unwrap();
    std::fs::write(dir.path().join("b.xml"), "<scene version=\"3.0.0\"><include filename=\"a.xml\"/></scene>").unwrap();
    let e = load_mitsuba(&dir.path().join("a.xml"), &[]).unwrap_err().to_string();
    assert!(e.contains("includes itself"), "{e}");
}

#[test]
fn a_scene_file_references_a_mitsuba_scene_with_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let toml = dir.path().join("s.toml");
    let xml = data("cbox-mitsuba-data/cbox-rgb.xml");
    std::fs::write(&toml, format!("[geometry]\nmitsuba = \"{}\"\n[geometry.mitsuba_params]\nres = \"32\"\n", xml.display())).unwrap();
    // The XML lies outside the scene file's folder: refused unless allowed.
    let e = vpl_scene_io::load(toml.to_str().unwrap()).unwrap_err();
    assert!(matches!(e, SceneIoError::OutsideScene { .. }), "{e}");
    let allow = vpl_scene_io::LoadOptions::allowing(xml.parent().unwrap());
    let s = vpl_scene_io::load_with(toml.to_str().unwrap(), &allow).unwrap();
    assert_eq!(s.camera.resolution, (32, 32));
    assert_eq!(s.scene.geometry.triangles.len(), 38);
    assert!(!s.scene.two_sided);
    // The description names the file and its parameters again.
    assert!(vpl_scene_io::scene_toml::setup_toml(&s).contains("mitsuba_params"), "{}", vpl_scene_io::scene_toml::setup_toml(&s));
}

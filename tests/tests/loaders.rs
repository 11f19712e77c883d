//! Loading scenes: `cbox.obj` against the built-in `cornell`, the McGuire
//! Cornell box (negative indices, comments after values), polygons, scene
//! files, and every kind of bad input as a typed error.

use std::path::Path;
use vpl_core::glam::Vec3;
use vpl_core::{CoreError, SceneSetup};
use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render};
use vpl_render::compare::compare;
use vpl_scene_io::SceneIoError;
use vpl_tests::{data_dir, scratch_dir};

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

/// A scene file that loads `cbox.obj` with Mitsuba's camera and one-sided surfaces.
fn cbox_toml(dir: &Path) -> String {
    let obj = data_dir().join("cornell-box/cbox.obj");
    write(
        dir,
        "cbox.toml",
        &format!(
            "[geometry]\nobj = \"{}\"\nallow_outside = [\"{}\"]\ntwo_sided = false\n\n[camera]\norigin = [0.0, 0.0, 3.9]\ntarget = [0.0, 0.0, 0.0]\nfov = 39.3077\nresolution = [256, 256]\n",
            obj.display(),
            data_dir().display()
        ),
    )
}

#[test]
fn cbox_obj_has_the_geometry_and_materials_of_builtin_cornell() {
    let dir = scratch_dir("loaders-cbox");
    let file = vpl_scene_io::load(&cbox_toml(&dir)).unwrap();
    let builtin = SceneSetup::builtin("cornell").unwrap();
    let (a, b) = (&file.scene.geometry.triangles, &builtin.scene.geometry.triangles);
    assert_eq!(a.len(), b.len());
    for (i, (x, y)) in a.iter().zip(b.iter()).enumerate() {
        for (p, q) in [(x.p0, y.p0), (x.e1, y.e1), (x.e2, y.e2), (x.ng, y.ng)] {
            assert!((p - q).length() < 1e-6, "triangle {i}: {p} vs {q}");
        }
        let (ma, mb) = (&file.scene.materials[x.material as usize], &builtin.scene.materials[y.material as usize]);
        assert_eq!((ma.albedo, ma.emission), (mb.albedo, mb.emission), "triangle {i}");
    }
    assert_eq!(file.camera, builtin.camera);
    assert_eq!(file.scene.lights.len(), 2);
}

#[test]
fn cbox_obj_renders_the_same_as_builtin_cornell() {
    // Same seed, same paths: the images differ only where rounding in the
    // OBJ's vertex normals changes a path. Criterion: the per-pixel test of
    // the Mitsuba comparison (≥ 99 % at α = 0.01) and image means within 1e-4.
    let dir = scratch_dir("loaders-cbox-render");
    let file = vpl_scene_io::load(&cbox_toml(&dir)).unwrap();
    let builtin = SceneSetup::builtin("cornell").unwrap();
    let cam = builtin.camera.with_resolution((64, 64)).unwrap();
    let pt = PathTracer::new(5, Mode::Full);
    let s = RenderSettings { spp: 64, seed: 5, frame: 0 };
    let a = render(&file.scene, &cam, &pt, s, &|_, _| {}).unwrap();
    let b = render(&builtin.scene, &cam, &pt, s, &|_, _| {}).unwrap();
    let c = compare(&a.image, &a.stderr, &b.image, &b.stderr, 0.01).unwrap();
    assert!(c.pass_rate >= 0.99, "{}", c.pass_rate);
    for k in 0..3 {
        assert!((c.mean_a[k] - c.mean_b[k]).abs() <= 1e-4 * c.mean_b[k], "{:?} vs {:?}", c.mean_a, c.mean_b);
    }
}

#[test]
fn mcguire_box_negative_indices_and_trailing_comments() {
    let obj = data_dir().join("mcguire/CornellBox-Original.obj");
    let d = vpl_scene_io::obj::load_obj(&obj).unwrap();
    assert_eq!(d.mesh.triangles.len(), 36, "18 quads");
    let light = d.materials.iter().find(|m| m.name == "light").unwrap();
    assert_eq!(light.emission, Vec3::new(17.0, 12.0, 4.0));
    assert_eq!(light.albedo, Vec3::splat(0.78), "Kd after a commented Ka line");
    let left = d.materials.iter().find(|m| m.name == "leftWall").unwrap();
    assert_eq!(left.albedo, Vec3::new(0.63, 0.065, 0.05));
    // "f -4 -3 -2 -1" after the floor's four vertices: the floor quad.
    let t = d.mesh.triangles[0];
    assert_eq!(d.mesh.positions[t.v[0] as usize], Vec3::new(-1.01, 0.0, 0.99));
    let setup = vpl_scene_io::load(&obj.to_string_lossy()).unwrap();
    assert_eq!(setup.scene.lights.len(), 2, "the emissive quad becomes two area lights");
}

#[test]
fn polygons_are_triangulated_and_zero_area_triangles_counted() {
    let dir = scratch_dir("loaders-poly");
    write(&dir, "p.mtl", "newmtl lamp\nKd 0.5 0.5 0.5\nKe 1 1 1 # bright\n");
    let p = write(
        &dir,
        "p.obj",
        "mtllib p.mtl\nusemtl lamp\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0.5 1.5 0\nv 0 1 0\nf 1 2 3 4 5\nv 2 0 0\nv 3 0 0\nv 4 0 0\nf -3 -2 -1\n",
    );
    let s = vpl_scene_io::load(&p).unwrap();
    assert_eq!(s.scene.geometry.triangles.len(), 3, "a pentagon is three triangles");
    assert_eq!(s.scene.stats().degenerate, 1);
    assert!(s.warnings.iter().any(|w| w.contains("1 zero-area")), "{:?}", s.warnings);
}

#[test]
fn missing_mtl_gives_the_default_material_and_a_warning() {
    let dir = scratch_dir("loaders-nomtl");
    let p = write(&dir, "n.obj", "mtllib nowhere.mtl\nusemtl x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let d = vpl_scene_io::obj::load_obj(Path::new(&p)).unwrap();
    assert!(d.warnings.iter().any(|w| w.contains("material library")), "{:?}", d.warnings);
    assert_eq!(d.materials, vec![vpl_core::Material::default_material()]);
    // With a light from a scene file it renders.
    let t = write(
        &dir,
        "n.toml",
        "[geometry]\nobj = \"n.obj\"\n[[lights]]\ntype = \"point\"\nposition = [0.2, 0.2, 1.0]\nintensity = [1, 1, 1]\n",
    );
    let s = vpl_scene_io::load(&t).unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("nowhere.mtl")));
    // Without one it is a scene without lights.
    assert!(matches!(vpl_scene_io::load(&p), Err(SceneIoError::Core(CoreError::NoLights(_)))));
}

#[test]
fn bad_inputs_are_typed_errors() {
    let dir = scratch_dir("loaders-bad");
    type Case = (String, fn(&SceneIoError) -> bool);
    let cases: Vec<Case> = vec![
        (write(&dir, "malformed.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n"), |e| matches!(e, SceneIoError::Obj { .. })),
        (dir.join("missing.obj").to_string_lossy().into_owned(), |e| matches!(e, SceneIoError::Read { .. })),
        (write(&dir, "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n"), |e| {
            matches!(e, SceneIoError::Core(CoreError::NonFinite { .. }))
        }),
        (write(&dir, "inf.obj", "v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n"), |e| {
            matches!(e, SceneIoError::Core(CoreError::NonFinite { .. }))
        }),
        (write(&dir, "empty.obj", "# nothing\n"), |e| matches!(e, SceneIoError::Core(CoreError::EmptyScene(_)))),
        (write(&dir, "flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"), |e| matches!(e, SceneIoError::Core(CoreError::EmptyScene(_)))),
        (write(&dir, "dark.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"), |e| matches!(e, SceneIoError::Core(CoreError::NoLights(_)))),
        (write(&dir, "fov0.toml", "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0,0,3]\ntarget = [0,0,0]\nfov = 0\n"), |e| {
            matches!(e, SceneIoError::Core(CoreError::Camera(_)))
        }),
        (write(&dir, "fovneg.toml", "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0,0,3]\ntarget = [0,0,0]\nfov = -30\n"), |e| {
            matches!(e, SceneIoError::Core(CoreError::Camera(_)))
        }),
        (
            write(
                &dir,
                "size0.toml",
                "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0,0,3]\ntarget = [0,0,0]\nfov = 40\nresolution = [0, 10]\n",
            ),
            |e| matches!(e, SceneIoError::Core(CoreError::Camera(_))),
        ),
        (write(&dir, "unknown.toml", "[geometry]\nbuiltin = \"cornell\"\nshiny = true\n"), |e| {
            matches!(e, SceneIoError::Core(CoreError::SceneFile { .. })) && e.to_string().contains("shiny")
        }),
        (write(&dir, "badlight.toml", "[geometry]\nbuiltin = \"cornell\"\n[[lights]]\ntype = \"laser\"\n"), |e| {
            matches!(e, SceneIoError::Core(CoreError::SceneFile { .. }))
        }),
        ("no-such-builtin".into(), |e| matches!(e, SceneIoError::Core(CoreError::UnknownBuiltin(_)))),
    ];
    for (path, ok) in cases {
        match vpl_scene_io::load(&path) {
            Ok(_) => panic!("{path}: loaded"),
            Err(e) => {
                assert!(ok(&e), "{path}: unexpected error {e:?}");
                let msg = e.to_string();
                assert!(!msg.contains('\n') && !msg.is_empty(), "{path}: message is not one line: {msg:?}");
            }
        }
    }
}

#[test]
fn material_overrides_and_z_up() {
    let dir = scratch_dir("loaders-override");
    let obj = data_dir().join("cornell-box/cbox.obj");
    let t = write(
        &dir,
        "o.toml",
        &format!(
            "[geometry]\nobj = \"{}\"\nallow_outside = [\"{}\"]\nup = \"z\"\nscale = 2.0\n\n[[materials]]\nname = \"red\"\nalbedo = [0.1, 0.2, 0.3]\nkappa = 0.5\n",
            obj.display(),
            data_dir().display()
        ),
    );
    let s = vpl_scene_io::load(&t).unwrap();
    let red = s.scene.materials.iter().find(|m| m.name == "red").unwrap();
    assert_eq!(red.albedo, Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(red.layered.as_ref().unwrap().kappa, 0.5);
    // Z-up: the light plane y = 0.99 becomes z = −0.99, scaled by 2.
    let (lo, hi) = s.scene.geometry.bounds;
    assert!((hi.y - 2.0).abs() < 1e-5 && (lo.z + 2.0).abs() < 1e-5 && (hi.z - 2.02).abs() < 1e-4, "{lo} {hi}");
    let bad = write(
        &dir,
        "b.toml",
        &format!(
            "[geometry]\nobj = \"{}\"\nallow_outside = [\"{}\"]\n[[materials]]\nname = \"nope\"\n",
            obj.display(),
            data_dir().display()
        ),
    );
    assert!(vpl_scene_io::load(&bad).unwrap_err().to_string().contains("nope"));
}

#[test]
fn sequences_move_camera_and_lights() {
    let s = SceneSetup::builtin("atrium").unwrap();
    let (a, ca) = s.frame(0).unwrap();
    let (b, cb) = s.frame(240).unwrap();
    assert_ne!(a.lights, b.lights, "the atrium light moves");
    assert_eq!(a.geometry.triangles.len(), b.geometry.triangles.len());
    assert!(std::sync::Arc::ptr_eq(&a.geometry, &b.geometry), "frames share the BVH");
    assert_ne!(ca.target, cb.target);
}

/// The committed scene files on real geometry load, animate and light
/// their first and last frames, when the models are where the files name
/// them (`../shared/scenes`); otherwise the test says it skipped.
#[test]
fn real_scene_files_load_when_their_models_are_present() {
    for (file, triangles) in [("sponza-dabrovic.toml", 60_000), ("city-munich.toml", 30_000), ("city-munich-sky.toml", 30_000)] {
        let Some(path) = vpl_tests::real_scene(file) else { continue };
        let setup = vpl_scene_io::load(path.to_str().unwrap()).unwrap();
        assert!(setup.scene.geometry.triangles.len() > triangles, "{file}");
        let seq = setup.sequence.as_ref().expect("an animation");
        let last = seq.frame_count() - 1;
        let (first, _) = setup.frame(0).unwrap();
        let (end, _) = setup.frame(last).unwrap();
        assert_ne!(format!("{:?}", first.lights), format!("{:?}", end.lights), "{file}: the light does not move");
    }
}

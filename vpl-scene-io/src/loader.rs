//! Loading what a user names: a built-in scene, a TOML scene file, or a
//! bare model file, each read inside its sandbox.

use crate::error::{Result, SceneIoError};
use crate::sandbox::{LoadOptions, Sandbox};
use std::path::Path;
use vpl_core::CoreError;
use vpl_core::SceneSetup;
use vpl_core::builtin;
use vpl_core::scene_file::{GeometrySpec, SceneFile};
use vpl_core::setup::{Model, ModelLoader};

/// Loads `spec`: a built-in name, a `.toml` scene file, an `.obj` file or
/// a glTF 2.0 file (`.gltf`, `.glb`) or a Mitsuba 3 XML scene (`.xml`).
///
/// The files a scene file names must lie in its folder; see [`load_with`]
/// to allow more.
pub fn load(spec: &str) -> Result<SceneSetup> {
    load_with(spec, &LoadOptions::default())
}

/// [`load`] with `options`: the folders besides the scene's own that its
/// files may name, and the memory limit of loading (see [`crate::sandbox`]).
pub fn load_with(spec: &str, options: &LoadOptions) -> Result<SceneSetup> {
    let path = Path::new(spec);
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
    match ext.as_deref() {
        Some("toml") => {
            let file = crate::scene_toml::read_scene_file(path)?;
            // The description the user named may widen its own sandbox.
            let folder = path.parent().unwrap_or(Path::new("."));
            let mut options = options.clone();
            options.allow_outside.extend(file.geometry.allow_outside.iter().map(|r| folder.join(r)));
            let sandbox = Sandbox::for_scene(path, &options).map_err(|e| match e {
                SceneIoError::Core(CoreError::Invalid(r)) => {
                    CoreError::Invalid(r.replace("--allow-outside", "geometry.allow_outside")).into()
                }
                e => e,
            })?;
            // Values the description holds are named with the file they come from.
            SceneSetup::from_description(file, folder, &Files { sandbox: Some(sandbox) }).map_err(|e| match e {
                SceneIoError::Core(CoreError::BadValue { what, reason }) => {
                    CoreError::BadValue { what: format!("{spec}: {what}"), reason }.into()
                }
                SceneIoError::Core(CoreError::Invalid(s)) => CoreError::Invalid(format!("{spec}: {s}")).into(),
                e => e,
            })
        }
        Some(ext @ ("obj" | "gltf" | "glb" | "xml")) => {
            let geometry = GeometrySpec {
                obj: (ext == "obj").then(|| spec.to_string()),
                gltf: (ext == "gltf" || ext == "glb").then(|| spec.to_string()),
                gltf_camera: None,
                mitsuba: (ext == "xml").then(|| spec.to_string()),
                mitsuba_params: Default::default(),
                builtin: None,
                up: "y".into(),
                scale: 1.0,
                two_sided: None,
                allow_outside: Vec::new(),
            };
            let file = SceneFile { geometry, camera: None, lights: None, materials: Vec::new(), sequence: None };
            SceneSetup::from_description(file, Path::new(""), &Files { sandbox: Some(Sandbox::for_scene(path, options)?) })
        }
        _ if builtin::NAMES.contains(&spec) => Ok(SceneSetup::builtin(spec)?),
        _ if path.exists() => Err(CoreError::Invalid(format!("{spec}: scene files must end in .toml, .obj, .gltf, .glb or .xml")).into()),
        _ => Err(CoreError::UnknownBuiltin(spec.to_string()).into()),
    }
}

/// Builds from a parsed description; the model paths it names are relative
/// to `base` and must lie under it.
///
/// Everything the description places is in the model's frame (see
/// [`SceneSetup::from_description`]).
pub fn from_file(file: SceneFile, base: &Path) -> Result<SceneSetup> {
    SceneSetup::from_description(file, base, &Files { sandbox: None })
}

/// [`from_file`] whose files may also lie where `options` allow.
pub fn from_file_with(file: SceneFile, base: &Path, options: &LoadOptions) -> Result<SceneSetup> {
    let sandbox = if file.geometry.builtin.is_some() { None } else { Some(Sandbox::for_folder(base, options)?) };
    SceneSetup::from_description(file, base, &Files { sandbox })
}

/// The [`ModelLoader`] of this crate's formats: reads a description's OBJ,
/// glTF or Mitsuba XML model through `sandbox` (the sandbox of the
/// description's folder, with the default options, when `None`).
#[derive(Debug, Default)]
pub struct Files {
    /// Where the model's files may lie.
    pub sandbox: Option<Sandbox>,
}

impl ModelLoader for Files {
    type Error = SceneIoError;

    fn load_model(&self, geometry: &GeometrySpec, base: &Path, warnings: &mut Vec<String>) -> Result<Model> {
        let own;
        let sandbox = match &self.sandbox {
            Some(s) => s,
            None => {
                own = Sandbox::for_folder(base, &LoadOptions::default())?;
                &own
            }
        };
        if geometry.gltf.is_some() {
            gltf_model(geometry, base, sandbox, warnings)
        } else if geometry.mitsuba.is_some() {
            mitsuba_model(geometry, base, sandbox, warnings)
        } else {
            obj_model(geometry, base, sandbox, warnings)
        }
    }
}

/// A scene's name from its model file: the file's stem.
#[cfg(any(feature = "obj", feature = "gltf", feature = "mitsuba"))]
fn model_name(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into())
}

/// What a scene format that carries its own lights and camera (glTF,
/// Mitsuba XML) gives, read from `path`.
#[cfg(any(feature = "gltf", feature = "mitsuba"))]
fn scene_model(
    path: &Path,
    mesh: vpl_core::mesh::Mesh,
    materials: Vec<vpl_core::Material>,
    lights: Vec<vpl_core::scene_file::LightSpec>,
    camera: Option<vpl_core::scene_file::CameraSpec>,
    two_sided: bool,
) -> Model {
    let lights = (!lights.is_empty()).then_some(lights);
    Model { name: model_name(path), mesh, materials, lights, camera, two_sided }
}

/// The OBJ geometry of a description, in the model's frame; loading notes
/// go to `warnings`.
#[cfg(feature = "obj")]
fn obj_model(geometry: &GeometrySpec, base: &Path, sandbox: &Sandbox, warnings: &mut Vec<String>) -> Result<Model> {
    let p = sandbox.resolve(base, geometry.obj.as_deref().unwrap_or_default())?;
    let data = crate::obj::load_obj_in(&p, sandbox)?;
    warnings.extend(data.warnings);
    Ok(Model { name: model_name(&p), mesh: data.mesh, materials: data.materials, lights: None, camera: None, two_sided: true })
}

/// The glTF scene of a description, in the model's frame (glTF's own, +Y
/// up, unless the description says otherwise), with the file's lights and
/// camera.
#[cfg(feature = "gltf")]
fn gltf_model(geometry: &GeometrySpec, base: &Path, sandbox: &Sandbox, warnings: &mut Vec<String>) -> Result<Model> {
    let p = sandbox.resolve(base, geometry.gltf.as_deref().unwrap_or_default())?;
    let data = crate::gltf::load_gltf_in(&p, geometry.gltf_camera.as_deref(), sandbox)?;
    warnings.extend(data.warnings);
    Ok(scene_model(&p, data.mesh, data.materials, data.lights, data.camera, true))
}

/// The Mitsuba XML scene of a description, in the model's frame (the
/// file's own unless the description says otherwise), with its emitters,
/// sensor and sidedness.
#[cfg(feature = "mitsuba")]
fn mitsuba_model(geometry: &GeometrySpec, base: &Path, sandbox: &Sandbox, warnings: &mut Vec<String>) -> Result<Model> {
    let p = sandbox.resolve(base, geometry.mitsuba.as_deref().unwrap_or_default())?;
    let params: Vec<(String, String)> = geometry.mitsuba_params.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
    let data = crate::mitsuba::load_mitsuba_in(&p, &params, sandbox)?;
    warnings.extend(data.warnings);
    Ok(scene_model(&p, data.mesh, data.materials, data.lights, data.camera, data.two_sided))
}

/// The error of a format whose feature is off.
#[cfg(not(all(feature = "obj", feature = "gltf", feature = "mitsuba")))]
fn missing(file: Option<&str>, format: &str, feature: &str) -> SceneIoError {
    CoreError::Invalid(format!("{}: reading {format} files needs vpl-scene-io's `{feature}` feature", file.unwrap_or_default())).into()
}

/// Without the `mitsuba` feature there is no Mitsuba reader.
#[cfg(not(feature = "mitsuba"))]
fn mitsuba_model(geometry: &GeometrySpec, _base: &Path, _sandbox: &Sandbox, _warnings: &mut Vec<String>) -> Result<Model> {
    Err(missing(geometry.mitsuba.as_deref(), "Mitsuba XML", "mitsuba"))
}

/// Without the `obj` feature there is no OBJ reader.
#[cfg(not(feature = "obj"))]
fn obj_model(geometry: &GeometrySpec, _base: &Path, _sandbox: &Sandbox, _warnings: &mut Vec<String>) -> Result<Model> {
    Err(missing(geometry.obj.as_deref(), "OBJ", "obj"))
}

/// Without the `gltf` feature there is no glTF reader.
#[cfg(not(feature = "gltf"))]
fn gltf_model(geometry: &GeometrySpec, _base: &Path, _sandbox: &Sandbox, _warnings: &mut Vec<String>) -> Result<Model> {
    Err(missing(geometry.gltf.as_deref(), "glTF", "gltf"))
}

#[cfg(all(test, feature = "obj", feature = "toml"))]
mod frame_tests {
    use super::*;
    use crate::scene_toml::{parse_scene_file, setup_toml};
    use vpl_core::Light;

    /// A floor and a wall in a Z-up model, written as OBJ.
    const Z_UP_OBJ: &str = "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv -1 1 2\nv 1 1 2\nf 1 2 3\nf 1 3 4\nf 4 3 6\nf 4 6 5\n";

    fn twin_obj(text: &str) -> String {
        // The same model turned to Y up: (x, y, z) -> (x, z, -y).
        text.lines()
            .map(|l| match l.strip_prefix("v ") {
                Some(rest) => {
                    let v: Vec<f32> = rest.split_whitespace().map(|t| t.parse().unwrap()).collect();
                    format!("v {} {} {}", v[0], v[2], -v[1])
                }
                None => l.to_string(),
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    #[test]
    fn a_z_up_scene_and_its_y_up_twin_are_the_same_scene_camera_lights_and_keys() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("z.obj"), Z_UP_OBJ).unwrap();
        std::fs::write(dir.path().join("y.obj"), twin_obj(Z_UP_OBJ)).unwrap();
        let z = "[geometry]\nobj = \"z.obj\"\nup = \"z\"\nscale = 2.0\n\
                 [camera]\norigin = [0.0, -5.0, 1.0]\ntarget = [0.0, 0.0, 0.5]\nup = [0.0, 0.0, 1.0]\nfov = 50.0\n\
                 [[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 1.5]\nintensity = [1.0, 1.0, 1.0]\n\
                 [[lights]]\ntype = \"directional\"\ndirection = [0.0, 1.0, -1.0]\nirradiance = [1.0, 1.0, 1.0]\n\
                 [sequence]\nduration = 1.0\ncamera = [ { t = 1.0, origin = [1.0, -5.0, 1.0], target = [0.0, 0.0, 0.5] } ]\n\
                 lights = [ { light = 0, t = 1.0, position = [0.5, 0.0, 1.5] } ]\n";
        let y = "[geometry]\nobj = \"y.obj\"\nscale = 2.0\n\
                 [camera]\norigin = [0.0, 1.0, 5.0]\ntarget = [0.0, 0.5, 0.0]\nup = [0.0, 1.0, 0.0]\nfov = 50.0\n\
                 [[lights]]\ntype = \"point\"\nposition = [0.0, 1.5, 0.0]\nintensity = [1.0, 1.0, 1.0]\n\
                 [[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, -1.0]\nirradiance = [1.0, 1.0, 1.0]\n\
                 [sequence]\nduration = 1.0\ncamera = [ { t = 1.0, origin = [1.0, 1.0, 5.0], target = [0.0, 0.5, 0.0] } ]\n\
                 lights = [ { light = 0, t = 1.0, position = [0.5, 1.5, 0.0] } ]\n";
        let load = |name: &str, text: &str| {
            let p = dir.path().join(name);
            std::fs::write(&p, text).unwrap();
            load(p.to_str().unwrap()).unwrap()
        };
        let (a, b) = (load("z.toml", z), load("y.toml", y));
        for frame in [0, 15, 30] {
            let ((sa, ca), (sb, cb)) = (a.frame(frame).unwrap(), b.frame(frame).unwrap());
            assert_eq!(sa.geometry.bounds, sb.geometry.bounds);
            assert_eq!(sa.geometry.triangles.len(), sb.geometry.triangles.len());
            for (ta, tb) in sa.geometry.triangles.iter().zip(&sb.geometry.triangles) {
                assert!((ta.ng - tb.ng).length() < 1e-6, "{:?} {:?}", ta.ng, tb.ng);
            }
            assert!((ca.origin - cb.origin).length() < 1e-5 && (ca.target - cb.target).length() < 1e-5, "{ca:?} {cb:?}");
            assert!((ca.up - cb.up).length() < 1e-6);
            for (la, lb) in sa.lights.iter().zip(&sb.lights) {
                match (la, lb) {
                    (Light::Point { position: pa, .. }, Light::Point { position: pb, .. }) => assert!((*pa - *pb).length() < 1e-5),
                    (Light::Directional { direction: da, .. }, Light::Directional { direction: db, .. }) => {
                        assert!((*da - *db).length() < 1e-6)
                    }
                    (la, lb) => panic!("{la:?} {lb:?}"),
                }
            }
        }
        // The description keeps the model's frame: exported and loaded again, the same scene.
        let again = parse_scene_file(&setup_toml(&a), Path::new("again.toml")).unwrap();
        let c = from_file(again, dir.path()).unwrap();
        assert_eq!(c.camera, a.camera);
        // Without a [camera] the framing camera (found in the world) goes back to the model's frame.
        let bare = load(
            "bare.toml",
            "[geometry]\nobj = \"z.obj\"\nup = \"z\"\nscale = 2.0\n[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 1.5]\nintensity = [1.0, 1.0, 1.0]\n",
        );
        let again = from_file(parse_scene_file(&setup_toml(&bare), Path::new("b.toml")).unwrap(), dir.path()).unwrap();
        assert!((again.camera.origin - bare.camera.origin).length() < 1e-4, "{:?} {:?}", again.camera.origin, bare.camera.origin);
    }
}

#[cfg(all(test, feature = "obj", feature = "toml"))]
mod environment_tests {
    use super::*;
    use crate::scene_toml::{parse_scene_file, setup_toml};
    use vpl_core::Light;
    use vpl_core::environment::Sky;
    use vpl_core::glam::Vec3;

    /// A `[[lights]]` environment with a gradient becomes the scene's
    /// environment light, keeps its zenith at the toolkit's +Y in a Z-up
    /// file, survives animation frames, lights a scene alone, and writes
    /// back the same.
    #[test]
    fn an_environment_entry_is_the_scenes_sky() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("z.obj"), "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nf 1 2 3\n").unwrap();
        let text = "[geometry]\nobj = \"z.obj\"\nup = \"z\"\n\
                    [[lights]]\ntype = \"environment\"\nradiance = [0.2, 0.3, 0.9]\nhorizon = [1.0, 1.0, 1.0]\n\
                    [sequence]\nduration = 1.0\n";
        let p = dir.path().join("s.toml");
        std::fs::write(&p, text).unwrap();
        let s = load(p.to_str().unwrap()).unwrap();
        let sky = Sky { zenith: Vec3::new(0.2, 0.3, 0.9), horizon: Vec3::ONE, nadir: Vec3::ONE };
        let i = s.scene.environment.expect("an environment light");
        assert_eq!(s.scene.lights[i], Light::Environment { sky });
        assert!((s.scene.environment_radiance(Vec3::Y) - sky.zenith).abs().max_element() < 1e-6);
        let (frame, _) = s.frame(1).unwrap();
        assert_eq!(frame.environment.map(|i| frame.lights[i].clone()), Some(Light::Environment { sky }));
        let back = parse_scene_file(&setup_toml(&s), Path::new("back.toml")).unwrap();
        assert_eq!(back.lights, s.description.lights);
        // Two environments are refused.
        let two = text.replace("[sequence]", "[[lights]]\ntype = \"environment\"\nradiance = [1.0, 1.0, 1.0]\n[sequence]");
        std::fs::write(&p, two).unwrap();
        assert!(load(p.to_str().unwrap()).unwrap_err().to_string().contains("at most one environment"));
    }
}

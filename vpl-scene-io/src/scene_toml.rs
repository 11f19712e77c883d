//! Scene files in TOML (schema in DESIGN.md): read, checked and written.
//! Unknown keys are errors.

use crate::error::Result;
use std::path::Path;
use vpl_core::CoreError;
#[cfg(feature = "toml")]
use vpl_core::SceneSetup;
use vpl_core::scene_file::SceneFile;

/// Parses TOML text and checks it ([`SceneFile::validate`]); `path` only
/// names the file in errors.
#[cfg(feature = "toml")]
pub fn parse_scene_file(text: &str, path: &Path) -> Result<SceneFile> {
    let f: SceneFile = toml::from_str(text)
        .map_err(|e| CoreError::SceneFile { path: path.into(), reason: e.message().replace('\n', " ").trim().to_string() })?;
    f.validate(path)?;
    Ok(f)
}

/// Without the `toml` feature there is no scene file reader.
#[cfg(not(feature = "toml"))]
pub fn parse_scene_file(_text: &str, path: &Path) -> Result<SceneFile> {
    Err(CoreError::SceneFile { path: path.into(), reason: "reading scene files needs vpl-scene-io's `toml` feature".into() }.into())
}

/// Reads and parses a scene file (at most
/// [`crate::input::MAX_TEXT_BYTES`]).
pub fn read_scene_file(path: &Path) -> Result<SceneFile> {
    let text = crate::input::read_text(path, crate::input::MAX_TEXT_BYTES)?;
    parse_scene_file(&text, path)
}

/// The TOML text of a description (what `vpl export-scene` prints for a
/// [`SceneSetup`]'s `description`).
#[cfg(feature = "toml")]
pub fn scene_toml(file: &SceneFile) -> String {
    toml::to_string_pretty(file).expect("scene descriptions always serialise")
}

/// The TOML text of a loaded scene's description.
#[cfg(feature = "toml")]
pub fn setup_toml(setup: &SceneSetup) -> String {
    scene_toml(&setup.description)
}

#[cfg(all(test, feature = "toml"))]
mod tests {
    use super::*;
    use vpl_core::Light;
    use vpl_core::glam::Vec3;

    fn parse(text: &str, path: &Path) -> Result<SceneFile> {
        parse_scene_file(text, path)
    }

    #[test]
    fn relocated_paths_lead_to_the_same_model() {
        let text = "[geometry]\nobj = \"models/box.obj\"\n";
        let f = parse(text, Path::new("x.toml")).unwrap();
        let moved = f.clone().relocated(Path::new("/data/scenes"), Path::new("/data/out/seq"));
        assert_eq!(moved.geometry.obj.as_deref(), Some("../../scenes/models/box.obj"));
        let same = f.clone().relocated(Path::new("/a/./b/../c"), Path::new("/a/c"));
        assert_eq!(same.geometry.obj.as_deref(), Some("models/box.obj"));
        let builtin = parse("[geometry]\nbuiltin = \"cornell\"\n", Path::new("x.toml")).unwrap();
        assert_eq!(builtin.clone().relocated(Path::new("/a"), Path::new("/b")), builtin);
    }

    #[test]
    fn unknown_keys_are_errors_that_name_the_key() {
        let p = Path::new("x.toml");
        let ok = "[geometry]\nbuiltin = \"cornell\"\n[[lights]]\ntype = \"point\"\nposition = [0,1,0]\nintensity = [1,1,1]\n";
        assert!(parse(ok, p).is_ok());
        for (bad, key) in [
            ("[geometry]\nbuiltin = \"cornell\"\ncolour = 1\n", "colour"),
            (
                "[geometry]\nbuiltin = \"cornell\"\n[[lights]]\ntype = \"point\"\nposition = [0,1,0]\nintensity = [1,1,1]\nradius = 2\n",
                "radius",
            ),
            ("[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin=[0,0,1]\ntarget=[0,0,0]\nfov=40\nzoom=2\n", "zoom"),
            ("[geometry]\nbuiltin = \"cornell\"\n[extra]\n", "extra"),
        ] {
            let e = parse(bad, p).unwrap_err().to_string();
            assert!(e.contains(key), "{e}");
        }
        assert!(parse("[geometry]\n", p).is_err());
    }

    /// A sequence's rate and length are finite and its frames bounded, so
    /// no command that walks it allocates per frame without end.
    #[test]
    fn sequences_of_unbounded_length_are_refused() {
        let p = Path::new("x.toml");
        let file =
            |fps: &str, duration: &str| format!("[geometry]\nbuiltin = \"cornell\"\n[sequence]\nfps = {fps}\nduration = {duration}\n");
        assert!(parse(&file("30", "20.0"), p).is_ok());
        assert!(parse(&file("30", "33000.0"), p).is_ok(), "990 001 frames are allowed");
        for (fps, duration, says) in [
            ("inf", "20.0", "finite"),
            ("nan", "20.0", "finite"),
            ("30", "1e30", "more than the 1000000"),
            ("30", "inf", "finite"),
            ("1e30", "1.0", "more than the 1000000"),
            ("30", "34000.0", "more than the 1000000"),
            ("0", "1.0", "positive"),
        ] {
            let e = parse(&file(fps, duration), p).unwrap_err().to_string();
            assert!(e.contains(says), "fps {fps}, duration {duration}: {e}");
        }
    }

    #[test]
    fn sun_direction_keys_turn_the_sun() {
        let text = "[geometry]\nbuiltin = \"courtyard\"\n[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\n\
                    [sequence]\nduration = 2.0\nlights = [ { light = 0, t = 0.0, direction = [0, -1, 0] }, { light = 0, t = 2.0, direction = [1, -1, 0] } ]\n";
        let f = parse(text, Path::new("s.toml")).unwrap();
        let s = crate::from_file(f, Path::new("")).unwrap();
        let (scene, _) = s.frame(60).unwrap();
        match &scene.lights[0] {
            Light::Directional { direction, .. } => assert!((*direction - Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-5),
            l => panic!("{l:?}"),
        }
        let bad = "[geometry]\nbuiltin = \"courtyard\"\n[sequence]\nduration = 2.0\nlights = [ { light = 3, t = 0.0 } ]\n";
        let f = parse(bad, Path::new("s.toml")).unwrap();
        assert!(crate::from_file(f, Path::new("")).unwrap_err().to_string().contains("light 3"));
    }

    /// An animation recorded in the toolkit's frame is written in the
    /// model's, and reads back from the TOML text as the same animation.
    #[test]
    fn a_world_sequence_survives_the_model_frame_and_the_file() {
        use vpl_core::scene_file::{CameraKeySpec, LightKeySpec, SequenceSpec};
        // atrium: one point light, the [[lights]] entry the key moves.
        let mut file = SceneSetup::builtin("atrium").unwrap().description;
        file.geometry.up = "z".into();
        file.geometry.scale = 2.0;
        file.sequence = None;
        let setup = crate::from_file(file, Path::new("")).unwrap();
        let o = Vec3::new(0.1, 2.0, -3.0);
        let g = Vec3::new(0.0, 1.0, 0.5);
        let d = Vec3::new(0.0, -1.0, 0.2).normalize();
        let key = |t: f32, x: f32| CameraKeySpec { t, origin: (o + Vec3::X * x).into(), target: g.into() };
        let world = SequenceSpec {
            fps: 10.0,
            duration: 1.0,
            camera: vec![key(0.0, 0.0), key(1.0, 1.0)],
            lights: vec![LightKeySpec { light: 0, t: 0.0, position: Some(g.into()), direction: Some(d.into()) }],
        };
        let setup = setup.with_world_sequence(world).unwrap();
        let check = |s: &SceneSetup| {
            let seq = s.sequence.as_ref().unwrap();
            let (so, sg) = seq.camera_at(1.0).unwrap();
            assert!((so - (o + Vec3::X)).length() < 1e-5 && (sg - g).length() < 1e-5, "{so} {sg}");
            let (p, dir) = seq.light_at(0, 0.0);
            assert!((p.unwrap() - g).length() < 1e-5 && (dir.unwrap() - d).length() < 1e-5);
        };
        check(&setup);
        let again = parse(&setup_toml(&setup), Path::new("x.toml")).unwrap();
        check(&crate::from_file(again, Path::new("")).unwrap());
    }

    #[test]
    fn every_builtin_exports_and_loads_again() {
        for name in vpl_core::builtin::NAMES {
            let s = SceneSetup::builtin(name).unwrap();
            // Export and load again: same scene description.
            let toml = setup_toml(&s);
            let f = parse(&toml, std::path::Path::new("x.toml")).unwrap();
            let again = crate::from_file(f, std::path::Path::new("")).unwrap();
            assert_eq!(again.scene.materials, s.scene.materials, "{name}");
            assert_eq!(again.scene.lights, s.scene.lights, "{name}");
            assert_eq!(again.camera, s.camera, "{name}");
            assert_eq!(again.sequence, s.sequence, "{name}");
        }
    }
}

//! Scene files: an OBJ or a built-in, plus camera, lights, material overrides
//! and an animation, in TOML (schema in DESIGN.md). Unknown keys are errors.

use crate::camera::FovAxis;
use crate::error::{CoreError, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The whole file.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Where the triangles come from.
    pub geometry: GeometrySpec,
    /// The camera (default: the built-in's, or one framing the OBJ's bounds).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub camera: Option<CameraSpec>,
    /// Point, spot and directional lights (emissive materials are area lights anyway).
    /// For a built-in, present lights replace the built-in's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lights: Option<Vec<LightSpec>>,
    /// Material overrides by name.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<MaterialSpec>,
    /// Optional animation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sequence: Option<SequenceSpec>,
}

/// `[geometry]`: exactly one of `obj`, `gltf`, `mitsuba` and `builtin`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GeometrySpec {
    /// OBJ path, relative to the TOML file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub obj: Option<String>,
    /// glTF 2.0 path (`.gltf` or `.glb`), relative to the TOML file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gltf: Option<String>,
    /// The glTF camera to use, by name (default: the file's first
    /// perspective camera); a `[camera]` table overrides either.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gltf_camera: Option<String>,
    /// Mitsuba 3 XML scene path, relative to the TOML file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mitsuba: Option<String>,
    /// Values of the Mitsuba file's `$name` parameters (they override its
    /// `<default>`s, as `mitsuba -D name=value` does).
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub mitsuba_params: std::collections::BTreeMap<String, String>,
    /// Name of a built-in scene.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub builtin: Option<String>,
    /// The model's up axis, "y" (default) or "z" (rotated to +Y up).
    #[serde(default = "default_up")]
    pub up: String,
    /// Uniform scale applied to the OBJ.
    #[serde(default = "one")]
    pub scale: f32,
    /// Diffuse surfaces reflect on both sides (default); `false`: back faces are black.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub two_sided: Option<bool>,
    /// Folders, relative to the TOML file, that the files it names (and the
    /// files those name) may lie under besides the TOML's own folder (see
    /// `vpl-scene-io`'s `sandbox`); as `--allow-outside` does for the command line.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub allow_outside: Vec<String>,
}

/// `[camera]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraSpec {
    /// Eye position.
    pub origin: [f32; 3],
    /// Point looked at.
    pub target: [f32; 3],
    /// Up hint; image right = normalize(target − origin) × up.
    #[serde(default = "default_up_vec")]
    pub up: [f32; 3],
    /// Full field of view in degrees.
    pub fov: f32,
    /// "x", "y" or "smaller" (default).
    #[serde(default = "default_fov_axis")]
    pub fov_axis: FovAxis,
    /// Default image size.
    #[serde(default = "default_resolution")]
    pub resolution: [u32; 2],
    /// Thin-lens aperture radius (0 = pinhole).
    #[serde(default)]
    pub lens_radius: f32,
    /// Focus distance.
    #[serde(default = "one")]
    pub focus_distance: f32,
}

/// `[[lights]]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase", deny_unknown_fields)]
pub enum LightSpec {
    /// An isotropic point light.
    Point {
        /// Position.
        position: [f32; 3],
        /// Intensity in W/sr.
        intensity: [f32; 3],
    },
    /// A spot light.
    Spot {
        /// Position.
        position: [f32; 3],
        /// Axis.
        direction: [f32; 3],
        /// Intensity on the axis in W/sr.
        intensity: [f32; 3],
        /// Half-angle of the cone in degrees.
        #[serde(default = "default_spot_angle")]
        angle: f32,
        /// Half-angle where the falloff begins (default: 0.8 × angle).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        falloff_start: Option<f32>,
    },
    /// The sun.
    Directional {
        /// Direction light travels.
        direction: [f32; 3],
        /// Irradiance (W/m²) on a surface facing the sun.
        irradiance: [f32; 3],
    },
    /// Light from infinitely far away: a constant environment, or a sky
    /// whose radiance runs linearly in height from the zenith (the model's
    /// up) to the horizon and on to the ground.
    Environment {
        /// Radiance (W/m²/sr) at the zenith, and everywhere when the other
        /// two are absent.
        radiance: [f32; 3],
        /// Radiance along the horizon (default: `radiance`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        horizon: Option<[f32; 3]>,
        /// Radiance from straight below (default: `horizon`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        ground: Option<[f32; 3]>,
    },
}

/// `[[materials]]`: overrides of a named material.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// Material name (from the MTL or the built-in).
    pub name: String,
    /// Diffuse albedo.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub albedo: Option<[f32; 3]>,
    /// Emitted radiance.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub emission: Option<[f32; 3]>,
    /// Layer glossiness κ (progressive renderer).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f32>,
    /// Specular reflectance of the layer.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub specular: Option<[f32; 3]>,
    /// Transmitted fraction (glass).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transmission: Option<f32>,
    /// Index of refraction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ior: Option<f32>,
    /// Abbe number (dispersion; 0 = none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub abbe: Option<f32>,
}

/// `[sequence]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SequenceSpec {
    /// Frames per second.
    #[serde(default = "default_fps")]
    pub fps: f32,
    /// Length in seconds.
    pub duration: f32,
    /// Camera keys.
    #[serde(default)]
    pub camera: Vec<CameraKeySpec>,
    /// Light keys.
    #[serde(default)]
    pub lights: Vec<LightKeySpec>,
}

/// A camera key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraKeySpec {
    /// Time (s).
    pub t: f32,
    /// Eye position.
    pub origin: [f32; 3],
    /// Point looked at.
    pub target: [f32; 3],
}

/// A light key.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightKeySpec {
    /// Index into `[[lights]]`.
    pub light: usize,
    /// Time (s).
    pub t: f32,
    /// New position.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f32; 3]>,
    /// New direction.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f32; 3]>,
}

/// `p` made absolute against the working folder, with `.` and `..`
/// resolved without reading the file system (the model need not exist yet).
fn lexical_absolute(p: &Path) -> std::path::PathBuf {
    use std::path::Component;
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut out = std::path::PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c.as_os_str()),
        }
    }
    out
}

/// The path from folder `base` to `target` (both absolute and lexical), or
/// `None` when they share no root.
fn relative_path(target: &Path, base: &Path) -> Option<std::path::PathBuf> {
    use std::path::Component;
    let (t, b): (Vec<Component>, Vec<Component>) = (target.components().collect(), base.components().collect());
    if t.first() != b.first() {
        return None;
    }
    let common = t.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut out = std::path::PathBuf::new();
    for _ in common..b.len() {
        out.push("..");
    }
    for c in &t[common..] {
        out.push(c.as_os_str());
    }
    Some(out)
}

fn default_up() -> String {
    "y".into()
}
fn one() -> f32 {
    1.0
}
fn default_up_vec() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn default_fov_axis() -> FovAxis {
    FovAxis::Smaller
}
fn default_resolution() -> [u32; 2] {
    [320, 240]
}
fn default_spot_angle() -> f32 {
    30.0
}
fn default_fps() -> f32 {
    30.0
}

impl SceneFile {
    /// Checks what the schema cannot say: exactly one geometry source,
    /// the up axis, a positive scale, and a sequence of bounded length.
    /// `path` names the file in errors. (`vpl-scene-io` reads the TOML
    /// text and calls this.)
    pub fn validate(&self, path: &Path) -> Result<()> {
        let f = self;
        let sources = [f.geometry.obj.is_some(), f.geometry.gltf.is_some(), f.geometry.mitsuba.is_some(), f.geometry.builtin.is_some()];
        if sources.iter().filter(|&&s| s).count() != 1 {
            return Err(CoreError::SceneFile {
                path: path.into(),
                reason: "[geometry] needs exactly one of `obj`, `gltf`, `mitsuba` and `builtin`".into(),
            });
        }
        if f.geometry.gltf_camera.is_some() && f.geometry.gltf.is_none() {
            return Err(CoreError::SceneFile { path: path.into(), reason: "geometry.gltf_camera needs geometry.gltf".into() });
        }
        if !f.geometry.mitsuba_params.is_empty() && f.geometry.mitsuba.is_none() {
            return Err(CoreError::SceneFile { path: path.into(), reason: "geometry.mitsuba_params needs geometry.mitsuba".into() });
        }
        if f.geometry.up != "y" && f.geometry.up != "z" {
            return Err(CoreError::SceneFile {
                path: path.into(),
                reason: format!("geometry.up must be \"y\" or \"z\", got \"{}\"", f.geometry.up),
            });
        }
        if !(f.geometry.scale.is_finite() && f.geometry.scale > 0.0) {
            return Err(CoreError::SceneFile {
                path: path.into(),
                reason: format!("geometry.scale must be positive, got {}", f.geometry.scale),
            });
        }
        if let Some(s) = &f.sequence {
            if !(s.fps.is_finite() && s.fps > 0.0 && s.duration.is_finite() && s.duration > 0.0) {
                return Err(CoreError::SceneFile {
                    path: path.into(),
                    reason: format!("sequence.fps and sequence.duration must be positive and finite, got {} and {}", s.fps, s.duration),
                });
            }
            // Every command that walks a sequence keeps something per frame.
            let frames = s.duration as f64 * s.fps as f64;
            if frames >= crate::sequence::MAX_FRAMES as f64 {
                return Err(CoreError::SceneFile {
                    path: path.into(),
                    reason: format!(
                        "sequence.duration × sequence.fps is {frames:.3e} frames, more than the {} a sequence may have",
                        crate::sequence::MAX_FRAMES
                    ),
                });
            }
        }
        Ok(())
    }

    /// The description with its model paths (`obj`, `gltf`, `mitsuba`), which
    /// are relative to the folder `from` (the one the file was read from),
    /// made relative to the folder `to` (where it will be written), so that
    /// the copy finds the same model. A path that no relative path leads to
    /// (another drive) is made absolute. A built-in needs no change.
    pub fn relocated(mut self, from: &Path, to: &Path) -> SceneFile {
        let g = &mut self.geometry;
        for p in [&mut g.obj, &mut g.gltf, &mut g.mitsuba].into_iter().flatten() {
            // An empty folder is the working one.
            let dot = |d: &Path| if d.as_os_str().is_empty() { Path::new(".").to_path_buf() } else { d.to_path_buf() };
            let target = lexical_absolute(&dot(from).join(p.as_str()));
            let here = lexical_absolute(&dot(to));
            *p = relative_path(&target, &here).unwrap_or(target).to_string_lossy().into_owned();
        }
        self
    }
}

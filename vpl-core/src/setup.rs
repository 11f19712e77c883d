//! A loaded scene with its camera and animation: from a built-in name, a
//! scene file (TOML) or a bare OBJ.

use crate::builtin;
use crate::camera::{Camera, FovAxis};
use crate::error::{CoreError, Result};
use crate::light::Light;
use crate::material::{Layered, Material};
#[cfg(feature = "formats")]
use crate::obj::load_obj;
use crate::scene::Scene;
use crate::scene_file::{CameraSpec, GeometrySpec, LightSpec, SceneFile, SequenceSpec};
use crate::sequence::{CameraKey, LightKey, Sequence};
use glam::Vec3;
use std::path::Path;

/// Everything needed to render a scene or its animation.
#[derive(Clone, Debug)]
pub struct SceneSetup {
    /// The scene at time 0 (lights as the description gives them).
    pub scene: Scene,
    /// The camera at time 0.
    pub camera: Camera,
    /// The animation, if any.
    pub sequence: Option<Sequence>,
    /// What loading noticed (missing MTL, skipped triangles, …).
    pub warnings: Vec<String>,
    /// The description this setup was made from (`vpl export-scene` writes it).
    pub description: SceneFile,
}

impl SceneSetup {
    /// Loads `spec`: a built-in name, a `.toml` scene file or an `.obj` file.
    pub fn load(spec: &str) -> Result<SceneSetup> {
        let path = Path::new(spec);
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            #[cfg(feature = "formats")]
            Some("toml") => {
                let file = SceneFile::read(path)?;
                // Values the description holds are named with the file they come from.
                Self::from_file(file, path.parent().unwrap_or(Path::new("."))).map_err(|e| match e {
                    CoreError::BadValue { what, reason } => CoreError::BadValue { what: format!("{spec}: {what}"), reason },
                    CoreError::Invalid(s) => CoreError::Invalid(format!("{spec}: {s}")),
                    e => e,
                })
            }
            #[cfg(not(feature = "formats"))]
            Some("toml") => Err(CoreError::Invalid(format!("{spec}: reading scene files needs vpl-core's `formats` feature"))),
            Some("obj") => {
                let file = SceneFile {
                    geometry: GeometrySpec { obj: Some(spec.to_string()), builtin: None, up: "y".into(), scale: 1.0, two_sided: None },
                    camera: None,
                    lights: None,
                    materials: Vec::new(),
                    sequence: None,
                };
                Self::from_file(file, Path::new(""))
            }
            _ if builtin::NAMES.contains(&spec) => Self::builtin(spec),
            _ if path.exists() => Err(CoreError::Invalid(format!("{spec}: scene files must end in .toml or .obj"))),
            _ => Err(CoreError::UnknownBuiltin(spec.to_string())),
        }
    }

    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Result<SceneSetup> {
        let b = builtin::build(name)?;
        let file = b.description();
        Self::from_file(file, Path::new(""))
    }

    /// Builds from a parsed description; OBJ paths are relative to `base`.
    pub fn from_file(file: SceneFile, base: &Path) -> Result<SceneSetup> {
        let mut warnings = Vec::new();
        let (name, mesh, mut materials, defaults, two_sided_default) = if let Some(b) = &file.geometry.builtin {
            let b = builtin::build(b)?;
            let d = b.description();
            (b.name.to_string(), b.mesh, b.materials, Some(d), b.two_sided)
        } else {
            let (name, mesh, materials) = obj_geometry(&file.geometry, base, &mut warnings)?;
            (name, mesh, materials, None, true)
        };
        for m in &file.materials {
            let target = materials
                .iter_mut()
                .find(|x| x.name == m.name)
                .ok_or_else(|| CoreError::Invalid(format!("material override names unknown material '{}'", m.name)))?;
            apply_override(target, m)?;
        }
        let lights_spec = file.lights.clone().or_else(|| defaults.as_ref().and_then(|d| d.lights.clone())).unwrap_or_default();
        let lights = lights_spec.iter().map(light_from_spec).collect::<Result<Vec<_>>>()?;
        let two_sided = file.geometry.two_sided.unwrap_or(two_sided_default);
        let scene = Scene::new(name, &mesh, materials, lights, two_sided).map_err(|e| match e {
            // Say what loading noticed: a missing material library is the usual reason for a dark OBJ.
            CoreError::NoLights(n) if !warnings.is_empty() => CoreError::NoLights(format!("{n} ({})", warnings.join("; "))),
            e => e,
        })?;
        warnings.extend(scene.warnings.iter().cloned());
        let camera_spec = file.camera.clone().or_else(|| defaults.as_ref().and_then(|d| d.camera.clone()));
        let camera = match &camera_spec {
            Some(c) => camera_from_spec(c)?,
            None => framing_camera(&scene)?,
        };
        let seq_spec = file.sequence.clone().or_else(|| defaults.as_ref().and_then(|d| d.sequence.clone()));
        let sequence = seq_spec.as_ref().map(|s| sequence_from_spec(s, lights_spec.len())).transpose()?;
        let mut description = file;
        description.camera = camera_spec.or_else(|| Some(camera_to_spec(&camera)));
        description.lights = Some(lights_spec);
        description.sequence = seq_spec;
        Ok(SceneSetup { scene, camera, sequence, warnings, description })
    }

    /// The same scene with the animation `spec` instead of its own (checked
    /// as a scene file's `[sequence]` is; `vpl export-scene` then writes it).
    pub fn with_sequence(mut self, spec: SequenceSpec) -> Result<SceneSetup> {
        let n_lights = self.description.lights.as_ref().map_or(0, |l| l.len());
        self.sequence = Some(sequence_from_spec(&spec, n_lights)?);
        self.description.sequence = Some(spec);
        Ok(self)
    }

    /// The camera at frame `frame` of the sequence (the scene's camera without one).
    pub fn camera_at_frame(&self, frame: u32) -> Result<Camera> {
        match self.sequence.as_ref().and_then(|seq| seq.camera_at(seq.time(frame))) {
            Some((o, g)) => self.camera.looking(o, g),
            None => Ok(self.camera.clone()),
        }
    }

    /// Scene and camera at frame `frame` of the sequence (frame 0 without one).
    pub fn frame(&self, frame: u32) -> Result<(Scene, Camera)> {
        let camera = self.camera_at_frame(frame)?;
        let Some(seq) = &self.sequence else {
            return Ok((self.scene.clone(), camera));
        };
        let t = seq.time(frame);
        if seq.lights.is_empty() {
            return Ok((self.scene.clone(), camera));
        }
        let mut lights = self.scene.extra_lights();
        for (i, l) in lights.iter_mut().enumerate() {
            let (p, d) = seq.light_at(i, t);
            match l {
                Light::Point { position, .. } => *position = p.unwrap_or(*position),
                Light::Spot { position, direction, .. } => {
                    *position = p.unwrap_or(*position);
                    *direction = d.filter(|d| *d != Vec3::ZERO).unwrap_or(*direction);
                }
                Light::Directional { direction, .. } => *direction = d.filter(|d| *d != Vec3::ZERO).unwrap_or(*direction),
                Light::Area { .. } => {}
            }
        }
        Ok((self.scene.with_lights(lights)?, camera))
    }

    /// The scene description as TOML (what `vpl export-scene` prints).
    #[cfg(feature = "formats")]
    pub fn to_toml(&self) -> String {
        self.description.to_toml()
    }
}

fn vec3(a: [f32; 3], what: &str) -> Result<Vec3> {
    let v = Vec3::from(a);
    if v.is_finite() { Ok(v) } else { Err(CoreError::Invalid(format!("{what} must be finite, got {} {} {}", a[0], a[1], a[2]))) }
}

fn nonneg(a: [f32; 3], what: &str) -> Result<Vec3> {
    let v = vec3(a, what)?;
    if v.min_element() >= 0.0 { Ok(v) } else { Err(CoreError::Invalid(format!("{what} must not be negative"))) }
}

fn apply_override(m: &mut Material, o: &crate::scene_file::MaterialSpec) -> Result<()> {
    if let Some(a) = o.albedo {
        m.albedo = nonneg(a, &format!("material '{}' albedo", o.name))?;
    }
    if let Some(e) = o.emission {
        m.emission = nonneg(e, &format!("material '{}' emission", o.name))?;
    }
    if o.kappa.is_some() || o.specular.is_some() || o.transmission.is_some() || o.ior.is_some() || o.abbe.is_some() {
        let mut l = m.layered.clone().unwrap_or(Layered { kappa: 0.0, specular: Vec3::ZERO, transmission: 0.0, ior: 1.5, abbe: 0.0 });
        if let Some(k) = o.kappa {
            if !(0.0..=1.0).contains(&k) {
                return Err(CoreError::Invalid(format!("kappa of '{}' must be in [0, 1], got {k}", o.name)));
            }
            l.kappa = k;
        }
        if let Some(s) = o.specular {
            l.specular = nonneg(s, &format!("material '{}' specular", o.name))?;
        }
        if let Some(t) = o.transmission {
            l.transmission = t;
        }
        if let Some(i) = o.ior {
            l.ior = i;
        }
        if let Some(a) = o.abbe {
            l.abbe = a;
        }
        m.layered = Some(l);
    }
    Ok(())
}

/// The [`Light`] a `[[lights]]` entry describes.
pub fn light_from_spec(s: &LightSpec) -> Result<Light> {
    Ok(match s {
        LightSpec::Point { position, intensity } => {
            Light::Point { position: vec3(*position, "light position")?, intensity: nonneg(*intensity, "light intensity")? }
        }
        LightSpec::Spot { position, direction, intensity, angle, falloff_start } => {
            let d = vec3(*direction, "spot direction")?.normalize_or_zero();
            if d == Vec3::ZERO || !(*angle > 0.0 && *angle <= 180.0) {
                return Err(CoreError::Invalid("spot light needs a nonzero direction and an angle in (0, 180]".into()));
            }
            let start = falloff_start.unwrap_or(0.8 * angle).min(*angle);
            Light::Spot {
                position: vec3(*position, "light position")?,
                direction: d,
                intensity: nonneg(*intensity, "light intensity")?,
                cos_falloff_start: start.to_radians().cos(),
                cos_total: angle.to_radians().cos(),
            }
        }
        LightSpec::Directional { direction, irradiance } => {
            let d = vec3(*direction, "sun direction")?.normalize_or_zero();
            if d == Vec3::ZERO {
                return Err(CoreError::Invalid("sun direction must be nonzero".into()));
            }
            Light::Directional { direction: d, irradiance: nonneg(*irradiance, "sun irradiance")? }
        }
    })
}

/// The [`Camera`] a `[camera]` table describes.
pub fn camera_from_spec(c: &CameraSpec) -> Result<Camera> {
    Camera::thin_lens(
        vec3(c.origin, "camera origin")?,
        vec3(c.target, "camera target")?,
        vec3(c.up, "camera up")?,
        c.fov,
        c.fov_axis,
        (c.resolution[0], c.resolution[1]),
        c.lens_radius,
        c.focus_distance,
    )
}

fn material_to_spec(m: &Material) -> crate::scene_file::MaterialSpec {
    let l = m.layered.as_ref();
    crate::scene_file::MaterialSpec {
        name: m.name.clone(),
        albedo: Some(m.albedo.into()),
        emission: m.is_emissive().then(|| m.emission.into()),
        kappa: l.map(|l| l.kappa),
        specular: l.map(|l| l.specular.into()),
        transmission: l.map(|l| l.transmission),
        ior: l.map(|l| l.ior),
        abbe: l.map(|l| l.abbe),
    }
}

fn camera_to_spec(c: &Camera) -> CameraSpec {
    CameraSpec {
        origin: c.origin.into(),
        target: c.target.into(),
        up: c.up.into(),
        fov: c.fov_deg,
        fov_axis: c.fov_axis,
        resolution: [c.resolution.0, c.resolution.1],
        lens_radius: c.lens_radius,
        focus_distance: c.focus_distance,
    }
}

fn sequence_from_spec(s: &SequenceSpec, n_lights: usize) -> Result<Sequence> {
    let mut camera: Vec<CameraKey> = s
        .camera
        .iter()
        .map(|k| Ok(CameraKey { t: k.t, origin: vec3(k.origin, "camera key origin")?, target: vec3(k.target, "camera key target")? }))
        .collect::<Result<_>>()?;
    camera.sort_by(|a, b| a.t.total_cmp(&b.t));
    let mut lights = Vec::new();
    for k in &s.lights {
        if k.light >= n_lights {
            return Err(CoreError::Invalid(format!("sequence light key names light {} but there are {n_lights} [[lights]]", k.light)));
        }
        lights.push(LightKey {
            light: k.light,
            t: k.t,
            position: k.position.map(|p| vec3(p, "light key position")).transpose()?,
            direction: k.direction.map(|p| vec3(p, "light key direction")).transpose()?,
        });
    }
    lights.sort_by(|a, b| a.t.total_cmp(&b.t));
    Ok(Sequence { fps: s.fps, duration: s.duration, camera, lights })
}

/// A camera on the +Z side of the scene's bounds that frames its bounding sphere.
fn framing_camera(scene: &Scene) -> Result<Camera> {
    let (lo, hi) = scene.geometry.bounds;
    let c = 0.5 * (lo + hi);
    let r = scene.radius().max(1e-3);
    let fov: f32 = 60.0;
    let d = 1.1 * r / (0.5 * fov.to_radians()).sin();
    Camera::new(c + Vec3::Z * d, c, Vec3::Y, fov, FovAxis::Smaller, (320, 240))
}

/// The OBJ geometry of a description: name, mesh (rotated to Y-up and
/// scaled as `geometry` says) and materials; loading notes go to `warnings`.
#[cfg(feature = "formats")]
fn obj_geometry(geometry: &GeometrySpec, base: &Path, warnings: &mut Vec<String>) -> Result<(String, crate::mesh::Mesh, Vec<Material>)> {
    let p = base.join(geometry.obj.as_deref().unwrap_or_default());
    let data = load_obj(&p)?;
    warnings.extend(data.warnings);
    let mut mesh = data.mesh;
    let s = geometry.scale;
    let z_up = geometry.up == "z";
    for v in mesh.positions.iter_mut() {
        *v = if z_up { Vec3::new(v.x, v.z, -v.y) } else { *v } * s;
    }
    for n in mesh.normals.iter_mut() {
        if z_up {
            *n = Vec3::new(n.x, n.z, -n.y);
        }
    }
    let name = p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into());
    Ok((name, mesh, data.materials))
}

/// Without the `formats` feature there is no OBJ reader.
#[cfg(not(feature = "formats"))]
fn obj_geometry(geometry: &GeometrySpec, _base: &Path, _warnings: &mut Vec<String>) -> Result<(String, crate::mesh::Mesh, Vec<Material>)> {
    let obj = geometry.obj.as_deref().unwrap_or_default();
    Err(CoreError::Invalid(format!("{obj}: reading OBJ files needs vpl-core's `formats` feature")))
}

impl builtin::Builtin {
    /// The description `vpl export-scene` writes for this built-in.
    pub fn description(&self) -> SceneFile {
        SceneFile {
            geometry: GeometrySpec {
                obj: None,
                builtin: Some(self.name.to_string()),
                up: "y".into(),
                scale: 1.0,
                two_sided: Some(self.two_sided),
            },
            camera: Some(self.camera.clone()),
            lights: Some(self.lights.clone()),
            materials: self.materials.iter().map(material_to_spec).collect(),
            sequence: Some(self.sequence.clone()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn light_specs_become_lights() {
        let spot = light_from_spec(&LightSpec::Spot {
            position: [0.0, 2.0, 0.0],
            direction: [0.0, -2.0, 0.0],
            intensity: [5.0; 3],
            angle: 60.0,
            falloff_start: None,
        })
        .unwrap();
        match spot {
            Light::Spot { direction, cos_total, cos_falloff_start, .. } => {
                assert_eq!(direction, -Vec3::Y);
                assert!((cos_total - 0.5).abs() < 1e-6);
                assert!((cos_falloff_start - 48f32.to_radians().cos()).abs() < 1e-6);
            }
            _ => panic!("not a spot"),
        }
        assert!(light_from_spec(&LightSpec::Directional { direction: [0.0; 3], irradiance: [1.0; 3] }).is_err());
        assert!(light_from_spec(&LightSpec::Point { position: [0.0; 3], intensity: [-1.0, 1.0, 1.0] }).is_err());
    }

    #[test]
    #[cfg(feature = "formats")]
    fn sun_direction_keys_turn_the_sun() {
        let text = "[geometry]\nbuiltin = \"courtyard\"\n[[lights]]\ntype = \"directional\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\n\
                    [sequence]\nduration = 2.0\nlights = [ { light = 0, t = 0.0, direction = [0, -1, 0] }, { light = 0, t = 2.0, direction = [1, -1, 0] } ]\n";
        let f = SceneFile::parse(text, Path::new("s.toml")).unwrap();
        let s = SceneSetup::from_file(f, Path::new("")).unwrap();
        let (scene, _) = s.frame(60).unwrap();
        match &scene.lights[0] {
            Light::Directional { direction, .. } => assert!((*direction - Vec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-5),
            l => panic!("{l:?}"),
        }
        let bad = "[geometry]\nbuiltin = \"courtyard\"\n[sequence]\nduration = 2.0\nlights = [ { light = 3, t = 0.0 } ]\n";
        let f = SceneFile::parse(bad, Path::new("s.toml")).unwrap();
        assert!(SceneSetup::from_file(f, Path::new("")).unwrap_err().to_string().contains("light 3"));
    }
}

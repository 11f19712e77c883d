//! A loaded scene with its camera and animation, from a built-in or from a
//! description whose model file a [`ModelLoader`] reads (`vpl-scene-io`).

use crate::builtin;
use crate::camera::{Camera, FovAxis};
use crate::error::{CoreError, Result};
use crate::light::Light;
use crate::material::{Layered, Material};
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
    /// A built-in scene by name (see [`builtin::NAMES`]). Scene files (TOML,
    /// OBJ, glTF, Mitsuba XML) are read by the `vpl-scene-io` crate, whose
    /// `load` takes a built-in name or a file.
    pub fn builtin(name: &str) -> Result<SceneSetup> {
        let b = builtin::build(name)?;
        let file = b.description();
        Self::from_description(file, Path::new(""), &NoModelFiles)
    }

    /// Builds from a parsed description; the model file it names (OBJ,
    /// glTF, Mitsuba XML; paths relative to `base`) is read by `models`
    /// (`vpl-scene-io`'s readers, or [`NoModelFiles`] for descriptions of
    /// built-ins).
    ///
    /// Everything the description places (the geometry, `[camera]`,
    /// `[[lights]]`, the sequence's keys, and a glTF file's own camera and
    /// lights) is in the model's frame: `geometry.up = "z"` turns all of it
    /// to the toolkit's +Y up, and `geometry.scale` scales all positions.
    pub fn from_description<L: ModelLoader + ?Sized>(
        file: SceneFile,
        base: &Path,
        models: &L,
    ) -> std::result::Result<SceneSetup, L::Error> {
        let mut warnings = Vec::new();
        let frame = ModelFrame::of(&file.geometry);
        let (Model { name, mut mesh, mut materials, lights: file_lights, camera: file_camera, two_sided: two_sided_default }, defaults) =
            if let Some(b) = &file.geometry.builtin {
                let b = builtin::build(b)?;
                let d = b.description();
                let model = Model {
                    name: b.name.to_string(),
                    mesh: b.mesh,
                    materials: b.materials,
                    lights: None,
                    camera: None,
                    two_sided: b.two_sided,
                };
                (model, Some(d))
            } else {
                (models.load_model(&file.geometry, base, &mut warnings)?, None)
            };
        for v in mesh.positions.iter_mut() {
            *v = frame.point(*v);
        }
        for n in mesh.normals.iter_mut() {
            *n = frame.direction(*n);
        }
        for m in &file.materials {
            let target = materials
                .iter_mut()
                .find(|x| x.name == m.name)
                .ok_or_else(|| CoreError::Invalid(format!("material override names unknown material '{}'", m.name)))?;
            apply_override(target, m)?;
        }
        // Lights and camera as the model's frame gives them.
        let lights_spec =
            file.lights.clone().or(file_lights).or_else(|| defaults.as_ref().and_then(|d| d.lights.clone())).unwrap_or_default();
        let lights = lights_spec.iter().map(|l| light_from_spec(&frame.light(l))).collect::<Result<Vec<_>>>()?;
        let two_sided = file.geometry.two_sided.unwrap_or(two_sided_default);
        let scene = Scene::new(name, &mesh, materials, lights, two_sided).map_err(|e| match e {
            // Say what loading noticed: a missing material library is the usual reason for a dark OBJ.
            CoreError::NoLights(n) if !warnings.is_empty() => CoreError::NoLights(format!("{n} ({})", warnings.join("; "))),
            e => e,
        })?;
        warnings.extend(scene.warnings.iter().cloned());
        let camera_spec = file.camera.clone().or(file_camera).or_else(|| defaults.as_ref().and_then(|d| d.camera.clone()));
        let camera = match &camera_spec {
            Some(c) => camera_from_spec(&frame.camera(c))?,
            None => framing_camera(&scene)?,
        };
        let seq_spec = file.sequence.clone().or_else(|| defaults.as_ref().and_then(|d| d.sequence.clone()));
        let sequence = seq_spec.as_ref().map(|s| sequence_from_spec(&frame.sequence(s), lights_spec.len())).transpose()?;
        let mut description = file;
        description.camera = camera_spec.or_else(|| Some(frame.camera_back(&camera_to_spec(&camera))));
        description.lights = Some(lights_spec);
        description.sequence = seq_spec;
        Ok(SceneSetup { scene, camera, sequence, warnings, description })
    }

    /// The same scene with the animation `spec` instead of its own (checked
    /// as a scene file's `[sequence]` is, and like it in the model's frame:
    /// `geometry.up` and `geometry.scale` apply; `vpl export-scene` then
    /// writes it).
    pub fn with_sequence(mut self, spec: SequenceSpec) -> Result<SceneSetup> {
        let n_lights = self.description.lights.as_ref().map_or(0, |l| l.len());
        let frame = ModelFrame::of(&self.description.geometry);
        self.sequence = Some(sequence_from_spec(&frame.sequence(&spec), n_lights)?);
        self.description.sequence = Some(spec);
        Ok(self)
    }

    /// [`SceneSetup::with_sequence`] for an animation in the toolkit's
    /// frame (+Y up, the scene's units), as a viewer records it: the
    /// description gets it in the model's frame.
    pub fn with_world_sequence(self, world: SequenceSpec) -> Result<SceneSetup> {
        let frame = ModelFrame::of(&self.description.geometry);
        let spec = frame.sequence_back(&world);
        self.with_sequence(spec)
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
                Light::Area { .. } | Light::Environment { .. } => {}
            }
        }
        Ok((self.scene.with_lights(lights)?, camera))
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
        LightSpec::Environment { radiance, horizon, ground } => {
            let zenith = nonneg(*radiance, "environment radiance")?;
            let horizon = horizon.map(|h| nonneg(h, "environment horizon")).transpose()?.unwrap_or(zenith);
            let nadir = ground.map(|g| nonneg(g, "environment ground")).transpose()?.unwrap_or(horizon);
            Light::Environment { sky: crate::environment::Sky { zenith, horizon, nadir } }
        }
    })
}

/// The [`Camera`] a `[camera]` table describes.
pub fn camera_from_spec(c: &CameraSpec) -> Result<Camera> {
    Camera::new(
        vec3(c.origin, "camera origin")?,
        vec3(c.target, "camera target")?,
        vec3(c.up, "camera up")?,
        c.fov,
        c.fov_axis,
        (c.resolution[0], c.resolution[1]),
    )?
    .with_lens(c.lens_radius, c.focus_distance)
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

/// What a description's model file gives, in the model's frame.
#[derive(Clone, Debug)]
pub struct Model {
    /// The scene's name (the model file's stem).
    pub name: String,
    /// The triangles.
    pub mesh: crate::mesh::Mesh,
    /// Their materials, by the mesh's material indices.
    pub materials: Vec<Material>,
    /// Lights the file itself holds (glTF, Mitsuba XML).
    pub lights: Option<Vec<LightSpec>>,
    /// The camera the file itself holds (glTF, Mitsuba XML).
    pub camera: Option<CameraSpec>,
    /// Whether surfaces reflect on both sides unless the description says.
    pub two_sided: bool,
}

/// Reads the model file a description's `[geometry]` names (`obj`, `gltf`
/// or `mitsuba`, relative to `base`); notes on what loading noticed go to
/// `warnings`. `vpl-scene-io` implements it for its file formats, behind
/// its sandbox and input limits.
pub trait ModelLoader {
    /// What a failed read says; the core's own errors (a bad value in the
    /// description) convert into it.
    type Error: From<CoreError>;
    /// The model of `geometry`.
    fn load_model(&self, geometry: &GeometrySpec, base: &Path, warnings: &mut Vec<String>) -> std::result::Result<Model, Self::Error>;
}

/// A [`ModelLoader`] that reads no files: descriptions of built-ins only.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoModelFiles;

impl ModelLoader for NoModelFiles {
    type Error = CoreError;

    fn load_model(&self, geometry: &GeometrySpec, _base: &Path, _warnings: &mut Vec<String>) -> Result<Model> {
        let named = [&geometry.obj, &geometry.gltf, &geometry.mitsuba].into_iter().flatten().next().cloned().unwrap_or_default();
        Err(CoreError::Invalid(format!("{named}: reading model files needs the vpl-scene-io crate")))
    }
}

/// The map from a description's model frame to the toolkit's world (+Y
/// up): `up = "z"` turns (x, y, z) into (x, z, −y), then positions scale.
#[derive(Clone, Copy, Debug)]
struct ModelFrame {
    z_up: bool,
    scale: f32,
}

impl ModelFrame {
    fn of(g: &GeometrySpec) -> ModelFrame {
        ModelFrame { z_up: g.up == "z", scale: g.scale }
    }

    fn direction(self, v: Vec3) -> Vec3 {
        if self.z_up { Vec3::new(v.x, v.z, -v.y) } else { v }
    }

    fn point(self, p: Vec3) -> Vec3 {
        self.direction(p) * self.scale
    }

    fn direction_back(self, v: Vec3) -> Vec3 {
        if self.z_up { Vec3::new(v.x, -v.z, v.y) } else { v }
    }

    fn point_back(self, p: Vec3) -> Vec3 {
        self.direction_back(p / self.scale)
    }

    fn p(self, a: [f32; 3]) -> [f32; 3] {
        self.point(Vec3::from(a)).into()
    }

    fn d(self, a: [f32; 3]) -> [f32; 3] {
        self.direction(Vec3::from(a)).into()
    }

    fn light(self, l: &LightSpec) -> LightSpec {
        match l.clone() {
            LightSpec::Point { position, intensity } => LightSpec::Point { position: self.p(position), intensity },
            LightSpec::Spot { position, direction, intensity, angle, falloff_start } => {
                LightSpec::Spot { position: self.p(position), direction: self.d(direction), intensity, angle, falloff_start }
            }
            LightSpec::Directional { direction, irradiance } => LightSpec::Directional { direction: self.d(direction), irradiance },
            // The sky's zenith is the toolkit's +Y, which is the model's up.
            e @ LightSpec::Environment { .. } => e,
        }
    }

    fn camera(self, c: &CameraSpec) -> CameraSpec {
        let mut c = c.clone();
        c.origin = self.p(c.origin);
        c.target = self.p(c.target);
        c.up = self.d(c.up);
        c.focus_distance *= self.scale;
        c.lens_radius *= self.scale;
        c
    }

    fn camera_back(self, c: &CameraSpec) -> CameraSpec {
        let mut c = c.clone();
        c.origin = self.point_back(Vec3::from(c.origin)).into();
        c.target = self.point_back(Vec3::from(c.target)).into();
        c.up = self.direction_back(Vec3::from(c.up)).into();
        c.focus_distance /= self.scale;
        c.lens_radius /= self.scale;
        c
    }

    fn sequence_back(self, s: &SequenceSpec) -> SequenceSpec {
        let mut s = s.clone();
        for k in s.camera.iter_mut() {
            k.origin = self.point_back(Vec3::from(k.origin)).into();
            k.target = self.point_back(Vec3::from(k.target)).into();
        }
        for k in s.lights.iter_mut() {
            k.position = k.position.map(|p| self.point_back(Vec3::from(p)).into());
            k.direction = k.direction.map(|d| self.direction_back(Vec3::from(d)).into());
        }
        s
    }

    fn sequence(self, s: &SequenceSpec) -> SequenceSpec {
        let mut s = s.clone();
        for k in s.camera.iter_mut() {
            k.origin = self.p(k.origin);
            k.target = self.p(k.target);
        }
        for k in s.lights.iter_mut() {
            k.position = k.position.map(|p| self.p(p));
            k.direction = k.direction.map(|d| self.d(d));
        }
        s
    }
}

impl builtin::Builtin {
    /// The description `vpl export-scene` writes for this built-in.
    pub fn description(&self) -> SceneFile {
        SceneFile {
            geometry: GeometrySpec {
                obj: None,
                gltf: None,
                gltf_camera: None,
                mitsuba: None,
                mitsuba_params: Default::default(),
                builtin: Some(self.name.to_string()),
                up: "y".into(),
                scale: 1.0,
                two_sided: Some(self.two_sided),
                allow_outside: Vec::new(),
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

    /// An animation recorded in the toolkit's frame is written in the
    /// model's, and reads back as the same animation.
    #[test]
    fn a_world_sequence_survives_the_model_frame() {
        // atrium: one point light, the [[lights]] entry the key moves.
        let mut file = SceneSetup::builtin("atrium").unwrap().description;
        file.geometry.up = "z".into();
        file.geometry.scale = 2.0;
        file.sequence = None;
        let setup = SceneSetup::from_description(file, Path::new(""), &NoModelFiles).unwrap();
        let o = Vec3::new(0.1, 2.0, -3.0);
        let g = Vec3::new(0.0, 1.0, 0.5);
        let d = Vec3::new(0.0, -1.0, 0.2).normalize();
        let key = |t: f32, x: f32| crate::scene_file::CameraKeySpec { t, origin: (o + Vec3::X * x).into(), target: g.into() };
        let world = SequenceSpec {
            fps: 10.0,
            duration: 1.0,
            camera: vec![key(0.0, 0.0), key(1.0, 1.0)],
            lights: vec![crate::scene_file::LightKeySpec { light: 0, t: 0.0, position: Some(g.into()), direction: Some(d.into()) }],
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
        let written = setup.description.sequence.as_ref().unwrap();
        assert_ne!(Vec3::from(written.camera[0].origin), o, "the file holds the model's frame");
    }

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
}

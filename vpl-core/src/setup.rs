//! A loaded scene with its camera and animation: from a built-in name, a
//! scene file (TOML) or a bare OBJ.

use crate::builtin;
use crate::camera::{Camera, FovAxis};
use crate::error::{CoreError, Result};
use crate::light::Light;
use crate::material::{Layered, Material};
use crate::sandbox::{LoadOptions, Sandbox};
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
    /// Loads `spec`: a built-in name, a `.toml` scene file, an `.obj` file or
    /// a glTF 2.0 file (`.gltf`, `.glb`) or a Mitsuba 3 XML scene (`.xml`).
    ///
    /// The files a scene file names must lie in its folder; see
    /// [`SceneSetup::load_with`] to allow more.
    pub fn load(spec: &str) -> Result<SceneSetup> {
        Self::load_with(spec, &LoadOptions::default())
    }

    /// [`SceneSetup::load`] with `options`: the folders besides the
    /// scene's own that its files may name, and the memory limit of
    /// loading (see [`crate::sandbox`]).
    pub fn load_with(spec: &str, options: &LoadOptions) -> Result<SceneSetup> {
        let path = Path::new(spec);
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match ext.as_deref() {
            #[cfg(feature = "formats")]
            Some("toml") => {
                let file = SceneFile::read(path)?;
                // The description the user named may widen its own sandbox.
                let folder = path.parent().unwrap_or(Path::new("."));
                let mut options = options.clone();
                options.allow_outside.extend(file.geometry.allow_outside.iter().map(|r| folder.join(r)));
                let sandbox = Sandbox::for_scene(path, &options).map_err(|e| match e {
                    CoreError::Invalid(r) => CoreError::Invalid(r.replace("--allow-outside", "geometry.allow_outside")),
                    e => e,
                })?;
                // Values the description holds are named with the file they come from.
                Self::build(file, path.parent().unwrap_or(Path::new(".")), Some(sandbox)).map_err(|e| match e {
                    CoreError::BadValue { what, reason } => CoreError::BadValue { what: format!("{spec}: {what}"), reason },
                    CoreError::Invalid(s) => CoreError::Invalid(format!("{spec}: {s}")),
                    e => e,
                })
            }
            #[cfg(not(feature = "formats"))]
            Some("toml") => Err(CoreError::Invalid(format!("{spec}: reading scene files needs vpl-core's `formats` feature"))),
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
                Self::build(file, Path::new(""), Some(Sandbox::for_scene(path, options)?))
            }
            _ if builtin::NAMES.contains(&spec) => Self::builtin(spec),
            _ if path.exists() => Err(CoreError::Invalid(format!("{spec}: scene files must end in .toml, .obj, .gltf, .glb or .xml"))),
            _ => Err(CoreError::UnknownBuiltin(spec.to_string())),
        }
    }

    /// A built-in scene by name.
    pub fn builtin(name: &str) -> Result<SceneSetup> {
        let b = builtin::build(name)?;
        let file = b.description();
        Self::from_file(file, Path::new(""))
    }

    /// Builds from a parsed description; OBJ and glTF paths are relative to
    /// `base`.
    ///
    /// Everything the description places (the geometry, `[camera]`,
    /// `[[lights]]`, the sequence's keys, and a glTF file's own camera and
    /// lights) is in the model's frame: `geometry.up = "z"` turns all of it
    /// to the toolkit's +Y up, and `geometry.scale` scales all positions.
    ///
    /// The files it names must lie under `base`.
    pub fn from_file(file: SceneFile, base: &Path) -> Result<SceneSetup> {
        Self::build(file, base, None)
    }

    /// [`SceneSetup::from_file`] whose files may also lie where `options`
    /// allow.
    pub fn from_file_with(file: SceneFile, base: &Path, options: &LoadOptions) -> Result<SceneSetup> {
        let sandbox = if file.geometry.builtin.is_some() { None } else { Some(Sandbox::for_folder(base, options)?) };
        Self::build(file, base, sandbox)
    }

    /// Builds from `file`, reading its files through `sandbox` (the
    /// sandbox of `base` when `None` and files are read).
    fn build(file: SceneFile, base: &Path, sandbox: Option<Sandbox>) -> Result<SceneSetup> {
        let mut warnings = Vec::new();
        let frame = ModelFrame::of(&file.geometry);
        let Loaded { name, mut mesh, mut materials, lights: file_lights, camera: file_camera, defaults, two_sided: two_sided_default } =
            if let Some(b) = &file.geometry.builtin {
                let b = builtin::build(b)?;
                let d = b.description();
                Loaded {
                    name: b.name.to_string(),
                    mesh: b.mesh,
                    materials: b.materials,
                    lights: None,
                    camera: None,
                    defaults: Some(d),
                    two_sided: b.two_sided,
                }
            } else {
                let sandbox = match sandbox {
                    Some(s) => s,
                    None => Sandbox::for_folder(base, &LoadOptions::default())?,
                };
                if file.geometry.gltf.is_some() {
                    gltf_geometry(&file.geometry, base, &sandbox, &mut warnings)?
                } else if file.geometry.mitsuba.is_some() {
                    mitsuba_geometry(&file.geometry, base, &sandbox, &mut warnings)?
                } else {
                    obj_geometry(&file.geometry, base, &sandbox, &mut warnings)?
                }
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

/// What a geometry source gives, in the model's frame.
struct Loaded {
    name: String,
    mesh: crate::mesh::Mesh,
    materials: Vec<Material>,
    /// Lights the file itself holds (glTF).
    lights: Option<Vec<LightSpec>>,
    /// The camera the file itself holds (glTF).
    camera: Option<CameraSpec>,
    /// A built-in's own description.
    defaults: Option<SceneFile>,
    two_sided: bool,
}

impl Loaded {
    /// What a scene format that carries its own lights and camera (glTF,
    /// Mitsuba XML) gives, read from `path`.
    #[cfg(feature = "formats")]
    fn scene_file(
        path: &Path,
        mesh: crate::mesh::Mesh,
        materials: Vec<Material>,
        lights: Vec<LightSpec>,
        camera: Option<CameraSpec>,
        two_sided: bool,
    ) -> Loaded {
        let lights = (!lights.is_empty()).then_some(lights);
        Loaded { name: model_name(path), mesh, materials, lights, camera, defaults: None, two_sided }
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

/// A scene's name from its model file: the file's stem.
#[cfg(feature = "formats")]
fn model_name(p: &Path) -> String {
    p.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "scene".into())
}

/// The OBJ geometry of a description, in the model's frame; loading notes
/// go to `warnings`.
#[cfg(feature = "formats")]
fn obj_geometry(geometry: &GeometrySpec, base: &Path, sandbox: &Sandbox, warnings: &mut Vec<String>) -> Result<Loaded> {
    let p = sandbox.resolve(base, geometry.obj.as_deref().unwrap_or_default())?;
    let data = crate::obj::load_obj_in(&p, sandbox)?;
    warnings.extend(data.warnings);
    Ok(Loaded {
        name: model_name(&p),
        mesh: data.mesh,
        materials: data.materials,
        lights: None,
        camera: None,
        defaults: None,
        two_sided: true,
    })
}

/// The glTF scene of a description, in the model's frame (glTF's own, +Y
/// up, unless the description says otherwise), with the file's lights and
/// camera.
#[cfg(feature = "formats")]
fn gltf_geometry(geometry: &GeometrySpec, base: &Path, sandbox: &Sandbox, warnings: &mut Vec<String>) -> Result<Loaded> {
    let p = sandbox.resolve(base, geometry.gltf.as_deref().unwrap_or_default())?;
    let data = crate::gltf_file::load_gltf_in(&p, geometry.gltf_camera.as_deref(), sandbox)?;
    warnings.extend(data.warnings);
    Ok(Loaded::scene_file(&p, data.mesh, data.materials, data.lights, data.camera, true))
}

/// The Mitsuba XML scene of a description, in the model's frame (the
/// file's own unless the description says otherwise), with its emitters,
/// sensor and sidedness.
#[cfg(feature = "formats")]
fn mitsuba_geometry(geometry: &GeometrySpec, base: &Path, sandbox: &Sandbox, warnings: &mut Vec<String>) -> Result<Loaded> {
    let p = sandbox.resolve(base, geometry.mitsuba.as_deref().unwrap_or_default())?;
    let params: Vec<(String, String)> = geometry.mitsuba_params.iter().map(|(k, v)| (k.clone(), v.clone())).collect();
    let data = crate::mitsuba::load_mitsuba_in(&p, &params, sandbox)?;
    warnings.extend(data.warnings);
    Ok(Loaded::scene_file(&p, data.mesh, data.materials, data.lights, data.camera, data.two_sided))
}

/// Without the `formats` feature there is no Mitsuba reader.
#[cfg(not(feature = "formats"))]
fn mitsuba_geometry(geometry: &GeometrySpec, _base: &Path, _sandbox: &Sandbox, _warnings: &mut Vec<String>) -> Result<Loaded> {
    let m = geometry.mitsuba.as_deref().unwrap_or_default();
    Err(CoreError::Invalid(format!("{m}: reading Mitsuba XML files needs vpl-core's `formats` feature")))
}

/// Without the `formats` feature there is no OBJ reader.
#[cfg(not(feature = "formats"))]
fn obj_geometry(geometry: &GeometrySpec, _base: &Path, _sandbox: &Sandbox, _warnings: &mut Vec<String>) -> Result<Loaded> {
    let obj = geometry.obj.as_deref().unwrap_or_default();
    Err(CoreError::Invalid(format!("{obj}: reading OBJ files needs vpl-core's `formats` feature")))
}

/// Without the `formats` feature there is no glTF reader.
#[cfg(not(feature = "formats"))]
fn gltf_geometry(geometry: &GeometrySpec, _base: &Path, _sandbox: &Sandbox, _warnings: &mut Vec<String>) -> Result<Loaded> {
    let g = geometry.gltf.as_deref().unwrap_or_default();
    Err(CoreError::Invalid(format!("{g}: reading glTF files needs vpl-core's `formats` feature")))
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
        let setup = SceneSetup::from_file(file, Path::new("")).unwrap();
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
        #[cfg(feature = "formats")]
        {
            let again = SceneFile::parse(&setup.to_toml(), Path::new("x.toml")).unwrap();
            check(&SceneSetup::from_file(again, Path::new("")).unwrap());
        }
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

#[cfg(all(test, feature = "formats"))]
mod frame_tests {
    use super::*;

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
            SceneSetup::load(p.to_str().unwrap()).unwrap()
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
        let again = SceneFile::parse(&a.to_toml(), Path::new("again.toml")).unwrap();
        let c = SceneSetup::from_file(again, dir.path()).unwrap();
        assert_eq!(c.camera, a.camera);
        // Without a [camera] the framing camera (found in the world) goes back to the model's frame.
        let bare = load(
            "bare.toml",
            "[geometry]\nobj = \"z.obj\"\nup = \"z\"\nscale = 2.0\n[[lights]]\ntype = \"point\"\nposition = [0.0, 0.0, 1.5]\nintensity = [1.0, 1.0, 1.0]\n",
        );
        let again = SceneSetup::from_file(SceneFile::parse(&bare.to_toml(), Path::new("b.toml")).unwrap(), dir.path()).unwrap();
        assert!((again.camera.origin - bare.camera.origin).length() < 1e-4, "{:?} {:?}", again.camera.origin, bare.camera.origin);
    }
}

#[cfg(all(test, feature = "formats"))]
mod environment_tests {
    use super::*;
    use crate::environment::Sky;

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
        let s = SceneSetup::load(p.to_str().unwrap()).unwrap();
        let sky = Sky { zenith: Vec3::new(0.2, 0.3, 0.9), horizon: Vec3::ONE, nadir: Vec3::ONE };
        let i = s.scene.environment.expect("an environment light");
        assert_eq!(s.scene.lights[i], Light::Environment { sky });
        assert!((s.scene.environment_radiance(Vec3::Y) - sky.zenith).abs().max_element() < 1e-6);
        let (frame, _) = s.frame(1).unwrap();
        assert_eq!(frame.environment.map(|i| frame.lights[i].clone()), Some(Light::Environment { sky }));
        let back = SceneFile::parse(&s.to_toml(), Path::new("back.toml")).unwrap();
        assert_eq!(back.lights, s.description.lights);
        // Two environments are refused.
        let two = text.replace("[sequence]", "[[lights]]\ntype = \"environment\"\nradiance = [1.0, 1.0, 1.0]\n[sequence]");
        std::fs::write(&p, two).unwrap();
        assert!(SceneSetup::load(p.to_str().unwrap()).unwrap_err().to_string().contains("at most one environment"));
    }
}

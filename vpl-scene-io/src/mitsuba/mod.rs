//! Mitsuba 3 XML scenes: the subset that Mitsuba's own test scenes and
//! Bitterli's rendering resources use, read onto the toolkit's scene.
//!
//! - **The file.** `<scene version="2.x|3.x">` with `<include>`s (relative
//!   to the including file, or else the scene's folder; cycles refused),
//!   `<default>`s and `$name` parameters anywhere in an attribute (values
//!   given to [`load_mitsuba`] win over the file's defaults), `id`s and
//!   `<ref>`s in any order (a shape may name an emitter defined after it).
//!   Properties: `float`, `integer`, `boolean`, `string`, `rgb` (one value
//!   or three), `spectrum` (one value, or `wavelength:value` pairs turned to
//!   linear sRGB as Mitsuba's RGB modes do, see
//!   [`vpl_core::spectral::spectrum_to_rgb`]), `point`, `vector`, and
//!   `transform` with `translate`, `scale`, `rotate`, `matrix`, `lookat`.
//! - **Shapes.** `obj`, `ply`, `rectangle`, `cube`, `disk` and `sphere`
//!   (tessellated, 48 × 96; `center`, `radius`), with `to_world`,
//!   `flip_normals` and `face_normals`. A mirroring `to_world` flips the
//!   winding, so a shape keeps its outside.
//! - **BSDFs.** The table in `docs/scene-files.md` maps diffuse, (rough) conductor, (rough)
//!   dielectric, thin dielectric, (rough) plastic and twosided. Colours may
//!   be a `bitmap` texture (its average linear colour; PNG or JPEG) or a
//!   `checkerboard` (the mean of its two colours). The toolkit's scenes are
//!   one-sided or two-sided as a whole: two-sided when every opaque BSDF is
//!   wrapped in `twosided`, one-sided (as Mitsuba draws a bare BSDF) when
//!   none is, and with a warning when they differ.
//! - **Emitters.** `area` inside a shape (or `<ref>`ed by one) as emission
//!   of the shape's material; `point` (`position` or `to_world`), `spot`
//!   (`cutoff_angle`, `beam_width`; the falloff is the toolkit's smoothstep
//!   between them, where Mitsuba's is linear in angle) and `directional`
//!   (`direction` or `to_world`) as lights, with `intensity`/`irradiance`;
//!   `constant` (`radiance`) as the environment light.
//! - **Sensor.** The first `perspective` or `thinlens` sensor: `to_world`,
//!   `fov` with `fov_axis` (`x`, `y`, `smaller`, `larger`, `diagonal`) or
//!   `focal_length` (of a 35 mm film's diagonal), `aperture_radius` and
//!   `focus_distance` for `thinlens`, and its film's `width` and `height`
//!   (768 × 576 by default).
//! - **Ignored with no effect on the picture:** `<integrator>` (any type:
//!   each method sets its own depth), `<sampler>`, `<rfilter>`, and the
//!   film's and sensor's other parameters (listed in the warnings).
//!
//! Anything else (other shapes, BSDFs, emitters such as `envmap` and
//! `sky`, textures, media, `shapegroup`/`instance`) is an error that
//! names the element, its file and line.

mod bsdf;
mod shape;
mod transform;
mod xml;

pub use bsdf::{CONDUCTORS, IOR_NAMES, conductor_f0, kappa_from_alpha};

use crate::error::Result;
use crate::sandbox::Sandbox;
use glam::{Mat4, Vec3};
use std::collections::HashMap;
use std::path::Path;
use vpl_core::camera::FovAxis;
use vpl_core::material::Material;
use vpl_core::mesh::Mesh;
use vpl_core::scene_file::{CameraSpec, LightSpec};
use vpl_core::spectral::SpectrumKind;
use xml::{Child, Document, Loc, Object, Prop, Value};

/// A Mitsuba scene as the toolkit reads it.
#[derive(Clone, Debug, Default)]
pub struct MitsubaData {
    /// Triangles in world space; their materials index `materials`.
    pub mesh: Mesh,
    /// One material per (BSDF, area emitter) pair the shapes use.
    pub materials: Vec<Material>,
    /// Point, spot and directional emitters.
    pub lights: Vec<LightSpec>,
    /// The first perspective sensor, if any.
    pub camera: Option<CameraSpec>,
    /// Whether opaque surfaces reflect on both sides (see the module docs).
    pub two_sided: bool,
    /// What loading skipped or noticed.
    pub warnings: Vec<String>,
}

/// Loads a Mitsuba 3 XML scene; `params` are `$name` values that take
/// precedence over the file's `<default>`s (as `mitsuba -D name=value`).
/// The files it includes and names must lie in its folder (see
/// [`load_mitsuba_in`]).
pub fn load_mitsuba(path: &Path, params: &[(String, String)]) -> Result<MitsubaData> {
    load_mitsuba_in(path, params, &Sandbox::for_scene(path, &Default::default())?)
}

/// [`load_mitsuba`] reading includes, meshes and bitmaps only where
/// `sandbox` allows, and decoding bitmaps within its memory limit.
pub fn load_mitsuba_in(path: &Path, params: &[(String, String)], sandbox: &Sandbox) -> Result<MitsubaData> {
    let doc = xml::read_document(path, params, sandbox)?;
    let mut ids: HashMap<&str, &Object> = HashMap::new();
    for o in &doc.objects {
        if let Some(id) = &o.id {
            if ids.insert(id.as_str(), o).is_some() {
                return Err(doc.err(o.at, format!("the id '{id}' is used twice")));
            }
        }
    }
    let mut ctx = Ctx {
        doc: &doc,
        ids,
        data: MitsubaData::default(),
        materials: HashMap::new(),
        sides: Vec::new(),
        emitters_used: Vec::new(),
        mesh_bytes: 0,
    };
    let mut sensor_seen = false;
    for o in &doc.objects {
        match o.tag.as_str() {
            "shape" => ctx.shape(o)?,
            "emitter" => ctx.emitter(o)?,
            "sensor" if sensor_seen => ctx.warn(o.at, format!("{}: only the first sensor is used", o.what())),
            "sensor" => {
                sensor_seen = true;
                ctx.data.camera = Some(ctx.sensor(o)?);
            }
            // Standalone BSDFs and textures are read where they are referenced.
            "bsdf" | "texture" => {}
            "integrator" | "sampler" | "rfilter" | "film" => {}
            _ => return Err(doc.err(o.at, format!("{} is not supported", o.what()))),
        }
    }
    for o in &doc.objects {
        if o.tag == "emitter" && o.ty == "area" && !ctx.emitters_used.contains(&(o as *const Object)) {
            ctx.warn(o.at, format!("{} is attached to no shape: it emits nothing", o.what()));
        }
    }
    let opaque_sides = &ctx.sides;
    ctx.data.two_sided = !opaque_sides.is_empty() && opaque_sides.iter().all(|s| *s);
    if opaque_sides.iter().any(|s| *s) && !ctx.data.two_sided {
        ctx.data
            .warnings
            .push(format!("{}: some BSDFs are twosided and some are not; the scene is drawn one-sided (back faces black)", path.display()));
    }
    Ok(ctx.data)
}

/// Whether a colour parameter may be a texture.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum TexParam {
    Allowed,
    No,
}

/// The reading state: the document, its ids and what has been built.
pub(crate) struct Ctx<'a> {
    doc: &'a Document,
    ids: HashMap<&'a str, &'a Object>,
    data: MitsubaData,
    /// Material index by (BSDF object, emitted radiance bits).
    materials: HashMap<(usize, [u32; 3]), u32>,
    /// Two-sidedness of each opaque BSDF in use.
    sides: Vec<bool>,
    /// Area emitters that shapes referenced.
    emitters_used: Vec<*const Object>,
    /// Bytes of mesh files read so far, all shapes together: a scene may
    /// name one file from many shapes, and each is read and expanded.
    mesh_bytes: u64,
}

impl<'a> Ctx<'a> {
    fn warn(&mut self, at: Loc, msg: String) {
        self.data.warnings.push(format!("{}:{}: {msg}", self.doc.files[at.file].display(), at.line));
    }

    /// One warning listing the parameters of `o` nobody read (but `quiet`).
    fn unused(&mut self, o: &Object, quiet: &[&str]) {
        let names: Vec<String> = o.unused().filter(|p| !quiet.contains(&p.name.as_str())).map(|p| p.name.clone()).collect();
        if !names.is_empty() {
            self.warn(o.at, format!("{}: ignored {}", o.what(), names.join(", ")));
        }
    }

    /// The nested objects of `o` with tag `tag`, and those its unnamed
    /// `<ref>`s name.
    fn nested<'b>(&self, o: &'b Object, tag: &str) -> Result<Vec<&'b Object>>
    where
        'a: 'b,
    {
        let mut out = Vec::new();
        for c in &o.children {
            match c {
                Child::Object(x) if x.tag == tag && x.name.is_none() => out.push(x),
                Child::Ref { id, name: None, at } => {
                    let x =
                        self.ids.get(id.as_str()).ok_or_else(|| self.doc.err(*at, format!("<ref id=\"{id}\">: no object has this id")))?;
                    if x.tag == tag {
                        out.push(*x);
                    }
                }
                _ => {}
            }
        }
        Ok(out)
    }

    /// The value of a numeric parameter (float or integer).
    fn float_value(&self, o: &Object, p: &Prop) -> Result<f32> {
        match p.value {
            Value::Float(f) => Ok(f),
            Value::Integer(i) => Ok(i as f32),
            ref v => Err(self.doc.err(p.at, format!("{}: {} must be a float, not a {}", o.what(), p.name, v.kind()))),
        }
    }

    fn float(&self, o: &Object, key: &str, default: f32) -> Result<f32> {
        o.prop(key).map_or(Ok(default), |p| self.float_value(o, p))
    }

    fn integer(&self, o: &Object, key: &str, default: i64) -> Result<i64> {
        match o.prop(key) {
            None => Ok(default),
            Some(Prop { value: Value::Integer(i), .. }) => Ok(*i),
            Some(p) => Err(self.doc.err(p.at, format!("{}: {key} must be an integer, not a {}", o.what(), p.value.kind()))),
        }
    }

    fn boolean(&self, o: &Object, key: &str, default: bool) -> Result<bool> {
        match o.prop(key) {
            None => Ok(default),
            Some(Prop { value: Value::Boolean(b), .. }) => Ok(*b),
            Some(p) => Err(self.doc.err(p.at, format!("{}: {key} must be a boolean, not a {}", o.what(), p.value.kind()))),
        }
    }

    fn string(&self, o: &Object, key: &str) -> Result<Option<String>> {
        match o.prop(key) {
            None => Ok(None),
            Some(Prop { value: Value::String(s), .. }) => Ok(Some(s.clone())),
            Some(p) => Err(self.doc.err(p.at, format!("{}: {key} must be a string, not a {}", o.what(), p.value.kind()))),
        }
    }

    fn transform(&self, o: &Object, key: &str) -> Result<Mat4> {
        match o.prop(key) {
            None => Ok(Mat4::IDENTITY),
            Some(Prop { value: Value::Transform(m), .. }) => Ok(*m),
            Some(p) => Err(self.doc.err(p.at, format!("{}: {key} must be a transform, not a {}", o.what(), p.value.kind()))),
        }
    }

    fn point(&self, o: &Object, key: &str) -> Result<Option<Vec3>> {
        match o.prop(key) {
            None => Ok(None),
            Some(Prop { value: Value::Point(v) | Value::Vector(v), .. }) => Ok(Some(*v)),
            Some(p) => Err(self.doc.err(p.at, format!("{}: {key} must be a point or vector, not a {}", o.what(), p.value.kind()))),
        }
    }

    /// The linear RGB of a colour property.
    fn colour_of(&self, o: &Object, p: &Prop, kind: SpectrumKind) -> Result<Vec3> {
        let c = xml::colour(&p.value, kind).ok_or_else(|| {
            self.doc.err(p.at, format!("{}: {} must be a colour (rgb, spectrum or float), not a {}", o.what(), p.name, p.value.kind()))
        })?;
        if !c.is_finite() || c.min_element() < 0.0 {
            return Err(self.doc.err(p.at, format!("{}: {} = {c} must be finite and not negative", o.what(), p.name)));
        }
        Ok(c)
    }

    /// A colour parameter: a property, or (where `tex` allows) a nested or
    /// referenced texture bound to `key`; `default` without either.
    fn colour(&mut self, o: &Object, key: &str, default: Vec3, kind: SpectrumKind, tex: TexParam) -> Result<Vec3> {
        if let Some(p) = o.prop(key) {
            return self.colour_of(o, p, kind);
        }
        let mut texture = None;
        for c in &o.children {
            match c {
                Child::Object(x) if x.name.as_deref() == Some(key) => texture = Some(x),
                Child::Ref { id, name: Some(n), at } if n == key => {
                    texture = Some(
                        *self.ids.get(id.as_str()).ok_or_else(|| self.doc.err(*at, format!("<ref id=\"{id}\">: no object has this id")))?,
                    )
                }
                _ => {}
            }
        }
        let Some(t) = texture else { return Ok(default) };
        if tex == TexParam::No || t.tag != "texture" {
            return Err(self.doc.err(t.at, format!("{}: {key} cannot be {}", o.what(), t.what())));
        }
        self.texture_average(t, kind)
    }

    /// The average colour of a texture.
    fn texture_average(&mut self, t: &Object, kind: SpectrumKind) -> Result<Vec3> {
        let c = match t.ty.as_str() {
            "checkerboard" => {
                let a = self.colour(t, "color0", Vec3::splat(0.4), kind, TexParam::No)?;
                let b = self.colour(t, "color1", Vec3::splat(0.2), kind, TexParam::No)?;
                0.5 * (a + b)
            }
            "bitmap" => {
                let Some(name) = self.string(t, "filename")? else {
                    return Err(self.doc.err(t.at, format!("{} needs a filename", t.what())));
                };
                let raw = self.boolean(t, "raw", false)?;
                let path = self.doc.resolve(&name, t.at)?;
                bitmap_average(&path, raw, self.doc.sandbox.memory_limit())
                    .map_err(|r| self.doc.err(t.at, format!("{} '{name}': {r}", t.what())))?
            }
            other => return Err(self.doc.err(t.at, format!("<texture type=\"{other}\"> is not supported (bitmap and checkerboard are)"))),
        };
        self.unused(t, &["filter_type", "wrap_mode", "to_uv", "format"]);
        Ok(c)
    }

    /// Index of the material for BSDF `b` (the default grey without one)
    /// emitting `emission`.
    fn material(&mut self, b: Option<&Object>, emission: Vec3) -> Result<u32> {
        let key = (b.map_or(0, |b| b as *const Object as usize), emission.to_array().map(f32::to_bits));
        if let Some(i) = self.materials.get(&key) {
            return Ok(*i);
        }
        let (mut m, two_sided) = match b {
            Some(b) => {
                let x = self.bsdf(b, 0)?;
                (x.material, x.two_sided)
            }
            None => (Material::diffuse("default", Vec3::splat(0.5)), false),
        };
        let transmissive = m.layered.as_ref().is_some_and(|l| l.transmission > 0.0);
        if !transmissive {
            self.sides.push(two_sided);
        }
        if emission != Vec3::ZERO {
            m.emission = emission;
            m.name = format!("{}+emitter", m.name);
        }
        let i = self.data.materials.len() as u32;
        self.data.materials.push(m);
        self.materials.insert(key, i);
        Ok(i)
    }

    /// A top-level emitter.
    fn emitter(&mut self, e: &Object) -> Result<()> {
        let m = self.transform(e, "to_world")?;
        let spec = match e.ty.as_str() {
            // Attached to shapes by reference.
            "area" => return Ok(()),
            "point" => {
                let position = self.point(e, "position")?.unwrap_or_else(|| m.transform_point3(Vec3::ZERO));
                let intensity = self.colour(e, "intensity", Vec3::ONE, SpectrumKind::Emission, TexParam::No)?;
                LightSpec::Point { position: position.into(), intensity: intensity.into() }
            }
            "spot" => {
                let cutoff = self.float(e, "cutoff_angle", 20.0)?;
                let beam = self.float(e, "beam_width", cutoff * 0.75)?;
                if !(cutoff > 0.0 && cutoff <= 90.0 && beam >= 0.0 && beam <= cutoff) {
                    return Err(self
                        .doc
                        .err(e.at, format!("{}: need 0 ≤ beam_width ≤ cutoff_angle ≤ 90, got {beam} and {cutoff}", e.what())));
                }
                let intensity = self.colour(e, "intensity", Vec3::ONE, SpectrumKind::Emission, TexParam::No)?;
                LightSpec::Spot {
                    position: m.transform_point3(Vec3::ZERO).into(),
                    direction: m.transform_vector3(Vec3::Z).normalize_or_zero().into(),
                    intensity: intensity.into(),
                    angle: cutoff,
                    falloff_start: Some(beam),
                }
            }
            "directional" => {
                let d = match self.point(e, "direction")? {
                    Some(d) => d,
                    None => m.transform_vector3(Vec3::Z),
                };
                let d = d.try_normalize().ok_or_else(|| self.doc.err(e.at, format!("{}: the direction is zero", e.what())))?;
                let irradiance = self.colour(e, "irradiance", Vec3::ONE, SpectrumKind::Emission, TexParam::No)?;
                LightSpec::Directional { direction: d.into(), irradiance: irradiance.into() }
            }
            "constant" => {
                let radiance = self.colour(e, "radiance", Vec3::ONE, SpectrumKind::Emission, TexParam::No)?;
                LightSpec::Environment { radiance: radiance.into(), horizon: None, ground: None }
            }
            other => {
                return Err(self.doc.err(
                    e.at,
                    format!(
                        "<emitter type=\"{other}\"> is not supported (area, point, spot, directional and constant are; envmap and sky lights are not)"
                    ),
                ));
            }
        };
        self.unused(e, &[]);
        self.data.lights.push(spec);
        Ok(())
    }

    /// The radiance of the area emitters attached to shape `s`.
    fn area_emission(&mut self, s: &Object) -> Result<Vec3> {
        let mut total = Vec3::ZERO;
        for e in self.nested(s, "emitter")? {
            if e.ty != "area" {
                return Err(self.doc.err(e.at, format!("{} inside a shape: only area emitters can be attached to shapes", e.what())));
            }
            let Some(p) = e.prop("radiance") else {
                return Err(self.doc.err(e.at, format!("{} needs a radiance", e.what())));
            };
            total += self.colour_of(e, p, SpectrumKind::Emission)?;
            self.unused(e, &[]);
            self.emitters_used.push(e as *const Object);
        }
        Ok(total)
    }

    /// The camera of a sensor.
    fn sensor(&mut self, s: &Object) -> Result<CameraSpec> {
        if s.ty != "perspective" && s.ty != "thinlens" {
            return Err(self.doc.err(s.at, format!("<sensor type=\"{}\"> is not supported (perspective and thinlens are)", s.ty)));
        }
        let films = self.nested(s, "film")?;
        let (w, h) = match films.first() {
            Some(f) => {
                let w = self.integer(f, "width", 768)?;
                let h = self.integer(f, "height", 576)?;
                self.unused(f, &["pixel_format", "component_format", "file_format", "rfilter", "sample_border", "compensate"]);
                (w, h)
            }
            None => (768, 576),
        };
        let max = vpl_core::camera::MAX_RESOLUTION as i64;
        if !(1..=max).contains(&w) || !(1..=max).contains(&h) {
            return Err(self.doc.err(s.at, format!("{}: film {w} × {h} is outside 1 … {max}", s.what())));
        }
        let (w, h) = (w as u32, h as u32);
        let m = self.transform(s, "to_world")?;
        if m.determinant() < 0.0 {
            self.warn(s.at, format!("{}: to_world mirrors the image; it is rendered unmirrored", s.what()));
        }
        let origin = m.transform_point3(Vec3::ZERO);
        let forward = m.transform_vector3(Vec3::Z).try_normalize();
        let up = m.transform_vector3(Vec3::Y).try_normalize();
        let (Some(forward), Some(up)) = (forward, up) else {
            return Err(self.doc.err(s.at, format!("{}: to_world is singular", s.what())));
        };
        let (fov, fov_axis) = match (s.prop("fov"), s.prop("focal_length")) {
            (Some(p), _) => {
                let fov = self.float_value(s, p)?;
                let axis = self.string(s, "fov_axis")?.unwrap_or_else(|| "x".into());
                fov_for_axis(fov, &axis, w, h).ok_or_else(|| {
                    self.doc.err(s.at, format!("{}: fov_axis '{axis}' is not x, y, smaller, larger or diagonal", s.what()))
                })?
            }
            (None, Some(p)) => {
                let Value::String(f) = &p.value else {
                    return Err(self.doc.err(p.at, format!("{}: focal_length must be a string like \"50mm\"", s.what())));
                };
                let mm = xml::parse_f32(f.trim().trim_end_matches("mm"))
                    .map_err(|r| self.doc.err(p.at, format!("{}: focal_length {r}", s.what())))?;
                if mm <= 0.0 {
                    return Err(self.doc.err(p.at, format!("{}: focal_length must be positive", s.what())));
                }
                let diag = 2.0 * ((36.0f32.hypot(24.0) / (2.0 * mm)).atan()).to_degrees();
                fov_for_axis(diag, "diagonal", w, h).expect("diagonal is a known axis")
            }
            (None, None) => {
                // Mitsuba's default: a 50 mm lens.
                let diag = 2.0 * ((36.0f32.hypot(24.0) / 100.0).atan()).to_degrees();
                fov_for_axis(diag, "diagonal", w, h).expect("diagonal is a known axis")
            }
        };
        if !(fov > 0.0 && fov < 180.0) {
            return Err(self.doc.err(s.at, format!("{}: fov {fov} is outside (0, 180)", s.what())));
        }
        let (lens_radius, focus_distance) =
            if s.ty == "thinlens" { (self.float(s, "aperture_radius", 0.0)?, self.float(s, "focus_distance", 1.0)?) } else { (0.0, 1.0) };
        self.unused(s, &["near_clip", "far_clip", "focus_distance", "shutter_open", "shutter_close", "fov_axis"]);
        Ok(CameraSpec {
            origin: origin.into(),
            target: (origin + forward).into(),
            up: up.into(),
            fov,
            fov_axis,
            resolution: [w, h],
            lens_radius,
            focus_distance,
        })
    }
}

/// A field of view about Mitsuba's `axis` as one about an axis the
/// toolkit's camera knows: `larger` is the longer side, `diagonal` becomes
/// the horizontal angle with the same tangent ratio.
fn fov_for_axis(fov: f32, axis: &str, w: u32, h: u32) -> Option<(f32, FovAxis)> {
    Some(match axis {
        "x" => (fov, FovAxis::X),
        "y" => (fov, FovAxis::Y),
        "smaller" => (fov, FovAxis::Smaller),
        "larger" => (fov, if w >= h { FovAxis::X } else { FovAxis::Y }),
        "diagonal" => {
            let (w, h) = (w as f32, h as f32);
            let t = (0.5 * fov.to_radians()).tan() * w / w.hypot(h);
            (2.0 * t.atan().to_degrees(), FovAxis::X)
        }
        _ => return None,
    })
}

/// The mean linear colour of an image file (8- and 16-bit images are sRGB
/// unless `raw`; float images linear), decoded within `memory_limit`.
fn bitmap_average(path: &Path, raw: bool, memory_limit: Option<u64>) -> std::result::Result<Vec3, String> {
    let bytes = crate::input::read_bytes(path, crate::input::MAX_IMAGE_BYTES).map_err(|e| e.to_string())?;
    let img = crate::bitmap::decode(&bytes, None, memory_limit)?;
    drop(bytes);
    let texels = crate::bitmap::texels(&img);
    Ok(crate::bitmap::mean_colour(texels, !raw, Default::default()).unwrap_or(Vec3::ZERO))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diagonal_fov_becomes_horizontal() {
        let (fx, axis) = fov_for_axis(90.0, "diagonal", 4, 3).unwrap();
        assert_eq!(axis, FovAxis::X);
        // tan(fx/2) = tan(45°) · 4/5.
        assert!(((0.5 * fx.to_radians()).tan() - 0.8).abs() < 1e-5);
        assert_eq!(fov_for_axis(30.0, "larger", 3, 4), Some((30.0, FovAxis::Y)));
        assert!(fov_for_axis(30.0, "z", 3, 4).is_none());
    }
}

//! Reading a Mitsuba 3 XML file into a tree of objects and their
//! properties: `<include>`s spliced in, `<default>`s and `$name`
//! substitution applied, every value parsed where it stands so that an
//! error names its file and line.

use crate::error::{Result, SceneIoError};
use crate::input::{MAX_TEXT_BYTES, read_text};
use crate::sandbox::Sandbox;
use glam::{Mat4, Vec3};
use std::cell::Cell;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use vpl_core::spectral::{SpectrumKind, spectrum_to_rgb};

/// How deep `<include>`s and objects may nest.
const MAX_DEPTH: usize = 64;

/// How many `<include>`s one scene may expand, all files together: a file
/// may include another more than once, so without a bound 40 files that
/// each include the next twice expand 2⁴⁰ times.
pub const MAX_INCLUDES: usize = 4096;

/// How much XML text one scene may read, all includes together (256 MiB).
pub const MAX_SCENE_TEXT: u64 = 256 << 20;

/// The most attributes one element may carry. The XML parser compares each
/// attribute with the element's earlier ones, so an element with 200,000
/// of them takes minutes; Mitsuba's elements have at most a handful.
pub const MAX_ATTRIBUTES: usize = 64;

/// Where something stands: a file (index into [`Document::files`]) and a
/// 1-based line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Loc {
    pub file: usize,
    pub line: u32,
}

/// A parsed scene: its top-level objects in document order, and the files
/// read (the scene's first).
#[derive(Debug)]
pub(crate) struct Document {
    pub files: Vec<PathBuf>,
    pub objects: Vec<Object>,
    /// Where the scene's files may be read from.
    pub sandbox: Sandbox,
}

impl Document {
    /// The error for something at `at`.
    pub fn err(&self, at: Loc, reason: impl Into<String>) -> SceneIoError {
        mitsuba_err(&self.files[at.file], at.line, reason.into())
    }

    /// The folder of the scene file (where Mitsuba resolves relative paths).
    pub fn scene_dir(&self) -> PathBuf {
        parent_dir(&self.files[0])
    }

    /// A file named by an object at `at`: relative to the scene's folder,
    /// or else to the folder of the file that names it; inside the sandbox.
    pub fn resolve(&self, name: &str, at: Loc) -> Result<PathBuf> {
        let dirs = [self.scene_dir(), parent_dir(&self.files[at.file])];
        find_file(&self.sandbox, &dirs, name).map_err(|e| self.err(at, e))
    }
}

/// `name` relative to the first of `dirs` where it exists, through the
/// sandbox; a line naming the reference when it leaves the sandbox or
/// exists nowhere.
fn find_file(sandbox: &Sandbox, dirs: &[PathBuf], name: &str) -> std::result::Result<PathBuf, String> {
    for dir in dirs {
        match sandbox.resolve(dir, name) {
            Ok(p) => return Ok(p),
            Err(SceneIoError::Read { source, .. }) if source.kind() == std::io::ErrorKind::NotFound => continue,
            Err(e @ SceneIoError::OutsideScene { .. }) => return Err(e.to_string()),
            Err(SceneIoError::Read { source, .. }) => return Err(format!("'{name}': {source}")),
            Err(e) => return Err(format!("'{name}': {e}")),
        }
    }
    Err(format!("'{name}': no such file"))
}

pub(crate) fn mitsuba_err(path: &Path, line: u32, reason: String) -> SceneIoError {
    SceneIoError::Mitsuba { path: path.into(), line: line as usize, reason }
}

fn parent_dir(p: &Path) -> PathBuf {
    p.parent().map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."))
}

/// An object element (`<shape>`, `<bsdf>`, `<emitter>`, `<sensor>`,
/// `<film>`, `<texture>`, …) with its properties and nested objects.
#[derive(Debug)]
pub(crate) struct Object {
    /// The element's tag: "shape", "bsdf", …
    pub tag: String,
    /// Its `type` attribute.
    pub ty: String,
    pub id: Option<String>,
    /// The `name` attribute of a nested object bound to a parameter
    /// (a texture given as `reflectance`).
    pub name: Option<String>,
    pub props: Vec<Prop>,
    pub children: Vec<Child>,
    pub at: Loc,
}

/// A nested object or a `<ref>` to one.
#[derive(Debug)]
pub(crate) enum Child {
    Object(Object),
    Ref { id: String, name: Option<String>, at: Loc },
}

/// A named property; `used` records that the reader took it.
#[derive(Debug)]
pub(crate) struct Prop {
    pub name: String,
    pub value: Value,
    pub at: Loc,
    pub used: Cell<bool>,
}

/// A property value, parsed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum Value {
    Float(f32),
    Integer(i64),
    Boolean(bool),
    String(String),
    /// An `<rgb>`.
    Rgb(Vec3),
    /// A `<spectrum>`: one value (flat) or (wavelength, value) pairs.
    Spectrum(Vec<(f32, f32)>),
    Point(Vec3),
    Vector(Vec3),
    Transform(Mat4),
}

impl Value {
    /// What the value is, for messages.
    pub fn kind(&self) -> &'static str {
        match self {
            Value::Float(_) => "float",
            Value::Integer(_) => "integer",
            Value::Boolean(_) => "boolean",
            Value::String(_) => "string",
            Value::Rgb(_) => "rgb",
            Value::Spectrum(_) => "spectrum",
            Value::Point(_) => "point",
            Value::Vector(_) => "vector",
            Value::Transform(_) => "transform",
        }
    }
}

impl Object {
    /// `<tag type="ty">`, for messages.
    pub fn what(&self) -> String {
        match &self.id {
            Some(id) => format!("<{} type=\"{}\" id=\"{}\">", self.tag, self.ty, id),
            None => format!("<{} type=\"{}\">", self.tag, self.ty),
        }
    }

    /// The property `name`, marked as used.
    pub fn prop(&self, name: &str) -> Option<&Prop> {
        let p = self.props.iter().find(|p| p.name == name)?;
        p.used.set(true);
        Some(p)
    }

    /// Properties nobody read.
    pub fn unused(&self) -> impl Iterator<Item = &Prop> {
        self.props.iter().filter(|p| !p.used.get())
    }
}

/// Reads `path` with the parameters `params` (which take precedence over
/// the file's `<default>`s).
pub(crate) fn read_document(path: &Path, params: &[(String, String)], sandbox: &Sandbox) -> Result<Document> {
    let mut r = DocReader {
        files: Vec::new(),
        params: params.iter().cloned().collect(),
        open: Vec::new(),
        sandbox: sandbox.clone(),
        includes: 0,
        text: 0,
    };
    let mut objects = Vec::new();
    r.scene_file(path, &mut objects, 0)?;
    Ok(Document { files: r.files, objects, sandbox: r.sandbox })
}

struct DocReader {
    files: Vec<PathBuf>,
    params: HashMap<String, String>,
    /// Files being read (an include cycle is an error).
    open: Vec<PathBuf>,
    sandbox: Sandbox,
    /// `<include>`s expanded so far.
    includes: usize,
    /// Bytes of XML read so far.
    text: u64,
}

/// Object tags the reader knows; others are errors.
const OBJECT_TAGS: &[&str] =
    &["shape", "bsdf", "emitter", "sensor", "film", "sampler", "rfilter", "integrator", "texture", "medium", "phase", "volume"];

impl DocReader {
    fn scene_file(&mut self, path: &Path, out: &mut Vec<Object>, depth: usize) -> Result<()> {
        let canonical = path.canonicalize().unwrap_or_else(|_| path.to_path_buf());
        if self.open.contains(&canonical) {
            return Err(mitsuba_err(path, 0, "includes itself (an <include> cycle)".into()));
        }
        let text = read_text(path, MAX_TEXT_BYTES)?;
        self.text += text.len() as u64;
        if self.text > MAX_SCENE_TEXT {
            return Err(mitsuba_err(path, 0, format!("the scene and its includes hold more than {MAX_SCENE_TEXT} bytes of XML")));
        }
        check_attribute_counts(&text).map_err(|(line, n)| {
            mitsuba_err(path, line, format!("an element has {n} attributes or more; at most {MAX_ATTRIBUTES} are read"))
        })?;
        let file = self.files.len();
        self.files.push(path.to_path_buf());
        let doc = roxmltree::Document::parse(&text).map_err(|e| mitsuba_err(path, e.pos().row, format!("not well-formed XML: {e}")))?;
        let root = doc.root_element();
        let loc = |n: roxmltree::Node| Loc { file, line: doc.text_pos_at(n.range().start).row };
        if root.tag_name().name() != "scene" {
            return Err(mitsuba_err(path, loc(root).line, format!("the root element is <{}>, not <scene>", root.tag_name().name())));
        }
        if let Some(v) = root.attribute("version") {
            if !v.starts_with('3') && !v.starts_with('2') {
                return Err(mitsuba_err(
                    path,
                    loc(root).line,
                    format!("scene version {v}: only Mitsuba 2 and 3 files (version 2.x, 3.x) are read"),
                ));
            }
        }
        self.open.push(canonical);
        let r = self.scene_children(root, path, file, &loc, out, depth);
        self.open.pop();
        r
    }

    fn scene_children(
        &mut self,
        root: roxmltree::Node,
        path: &Path,
        file: usize,
        loc: &dyn Fn(roxmltree::Node) -> Loc,
        out: &mut Vec<Object>,
        depth: usize,
    ) -> Result<()> {
        for n in root.children().filter(|n| n.is_element()) {
            let at = loc(n);
            let err = |reason: String| mitsuba_err(path, at.line, reason);
            match n.tag_name().name() {
                "default" => {
                    let name = n.attribute("name").ok_or_else(|| err("<default> needs a name".into()))?;
                    let value = n.attribute("value").ok_or_else(|| err(format!("<default name=\"{name}\"> needs a value")))?;
                    // A parameter given by the caller wins over the file's default.
                    self.params.entry(name.to_string()).or_insert_with(|| value.to_string());
                }
                "include" => {
                    if depth >= MAX_DEPTH {
                        return Err(err(format!("<include>s nest deeper than {MAX_DEPTH}")));
                    }
                    self.includes += 1;
                    if self.includes > MAX_INCLUDES {
                        return Err(err(format!("the scene expands more than {MAX_INCLUDES} <include>s")));
                    }
                    let name = self.attr(n, "filename", path, at)?.ok_or_else(|| err("<include> needs a filename".into()))?;
                    let dirs = [parent_dir(path), parent_dir(&self.files[0])];
                    let target = find_file(&self.sandbox, &dirs, &name).map_err(|r| err(format!("<include>: {r}")))?;
                    self.scene_file(&target, out, depth + 1)?;
                }
                tag if OBJECT_TAGS.contains(&tag) => out.push(self.object(n, path, file, loc, 0)?),
                "path" => {} // extra search paths: files resolve from the scene's folder anyway
                tag => return Err(err(format!("<{tag}> is not supported at the top level of a scene"))),
            }
        }
        Ok(())
    }

    /// Attribute `name` of `n` with `$params` substituted.
    fn attr(&self, n: roxmltree::Node, name: &str, path: &Path, at: Loc) -> Result<Option<String>> {
        let Some(v) = n.attribute(name) else { return Ok(None) };
        self.substitute(v).map(Some).map_err(|p| {
            mitsuba_err(
                path,
                at.line,
                format!("<{} {name}=\"{v}\">: parameter ${p} has no value (no <default> and none given)", n.tag_name().name()),
            )
        })
    }

    /// `$name` replaced by the parameter's value (the longest name that
    /// has one, as in `$res_x`); the name of a missing one as the error.
    fn substitute(&self, s: &str) -> std::result::Result<String, String> {
        if !s.contains('$') {
            return Ok(s.to_string());
        }
        let mut out = String::new();
        let mut rest = s;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..len];
            if name.is_empty() {
                return Err(String::new());
            }
            let v = self.params.get(name).ok_or_else(|| name.to_string())?;
            out.push_str(v);
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    fn object(&self, n: roxmltree::Node, path: &Path, file: usize, loc: &dyn Fn(roxmltree::Node) -> Loc, depth: usize) -> Result<Object> {
        let at = loc(n);
        let tag = n.tag_name().name().to_string();
        if depth > MAX_DEPTH {
            return Err(mitsuba_err(path, at.line, format!("objects nest deeper than {MAX_DEPTH}")));
        }
        let ty = self.attr(n, "type", path, at)?.unwrap_or_default();
        let mut obj = Object {
            tag,
            ty,
            id: self.attr(n, "id", path, at)?,
            name: self.attr(n, "name", path, at)?,
            props: Vec::new(),
            children: Vec::new(),
            at,
        };
        if obj.ty.is_empty() && obj.tag != "scene" {
            return Err(mitsuba_err(path, at.line, format!("<{}> needs a type", obj.tag)));
        }
        let _ = file;
        for c in n.children().filter(|c| c.is_element()) {
            let cat = loc(c);
            let err = |reason: String| mitsuba_err(path, cat.line, reason);
            let tag = c.tag_name().name();
            match tag {
                "ref" => {
                    let id = self.attr(c, "id", path, cat)?.ok_or_else(|| err("<ref> needs an id".into()))?;
                    obj.children.push(Child::Ref { id, name: self.attr(c, "name", path, cat)?, at: cat });
                }
                t if OBJECT_TAGS.contains(&t) => obj.children.push(Child::Object(self.object(c, path, file, loc, depth + 1)?)),
                "float" | "integer" | "boolean" | "string" | "rgb" | "spectrum" | "point" | "vector" | "transform" => {
                    let name = self.attr(c, "name", path, cat)?.ok_or_else(|| err(format!("<{tag}> needs a name")))?;
                    if tag == "spectrum" && c.attribute("value").is_none() && c.attribute("filename").is_some() {
                        return Err(err(format!("<spectrum name=\"{name}\" filename=…>: spectra from files are not supported")));
                    }
                    let value = self.value(c, tag, &name, path, cat, loc)?;
                    if obj.props.iter().any(|p| p.name == name) {
                        return Err(err(format!("{}: the parameter {name} is given twice", obj.what())));
                    }
                    obj.props.push(Prop { name, value, at: cat, used: Cell::new(false) });
                }
                "default" | "include" => return Err(err(format!("<{tag}> may only stand at the top level of a scene"))),
                t => return Err(err(format!("{}: <{t}> is not supported here", obj.what()))),
            }
        }
        Ok(obj)
    }

    fn value(
        &self,
        n: roxmltree::Node,
        tag: &str,
        name: &str,
        path: &Path,
        at: Loc,
        loc: &dyn Fn(roxmltree::Node) -> Loc,
    ) -> Result<Value> {
        let err = |reason: String| mitsuba_err(path, at.line, format!("<{tag} name=\"{name}\">: {reason}"));
        let get = |a: &str| self.attr(n, a, path, at);
        let need = |a: &str| -> Result<String> { get(a)?.ok_or_else(|| err(format!("needs a {a} attribute"))) };
        Ok(match tag {
            "float" => Value::Float(parse_f32(&need("value")?).map_err(err)?),
            "integer" => {
                let v = need("value")?;
                Value::Integer(v.trim().parse().map_err(|_| err(format!("'{v}' is not an integer")))?)
            }
            "boolean" => Value::Boolean(match need("value")?.trim() {
                "true" => true,
                "false" => false,
                v => return Err(err(format!("'{v}' is neither true nor false"))),
            }),
            "string" => Value::String(need("value")?),
            "rgb" => {
                let v = need("value")?;
                let xs = parse_list(&v).map_err(err)?;
                match xs.as_slice() {
                    [a] => Value::Rgb(Vec3::splat(*a)),
                    [r, g, b] => Value::Rgb(Vec3::new(*r, *g, *b)),
                    _ => return Err(err(format!("'{v}' is neither one value nor three"))),
                }
            }
            "spectrum" => {
                let v = need("value")?;
                Value::Spectrum(parse_spectrum(&v).map_err(err)?)
            }
            "point" | "vector" => {
                let v = vec3_attr(&get("value")?, &get("x")?, &get("y")?, &get("z")?, 0.0).map_err(err)?;
                if tag == "point" { Value::Point(v) } else { Value::Vector(v) }
            }
            "transform" => {
                let mut m = Mat4::IDENTITY;
                for op in n.children().filter(|c| c.is_element()) {
                    let oat = loc(op);
                    let mut attrs = HashMap::new();
                    for a in op.attributes() {
                        attrs.insert(a.name().to_string(), self.attr(op, a.name(), path, oat)?.unwrap_or_default());
                    }
                    let step = super::transform::op(op.tag_name().name(), &attrs).map_err(|r| {
                        mitsuba_err(path, oat.line, format!("<{}> in <transform name=\"{name}\">: {r}", op.tag_name().name()))
                    })?;
                    m = step * m;
                }
                if !m.is_finite() {
                    return Err(err("the transform is not finite".into()));
                }
                Value::Transform(m)
            }
            _ => unreachable!("value() is called for property tags only"),
        })
    }
}

/// A float, with its text quoted in the error.
pub(crate) fn parse_f32(s: &str) -> std::result::Result<f32, String> {
    let v: f32 = s.trim().parse().map_err(|_| format!("'{s}' is not a number"))?;
    if v.is_finite() { Ok(v) } else { Err(format!("'{s}' is not finite")) }
}

/// Numbers separated by commas and/or white space.
pub(crate) fn parse_list(s: &str) -> std::result::Result<Vec<f32>, String> {
    s.split(|c: char| c == ',' || c.is_whitespace()).filter(|t| !t.is_empty()).map(parse_f32).collect()
}

/// A vector from `value="x, y, z"` or from `x`, `y`, `z` attributes (each
/// `default` where absent).
pub(crate) fn vec3_attr(
    value: &Option<String>,
    x: &Option<String>,
    y: &Option<String>,
    z: &Option<String>,
    default: f32,
) -> std::result::Result<Vec3, String> {
    if let Some(v) = value {
        let xs = parse_list(v)?;
        return match xs.as_slice() {
            [a] => Ok(Vec3::splat(*a)),
            [a, b, c] => Ok(Vec3::new(*a, *b, *c)),
            _ => Err(format!("'{v}' is neither one value nor three")),
        };
    }
    let f = |a: &Option<String>| a.as_deref().map(parse_f32).transpose().map(|v| v.unwrap_or(default));
    Ok(Vec3::new(f(x)?, f(y)?, f(z)?))
}

/// A spectrum's value: one number, or `wavelength:value` pairs.
fn parse_spectrum(s: &str) -> std::result::Result<Vec<(f32, f32)>, String> {
    if !s.contains(':') {
        let v = parse_f32(s)?;
        return Ok(vec![(0.0, v)]);
    }
    let mut out = Vec::new();
    for pair in s.split(',').map(str::trim).filter(|t| !t.is_empty()) {
        let (l, v) = pair.split_once(':').ok_or_else(|| format!("'{pair}' is not wavelength:value"))?;
        out.push((parse_f32(l)?, parse_f32(v)?));
    }
    if out.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err("the wavelengths do not increase".into());
    }
    Ok(out)
}

/// The linear RGB a colour property holds (`<rgb>` as written, a
/// `<spectrum>` integrated as [`spectrum_to_rgb`] says, a float as grey).
pub(crate) fn colour(v: &Value, kind: SpectrumKind) -> Option<Vec3> {
    match v {
        Value::Rgb(c) => Some(*c),
        Value::Float(f) => Some(Vec3::splat(*f)),
        Value::Spectrum(s) if s.len() == 1 => {
            let x = s[0].1;
            match kind {
                SpectrumKind::Emission => spectrum_to_rgb(&[(0.0, x)], kind),
                _ => Some(Vec3::splat(x)),
            }
        }
        Value::Spectrum(s) => spectrum_to_rgb(s, kind),
        _ => None,
    }
}

/// Refuses XML whose elements carry more than [`MAX_ATTRIBUTES`]
/// attributes, before it is parsed: the line of the first such element and
/// the count reached. A scan of the tags' `=` signs outside quoted values
/// (comments, CDATA and processing instructions skipped), linear in the text.
fn check_attribute_counts(text: &str) -> std::result::Result<(), (u32, usize)> {
    let b = text.as_bytes();
    let (mut i, mut line) = (0usize, 1u32);
    while i < b.len() {
        match b[i] {
            b'\n' => line += 1,
            b'<' => {
                let rest = &b[i..];
                let skip_to = |end: &[u8]| rest.windows(end.len()).position(|w| w == end).map(|p| p + end.len());
                let skipped = if rest.starts_with(b"<!--") {
                    skip_to(b"-->")
                } else if rest.starts_with(b"<![CDATA[") {
                    skip_to(b"]]>")
                } else if rest.starts_with(b"<?") {
                    skip_to(b"?>")
                } else if rest.starts_with(b"<!") {
                    skip_to(b">")
                } else {
                    None
                };
                if let Some(n) = skipped {
                    line += rest[..n].iter().filter(|&&c| c == b'\n').count() as u32;
                    i += n;
                    continue;
                }
                // An element tag: count `=` outside quotes up to its `>`.
                let (start, mut count, mut quote) = (line, 0usize, None::<u8>);
                i += 1;
                while i < b.len() {
                    let c = b[i];
                    match (quote, c) {
                        (_, b'\n') => line += 1,
                        (Some(q), c) if c == q => quote = None,
                        (Some(_), _) => {}
                        (None, b'"' | b'\'') => quote = Some(c),
                        (None, b'=') => {
                            count += 1;
                            if count > MAX_ATTRIBUTES {
                                return Err((start, count));
                            }
                        }
                        (None, b'>') => break,
                        _ => {}
                    }
                    i += 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

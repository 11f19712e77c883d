//! Wavefront material libraries (MTL), parsed by the toolkit itself so that
//! every malformed line ends in an error naming the file, the line and the
//! value (never a panic), and impossible values are refused where they are
//! written.
//!
//! What is read (Wavefront's MTL specification, with the usual extensions):
//!
//! | statement | meaning | accepted |
//! | --- | --- | --- |
//! | `newmtl NAME` | starts a material | a non-empty name (the rest of the line) |
//! | `Kd r [g b]` | diffuse albedo | one number (g = b = r, as the specification says) or three, each in [0, 1] |
//! | `Ks r [g b]` | specular colour | as `Kd` |
//! | `Ke r [g b]` | emitted radiance | one or three finite numbers in [0, [`MAX_RADIANCE`]] |
//! | `Ns e` | specular exponent | finite, ≥ 0 |
//! | `Ni n` | index of refraction | finite, > 0 |
//! | `d [-halo] a` | dissolve (opacity) | in [0, 1] |
//! | `Tr t` | transparency, 1 − d | in [0, 1] |
//! | `illum n` | illumination model | an integer 0 … 10 |
//! | `map_Kd [options] file` | diffuse texture | recorded (the loader warns that it is ignored) |
//!
//! `Ka`, `Tf`, the other `map_*`, `bump`, `disp`, `decal`, `refl`, `norm` and
//! the PBR extension (`Pr`, `Pm`, `Ps`, `Pc`, `Pcr`, `aniso`, `anisor`,
//! `sharpness`) are skipped silently; other statements are skipped with one
//! warning per file. A line that is an OBJ statement (`v`, `f`, …) means the
//! file is no material library (an `mtllib` that names the OBJ itself) and is
//! an error.

use crate::error::{Result, SceneIoError};
use glam::Vec3;
use std::collections::BTreeMap;
use std::path::Path;
use vpl_core::validate::MAX_RADIANCE;

/// One `newmtl` block, as written (absent statements are `None`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlMaterial {
    /// The name `usemtl` refers to.
    pub name: String,
    /// `Kd`.
    pub kd: Option<Vec3>,
    /// `Ks`.
    pub ks: Option<Vec3>,
    /// `Ke`.
    pub ke: Option<Vec3>,
    /// `Ns`.
    pub ns: Option<f32>,
    /// `Ni`.
    pub ni: Option<f32>,
    /// `d`, or 1 − `Tr` when only `Tr` is given.
    pub dissolve: Option<f32>,
    /// `illum`.
    pub illum: Option<u8>,
    /// The file of `map_Kd`.
    pub diffuse_texture: Option<String>,
}

/// The materials of one library and what parsing noticed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MtlLibrary {
    /// In file order; a name defined twice keeps its last definition.
    pub materials: Vec<MtlMaterial>,
    /// Skipped statements, duplicate names, an empty library.
    pub warnings: Vec<String>,
}

const SKIPPED: &[&str] = &[
    "Ka",
    "Tf",
    "bump",
    "disp",
    "decal",
    "refl",
    "norm",
    "Pr",
    "Pm",
    "Ps",
    "Pc",
    "Pcr",
    "aniso",
    "anisor",
    "sharpness",
    "map_Ka",
    "map_Ks",
    "map_Ke",
    "map_Ns",
    "map_d",
    "map_Tr",
    "map_bump",
    "map_Bump",
    "map_Pr",
    "map_Pm",
    "map_Ps",
    "map_Disp",
];
const OBJ_STATEMENTS: &[&str] = &["v", "vt", "vn", "vp", "f", "l", "p", "g", "o", "s", "usemtl", "mtllib", "cstype", "deg", "curv", "surf"];

/// Parses the text of an MTL file; `path` names the file in messages.
pub fn parse_mtl(text: &str, path: &Path) -> Result<MtlLibrary> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lib = MtlLibrary::default();
    let mut by_name: BTreeMap<String, usize> = BTreeMap::new();
    let mut current: Option<MtlMaterial> = None;
    let mut tr: Option<f32> = None;
    let mut unknown: BTreeMap<String, usize> = BTreeMap::new();
    let mut orphan_lines = 0usize;
    let mut finish = |m: Option<MtlMaterial>, tr: Option<f32>, lib: &mut MtlLibrary| {
        if let Some(mut m) = m {
            if m.dissolve.is_none() {
                m.dissolve = tr.map(|t| 1.0 - t);
            }
            match by_name.get(&m.name) {
                Some(&i) => {
                    lib.warnings.push(format!("{}: material '{}' is defined twice; the last definition is used", path.display(), m.name));
                    lib.materials[i] = m;
                }
                None => {
                    by_name.insert(m.name.clone(), lib.materials.len());
                    lib.materials.push(m);
                }
            }
        }
    };
    for (index, raw) in text.lines().enumerate() {
        let line_no = index + 1;
        let line = raw.split('#').next().unwrap_or("").trim();
        let Some(keyword) = line.split_whitespace().next() else { continue };
        let rest = line[keyword.len()..].trim();
        let err = |reason: String| SceneIoError::Mtl { path: path.into(), line: line_no, reason };
        if keyword == "newmtl" {
            if rest.is_empty() {
                return Err(err("newmtl needs a name".into()));
            }
            finish(current.take(), tr.take(), &mut lib);
            current = Some(MtlMaterial { name: rest.to_string(), ..Default::default() });
            continue;
        }
        if OBJ_STATEMENTS.contains(&keyword) {
            return Err(err(format!("'{keyword}' is an OBJ statement: this file is no material library")));
        }
        let Some(m) = current.as_mut() else {
            orphan_lines += 1;
            continue;
        };
        match keyword {
            "Kd" => {
                m.kd = Some(
                    colour(keyword, rest, 1.0, "a diffuse albedo is at most 1: it cannot reflect more than it receives").map_err(err)?,
                )
            }
            "Ks" => {
                m.ks = Some(
                    colour(keyword, rest, 1.0, "a specular reflectance is at most 1: it cannot reflect more than it receives")
                        .map_err(err)?,
                )
            }
            "Ke" => {
                m.ke = Some(
                    colour(keyword, rest, MAX_RADIANCE, "larger radiances overflow the renderers' single-precision sums").map_err(err)?,
                )
            }
            "Ns" => m.ns = Some(scalar(keyword, rest, 0.0, f32::MAX).map_err(err)?),
            "Ni" => {
                let n = scalar(keyword, rest, 0.0, f32::MAX).map_err(err)?;
                if n == 0.0 {
                    return Err(err("Ni must be positive".into()));
                }
                m.ni = Some(n);
            }
            // `d -halo 0.5`: the factor is the last number.
            "d" => m.dissolve = Some(scalar(keyword, rest.trim_start_matches("-halo").trim(), 0.0, 1.0).map_err(err)?),
            "Tr" => tr = Some(scalar(keyword, rest, 0.0, 1.0).map_err(err)?),
            "illum" => {
                let n: u8 =
                    rest.parse().ok().filter(|n| *n <= 10).ok_or_else(|| err(format!("illum needs an integer 0 … 10, got '{rest}'")))?;
                m.illum = Some(n);
            }
            "map_Kd" => {
                let file = rest.split_whitespace().last().ok_or_else(|| err("map_Kd needs a file name".into()))?;
                m.diffuse_texture = Some(file.to_string());
            }
            k if SKIPPED.contains(&k) => {}
            k => *unknown.entry(k.to_string()).or_default() += 1,
        }
    }
    finish(current.take(), tr.take(), &mut lib);
    if orphan_lines > 0 {
        lib.warnings.push(format!("{}: {orphan_lines} statement(s) before the first newmtl ignored", path.display()));
    }
    if !unknown.is_empty() {
        let list: Vec<String> = unknown.iter().map(|(k, n)| format!("{k} ({n}×)")).collect();
        lib.warnings.push(format!("{}: unknown statements ignored: {}", path.display(), list.join(", ")));
    }
    if lib.materials.is_empty() {
        lib.warnings.push(format!("{}: defines no materials (no newmtl line)", path.display()));
    }
    Ok(lib)
}

/// A finite number from one token.
fn number(keyword: &str, token: &str) -> std::result::Result<f32, String> {
    let v: f32 = token.parse().map_err(|_| format!("{keyword}: '{token}' is not a number"))?;
    if v.is_finite() { Ok(v) } else { Err(format!("{keyword}: '{token}' is not finite")) }
}

/// One number in [lo, hi].
fn scalar(keyword: &str, rest: &str, lo: f32, hi: f32) -> std::result::Result<f32, String> {
    let tokens: Vec<&str> = rest.split_whitespace().collect();
    let [token] = tokens[..] else { return Err(format!("{keyword} needs one number, got '{rest}'")) };
    let v = number(keyword, token)?;
    if v < lo || v > hi {
        let range = if hi == f32::MAX { format!("at least {lo}") } else { format!("in [{lo}, {hi}]") };
        return Err(format!("{keyword} must be {range}, got {token}"));
    }
    Ok(v)
}

/// `r [g b]`: one number stands for all three channels (MTL specification).
fn colour(keyword: &str, rest: &str, max: f32, why_max: &str) -> std::result::Result<Vec3, String> {
    let tokens: Vec<&str> = rest.split_whitespace().collect();
    if matches!(tokens.first(), Some(&"spectral" | &"xyz")) {
        return Err(format!("{keyword}: '{}' colours are not supported; give r g b", tokens[0]));
    }
    let v = match tokens[..] {
        [r] => Vec3::splat(number(keyword, r)?),
        [r, g, b] => Vec3::new(number(keyword, r)?, number(keyword, g)?, number(keyword, b)?),
        _ => return Err(format!("{keyword} needs one or three numbers, got {} ('{rest}')", tokens.len())),
    };
    if v.min_element() < 0.0 {
        return Err(format!("{keyword} must not be negative, got '{rest}'"));
    }
    if v.max_element() > max {
        let max = if max >= 1e7 { format!("{max:e}") } else { format!("{max}") };
        return Err(format!("{keyword} '{rest}' is above {max}: {why_max}"));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<MtlLibrary> {
        parse_mtl(text, Path::new("m.mtl"))
    }

    #[test]
    fn reads_the_statements_it_names() {
        let lib =
            parse("# c\nnewmtl a b\nKd 0.8\nKe 1 2 3\nNs 10\nNi 1.5\nd -halo 0.25\nillum 7\nmap_Kd -s 1 1 1 tex.png\nKa 1 1\n").unwrap();
        let m = &lib.materials[0];
        assert_eq!(m.name, "a b");
        assert_eq!(m.kd, Some(Vec3::splat(0.8)));
        assert_eq!(m.ke, Some(Vec3::new(1.0, 2.0, 3.0)));
        assert_eq!((m.ns, m.ni, m.dissolve, m.illum), (Some(10.0), Some(1.5), Some(0.25), Some(7)));
        assert_eq!(m.diffuse_texture.as_deref(), Some("tex.png"));
        assert!(lib.warnings.is_empty(), "{:?}", lib.warnings);
        // Tr is 1 − d; d wins when both are given.
        assert_eq!(parse("newmtl x\nTr 0.25\n").unwrap().materials[0].dissolve, Some(0.75));
        assert_eq!(parse("newmtl x\nTr 0.25\nd 0.5\n").unwrap().materials[0].dissolve, Some(0.5));
        // A byte-order mark, CRLF line ends.
        assert_eq!(parse("\u{feff}newmtl x\r\nKd 1 0 0\r\n").unwrap().materials[0].kd, Some(Vec3::X));
    }

    #[test]
    fn malformed_lines_are_errors_naming_line_and_value() {
        for (text, line, needle) in [
            ("newmtl a\nKe 10 10\n", 2, "one or three numbers, got 2"),
            ("newmtl a\nKd 0.5 x 0.5\n", 2, "'x' is not a number"),
            ("newmtl a\n\nKe inf 1 1\n", 3, "'inf' is not finite"),
            ("newmtl a\nKe nan\n", 2, "'nan' is not finite"),
            ("newmtl a\nKd 1.5 0.5 0.5\n", 2, "at most 1"),
            ("newmtl a\nKe 1e30\n", 2, "above"),
            ("newmtl a\nKd -0.1\n", 2, "negative"),
            ("newmtl a\nd 2\n", 2, "in [0, 1]"),
            ("newmtl a\nillum 99\n", 2, "illum"),
            ("newmtl a\nNi 0\n", 2, "positive"),
            ("newmtl\n", 1, "name"),
            ("v 0 0 0\nf 1 2 3\n", 1, "no material library"),
        ] {
            let e = parse(text).unwrap_err();
            assert!(matches!(&e, SceneIoError::Mtl { line: l, .. } if *l == line), "{text:?}: {e}");
            assert!(e.to_string().contains(needle) && e.to_string().starts_with(&format!("m.mtl:{line}:")), "{text:?}: {e}");
        }
    }

    #[test]
    fn oddities_are_warnings() {
        let lib = parse("Kd 1 1 1\nnewmtl a\nfoo 1\nfoo 2\nnewmtl a\nKd 0.5\n").unwrap();
        assert_eq!(lib.materials.len(), 1);
        assert_eq!(lib.materials[0].kd, Some(Vec3::splat(0.5)));
        let w = lib.warnings.join("\n");
        assert!(w.contains("defined twice") && w.contains("foo (2×)") && w.contains("before the first newmtl"), "{w}");
        assert!(parse("").unwrap().warnings[0].contains("no materials"));
    }
}

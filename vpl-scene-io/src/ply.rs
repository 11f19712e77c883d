//! PLY meshes (ASCII and binary, either byte order), read with the
//! `ply-rs-bw` crate: vertex positions `x y z`, optional normals
//! `nx ny nz`, and faces as `vertex_indices` (or `vertex_index`) lists,
//! polygons split into fans. Other elements and properties are ignored.

use crate::error::{Result, SceneIoError};
use crate::input::{MAX_MESH_BYTES, read_bytes};
use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::path::Path;
use vpl_core::CoreError;
use vpl_core::mesh::{Mesh, TriangleDesc};

/// Reads a PLY mesh; every triangle gets material 0.
pub fn load_ply(path: &Path) -> Result<Mesh> {
    let bytes = read_bytes(path, MAX_MESH_BYTES)?;
    parse_ply(&bytes, path)
}

/// Checks the header's element counts against the bytes after it, before
/// the parser allocates for them: each element takes at least its
/// properties' sizes in a binary file (a list at least its count) and two
/// bytes a property in an ASCII one (a digit and a separator). A 200-byte
/// file that declares 4·10⁹ vertices is refused here; without the check
/// the parser reserves room for all of them.
fn check_counts(bytes: &[u8]) -> std::result::Result<(), String> {
    let end = bytes.windows(10).position(|w| w == b"end_header").ok_or("no end_header line")?;
    let after = &bytes[end + 10..];
    let after = after.strip_prefix(b"\r").unwrap_or(after);
    let after = after.strip_prefix(b"\n").unwrap_or(after);
    let header = String::from_utf8_lossy(&bytes[..end]);
    let mut ascii = true;
    // (name, count, least bytes each)
    let mut elements: Vec<(String, u64, u64)> = Vec::new();
    for line in header.lines() {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.as_slice() {
            ["format", f, ..] => ascii = *f == "ascii",
            ["element", name, count, ..] => {
                let n = count.parse::<u64>().map_err(|_| format!("element {name}: its count is no whole number"))?;
                elements.push((name.to_string(), n, 0));
            }
            ["property", "list", count_type, ..] | ["property", count_type, ..] => {
                let size = scalar_size(count_type).ok_or_else(|| format!("property type {count_type} is unknown"))?;
                if let Some(e) = elements.last_mut() {
                    e.2 += if ascii { 2 } else { size };
                }
            }
            _ => {}
        }
    }
    // An ASCII file's last value may lack its separator.
    let body = after.len() as u64 + u64::from(ascii);
    let mut total = 0u64;
    for (name, n, least) in elements {
        if n > 0 && least == 0 {
            return Err(format!("element {name} declares {n} elements but no properties"));
        }
        total = total.saturating_add(n.saturating_mul(least));
        if total > body {
            return Err(format!(
                "element {name} declares {n} elements, more than the {body} bytes after the header can hold ({least} bytes each at least)"
            ));
        }
    }
    Ok(())
}

/// Bytes of a PLY scalar type.
fn scalar_size(t: &str) -> Option<u64> {
    Some(match t {
        "char" | "uchar" | "int8" | "uint8" => 1,
        "short" | "ushort" | "int16" | "uint16" => 2,
        "int" | "uint" | "float" | "int32" | "uint32" | "float32" => 4,
        "double" | "float64" => 8,
        _ => return None,
    })
}

/// Parses PLY bytes (`path` names them in errors).
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<Mesh> {
    let err = |reason: String| SceneIoError::Ply { path: path.into(), reason };
    check_counts(bytes).map_err(err)?;
    let ply = Parser::<DefaultElement>::new().read_ply(&mut std::io::Cursor::new(bytes)).map_err(|e| err(one_line(&e.to_string())))?;
    let vertices = ply.payload.get("vertex").ok_or_else(|| err("no vertex element".into()))?;
    let scalar = |e: &DefaultElement, k: &str| -> Option<f32> {
        Some(match e.get(k)? {
            Property::Float(v) => *v,
            Property::Double(v) => *v as f32,
            Property::Char(v) => *v as f32,
            Property::UChar(v) => *v as f32,
            Property::Short(v) => *v as f32,
            Property::UShort(v) => *v as f32,
            Property::Int(v) => *v as f32,
            Property::UInt(v) => *v as f32,
            _ => return None,
        })
    };
    let mut mesh = Mesh::default();
    let has_normals = vertices.first().is_some_and(|v| v.contains_key("nx"));
    for (i, v) in vertices.iter().enumerate() {
        let p = Vec3::new(
            scalar(v, "x").ok_or_else(|| err(format!("vertex {i} has no number x")))?,
            scalar(v, "y").ok_or_else(|| err(format!("vertex {i} has no number y")))?,
            scalar(v, "z").ok_or_else(|| err(format!("vertex {i} has no number z")))?,
        );
        if !p.is_finite() {
            return Err(CoreError::NonFinite { what: path.display().to_string(), index: i, value: format!("{p}") }.into());
        }
        mesh.positions.push(p);
        if has_normals {
            let n = Vec3::new(scalar(v, "nx").unwrap_or(0.0), scalar(v, "ny").unwrap_or(0.0), scalar(v, "nz").unwrap_or(0.0));
            mesh.normals.push(if n.is_finite() { n.normalize_or_zero() } else { Vec3::ZERO });
        }
    }
    let n_vertices = mesh.positions.len() as u64;
    let Some(faces) = ply.payload.get("face") else { return Ok(mesh) };
    for (f, face) in faces.iter().enumerate() {
        let list = face
            .get("vertex_indices")
            .or_else(|| face.get("vertex_index"))
            .ok_or_else(|| err(format!("face {f} has no vertex_indices")))?;
        let idx: Vec<i64> = match list {
            Property::ListChar(v) => v.iter().map(|x| *x as i64).collect(),
            Property::ListUChar(v) => v.iter().map(|x| *x as i64).collect(),
            Property::ListShort(v) => v.iter().map(|x| *x as i64).collect(),
            Property::ListUShort(v) => v.iter().map(|x| *x as i64).collect(),
            Property::ListInt(v) => v.iter().map(|x| *x as i64).collect(),
            Property::ListUInt(v) => v.iter().map(|x| *x as i64).collect(),
            _ => return Err(err(format!("face {f}: vertex_indices is not a list of integers"))),
        };
        if let Some(bad) = idx.iter().find(|i| **i < 0 || **i as u64 >= n_vertices) {
            return Err(err(format!("face {f} names vertex {bad}, but there are {n_vertices}")));
        }
        for k in 1..idx.len().saturating_sub(1) {
            let v = [idx[0] as u32, idx[k] as u32, idx[k + 1] as u32];
            mesh.triangles.push(TriangleDesc { v, n: has_normals.then_some(v), material: 0 });
        }
    }
    Ok(mesh)
}

/// The parser's message on one line: its first line (the others quote the
/// input and the grammar), at most 200 characters.
fn one_line(msg: &str) -> String {
    let first = msg.lines().map(str::trim).find(|l| !l.is_empty()).unwrap_or("unreadable");
    first.chars().take(200).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    const QUAD: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n\
element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    #[test]
    fn ascii_quad_becomes_two_triangles() {
        let m = parse_ply(QUAD.as_bytes(), Path::new("q.ply")).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(m.triangles[1].v, [0, 2, 3]);
    }

    #[test]
    fn binary_little_endian_with_normals() {
        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
property float nx\nproperty float ny\nproperty float nz\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n"
            .to_vec();
        for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
            for x in v.iter().chain([0.0f32, 0.0, 2.0].iter()) {
                b.extend_from_slice(&x.to_le_bytes());
            }
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        let m = parse_ply(&b, Path::new("t.ply")).unwrap();
        assert_eq!(m.triangles.len(), 1);
        assert_eq!(m.normals[2], Vec3::Z);
        assert_eq!(m.triangles[0].n, Some([0, 1, 2]));
    }

    /// Counts the bytes after the header cannot hold are refused before
    /// the parser reserves room for them (4·10⁹ vertices in 200 bytes
    /// asked the allocator for hundreds of GB).
    #[test]
    fn counts_beyond_the_bytes_present_are_refused_before_parsing() {
        let huge = QUAD.replace("element vertex 4", "element vertex 4000000000");
        let e = parse_ply(huge.as_bytes(), Path::new("q.ply")).unwrap_err().to_string();
        assert!(e.contains("element vertex declares 4000000000 elements"), "{e}");
        let binary =
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
        let mut b = binary.as_bytes().to_vec();
        b.extend_from_slice(&[0u8; 35]);
        let e = parse_ply(&b, Path::new("b.ply")).unwrap_err().to_string();
        assert!(e.contains("more than the 35 bytes"), "{e}");
        let e = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 4000000000\nend_header\n", Path::new("e.ply")).unwrap_err().to_string();
        assert!(e.contains("no properties"), "{e}");
    }

    #[test]
    fn bad_index_and_garbage_are_errors() {
        let bad = QUAD.replace("4 0 1 2 3", "4 0 1 2 9");
        assert!(parse_ply(bad.as_bytes(), Path::new("q.ply")).unwrap_err().to_string().contains("names vertex 9"));
        let e = parse_ply(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\nzz\n", Path::new("g.ply")).unwrap_err();
        assert!(!e.to_string().contains('\n'), "{e}");
        assert!(parse_ply(b"not a ply", Path::new("g.ply")).is_err());
        assert!(parse_ply(&QUAD.as_bytes()[..60], Path::new("t.ply")).is_err());
    }
}

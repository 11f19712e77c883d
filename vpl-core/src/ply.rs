//! PLY meshes (ASCII and binary, either byte order), read with the
//! `ply-rs-bw` crate: vertex positions `x y z`, optional normals
//! `nx ny nz`, and faces as `vertex_indices` (or `vertex_index`) lists,
//! polygons split into fans. Other elements and properties are ignored.

use crate::error::{CoreError, Result};
use crate::input::{MAX_MESH_BYTES, read_bytes};
use crate::mesh::{Mesh, TriangleDesc};
use glam::Vec3;
use ply_rs_bw::parser::Parser;
use ply_rs_bw::ply::{DefaultElement, Property};
use std::path::Path;

/// Reads a PLY mesh; every triangle gets material 0.
pub fn load_ply(path: &Path) -> Result<Mesh> {
    let bytes = read_bytes(path, MAX_MESH_BYTES)?;
    parse_ply(&bytes, path)
}

/// Parses PLY bytes (`path` names them in errors).
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<Mesh> {
    let err = |reason: String| CoreError::Ply { path: path.into(), reason };
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
            return Err(CoreError::NonFinite { what: path.display().to_string(), index: i, value: format!("{p}") });
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

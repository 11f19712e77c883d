//! Mitsuba shapes as triangles: meshes from OBJ and PLY files, and the
//! analytic shapes tessellated in their local frames, then placed by
//! `to_world`.

use super::Ctx;
use super::xml::Object;
use crate::error::Result;
use glam::{Mat3, Mat4, Vec3};
use vpl_core::mesh::{Mesh, TriangleDesc};

/// Rings and segments of a tessellated sphere (its area is 0.2 % under
/// the true sphere's).
const SPHERE_RINGS: u32 = 48;
const SPHERE_SEGMENTS: u32 = 96;
/// Segments of a tessellated disk.
const DISK_SEGMENTS: u32 = 96;

impl Ctx<'_> {
    /// Adds shape `s` to the scene.
    pub(crate) fn shape(&mut self, s: &Object) -> Result<()> {
        let mut to_world = self.transform(s, "to_world")?;
        let local = match s.ty.as_str() {
            "obj" | "ply" => {
                let Some(name) = self.string(s, "filename")? else {
                    return Err(self.doc.err(s.at, format!("{} needs a filename", s.what())));
                };
                let path = self.doc.resolve(&name, s.at)?;
                // The mesh files of all shapes together stay within the
                // memory limit (or the size limit of one mesh file).
                let size = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
                let limit = self.doc.sandbox.memory_limit().unwrap_or(crate::input::MAX_MESH_BYTES).min(crate::input::MAX_MESH_BYTES);
                self.mesh_bytes = self.mesh_bytes.saturating_add(size);
                if self.mesh_bytes > limit {
                    return Err(self.doc.err(
                        s.at,
                        format!(
                            "{}: the scene's mesh files come to more than {limit} bytes (a file named by many shapes counts each time)",
                            s.what()
                        ),
                    ));
                }
                let mut mesh = if s.ty == "obj" {
                    let bytes = crate::input::read_bytes(&path, crate::input::MAX_MESH_BYTES)?;
                    // The OBJ's own materials are not Mitsuba's: the shape's BSDF decides.
                    crate::obj::parse_obj(&bytes, &path, |_| Ok(None))?.mesh
                } else {
                    crate::ply::load_ply(&path)?
                };
                if self.boolean(s, "face_normals", false)? {
                    mesh.normals.clear();
                    for t in mesh.triangles.iter_mut() {
                        t.n = None;
                    }
                }
                mesh
            }
            "rectangle" => {
                let mut m = Mesh::default();
                m.push_quad(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0), 0);
                m
            }
            "cube" => {
                let mut m = Mesh::default();
                m.push_box(Vec3::splat(-1.0), Vec3::ONE, 0, false);
                m
            }
            "disk" => {
                let mut m = Mesh::default();
                let ring = |k: u32| {
                    let phi = 2.0 * std::f32::consts::PI * k as f32 / DISK_SEGMENTS as f32;
                    Vec3::new(phi.cos(), phi.sin(), 0.0)
                };
                for k in 0..DISK_SEGMENTS {
                    m.push_triangle(Vec3::ZERO, ring(k), ring(k + 1), 0);
                }
                m
            }
            "sphere" => {
                let center = self.point(s, "center")?.unwrap_or(Vec3::ZERO);
                let radius = self.float(s, "radius", 1.0)?;
                if !(radius > 0.0 && radius.is_finite()) {
                    return Err(self.doc.err(s.at, format!("{}: radius {radius} must be positive", s.what())));
                }
                to_world = to_world * Mat4::from_translation(center) * Mat4::from_scale(Vec3::splat(radius));
                let mut m = Mesh::default();
                m.push_sphere(Vec3::ZERO, 1.0, SPHERE_RINGS, SPHERE_SEGMENTS, 0);
                m
            }
            other => {
                return Err(self
                    .doc
                    .err(s.at, format!("<shape type=\"{other}\"> is not supported (obj, ply, rectangle, cube, disk and sphere are)")));
            }
        };
        let flip = self.boolean(s, "flip_normals", false)?;
        let bsdfs = self.nested(s, "bsdf")?;
        if bsdfs.len() > 1 {
            return Err(self.doc.err(s.at, format!("{} has {} BSDFs; a shape has one", s.what(), bsdfs.len())));
        }
        let emission = self.area_emission(s)?;
        let material = self.material(bsdfs.first().copied(), emission)?;
        for c in &s.children {
            if let super::xml::Child::Object(o) = c {
                if o.tag != "bsdf" && o.tag != "emitter" {
                    return Err(self.doc.err(o.at, format!("{} inside {} is not supported", o.what(), s.what())));
                }
            }
        }
        self.unused(s, &[]);
        append(&mut self.data.mesh, &local, to_world, material, flip);
        Ok(())
    }
}

/// Appends `local` placed by `m` with material `material`; `flip` reverses
/// the outside (`flip_normals`). A mirroring `m` reverses the winding too,
/// so the transformed shape keeps its outside.
fn append(out: &mut Mesh, local: &Mesh, m: Mat4, material: u32, flip: bool) {
    let base = out.positions.len() as u32;
    let nbase = out.normals.len() as u32;
    let normal_matrix = Mat3::from_mat4(m).inverse().transpose();
    let reverse = flip ^ (m.determinant() < 0.0);
    let sign = if flip { -1.0 } else { 1.0 };
    out.positions.extend(local.positions.iter().map(|p| m.transform_point3(*p)));
    out.normals.extend(local.normals.iter().map(|n| (normal_matrix * *n).normalize_or_zero() * sign));
    out.triangles.extend(local.triangles.iter().map(|t| {
        let mut v = t.v.map(|i| i + base);
        let mut n = t.n.map(|n| n.map(|i| i + nbase));
        if reverse {
            v.swap(1, 2);
            if let Some(n) = n.as_mut() {
                n.swap(1, 2);
            }
        }
        TriangleDesc { v, n, material }
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn normal(m: &Mesh, t: usize) -> Vec3 {
        let v = m.triangles[t].v.map(|i| m.positions[i as usize]);
        (v[1] - v[0]).cross(v[2] - v[0]).normalize()
    }

    #[test]
    fn a_mirror_keeps_the_outside() {
        let mut quad = Mesh::default();
        quad.push_quad(Vec3::new(-1.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(-1.0, 1.0, 0.0), 0);
        let mut out = Mesh::default();
        append(&mut out, &quad, Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)), 0, false);
        assert!((normal(&out, 0) - Vec3::Z).length() < 1e-6);
        append(&mut out, &quad, Mat4::IDENTITY, 0, true);
        assert!((normal(&out, 2) + Vec3::Z).length() < 1e-6);
    }
}

//! The triangle mesh a scene is built from.

use glam::Vec3;

/// One triangle: vertex indices, optional shading-normal indices, a material.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TriangleDesc {
    /// Indices into [`Mesh::positions`], counter-clockwise seen from the front.
    pub v: [u32; 3],
    /// Indices into [`Mesh::normals`], if the triangle has shading normals.
    pub n: Option<[u32; 3]>,
    /// Index into the scene's materials.
    pub material: u32,
}

/// An indexed triangle mesh with per-triangle materials and optional shading normals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Shading normals (need not be one per position).
    pub normals: Vec<Vec3>,
    /// Triangles.
    pub triangles: Vec<TriangleDesc>,
}

impl Mesh {
    /// Appends a triangle with flat shading; returns its index.
    pub fn push_triangle(&mut self, a: Vec3, b: Vec3, c: Vec3, material: u32) -> usize {
        let i = self.positions.len() as u32;
        self.positions.extend([a, b, c]);
        self.triangles.push(TriangleDesc { v: [i, i + 1, i + 2], n: None, material });
        self.triangles.len() - 1
    }

    /// Appends the quad a-b-c-d (counter-clockwise seen from the front) as two triangles.
    pub fn push_quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3, material: u32) {
        let i = self.positions.len() as u32;
        self.positions.extend([a, b, c, d]);
        self.triangles.push(TriangleDesc { v: [i, i + 1, i + 2], n: None, material });
        self.triangles.push(TriangleDesc { v: [i, i + 2, i + 3], n: None, material });
    }

    /// Appends an axis-aligned box from `lo` to `hi` with outward-facing sides.
    /// `skip_bottom` leaves out the face at `lo.y` (a box standing on a floor).
    pub fn push_box(&mut self, lo: Vec3, hi: Vec3, material: u32, skip_bottom: bool) {
        let (x0, y0, z0, x1, y1, z1) = (lo.x, lo.y, lo.z, hi.x, hi.y, hi.z);
        let v = |x, y, z| Vec3::new(x, y, z);
        // +Y top
        self.push_quad(v(x0, y1, z0), v(x0, y1, z1), v(x1, y1, z1), v(x1, y1, z0), material);
        if !skip_bottom {
            self.push_quad(v(x0, y0, z0), v(x1, y0, z0), v(x1, y0, z1), v(x0, y0, z1), material);
        }
        // +X
        self.push_quad(v(x1, y0, z0), v(x1, y1, z0), v(x1, y1, z1), v(x1, y0, z1), material);
        // -X
        self.push_quad(v(x0, y0, z0), v(x0, y0, z1), v(x0, y1, z1), v(x0, y1, z0), material);
        // +Z
        self.push_quad(v(x0, y0, z1), v(x1, y0, z1), v(x1, y1, z1), v(x0, y1, z1), material);
        // -Z
        self.push_quad(v(x0, y0, z0), v(x0, y1, z0), v(x1, y1, z0), v(x1, y0, z0), material);
    }

    /// Appends a UV sphere with smooth shading normals (`rings` ≥ 2, `segments` ≥ 3).
    pub fn push_sphere(&mut self, center: Vec3, radius: f32, rings: u32, segments: u32, material: u32) {
        let base = self.positions.len() as u32;
        let nbase = self.normals.len() as u32;
        for r in 0..=rings {
            let theta = std::f32::consts::PI * r as f32 / rings as f32;
            for s in 0..=segments {
                let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
                let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
                self.positions.push(center + n * radius);
                self.normals.push(n);
            }
        }
        let row = segments + 1;
        for r in 0..rings {
            for s in 0..segments {
                let a = r * row + s;
                let b = a + row;
                // counter-clockwise seen from outside; the pole rows have one triangle per segment
                let tris: &[[u32; 3]] = if r == 0 {
                    &[[a + 1, b + 1, b]]
                } else if r + 1 == rings {
                    &[[a, a + 1, b]]
                } else {
                    &[[a, a + 1, b], [a + 1, b + 1, b]]
                };
                for t in tris {
                    self.triangles.push(TriangleDesc {
                        v: [base + t[0], base + t[1], base + t[2]],
                        n: Some([nbase + t[0], nbase + t[1], nbase + t[2]]),
                        material,
                    });
                }
            }
        }
    }
}

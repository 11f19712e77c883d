//! `cornell`: Mitsuba 3.9.1's `cornell_box()`, vertex for vertex as
//! `shared/scenes/cornell-box/cbox.obj` exports it (same triangle order and
//! winding), its materials, light and camera. Back faces are black, as with
//! Mitsuba's one-sided `diffuse` BSDF.

use super::{Builtin, camera};
use crate::material::Material;
use crate::mesh::{Mesh, TriangleDesc};
use crate::scene_file::{CameraKeySpec, SequenceSpec};
use glam::Vec3;

/// Mitsuba's rectangles: vertices a, b, c, d as listed, triangles (b, c, a), (b, d, c).
fn rect(mesh: &mut Mesh, v: [[f32; 3]; 4], m: u32) {
    let i = mesh.positions.len() as u32;
    mesh.positions.extend(v.map(Vec3::from));
    mesh.triangles.push(TriangleDesc { v: [i + 1, i + 2, i], n: None, material: m });
    mesh.triangles.push(TriangleDesc { v: [i + 1, i + 3, i + 2], n: None, material: m });
}

/// Mitsuba's cube faces: vertices a, b, c, d, triangles (a, b, c), (d, a, c).
fn face(mesh: &mut Mesh, v: [Vec3; 4], m: u32) {
    let i = mesh.positions.len() as u32;
    mesh.positions.extend(v);
    mesh.triangles.push(TriangleDesc { v: [i, i + 1, i + 2], n: None, material: m });
    mesh.triangles.push(TriangleDesc { v: [i + 3, i, i + 2], n: None, material: m });
}

/// A rotated box from its four bottom corners (x, z) and heights, in the face
/// order of Mitsuba's cube mesh.
fn prism(mesh: &mut Mesh, c: [[f32; 2]; 4], y0: f32, y1: f32, m: u32) {
    let b = |i: usize| Vec3::new(c[i][0], y0, c[i][1]);
    let t = |i: usize| Vec3::new(c[i][0], y1, c[i][1]);
    face(mesh, [b(0), b(1), b(2), b(3)], m);
    face(mesh, [t(0), t(3), t(2), t(1)], m);
    face(mesh, [b(0), t(0), t(1), b(1)], m);
    face(mesh, [b(1), t(1), t(2), b(2)], m);
    face(mesh, [b(2), t(2), t(3), b(3)], m);
    face(mesh, [t(0), b(0), b(3), t(3)], m);
}

/// Albedo of Mitsuba's white, red and green, and the light's radiance.
pub const WHITE: [f32; 3] = [0.885809, 0.698859, 0.666422];
const RED: [f32; 3] = [0.570068, 0.0430135, 0.0443706];
const GREEN: [f32; 3] = [0.105421, 0.37798, 0.076425];
const LE: [f32; 3] = [18.387, 13.9873, 6.75357];

pub fn build() -> Builtin {
    let materials = vec![
        Material::diffuse("white", WHITE.into()),
        Material::diffuse("red", RED.into()),
        Material::diffuse("green", GREEN.into()),
        Material::emissive("light", WHITE.into(), LE.into()),
    ];
    let (white, red, green, light) = (0, 1, 2, 3);
    let mut mesh = Mesh::default();
    rect(&mut mesh, [[-1., -1., 1.], [1., -1., 1.], [-1., -1., -1.], [1., -1., -1.]], white); // floor
    rect(&mut mesh, [[-1., 1., -1.], [1., 1., -1.], [-1., 1., 1.], [1., 1., 1.]], white); // ceiling
    rect(&mut mesh, [[-1., -1., -1.], [1., -1., -1.], [-1., 1., -1.], [1., 1., -1.]], white); // back
    rect(&mut mesh, [[-1., -1., 1.], [-1., -1., -1.], [-1., 1., 1.], [-1., 1., -1.]], red);
    rect(&mut mesh, [[1., -1., -1.], [1., -1., 1.], [1., 1., -1.], [1., 1., 1.]], green);
    prism(&mut mesh, [[0.709603, 0.18082], [0.53418, 0.754603], [-0.039603, 0.57918], [0.13582, 0.005397]], -1.0, -0.4, white);
    prism(&mut mesh, [[-0.139039, -0.658859], [0.048859, -0.089039], [-0.520961, 0.098859], [-0.708859, -0.470961]], -1.01, 0.21, white);
    rect(&mut mesh, [[-0.23, 0.99, -0.18], [0.23, 0.99, -0.18], [-0.23, 0.99, 0.2], [0.23, 0.99, 0.2]], light);

    // 24 s: the camera starts on Mitsuba's view, drifts to the right and up, and returns.
    let key = |t: f32, o: [f32; 3]| CameraKeySpec { t, origin: o, target: [0.0, 0.0, 0.0] };
    let sequence = SequenceSpec {
        fps: 30.0,
        duration: 24.0,
        camera: vec![key(0.0, [0.0, 0.0, 3.9]), key(8.0, [0.6, 0.2, 3.7]), key(16.0, [-0.6, -0.2, 3.7]), key(24.0, [0.0, 0.0, 3.9])],
        lights: Vec::new(),
    };
    Builtin {
        name: "cornell",
        mesh,
        materials,
        lights: Vec::new(),
        camera: camera([0.0, 0.0, 3.9], [0.0, 0.0, 0.0], 39.3077, [256, 256]),
        sequence,
        two_sided: false,
    }
}

//! `colonnade`: a portico 40 m long (a row of 17 square columns under an
//! architrave and roof, a closed back wall) facing a paved court closed by
//! a high wall opposite. A low sun moves from one end to the other over the
//! sequence, throwing the columns' shadows across the portico; the camera
//! walks the portico looking out past the columns. Inside, nearly all the
//! light is indirect, reflected from the sunlit court and columns.

use super::{Builtin, horizontal, wall_x, wall_z};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene_file::{CameraKeySpec, LightKeySpec, LightSpec, SequenceSpec};
use glam::Vec3;

const HX: f32 = 20.0; // the portico runs along x in [−20, 20]
const DEPTH: f32 = 4.0; // columns at z = 0, back wall at z = 4
const H: f32 = 5.0; // height under the architrave
const COURT: f32 = 14.0; // the opposite wall at z = −14

pub fn build() -> Builtin {
    let materials = vec![
        Material::diffuse("paving", Vec3::new(0.55, 0.5, 0.44)),
        Material::diffuse("marble", Vec3::new(0.8, 0.78, 0.72)),
        Material::diffuse("plaster", Vec3::new(0.7, 0.55, 0.42)),
        Material::diffuse("roof", Vec3::new(0.5, 0.24, 0.16)),
    ];
    let (paving, marble, plaster, roof) = (0, 1, 2, 3);
    let mut mesh = Mesh::default();
    horizontal(&mut mesh, (-HX - 6.0, HX + 6.0), (-COURT, DEPTH), 0.0, true, paving);
    // Back wall with two doorways into darkness, end walls of the portico.
    wall_z(&mut mesh, DEPTH, -HX, HX, H + 1.0, &[(-8.0, 1.6, 2.6), (8.0, 1.6, 2.6)], plaster);
    wall_x(&mut mesh, -HX, 0.0, DEPTH, H + 1.0, &[], plaster);
    wall_x(&mut mesh, HX, 0.0, DEPTH, H + 1.0, &[], plaster);
    // The rooms behind the doorways: closed boxes seen only through them.
    for xc in [-8.0f32, 8.0] {
        horizontal(&mut mesh, (xc - 2.0, xc + 2.0), (DEPTH, DEPTH + 3.0), H, false, plaster);
        wall_z(&mut mesh, DEPTH + 3.0, xc - 2.0, xc + 2.0, H, &[], plaster);
        wall_x(&mut mesh, xc - 2.0, DEPTH, DEPTH + 3.0, H, &[], plaster);
        wall_x(&mut mesh, xc + 2.0, DEPTH, DEPTH + 3.0, H, &[], plaster);
    }
    // Columns every 2.5 m, the architrave above them, the roof slab.
    for k in 0..17 {
        let x = -HX + k as f32 * 2.5;
        mesh.push_box(Vec3::new(x - 0.3, 0.0, -0.3), Vec3::new(x + 0.3, H, 0.3), marble, true);
    }
    mesh.push_box(Vec3::new(-HX, H, -0.4), Vec3::new(HX, H + 0.8, 0.4), marble, false);
    mesh.push_box(Vec3::new(-HX, H + 0.8, -0.6), Vec3::new(HX, H + 1.2, DEPTH), roof, false);
    // The court's far wall and its two side walls, lower.
    wall_z(&mut mesh, -COURT, -HX - 6.0, HX + 6.0, 7.0, &[], plaster);
    wall_x(&mut mesh, -HX - 6.0, -COURT, DEPTH, 3.0, &[], plaster);
    wall_x(&mut mesh, HX + 6.0, -COURT, DEPTH, 3.0, &[], plaster);
    // The sun travels +z into the portico, low, from one end to the other.
    let sun = |t: f32, d: [f32; 3]| LightKeySpec { light: 0, t, position: None, direction: Some(d) };
    let keys = [[0.75, -0.3, 0.6], [0.1, -0.7, 0.7], [-0.7, -0.35, 0.62]];
    let lights = vec![LightSpec::Directional { direction: keys[0], irradiance: [3.0, 2.8, 2.4] }];
    let ck = |t: f32, x: f32| CameraKeySpec { t, origin: [x, 1.7, 2.6], target: [x + 6.0, 1.8, -1.5] };
    let sequence = SequenceSpec {
        fps: 30.0,
        duration: 24.0,
        camera: vec![ck(0.0, -17.0), ck(12.0, -3.0), ck(24.0, 11.0)],
        lights: vec![sun(0.0, keys[0]), sun(12.0, keys[1]), sun(24.0, keys[2])],
    };
    Builtin::from_sequence("colonnade", mesh, materials, lights, sequence, 70.0)
}

//! `corner`: an L-shaped corridor; a point light sits around the corner behind
//! the camera, so what the camera sees is lit only after two or more bounces.

use super::{Builtin, horizontal, wall_x, wall_z};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene_file::{CameraKeySpec, LightSpec, SequenceSpec};
use glam::Vec3;

pub fn build() -> Builtin {
    // Leg A: x ∈ [0, 2.5], z ∈ [−14, 0]  (the camera looks along −z, away from the corner at z = 0 … 2.5)
    // Leg B: x ∈ [0, 12],  z ∈ [0, 2.5]  (the light is at x = 9)
    let materials = vec![
        Material::diffuse("floor", Vec3::new(0.5, 0.45, 0.4)),
        Material::diffuse("wall", Vec3::new(0.8, 0.8, 0.78)),
        Material::diffuse("ceiling", Vec3::splat(0.7)),
        Material::diffuse("crate", Vec3::new(0.6, 0.45, 0.3)),
    ];
    let (floor, wall, ceil, crate_m) = (0, 1, 2, 3);
    let h = 3.0;
    let mut mesh = Mesh::default();
    horizontal(&mut mesh, (0.0, 2.5), (-14.0, 0.0), 0.0, true, floor);
    horizontal(&mut mesh, (0.0, 12.0), (0.0, 2.5), 0.0, true, floor);
    horizontal(&mut mesh, (0.0, 2.5), (-14.0, 0.0), h, false, ceil);
    horizontal(&mut mesh, (0.0, 12.0), (0.0, 2.5), h, false, ceil);
    wall_x(&mut mesh, 0.0, -14.0, 2.5, h, &[], wall); // outer wall of leg A and the corner
    wall_x(&mut mesh, 2.5, -14.0, 0.0, h, &[], wall); // inner wall of leg A
    wall_z(&mut mesh, -14.0, 0.0, 2.5, h, &[], wall); // far end of leg A
    wall_z(&mut mesh, 2.5, 0.0, 12.0, h, &[], wall); // outer wall of leg B
    wall_z(&mut mesh, 0.0, 2.5, 12.0, h, &[], wall); // inner wall of leg B
    wall_x(&mut mesh, 12.0, 0.0, 2.5, h, &[], wall); // end of leg B
    mesh.push_box(Vec3::new(0.3, 0.0, -9.0), Vec3::new(1.2, 0.9, -8.0), crate_m, true);
    mesh.push_box(Vec3::new(1.4, 0.0, -12.5), Vec3::new(2.3, 1.4, -11.4), crate_m, true);
    let lights = vec![LightSpec::Point { position: [9.0, 2.0, 1.25], intensity: [240.0, 220.0, 190.0] }];
    let ck = |t: f32, z: f32| CameraKeySpec { t, origin: [1.25, 1.6, z], target: [1.1, 1.2, z - 6.0] };
    let sequence =
        SequenceSpec { fps: 30.0, duration: 20.0, camera: vec![ck(0.0, 0.5), ck(10.0, -4.0), ck(20.0, 0.5)], lights: Vec::new() };
    Builtin::from_sequence("corner", mesh, materials, lights, sequence, 65.0)
}

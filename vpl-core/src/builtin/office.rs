//! `office`: a 40 m corridor with six rooms on each side behind door openings,
//! 14 ceiling panels (eight in the corridor, six in rooms, most of them far
//! down the corridor); the camera walks the corridor and rooms come into view
//! at its far end. Most rooms are invisible from the corridor: VPLs there are wasted.

use super::{Builtin, ceiling_lamp, horizontal, wall_x, wall_z};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene_file::{CameraKeySpec, SequenceSpec};
use glam::Vec3;

const L: f32 = 40.0; // corridor length (along −z)
const W: f32 = 3.0; // corridor width (x in [−W/2, W/2])
const H: f32 = 3.0;
const ROOM: f32 = 6.0; // room depth
const PITCH: f32 = L / 6.0; // room width along the corridor

pub fn build() -> Builtin {
    let materials = vec![
        Material::diffuse("floor", Vec3::new(0.35, 0.3, 0.25)),
        Material::diffuse("wall", Vec3::new(0.8, 0.78, 0.7)),
        Material::diffuse("ceiling", Vec3::splat(0.75)),
        Material::diffuse("desk", Vec3::new(0.5, 0.35, 0.2)),
        Material::emissive("panel", Vec3::splat(0.8), Vec3::new(12.0, 12.0, 11.0)),
    ];
    let (floor, wall, ceil, desk, panel) = (0, 1, 2, 3, 4);
    let mut mesh = Mesh::default();
    let xo = 0.5 * W + ROOM;
    horizontal(&mut mesh, (-xo, xo), (-L, 0.0), 0.0, true, floor);
    horizontal(&mut mesh, (-xo, xo), (-L, 0.0), H, false, ceil);
    // Corridor walls with one door per room; room side walls; end walls.
    let doors: Vec<(f32, f32, f32)> = (0..6).map(|k| (-L + (k as f32 + 0.5) * PITCH, 1.2, 2.2)).collect();
    wall_x(&mut mesh, -0.5 * W, -L, 0.0, H, &doors, wall);
    wall_x(&mut mesh, 0.5 * W, -L, 0.0, H, &doors, wall);
    wall_x(&mut mesh, -xo, -L, 0.0, H, &[], wall);
    wall_x(&mut mesh, xo, -L, 0.0, H, &[], wall);
    for k in 0..=6 {
        let z = -L + k as f32 * PITCH;
        wall_z(&mut mesh, z, -xo, -0.5 * W, H, &[], wall);
        wall_z(&mut mesh, z, 0.5 * W, xo, H, &[], wall);
    }
    wall_z(&mut mesh, -L, -0.5 * W, 0.5 * W, H, &[], wall);
    wall_z(&mut mesh, 0.0, -0.5 * W, 0.5 * W, H, &[], wall);
    // A desk in every room.
    for k in 0..6 {
        let zc = -L + (k as f32 + 0.5) * PITCH;
        for side in [-1.0f32, 1.0] {
            let xc = side * (0.5 * W + 0.6 * ROOM);
            mesh.push_box(Vec3::new(xc - 0.8, 0.0, zc - 1.2), Vec3::new(xc + 0.8, 0.75, zc + 1.2), desk, true);
        }
    }
    // 8 corridor panels, 6 room panels (the three far rooms on each side).
    for k in 0..8 {
        ceiling_lamp(&mut mesh, 0.0, H - 0.01, -2.5 - k as f32 * 5.0, 0.6, panel);
    }
    for k in 0..3 {
        let zc = -L + (k as f32 + 0.5) * PITCH;
        for side in [-1.0f32, 1.0] {
            ceiling_lamp(&mut mesh, side * (0.5 * W + 0.5 * ROOM), H - 0.01, zc, 0.8, panel);
        }
    }
    let key = |t: f32, z: f32, look_x: f32| CameraKeySpec { t, origin: [0.3 * (z * 0.3).sin(), 1.6, z], target: [look_x, 1.5, z - 6.0] };
    let sequence = SequenceSpec {
        fps: 30.0,
        duration: 25.0,
        camera: vec![key(0.0, -1.0, 0.0), key(10.0, -14.0, 0.0), key(18.0, -26.0, 0.5), key(21.0, -31.0, -3.0), key(25.0, -35.0, 3.0)],
        lights: Vec::new(),
    };
    Builtin::from_sequence("office", mesh, materials, Vec::new(), sequence, 70.0)
}

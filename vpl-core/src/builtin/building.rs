//! `building`: a single storey of 3×3 rooms (6 m square, 3 m high) joined by
//! doorways in the middle of every inner wall, under a closed ceiling. Two
//! ceiling lamps light two rooms the camera never enters; a lamp carried
//! through the rooms moves along another path than the camera's. Most of
//! the light the camera sees has come through one or two doorways.

use super::{Builtin, ceiling_lamp, horizontal, walk, wall_x, wall_z};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene_file::{LightKeySpec, LightSpec};
use glam::Vec3;

const N: usize = 3;
const ROOM: f32 = 6.0;
const H: f32 = 3.0;
const DOOR: (f32, f32) = (1.0, 2.1); // width, height

/// The centre of room (i, j) at height `y`.
fn centre(i: usize, j: usize, y: f32) -> Vec3 {
    Vec3::new((i as f32 + 0.5) * ROOM, y, (j as f32 + 0.5) * ROOM)
}

pub fn build() -> Builtin {
    let materials = vec![
        Material::diffuse("floor", Vec3::new(0.42, 0.36, 0.3)),
        Material::diffuse("wall", Vec3::new(0.78, 0.76, 0.7)),
        Material::diffuse("ceiling", Vec3::splat(0.72)),
        Material::diffuse("cabinet", Vec3::new(0.3, 0.42, 0.5)),
        Material::emissive("lamp", Vec3::splat(0.8), Vec3::new(40.0, 37.0, 32.0)),
    ];
    let (floor, wall, ceil, cabinet, lamp) = (0, 1, 2, 3, 4);
    let mut mesh = Mesh::default();
    let size = N as f32 * ROOM;
    horizontal(&mut mesh, (0.0, size), (0.0, size), 0.0, true, floor);
    horizontal(&mut mesh, (0.0, size), (0.0, size), H, false, ceil);
    // Outer walls closed; every inner wall has a doorway into each room pair it parts.
    let doors: Vec<(f32, f32, f32)> = (0..N).map(|k| ((k as f32 + 0.5) * ROOM, DOOR.0, DOOR.1)).collect();
    for k in 0..=N {
        let at = k as f32 * ROOM;
        let d: &[(f32, f32, f32)] = if k == 0 || k == N { &[] } else { &doors };
        wall_x(&mut mesh, at, 0.0, size, H, d, wall);
        wall_z(&mut mesh, at, 0.0, size, H, d, wall);
    }
    // A tall cabinet against a wall of every room, off the doorways' line.
    for i in 0..N {
        for j in 0..N {
            let c = centre(i, j, 0.0);
            mesh.push_box(c + Vec3::new(1.2, 0.0, -2.9), c + Vec3::new(2.6, 2.0, -2.3), cabinet, true);
        }
    }
    // Lamps in the two rooms off the camera's path.
    for (i, j) in [(2, 0), (0, 2)] {
        let c = centre(i, j, 0.0);
        ceiling_lamp(&mut mesh, c.x, H - 0.01, c.z, 1.0, lamp);
    }
    // The camera: (0,0) → (1,0) → (1,1) → (2,1) → (2,2), through the doorways.
    let h = 1.6;
    let pts = [
        centre(0, 0, h),
        Vec3::new(ROOM, h, 0.5 * ROOM),
        centre(1, 0, h),
        Vec3::new(1.5 * ROOM, h, ROOM),
        centre(1, 1, h),
        Vec3::new(2.0 * ROOM, h, 1.5 * ROOM),
        centre(2, 1, h),
        Vec3::new(2.5 * ROOM, h, 2.0 * ROOM),
        centre(2, 2, h),
    ];
    let mut sequence = walk(&pts, 24.0, 1.4);
    // The carried lamp: (1,0) → (1,1) → (0,1) → (0,2) → (1,2) → (2,2), at
    // 1.8 m, under the doorways' lintels: it starts next to the camera's
    // room and ends in it.
    let y = 1.8;
    let lamp_path = [centre(1, 0, y), centre(1, 1, y), centre(0, 1, y), centre(0, 2, y), centre(1, 2, y), centre(2, 2, y)];
    sequence.lights = lamp_path
        .iter()
        .enumerate()
        .map(|(k, p)| LightKeySpec {
            light: 0,
            t: 24.0 * k as f32 / (lamp_path.len() - 1) as f32,
            position: Some(p.to_array()),
            direction: None,
        })
        .collect();
    let lights = vec![LightSpec::Point { position: lamp_path[0].to_array(), intensity: [80.0, 72.0, 60.0] }];
    Builtin::from_sequence("building", mesh, materials, lights, sequence, 70.0)
}

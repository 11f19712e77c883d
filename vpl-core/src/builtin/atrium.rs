//! `atrium`: an arcaded court (two storeys of pillars and galleries along both
//! long sides, closed ends, open to a black sky) with one point light that
//! moves down the court and back while the camera pans.

use super::{Builtin, horizontal, wall_x, wall_z};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene_file::{CameraKeySpec, LightKeySpec, LightSpec, SequenceSpec};
use glam::Vec3;

const LEN: f32 = 30.0; // along x in [−15, 15]
const COURT: f32 = 5.0; // court half-width (z in [−5, 5])
const GALLERY: f32 = 3.0; // gallery depth behind the arcade
const STOREY: f32 = 5.0;

pub fn build() -> Builtin {
    let materials = vec![
        Material::diffuse("floor", Vec3::new(0.55, 0.5, 0.42)),
        Material::diffuse("stone", Vec3::new(0.72, 0.66, 0.55)),
        Material::diffuse("drape_red", Vec3::new(0.6, 0.1, 0.08)),
        Material::diffuse("drape_blue", Vec3::new(0.1, 0.15, 0.5)),
    ];
    let (floor, stone, red, blue) = (0, 1, 2, 3);
    let mut mesh = Mesh::default();
    let hx = 0.5 * LEN;
    let zo = COURT + GALLERY;
    horizontal(&mut mesh, (-hx, hx), (-zo, zo), 0.0, true, floor);
    // Back walls of the galleries, end walls (to three storeys).
    let top = 3.0 * STOREY;
    wall_z(&mut mesh, -zo, -hx, hx, 2.0 * STOREY, &[], stone);
    wall_z(&mut mesh, zo, -hx, hx, 2.0 * STOREY, &[], stone);
    wall_x(&mut mesh, -hx, -zo, zo, top, &[], stone);
    wall_x(&mut mesh, hx, -zo, zo, top, &[(0.0, 3.0, 4.0)], stone);
    for side in [-1.0f32, 1.0] {
        let z_in = side * COURT;
        let (za, zb) = if side < 0.0 { (-zo, -COURT) } else { (COURT, zo) };
        for s in 0..2 {
            let y0 = s as f32 * STOREY;
            // gallery ceiling / upper floor slab
            mesh.push_box(Vec3::new(-hx, y0 + STOREY - 0.4, za), Vec3::new(hx, y0 + STOREY, zb), stone, false);
            // pillars every 3 m and the beam above the arches
            for k in 0..=10 {
                let x = -hx + 1.5 + k as f32 * 2.7;
                mesh.push_box(Vec3::new(x - 0.3, y0, z_in - 0.3), Vec3::new(x + 0.3, y0 + STOREY - 0.4, z_in + 0.3), stone, true);
            }
            mesh.push_box(Vec3::new(-hx, y0 + STOREY - 1.2, z_in - 0.3), Vec3::new(hx, y0 + STOREY - 0.4, z_in + 0.3), stone, true);
        }
        // drapes hanging in the upper arcade
        for k in 0..5 {
            let x = -hx + 4.2 + k as f32 * 5.4;
            let m = if k % 2 == 0 { red } else { blue };
            let z = z_in - side * 0.35;
            mesh.push_quad(
                Vec3::new(x - 1.0, STOREY + 0.5, z),
                Vec3::new(x + 1.0, STOREY + 0.5, z),
                Vec3::new(x + 1.0, 2.0 * STOREY - 1.3, z),
                Vec3::new(x - 1.0, 2.0 * STOREY - 1.3, z),
                m,
            );
        }
    }
    let lights = vec![LightSpec::Point { position: [-12.0, 2.5, 0.0], intensity: [90.0, 80.0, 65.0] }];
    let lk = |t: f32, x: f32, z: f32| LightKeySpec { light: 0, t, position: Some([x, 2.5, z]), direction: None };
    let ck = |t: f32, target_x: f32| CameraKeySpec { t, origin: [13.5, 1.7, -2.0], target: [target_x, 3.5, 0.5] };
    let sequence = SequenceSpec {
        fps: 30.0,
        duration: 24.0,
        camera: vec![ck(0.0, -10.0), ck(12.0, 0.0), ck(24.0, -10.0)],
        lights: vec![lk(0.0, -12.0, 0.0), lk(8.0, 0.0, 3.5), lk(16.0, 10.0, -3.5), lk(24.0, -12.0, 0.0)],
    };
    Builtin::from_sequence("atrium", mesh, materials, lights, sequence, 70.0)
}

//! `courtyard`: a small town of blocks around a square under a low sun; the
//! camera walks a street at eye height into the square. Most sunlit surfaces
//! (roofs, upper walls facing away) cannot be seen from the street.

use super::{Builtin, horizontal, walk};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::rng::{Purpose, stream};
use crate::scene_file::LightSpec;
use glam::Vec3;

pub fn build() -> Builtin {
    let materials = vec![
        Material::diffuse("ground", Vec3::new(0.4, 0.38, 0.35)),
        Material::diffuse("stone", Vec3::new(0.7, 0.62, 0.5)),
        Material::diffuse("plaster", Vec3::new(0.8, 0.75, 0.65)),
        Material::diffuse("roof", Vec3::new(0.55, 0.25, 0.18)),
    ];
    let (ground, stone, plaster, roof) = (0, 1, 2, 3);
    let mut mesh = Mesh::default();
    horizontal(&mut mesh, (-60.0, 60.0), (-60.0, 60.0), 0.0, true, ground);
    let mut rng = stream(11, 0, Purpose::SCENE, 2);
    // A 6×6 grid of blocks of 12 m with 6 m streets; the four centre blocks are the square.
    for i in 0..6 {
        for j in 0..6 {
            if (2..4).contains(&i) && (2..4).contains(&j) {
                continue;
            }
            let x0 = -54.0 + i as f32 * 18.0;
            let z0 = -54.0 + j as f32 * 18.0;
            // Each block: two to three buildings of random height.
            let parts = 2 + rng.below(2) as usize;
            let w = 12.0 / parts as f32;
            for p in 0..parts {
                let h = 6.0 + 14.0 * rng.next_f32();
                let m = if rng.next_f32() < 0.5 { stone } else { plaster };
                let (a, b) = (x0 + p as f32 * w, x0 + (p + 1) as f32 * w);
                mesh.push_box(Vec3::new(a + 0.2, 0.0, z0), Vec3::new(b - 0.2, h, z0 + 12.0), m, true);
                // a pitched cap on top, seen only from above
                mesh.push_box(Vec3::new(a + 0.6, h, z0 + 0.4), Vec3::new(b - 0.6, h + 1.0, z0 + 11.6), roof, true);
            }
        }
    }
    // A fountain block in the square.
    mesh.push_box(Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 0.8, 2.0), stone, true);
    mesh.push_box(Vec3::new(-0.4, 0.8, -0.4), Vec3::new(0.4, 3.0, 0.4), stone, true);
    let pts: Vec<Vec3> = [(-3.0, 50.0), (-3.0, 36.0), (-3.0, 24.0), (-3.0, 14.0), (-6.0, 6.0), (-9.0, -4.0), (-4.0, -9.0), (4.0, -8.0)]
        .iter()
        .map(|&(x, z)| Vec3::new(x, 1.7, z))
        .collect();
    let sequence = walk(&pts, 24.0, 3.0);
    let sun = LightSpec::Directional { direction: [0.45, -0.55, -0.7], irradiance: [3.2, 3.0, 2.6] };
    Builtin::from_sequence("courtyard", mesh, materials, vec![sun], sequence, 70.0)
}

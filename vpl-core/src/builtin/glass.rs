//! `glass`: a closed box lit by a ceiling panel holding a glass sphere, a
//! mirror on the back wall and a row of spheres with κ = 0, 0.1, 0.199, 0.2,
//! 0.3 … 0.9 (Dammertz et al. 2010, §4: κ < 0.2 is diffuse). Until the
//! progressive renderer exists every material renders by its diffuse albedo.

use super::{Builtin, horizontal, wall_x, wall_z};
use crate::material::{Layered, Material};
use crate::mesh::Mesh;
use crate::scene_file::{CameraKeySpec, SequenceSpec};
use glam::Vec3;

/// The κ values of the sphere row.
pub const KAPPAS: [f32; 11] = [0.0, 0.1, 0.199, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];

pub fn build() -> Builtin {
    let mut materials = vec![
        Material::diffuse("white", Vec3::splat(0.75)),
        Material::diffuse("red", Vec3::new(0.63, 0.07, 0.05)),
        Material::diffuse("green", Vec3::new(0.12, 0.45, 0.09)),
        Material::emissive("light", Vec3::splat(0.75), Vec3::new(16.0, 15.0, 13.0)),
        Material {
            name: "glass".into(),
            albedo: Vec3::splat(0.0),
            emission: Vec3::ZERO,
            layered: Some(Layered { kappa: 1.0, specular: Vec3::ONE, transmission: 1.0, ior: 1.5, abbe: 40.0 }),
        },
        Material {
            name: "mirror".into(),
            albedo: Vec3::splat(0.0),
            emission: Vec3::ZERO,
            layered: Some(Layered { kappa: 1.0, specular: Vec3::splat(0.95), transmission: 0.0, ior: 1.5, abbe: 0.0 }),
        },
    ];
    for k in KAPPAS {
        materials.push(Material {
            name: format!("kappa_{k}"),
            albedo: Vec3::new(0.7, 0.6, 0.3),
            emission: Vec3::ZERO,
            layered: Some(Layered { kappa: k, specular: Vec3::splat(0.9), transmission: 0.0, ior: 1.5, abbe: 0.0 }),
        });
    }
    let (white, red, green, light, glass, mirror) = (0, 1, 2, 3, 4, 5);
    let mut mesh = Mesh::default();
    // Box x ∈ [−3, 3], y ∈ [0, 3], z ∈ [−3, 3]; the camera looks in from z = 7 through the open front.
    horizontal(&mut mesh, (-3.0, 3.0), (-3.0, 3.0), 0.0, true, white);
    horizontal(&mut mesh, (-3.0, 3.0), (-3.0, 3.0), 3.0, false, white);
    wall_z(&mut mesh, -3.0, -3.0, 3.0, 3.0, &[], white);
    wall_x(&mut mesh, -3.0, -3.0, 3.0, 3.0, &[], red);
    wall_x(&mut mesh, 3.0, -3.0, 3.0, 3.0, &[], green);
    horizontal(&mut mesh, (-0.6, 0.6), (-0.6, 0.6), 2.99, false, light);
    // Mirror panel in front of the back wall.
    mesh.push_quad(
        Vec3::new(-2.5, 0.8, -2.98),
        Vec3::new(-2.5, 2.6, -2.98),
        Vec3::new(-0.8, 2.6, -2.98),
        Vec3::new(-0.8, 0.8, -2.98),
        mirror,
    );
    mesh.push_sphere(Vec3::new(1.2, 0.8, -0.8), 0.8, 24, 48, glass);
    for (i, _) in KAPPAS.iter().enumerate() {
        let x = -2.5 + i as f32 * 0.5;
        mesh.push_sphere(Vec3::new(x, 0.22, 1.6), 0.22, 12, 24, 6 + i as u32);
    }
    let ck = |t: f32, x: f32| CameraKeySpec { t, origin: [x, 1.5, 7.0], target: [0.0, 1.2, 0.0] };
    let sequence = SequenceSpec { fps: 30.0, duration: 20.0, camera: vec![ck(0.0, 0.0), ck(10.0, 1.5), ck(20.0, 0.0)], lights: Vec::new() };
    Builtin {
        name: "glass",
        mesh,
        materials,
        lights: Vec::new(),
        camera: super::camera([0.0, 1.5, 7.0], [0.0, 1.2, 0.0], 45.0, [320, 240]),
        sequence,
        two_sided: true,
    }
}

//! Built-in procedural scenes, each with its default animated sequence.
//!
//! | name | stands in for | exercises |
//! | --- | --- | --- |
//! | `cornell` | Mitsuba 3.9.1's Cornell box, exactly | the ruler against an independent renderer |
//! | `maze` | the SMC paper's Maze (13 lights) | heavy occlusion, many small lights, a corridor walk |
//! | `office` | Soda Hall (14 lights) | a long corridor with rooms behind doors |
//! | `courtyard` | Epic Citadel (one sun) | sunlit roofs invisible from the street |
//! | `atrium` | Crytek Sponza (one moving light) | an arcaded court, a light moving through it |
//! | `corner` | Georgiev & Slusallek's scene | a light around the corner behind the camera |
//! | `glass` | Dammertz et al.'s box scenes | glass, a mirror, glossy spheres κ = 0 … 0.9 |
//! | `building` | a storey of rooms | light through one or two doorways, a lamp carried from room to room |
//! | `colonnade` | a portico on a court | a low sun through a row of columns, a portico lit from the court |

mod atrium;
mod building;
mod colonnade;
mod cornell;
mod corner;
mod courtyard;
mod glass;
mod maze;
mod office;

use crate::camera::FovAxis;
use crate::error::{CoreError, Result};
use crate::material::Material;
use crate::mesh::Mesh;
use crate::scene_file::{CameraKeySpec, CameraSpec, LightSpec, SequenceSpec};
use glam::Vec3;

/// Names of the built-in scenes.
/// The first seven stand in for the papers' scenes; the last two are heavy
/// occlusion of the toolkit's own.
pub const NAMES: [&str; 9] = ["cornell", "maze", "office", "courtyard", "atrium", "corner", "glass", "building", "colonnade"];

/// A built-in scene before it becomes a [`crate::Scene`].
#[derive(Clone, Debug)]
pub struct Builtin {
    /// Its name.
    pub name: &'static str,
    /// Geometry.
    pub mesh: Mesh,
    /// Materials (emissive ones make area lights).
    pub materials: Vec<Material>,
    /// Point, spot and directional lights.
    pub lights: Vec<LightSpec>,
    /// The camera at time 0.
    pub camera: CameraSpec,
    /// The default animation.
    pub sequence: SequenceSpec,
    /// Whether diffuse surfaces reflect on both sides.
    pub two_sided: bool,
}

impl Builtin {
    /// A two-sided scene whose camera starts at the first key of `sequence`
    /// (320×240, field of view `fov` degrees across the smaller side).
    fn from_sequence(
        name: &'static str,
        mesh: Mesh,
        materials: Vec<Material>,
        lights: Vec<LightSpec>,
        sequence: SequenceSpec,
        fov: f32,
    ) -> Builtin {
        let c0 = &sequence.camera[0];
        let camera = camera(c0.origin, c0.target, fov, [320, 240]);
        Builtin { name, mesh, materials, lights, camera, sequence, two_sided: true }
    }
}

/// Builds the built-in scene `name`.
pub fn build(name: &str) -> Result<Builtin> {
    Ok(match name {
        "cornell" => cornell::build(),
        "maze" => maze::build(),
        "office" => office::build(),
        "courtyard" => courtyard::build(),
        "atrium" => atrium::build(),
        "corner" => corner::build(),
        "glass" => glass::build(),
        "building" => building::build(),
        "colonnade" => colonnade::build(),
        _ => return Err(CoreError::UnknownBuiltin(name.to_string())),
    })
}

/// A pinhole camera description.
fn camera(origin: [f32; 3], target: [f32; 3], fov: f32, resolution: [u32; 2]) -> CameraSpec {
    CameraSpec { origin, target, up: [0.0, 1.0, 0.0], fov, fov_axis: FovAxis::Smaller, resolution, lens_radius: 0.0, focus_distance: 1.0 }
}

/// A camera path through `points` (eye positions), looking `ahead` keys forward,
/// spread evenly over `duration` seconds at 30 fps.
fn walk(points: &[Vec3], duration: f32, look_height: f32) -> SequenceSpec {
    let n = points.len();
    let camera = (0..n)
        .map(|i| {
            let t = duration * i as f32 / (n - 1).max(1) as f32;
            let here = points[i];
            let next = if i + 1 < n { points[i + 1] } else { here + (here - points[i.saturating_sub(1)]) };
            let dir = (next - here).normalize_or_zero();
            let target = here + dir * 4.0 + Vec3::Y * (look_height - here.y);
            CameraKeySpec { t, origin: here.into(), target: target.into() }
        })
        .collect();
    SequenceSpec { fps: 30.0, duration, camera, lights: Vec::new() }
}

/// A vertical wall of height `h` from y = 0, spanning `u0..u1` along the axis
/// that `at(u, y)` maps to 3D, with door openings `(u_center, width, height)`.
fn wall(mesh: &mut Mesh, at: impl Fn(f32, f32) -> Vec3, u0: f32, u1: f32, h: f32, doors: &[(f32, f32, f32)], m: u32) {
    let mut ds: Vec<_> = doors.to_vec();
    ds.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut q = |ua: f32, ub: f32, ya: f32, yb: f32| {
        if ub > ua && yb > ya {
            mesh.push_quad(at(ua, ya), at(ub, ya), at(ub, yb), at(ua, yb), m);
        }
    };
    let mut u = u0;
    for (uc, w, dh) in ds {
        let (a, b) = (uc - 0.5 * w, uc + 0.5 * w);
        q(u, a, 0.0, h);
        q(a, b, dh, h);
        u = b;
    }
    q(u, u1, 0.0, h);
}

/// A wall in the plane `x = x` from `z0` to `z1` (see [`wall`]).
fn wall_x(mesh: &mut Mesh, x: f32, z0: f32, z1: f32, h: f32, doors: &[(f32, f32, f32)], m: u32) {
    wall(mesh, |z, y| Vec3::new(x, y, z), z0, z1, h, doors, m);
}

/// A wall in the plane `z = z` from `x0` to `x1` (see [`wall`]).
fn wall_z(mesh: &mut Mesh, z: f32, x0: f32, x1: f32, h: f32, doors: &[(f32, f32, f32)], m: u32) {
    wall(mesh, |x, y| Vec3::new(x, y, z), x0, x1, h, doors, m);
}

/// A horizontal rectangle over `x0..x1` × `z0..z1` at height `y`, facing
/// up (`up = true`) or down.
fn horizontal(mesh: &mut Mesh, (x0, x1): (f32, f32), (z0, z1): (f32, f32), y: f32, up: bool, m: u32) {
    let (a, b, c, d) = (Vec3::new(x0, y, z0), Vec3::new(x0, y, z1), Vec3::new(x1, y, z1), Vec3::new(x1, y, z0));
    if up { mesh.push_quad(a, b, c, d, m) } else { mesh.push_quad(a, d, c, b, m) }
}

/// A square emissive panel of side `s` centred at (x, y, z), facing down.
fn ceiling_lamp(mesh: &mut Mesh, x: f32, y: f32, z: f32, s: f32, m: u32) {
    horizontal(mesh, (x - 0.5 * s, x + 0.5 * s), (z - 0.5 * s, z + 0.5 * s), y, false, m);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::SceneSetup;

    #[test]
    fn every_builtin_builds_renders_setup_and_has_a_20_to_30_s_sequence() {
        for name in NAMES {
            let s = SceneSetup::builtin(name).unwrap();
            let seq = s.sequence.as_ref().unwrap();
            assert!((20.0..=30.0).contains(&seq.duration), "{name}: {}", seq.duration);
            assert!(!s.scene.lights.is_empty());
            let last = seq.frame_count() - 1;
            s.frame(last).unwrap();
        }
    }
}

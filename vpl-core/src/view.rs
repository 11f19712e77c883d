//! What a camera sees, checked before a render: a grid of camera rays tells
//! a view of nothing (the camera outside the scene, looking away), a view
//! of back faces only (the camera outside a closed room of a one-sided
//! scene) and a view of surfaces no light reaches directly (the camera
//! outside a closed, lit room) apart, each a one-line warning, instead of a
//! black image without a word.
//!
//! ```
//! use vpl_core::{view::check_view, SceneSetup};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! assert_eq!(check_view(&setup.scene, &setup.camera), None);
//! let away = setup.camera.looking(setup.camera.origin, setup.camera.origin * 2.0).unwrap();
//! assert!(check_view(&setup.scene, &away).unwrap().contains("sees no surface"));
//! ```

use crate::camera::Camera;
use crate::rng::{Purpose, stream};
use crate::scene::Scene;

/// Rays across the image, at most this many a side.
const GRID: (u32, u32) = (64, 48);
/// Light samples at each surface point the grid sees.
const LIGHT_SAMPLES: u32 = 4;

/// A one-line warning when `camera` sees nothing the renderers can show:
/// no surface at all, only the back of one-sided surfaces, or only
/// surfaces that no light sample reaches and that emit nothing (a closed
/// room seen from outside). `None` when some surface it sees is lit.
pub fn check_view(scene: &Scene, camera: &Camera) -> Option<String> {
    let (w, h) = camera.resolution;
    let (gw, gh) = (w.clamp(1, GRID.0), h.clamp(1, GRID.1));
    let (mut front, mut back, mut lit) = (0u32, 0u32, 0u32);
    for j in 0..gh {
        for i in 0..gw {
            let x = (i as f32 + 0.5) * w as f32 / gw as f32;
            let y = (j as f32 + 0.5) * h as f32 / gh as f32;
            let ray = camera.ray(x, y, (0.5, 0.5));
            let Some(hit) = scene.intersect(&ray) else { continue };
            let wo = -ray.d;
            if wo.dot(hit.point.ng) <= 0.0 && !scene.two_sided {
                back += 1;
                continue;
            }
            front += 1;
            if scene.emitted(&hit.point, wo) != glam::Vec3::ZERO {
                lit += 1;
                continue;
            }
            let sp = hit.point.facing(wo);
            let mut rng = stream(0, 0, Purpose::VIEW, (j * gw + i) as u64);
            let reached = (0..LIGHT_SAMPLES).any(|_| {
                let u_sel = rng.next_f32();
                let u = rng.next_2d();
                scene
                    .sample_light(sp.p, u_sel, u)
                    .is_some_and(|(ls, _)| ls.li.max_element() > 0.0 && ls.wi.dot(sp.ng) > 0.0 && scene.light_unoccluded(sp.p, sp.ng, &ls))
            });
            lit += reached as u32;
        }
    }
    let o = camera.origin;
    let at = format!(
        "from ({:.3}, {:.3}, {:.3}) toward ({:.3}, {:.3}, {:.3})",
        o.x, o.y, o.z, camera.target.x, camera.target.y, camera.target.z
    );
    if front + back == 0 {
        let (lo, hi) = scene.geometry.bounds;
        let what = if scene.environment.is_some() { "only the environment" } else { "a black image" };
        return Some(format!(
            "the camera sees no surface {at}: every ray misses the scene (bounds ({:.3}, {:.3}, {:.3}) to ({:.3}, {:.3}, {:.3})); the render shows {what}",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        ));
    }
    if front == 0 {
        return Some(format!("the camera sees only the back of one-sided surfaces {at} (is it outside a closed room?); they render black"));
    }
    if lit == 0 {
        return Some(format!(
            "no surface the camera sees {at} is reached by a light or emits (is it outside a closed room?); the image may be black"
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::setup::SceneSetup;
    use glam::Vec3;

    /// Behind the built-in Cornell box (one-sided, as Mitsuba's), the camera
    /// sees the back of its walls; with two-sided walls it sees their
    /// outside, which no light reaches; inside, nothing to say.
    #[test]
    fn outside_a_closed_room_is_told_apart() {
        let setup = SceneSetup::builtin("cornell").unwrap();
        assert!(!setup.scene.two_sided);
        let behind = setup.camera.looking(Vec3::new(0.3, 0.2, -6.0), Vec3::ZERO).unwrap();
        let w = check_view(&setup.scene, &behind).unwrap();
        assert!(w.contains("only the back of one-sided surfaces"), "{w}");
        let mut two = setup.scene.clone();
        two.two_sided = true;
        let w = check_view(&two, &behind).unwrap();
        assert!(w.contains("is reached by a light"), "{w}");
        assert_eq!(check_view(&two, &setup.camera), None);
    }
}

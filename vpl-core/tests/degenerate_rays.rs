//! Rays of a degenerate direction (zero, NaN, infinite) or origin end their
//! traversal: a miss, promptly, never a traversal that does not end.

use vpl_core::glam::Vec3;
use vpl_core::{Ray, SceneSetup};

#[test]
fn degenerate_rays_miss_promptly() {
    for name in ["cornell", "office", "courtyard"] {
        let scene = SceneSetup::builtin(name).unwrap().scene;
        let origins = [Vec3::ZERO, Vec3::new(0.1, 0.2, 0.3), Vec3::splat(1e20), Vec3::splat(f32::NAN), Vec3::new(f32::INFINITY, 0.0, 0.0)];
        let dirs = [Vec3::ZERO, Vec3::splat(f32::NAN), Vec3::new(f32::INFINITY, 0.0, 0.0), Vec3::new(1e-30, 0.0, 0.0), Vec3::Y];
        let t = std::time::Instant::now();
        for o in origins {
            for d in dirs {
                let r = Ray::new(o, d);
                let _ = scene.intersect(&r);
                let _ = scene.occluded(&r);
            }
        }
        assert!(t.elapsed().as_secs() < 10, "{name}: {:?}", t.elapsed());
    }
}

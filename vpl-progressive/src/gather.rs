//! VPL gathering at eye vertices (§5.1, Fig. 3c) and the visibility test of
//! stochastic culling (§5.1.1).

use crate::eye::EyeVertex;
use crate::light_paths::{Emitter, PassVpl};
use vpl_core::glam::Vec3;
use vpl_core::{GeometryClamp, Scene};

/// Radiance VPL `v` sends through eye vertex `e` toward the camera,
/// including `e`'s throughput: for a VPL at y with flux Φ that arrived from
/// w_in,
/// β_e · f_x(wo, x→y) · f_y(y→x, w_in) · Φ · |cos θ_x| |cos θ_y| / |x − y|² · V(x, y),
/// the geometry term clamped by `clamp`; for a primary VPL, the light
/// sample at the same point (no clamp, as for every connection to a light).
#[inline]
#[allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x > y)` is meant: a NaN fails the test
pub fn contribution(scene: &Scene, e: &EyeVertex, v: &PassVpl, clamp: Option<GeometryClamp>) -> Vec3 {
    let x = &e.x;
    match v.emitter {
        Emitter::Light { light, u_pos, scale } => {
            let Some(ls) = scene.sample_light_index(light, x.p, u_pos) else { return Vec3::ZERO };
            let f = e.layer.eval(x, e.wo, ls.wi, e.eta);
            if f == Vec3::ZERO {
                return Vec3::ZERO;
            }
            let li = if ls.delta { ls.li } else { ls.li / ls.pdf };
            let side = if ls.wi.dot(x.ng) >= 0.0 { x.ng } else { -x.ng };
            if !scene.light_unoccluded(x.p, side, &ls) {
                return Vec3::ZERO;
            }
            e.beta * f * li * (x.n.dot(ls.wi).abs() * scale)
        }
        Emitter::Surface { y, w_in, flux, layer, eta } => {
            let d = y.p - x.p;
            let dist2 = d.length_squared();
            if !(dist2 > 0.0) {
                return Vec3::ZERO;
            }
            let wi = d / dist2.sqrt();
            let fx = e.layer.eval(x, e.wo, wi, e.eta);
            if fx == Vec3::ZERO {
                return Vec3::ZERO;
            }
            let fy = layer.eval(&y, -wi, w_in, eta);
            if fy == Vec3::ZERO {
                return Vec3::ZERO;
            }
            let mut g = x.n.dot(wi).abs() * y.n.dot(wi).abs() / dist2;
            if let Some(c) = clamp {
                g = c.clamp(g);
            }
            let eps = scene.epsilon();
            if !scene.visible(x.offset_toward(wi, eps), y.offset_toward(-wi, eps)) {
                return Vec3::ZERO;
            }
            e.beta * fx * fy * flux * g
        }
    }
}

/// Whether VPL `v` would light eye vertex `e` at all (culling's test).
#[inline]
pub fn sees(scene: &Scene, e: &EyeVertex, v: &PassVpl) -> bool {
    contribution(scene, e, v, None).max_element() > 0.0
}

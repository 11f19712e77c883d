//! Reflective shadow maps (Dachsbacher & Stamminger 2005), rendered by ray
//! casting: for every texel of a light's map, the surface point its ray
//! meets, the normal there, and the flux it would carry as a VPL.

use rayon::prelude::*;
use std::f32::consts::FRAC_1_PI;
use vpl_core::Scene;
use vpl_core::glam::Vec3;

/// One texel: a candidate first-bounce VPL.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Texel {
    /// Where the texel's light ray meets the scene.
    pub y: Vec3,
    /// Normal there, toward the light.
    pub n: Vec3,
    /// Φ_t = β_t / R² · ρ(y) / π: the texel's share of the light's power
    /// times the reflectance, the flux of a VPL that stood for this texel alone.
    pub power: Vec3,
}

/// The reflective shadow map of one light, R × R texels.
#[derive(Clone, Debug, PartialEq)]
pub struct Rsm {
    /// Index of the light in the scene.
    pub light: usize,
    /// R.
    pub res: u32,
    /// Row-major texels; `None` where the ray leaves the scene or meets a
    /// surface that reflects nothing.
    pub texels: Vec<Option<Texel>>,
}

/// The 2D R2 sequence (Roberts 2018): well spread for any number of points.
#[inline]
fn r2(i: u64) -> (f32, f32) {
    const A1: f64 = 0.754_877_666_246_692_8;
    const A2: f64 = 0.569_840_290_998_053_3;
    let x = (0.5 + A1 * i as f64).fract();
    let y = (0.5 + A2 * i as f64).fract();
    (x as f32, y as f32)
}

impl Rsm {
    /// Renders light `light`'s map. Texel (s, t) leaves the light along the
    /// direction of cell (s, t) of [`Scene::emit_from`]'s direction square,
    /// from the position of point s + R·t of an R2 sequence over its
    /// position square: the texels together are R² stratified emission
    /// samples, and their fluxes sum to an estimate of the light's power
    /// times the albedo it meets.
    pub fn render(scene: &Scene, light: usize, res: u32) -> Rsm {
        let n = (res * res) as usize;
        let inv = 1.0 / (res * res) as f32;
        let texels = (0..n)
            .into_par_iter()
            .map(|t| {
                let (s, r) = ((t as u32 % res) as f32, (t as u32 / res) as f32);
                let u_dir = ((s + 0.5) / res as f32, (r + 0.5) / res as f32);
                let e = scene.emit_from(light, r2(t as u64), u_dir)?;
                let (sp, rho) = scene.reflecting_hit(&e.ray)?;
                Some(Texel { y: sp.p, n: sp.n, power: e.beta * rho * (inv * FRAC_1_PI) })
            })
            .collect();
        Rsm { light, res, texels }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::SceneSetup;

    /// The texels' flux summed is the first-bounce light of the light: on
    /// `cornell` within 3 % of IR's first-bounce flux (16 seeds of 4096
    /// paths, whose own spread is about 1 %).
    #[test]
    fn texel_flux_sums_to_the_first_bounce_light() {
        let scene = SceneSetup::builtin("cornell").unwrap().scene;
        let total: Vec3 =
            (0..scene.lights.len()).map(|l| Rsm::render(&scene, l, 64).texels.iter().flatten().map(|t| t.power).sum::<Vec3>()).sum();
        let mut ir = Vec3::ZERO;
        for seed in 0..16 {
            let g = vpl_ir_free_first_bounce(&scene, seed);
            ir += g / 16.0;
        }
        for c in 0..3 {
            assert!((total[c] / ir[c] - 1.0).abs() < 0.03, "channel {c}: RSM {} against {}", total[c], ir[c]);
        }
    }

    /// First-bounce flux of 4096 emission samples (IR's bounce 1, written out).
    fn vpl_ir_free_first_bounce(scene: &Scene, seed: u64) -> Vec3 {
        let n = 4096;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            let mut rng = vpl_core::stream(seed, 0, vpl_core::Purpose::TEST, i);
            let Some(e) = scene.sample_emission(rng.next_f32(), rng.next_2d(), rng.next_2d()) else { continue };
            let Some(hit) = scene.intersect(&e.ray) else { continue };
            if (-e.ray.d).dot(hit.point.ng) <= 0.0 && !scene.two_sided {
                continue;
            }
            sum += e.beta * scene.material(&hit.point).albedo * FRAC_1_PI;
        }
        sum / n as f32
    }
}

//! Light paths in primary sample space: a point u ∈ [0,1)^d is a light path
//! and the one VPL it deposits, so Metropolis-Hastings can mutate paths by
//! moving u (Kelemen et al. 2002).

use std::f32::consts::FRAC_1_PI;
use vpl_core::sampling::cosine_hemisphere;
use vpl_core::{LocalFrame, Ray, RngStream, Scene, Vpl};

/// Dimensions of a path with up to `bounces` bounces: light choice (1),
/// position (2), direction (2), the bounce that carries the VPL (1), and a
/// direction per further bounce (2 each).
pub fn dims(bounces: u32) -> usize {
    6 + 2 * bounces.saturating_sub(1) as usize
}

/// The VPL of path `u`: the light is chosen by power, the VPL sits at
/// bounce j = ⌊u₅·B⌋ + 1 (each of the B bounces with probability 1/B), and
/// its flux α·ρ(y)/π · B is a one-path estimate of all B bounces' light
/// (eq. 1 of Instant Radiosity with N = 1). `None` when the path leaves the
/// scene or is absorbed before bounce j.
pub fn path_vpl(scene: &Scene, u: &[f32], bounces: u32, id: u64) -> Option<Vpl> {
    let e = scene.sample_emission(u[0], (u[1], u[2]), (u[3], u[4]))?;
    let j = ((u[5] * bounces as f32) as u32).min(bounces - 1) + 1;
    let mut alpha = e.beta;
    let mut ray = e.ray;
    let eps = scene.epsilon();
    for b in 1..=j {
        let (sp, rho) = scene.reflecting_hit(&ray)?;
        if b == j {
            let flux = alpha * rho * (FRAC_1_PI * bounces as f32);
            return Some(Vpl { y: sp.p, n: sp.n, flux, id, bounce: j });
        }
        let k = 6 + 2 * (b as usize - 1);
        let wi = LocalFrame::from_normal(sp.n).to_world(cosine_hemisphere(u[k], u[k + 1]));
        if wi.dot(sp.ng) <= 0.0 {
            return None;
        }
        alpha *= rho;
        ray = Ray::new(sp.p + sp.ng * eps, wi);
    }
    None
}

/// Kelemen's small step: each coordinate moves by ±s₂·e^(−ln(s₂/s₁)·ξ)
/// (s₁ = 1/1024, s₂ = 1/64), wrapping around [0, 1); symmetric.
pub fn perturb(u: &mut [f32], rng: &mut RngStream) {
    const S1: f32 = 1.0 / 1024.0;
    const S2: f32 = 1.0 / 64.0;
    for x in u.iter_mut() {
        let (a, b) = rng.next_2d();
        let d = S2 * (-(S2 / S1).ln() * a).exp();
        let v = if b < 0.5 { *x + d } else { *x - d };
        *x = v - v.floor();
        if *x >= 1.0 {
            *x = 0.0;
        }
    }
}

/// A fresh uniform point (a large step, or a bootstrap path).
pub fn uniform(u: &mut [f32], rng: &mut RngStream) {
    u.iter_mut().for_each(|x| *x = rng.next_f32());
}

#[cfg(test)]
mod tests {
    use super::*;
    use vpl_core::{Purpose, SceneSetup, stream};

    /// The mean flux of uniform paths equals the total flux of an IR set
    /// (both estimate Σ_j of the light reflected at bounce j, over π): a
    /// z-test on 20 000 paths against 16 IR sets, |z| < 4.
    #[test]
    fn uniform_paths_carry_the_light_field_of_instant_radiosity() {
        let scene = SceneSetup::builtin("cornell").unwrap().scene;
        let mut u = vec![0.0; dims(3)];
        let n = 20_000u64;
        let xs: Vec<f64> = (0..n)
            .map(|i| {
                uniform(&mut u, &mut stream(1, 0, Purpose::TEST, i));
                path_vpl(&scene, &u, 3, i).map_or(0.0, |v| vpl_core::light::channel_mean(v.flux) as f64)
            })
            .collect();
        let (m, se) = mean_se(&xs);
        let ir = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 4096, bounces: 3, ..Default::default() }).unwrap();
        let ys: Vec<f64> = (0..16)
            .map(|s| {
                vpl_core::LightPathGenerator::generate(&ir, &scene, 4096, s, 0)
                    .iter()
                    .map(|v| vpl_core::light::channel_mean(v.flux) as f64)
                    .sum()
            })
            .collect();
        let (mi, sei) = mean_se(&ys);
        let z = (m - mi) / (se * se + sei * sei).sqrt();
        assert!(z.abs() < 4.0, "paths {m:.4} ± {se:.4}, IR {mi:.4} ± {sei:.4}, z {z:.2}");
        let mut w = vec![0.5; dims(3)];
        perturb(&mut w, &mut stream(2, 0, Purpose::TEST, 0));
        assert!(w.iter().all(|x| (0.0..1.0).contains(x) && (x - 0.5).abs() <= 1.0 / 64.0 + 1e-6));
    }

    fn mean_se(x: &[f64]) -> (f64, f64) {
        let n = x.len() as f64;
        let m = x.iter().sum::<f64>() / n;
        let v = x.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (n - 1.0);
        (m, (v / n).sqrt())
    }
}

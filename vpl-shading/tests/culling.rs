//! Stochastic light culling against exhaustive gathering of the same VPL
//! set: unbiased, so the mean of many frames' images (each with new ξ)
//! must equal the exhaustive image, in the image mean and in every 8×8
//! block, while most terms far from the VPLs are skipped.
//!
//! Tolerance: a z-test of the frames' mean against the exhaustive value,
//! |z| ≤ 4 with the standard error of the mean over 48 independent frames
//! (a true estimator fails one in about 16,000; the blocks of a scene
//! together about one in 500). The seeds are fixed.

use vpl_core::image::luminance;
use vpl_core::{Image, IndirectShader, SceneSetup, VplVisibility};
use vpl_shading::{CulledShader, ExhaustiveShader, render_gbuffer};
use vpl_visibility::RayTraced;

const FRAMES: usize = 48;
const BLOCK: u32 = 8;

/// Luminance means of the image and of its 8×8 blocks.
fn means(img: &Image) -> Vec<f64> {
    let (w, h) = (img.width, img.height);
    let mut out = vec![img.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.data.len() as f64];
    for by in (0..h).step_by(BLOCK as usize) {
        for bx in (0..w).step_by(BLOCK as usize) {
            let (mut s, mut k) = (0.0, 0);
            for y in by..(by + BLOCK).min(h) {
                for x in bx..(bx + BLOCK).min(w) {
                    s += luminance(img.data[(y * w + x) as usize]) as f64;
                    k += 1;
                }
            }
            out.push(s / k as f64);
        }
    }
    out
}

/// Culling at `bound` is unbiased on `scene_name` and skips at least `skips` of the terms.
fn unbiased(scene_name: &str, bound: f32, skips: f64) {
    let setup = SceneSetup::builtin(scene_name).unwrap();
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution((48, 36)).unwrap();
    let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls: 256, ..Default::default() }).unwrap().sample(scene, 5).clone();
    let gbuf = render_gbuffer(scene, &camera);
    let mut vis = RayTraced::default();
    vis.update(scene, &set);
    let truth = means(&ExhaustiveShader { clamp: None }.shade(&gbuf, &set, &vis));
    assert!(truth[0] > 0.0, "{scene_name}: a black image tests nothing");
    let mut shader = CulledShader::new(bound, None, 3);
    let mut share = 0.0;
    let frames: Vec<Vec<f64>> = (0..FRAMES)
        .map(|_| {
            let m = means(&shader.shade(&gbuf, &set, &vis));
            share += shader.evaluated_share() / FRAMES as f64;
            m
        })
        .collect();
    eprintln!("{scene_name}, bound {bound}: {:.1} % of the terms evaluated", 100.0 * share);
    assert!(share <= 1.0 - skips, "{scene_name}: {:.1} % evaluated, the roulette must skip at least {:.0} %", 100.0 * share, 100.0 * skips);
    for (k, &t) in truth.iter().enumerate() {
        let xs: Vec<f64> = frames.iter().map(|f| f[k]).collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let se = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        let what = if k == 0 { "the image".to_string() } else { format!("block {}", k - 1) };
        if se == 0.0 {
            assert!((mean - t).abs() <= 1e-6 * t.abs().max(1e-12), "{scene_name}, {what}: {mean} every frame against {t}");
            continue;
        }
        let z = (mean - t) / se;
        if k == 0 {
            eprintln!("{scene_name}: image mean {mean:.5} ± {se:.5} against {t:.5} (z {z:+.2})");
        }
        assert!(z.abs() <= 4.0, "{scene_name}, {what}: {mean:.6} ± {se:.6} against {t:.6}, z = {z:.2}");
    }
}

#[test]
fn stochastic_light_culling_is_unbiased_and_skips_terms() {
    unbiased("cornell", 4.0, 0.2);
    unbiased("office", 4.0, 0.2);
}

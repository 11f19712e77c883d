//! Stochastic lightcuts against exhaustive gathering of the same VPL set:
//! unbiased, so the mean of many frames' images (each drawn anew) must
//! equal the exhaustive image, in the image mean and in every 8×8 block.
//!
//! Tolerance: a z-test of the frames' mean against the exhaustive value,
//! |z| ≤ 4 with the standard error of the mean over 48 independent frames
//! (a true estimator fails one such test in about 16,000; the blocks, some
//! 30 a scene, together in about 500). The seeds are fixed, so the outcome
//! is the same on every run.

use vpl_core::image::luminance;
use vpl_core::{GeometryClamp, Image, IndirectShader, SceneSetup, VplVisibility};
use vpl_shading::{ExhaustiveShader, LightcutShader, render_gbuffer};
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

fn unbiased(scene_name: &str, cut: usize, clamp: Option<GeometryClamp>) {
    unbiased_with(scene_name, cut, clamp, 256, (48, 36));
}

fn unbiased_with(scene_name: &str, cut: usize, clamp: Option<GeometryClamp>, vpls: usize, size: (u32, u32)) {
    let setup = SceneSetup::builtin(scene_name).unwrap();
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution(size).unwrap();
    let set = vpl_ir::InstantRadiosity::new(vpl_ir::IrConfig { vpls, ..Default::default() }).unwrap().sample(scene, 5).clone();
    let gbuf = render_gbuffer(scene, &camera);
    let mut vis = RayTraced::default();
    vis.update(scene, &set);
    let truth = means(&ExhaustiveShader { clamp }.shade(&gbuf, &set, &vis));
    assert!(truth[0] > 0.0, "{scene_name}: a black image tests nothing");
    let mut shader = LightcutShader::new(cut, clamp, 7);
    let frames: Vec<Vec<f64>> = (0..FRAMES).map(|_| means(&shader.shade(&gbuf, &set, &vis))).collect();
    let mut varied = false;
    for (k, &t) in truth.iter().enumerate() {
        let xs: Vec<f64> = frames.iter().map(|f| f[k]).collect();
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        let what = if k == 0 { "the image".to_string() } else { format!("block {}", k - 1) };
        if se == 0.0 {
            assert!((mean - t).abs() <= 1e-6 * t.abs().max(1e-12), "{scene_name}, {what}: {mean} every frame against {t}");
            continue;
        }
        varied = true;
        let z = (mean - t) / se;
        if k == 0 {
            eprintln!("{scene_name}, cut {cut}: image mean {mean:.5} ± {se:.5} against {t:.5} (z {z:+.2})");
        }
        assert!(z.abs() <= 4.0, "{scene_name}, cut {cut}, {what}: {mean:.6} ± {se:.6} against {t:.6}, z = {z:.2}");
    }
    assert!(varied, "{scene_name}: the cut sampled nothing at random, which a test of its sampling cannot tell");
}

#[test]
fn stochastic_lightcuts_are_unbiased_on_cornell() {
    unbiased("cornell", 8, None);
}

#[test]
fn stochastic_lightcuts_are_unbiased_on_office() {
    unbiased("office", 8, None);
    unbiased("office", 32, Some(GeometryClamp::new(50.0)));
}

/// 65,536 VPLs (IR's light paths, shadow rays): the tree over them, a cut
/// of 32 a pixel, still unbiased against gathering all of them.
#[test]
fn stochastic_lightcuts_are_unbiased_over_64k_vpls() {
    unbiased_with("office", 32, None, 65_536, (16, 12));
}

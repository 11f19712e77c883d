//! Stochastic light culling against exhaustive gathering of the same VPL
//! set: unbiased, so the mean of many frames' images (each with new ξ)
//! must equal the exhaustive image, in the image mean and in every 8×8
//! block, while most terms far from the VPLs are skipped.
//!
//! Tolerance: a z-test of the frames' mean against the exhaustive value,
//! |z| ≤ 4 with the standard error of the mean over 48 independent frames
//! (a true estimator fails one in about 16,000; the blocks of a scene
//! together about one in 500). The seeds are fixed.

mod common;

use common::{assert_unbiased, means};
use vpl_core::{IndirectShader, SceneSetup, VplVisibility};
use vpl_shading::{CulledShader, ExhaustiveShader, render_gbuffer};
use vpl_visibility::RayTraced;

const FRAMES: usize = 48;

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
    assert_unbiased(scene_name, &truth, &frames);
}

#[test]
fn stochastic_light_culling_is_unbiased_and_skips_terms() {
    unbiased("cornell", 4.0, 0.2);
    unbiased("office", 4.0, 0.2);
}

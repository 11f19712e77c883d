//! Stochastic lightcuts against exhaustive gathering of the same VPL set:
//! unbiased, so the mean of many frames' images (each drawn anew) must
//! equal the exhaustive image, in the image mean and in every 8×8 block.
//!
//! Tolerance: a z-test of the frames' mean against the exhaustive value,
//! |z| ≤ 4 with the standard error of the mean over 48 independent frames
//! (a true estimator fails one such test in about 16,000; the blocks, some
//! 30 a scene, together in about 500). The seeds are fixed, so the outcome
//! is the same on every run.

mod common;

use common::{assert_unbiased, means};
use vpl_core::{GeometryClamp, IndirectShader, SceneSetup, VplVisibility};
use vpl_shading::{ExhaustiveShader, LightcutShader, render_gbuffer};
use vpl_visibility::RayTraced;

const FRAMES: usize = 48;

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
    let varied = assert_unbiased(&format!("{scene_name}, cut {cut}"), &truth, &frames);
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

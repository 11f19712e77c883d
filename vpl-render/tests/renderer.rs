//! The renderer builder against the stages assembled by hand: the same
//! frames bit for bit; the budget set once reaches the sampler, the
//! visibility and the clamp; bad settings are typed errors naming the key.

use vpl_core::{GeometryClamp, Mode, Params, SceneSetup};
use vpl_render::{Clamp, FrameRequest, FrameSettings, FrameStages, RenderError, Renderer, ShadingSpec, VisibilitySpec, render_frame};
use vpl_sampling::{InstantRadiosity, IrConfig, Registry, SamplingError};
use vpl_shading::ExhaustiveShader;
use vpl_visibility::RayTraced;

#[test]
fn the_builder_renders_what_the_stages_render_by_hand() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((24, 24)).unwrap();
    let mut renderer = Renderer::builder(&setup.scene)
        .vpls(96)
        .max_depth(4)
        .sampler("ir")
        .visibility(VisibilitySpec::RayTraced)
        .shader(ShadingSpec::Exhaustive)
        .mode(Mode::Full)
        .direct_samples(2)
        .seed(11)
        .build()
        .unwrap();
    // The auto clamp reads the budget and the first frame's view.
    assert_eq!(renderer.clamp(), None);
    let clamp = GeometryClamp::for_view(96, &setup.scene, &camera);
    assert_eq!(renderer.budget().max_depth, 4);

    let mut ir = InstantRadiosity::new(IrConfig { vpls: 96, bounces: 2, ..IrConfig::default() }).unwrap();
    let mut vis = RayTraced::default();
    let mut shader = ExhaustiveShader { clamp: Some(clamp) };
    for index in 0..2 {
        let built = renderer.render(&setup.scene, &camera, index, 0.0).unwrap();
        assert_eq!(renderer.clamp(), Some(clamp));
        let s = FrameSettings { mode: Mode::Full, max_depth: 4, direct_samples: 2, seed: 11, index, time: 0.0, compensation: None };
        let by_hand = render_frame(
            FrameRequest::new(&setup.scene, &camera, s),
            FrameStages { sampler: &mut ir, visibility: &mut vis, shader: &mut shader },
        );
        assert_eq!(built.stored, by_hand.stored, "frame {index}");
        assert!(built.image.data == by_hand.image.data, "frame {index}: the builder's image differs from the stages'");
        assert!(built.image.mean()[0] > 0.0);
        assert_eq!(built.sampler_stats.get("stored"), Some(built.stored as f64));
    }
}

#[test]
fn settings_are_checked_and_errors_name_the_key() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let build = |sampler: &str, params: &[&str], depth: u32| {
        Renderer::builder(&setup.scene).vpls(64).max_depth(depth).sampler(sampler).params(Params::parse(params).unwrap()).build()
    };
    // A key the sampler does not read.
    match build("ir", &["m-max=4"], 5) {
        Err(RenderError::Sampling(SamplingError::Unread { keys, .. })) => assert_eq!(keys, ["m-max"]),
        other => panic!("{:?}", other.err()),
    }
    // A value out of range names the key and the range.
    let e = build("smc", &["knn-k=0"], 5).err().unwrap();
    assert!(e.to_string().contains("knn-k=0"), "{e}");
    // SMC needs indirect light: depth 2 has none.
    assert!(matches!(build("smc", &[], 2), Err(RenderError::Sampling(SamplingError::Budget(..)))));
    assert!(matches!(build("nope", &[], 5), Err(RenderError::Sampling(SamplingError::Unknown(..)))));
    assert!(Renderer::builder(&setup.scene).vpls(0).build().is_err());
    // No clamp when asked, and a sampler built by the caller runs as given.
    let ir = InstantRadiosity::new(IrConfig { vpls: 32, ..IrConfig::default() }).unwrap();
    let mut r =
        Renderer::builder(&setup.scene).vpls(32).sampler(Box::new(ir) as Box<dyn vpl_core::VplSampler>).clamp(Clamp::Off).build().unwrap();
    assert_eq!(r.clamp(), None);
    let camera = setup.camera.with_resolution((8, 8)).unwrap();
    // IR leaves a slot empty when its light path leaves the scene: at most 32 stored.
    let stored = r.render(&setup.scene, &camera, 0, 0.0).unwrap().stored;
    assert!(stored > 0 && stored <= 32, "{stored}");
    // Registered samplers are found by name.
    assert!(Renderer::builder(&setup.scene).registry(&Registry::builtin()).sampler("tcas").vpls(16).build().is_ok());
}

/// A sampler with one broken VPL (NaN flux): the renderer refuses the frame
/// and names the stage, instead of returning a NaN image.
struct BrokenSampler(vpl_core::VplSet);

impl vpl_core::VplSampler for BrokenSampler {
    fn name(&self) -> &'static str {
        "broken"
    }
    fn next_frame(&mut self, _frame: &vpl_core::Frame) -> &vpl_core::VplSet {
        self.0.begin_frame();
        let v = vpl_core::Vpl {
            y: vpl_core::glam::Vec3::new(0.0, 0.5, 0.0),
            n: vpl_core::glam::Vec3::Y,
            flux: vpl_core::glam::Vec3::new(f32::NAN, 1.0, 1.0),
            id: 1,
            bounce: 1,
        };
        self.0.set(0, Some(v));
        &self.0
    }
}

#[test]
fn a_non_finite_vpl_fails_the_frame_naming_the_stage() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((8, 8)).unwrap();
    let sampler: Box<dyn vpl_core::VplSampler> = Box::new(BrokenSampler(vpl_core::VplSet::new(4)));
    let mut r = Renderer::builder(&setup.scene)
        .vpls(4)
        .sampler(sampler)
        .visibility(VisibilitySpec::RayTraced)
        .shader(ShadingSpec::Exhaustive)
        .mode(Mode::Indirect)
        .build()
        .unwrap();
    let e = r.render(&setup.scene, &camera, 0, 0.0).unwrap_err();
    assert!(matches!(e, RenderError::NonFinite { stage: "the VPL sampler", count: 1, frame: 0 }), "{e}");
    assert!(e.to_string().contains("the VPL sampler produced 1 non-finite value"), "{e}");
}

/// The default clamp is resolved from the first frame's view and follows
/// the camera when it moves; a rule that needs no view is resolved at build
/// time.
#[test]
fn the_view_clamp_is_resolved_at_the_first_frame_and_follows_the_camera() {
    let setup = SceneSetup::builtin("office").unwrap();
    let near = setup.camera.with_resolution((16, 12)).unwrap();
    let far = near.looking(near.origin - near.forward() * 10.0, near.target).unwrap();
    let (g_near, g_far) = (GeometryClamp::for_view(64, &setup.scene, &near), GeometryClamp::for_view(64, &setup.scene, &far));
    assert!((g_far.g_max / g_near.g_max - 1.0).abs() > 0.1, "the two views must differ for the test to tell");
    let mut r =
        Renderer::builder(&setup.scene).vpls(64).shader(ShadingSpec::Exhaustive).visibility(VisibilitySpec::RayTraced).build().unwrap();
    assert!(r.clamp().is_none() && r.shader().is_none());
    r.render(&setup.scene, &near, 0, 0.0).unwrap();
    assert_eq!(r.clamp(), Some(g_near));
    r.render(&setup.scene, &far, 1, 0.0).unwrap();
    assert_eq!(r.clamp(), Some(g_far), "the clamp follows the camera");
    let r = Renderer::builder(&setup.scene).vpls(64).clamp(Clamp::SceneArea).build().unwrap();
    assert_eq!(r.clamp(), Some(GeometryClamp::for_scene_area(64, setup.scene.surface_area())));
    assert!(r.shader().is_some());
}

/// A sampler that sets a cancel flag while it samples frame `at`: the
/// cancellation arrives mid-frame, after the sampler's step.
struct CancelsDuring<'f> {
    inner: vpl_sampling::SmcSampler,
    at: u64,
    flag: &'f std::sync::atomic::AtomicBool,
}

impl vpl_core::VplSampler for CancelsDuring<'static> {
    fn name(&self) -> &'static str {
        "cancels-during"
    }
    fn next_frame(&mut self, frame: &vpl_core::Frame) -> &vpl_core::VplSet {
        if frame.index == self.at {
            self.flag.store(true, std::sync::atomic::Ordering::Relaxed);
        }
        self.inner.next_frame(frame)
    }
}

/// Cancelling: a flag set before the frame answers `Cancelled` at once; an
/// unset flag renders `render`'s frame bit for bit; a flag set during the
/// sampler's step stops the frame after the visibility update, so that the
/// next frame (flag cleared) is bit for bit that of a renderer that was
/// never cancelled: sampler and shadow maps stayed in step. SMC over a
/// moving camera, so that slots move every frame.
#[test]
fn a_cancelled_frame_stops_and_leaves_the_renderer_in_step() {
    use std::sync::atomic::{AtomicBool, Ordering};
    let setup = SceneSetup::builtin("office").unwrap();
    let frames: Vec<_> = (0..3).map(|f| setup.frame(f * 40).unwrap()).collect();
    let smc =
        || vpl_sampling::SmcSampler::new(vpl_sampling::SmcConfig { vpls: 128, warmup: 2, ..vpl_sampling::SmcConfig::default() }).unwrap();
    let build = |sampler: Box<dyn vpl_core::VplSampler>| {
        Renderer::builder(&setup.scene)
            .vpls(128)
            .sampler(vpl_render::SamplerChoice::Built(sampler))
            .visibility(VisibilitySpec::ShadowMaps(32))
            .mode(Mode::Indirect)
            .seed(5)
            .build()
            .unwrap()
    };
    let mut plain = build(Box::new(smc()));
    let plain_frames: Vec<_> = frames
        .iter()
        .enumerate()
        .map(|(i, (scene, camera))| plain.render(scene, &camera.with_resolution((40, 24)).unwrap(), i as u64, 0.0).unwrap().image)
        .collect();

    static FLAG: AtomicBool = AtomicBool::new(false);
    let mut r = build(Box::new(CancelsDuring { inner: smc(), at: 1, flag: &FLAG }));
    let cam = |i: usize| frames[i].1.with_resolution((40, 24)).unwrap();
    let set = AtomicBool::new(true);
    assert!(matches!(r.render_cancellable(&frames[0].0, &cam(0), 0, 0.0, &set), Err(RenderError::Cancelled { frame: 0 })));
    let f0 = r.render_cancellable(&frames[0].0, &cam(0), 0, 0.0, &FLAG).unwrap();
    assert!(f0.image.data == plain_frames[0].data, "an uncancelled frame differs from render's");
    match r.render_cancellable(&frames[1].0, &cam(1), 1, 0.0, &FLAG) {
        Err(RenderError::Cancelled { frame: 1 }) => {}
        other => panic!("frame 1 was not cancelled: {:?}", other.map(|o| o.stored)),
    }
    FLAG.store(false, Ordering::Relaxed);
    let f2 = r.render_cancellable(&frames[2].0, &cam(2), 2, 0.0, &FLAG).unwrap();
    assert!(f2.moved > 0, "no slot moved on frame 2");
    assert!(f2.image.data == plain_frames[2].data, "the frame after a cancelled one differs from an uncancelled renderer's");
}

/// The view rule's G_max follows the camera: a camera that moves in from
/// the box's opening to its middle sees less surface, so A_view falls and
/// G_max = I / A_view rises; the renderer takes the new clamp at the frame
/// the camera moves, and shades with it: its image equals the stages'
/// with that clamp. A camera that stands still keeps the clamp.
#[test]
fn the_auto_clamp_follows_the_view() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let far = setup.camera.with_resolution((24, 24)).unwrap();
    let near = far.looking(far.origin * 0.4, far.target).unwrap();
    let mut renderer = Renderer::builder(&setup.scene)
        .vpls(96)
        .max_depth(4)
        .sampler("ir")
        .visibility(VisibilitySpec::RayTraced)
        .shader(ShadingSpec::Exhaustive)
        .seed(5)
        .build()
        .unwrap();
    let (c_far, c_near) = (GeometryClamp::for_view(96, &setup.scene, &far), GeometryClamp::for_view(96, &setup.scene, &near));
    assert!(c_near.g_max > 1.2 * c_far.g_max, "{c_far:?} {c_near:?}");
    renderer.render(&setup.scene, &far, 0, 0.0).unwrap();
    assert_eq!(renderer.clamp(), Some(c_far));
    renderer.render(&setup.scene, &far, 1, 0.0).unwrap();
    assert_eq!(renderer.clamp(), Some(c_far));
    let built = renderer.render(&setup.scene, &near, 2, 0.0).unwrap();
    assert_eq!(renderer.clamp(), Some(c_near));
    // The same frame by hand with the near clamp: the shader used it.
    let mut ir = InstantRadiosity::new(IrConfig { vpls: 96, bounces: 2, ..IrConfig::default() }).unwrap();
    let mut vis = RayTraced::default();
    let mut shader = ExhaustiveShader { clamp: Some(c_far) };
    let s = |index| FrameSettings { mode: Mode::Full, max_depth: 4, direct_samples: 16, seed: 5, index, time: 0.0, compensation: None };
    render_frame(FrameRequest::new(&setup.scene, &far, s(0)), FrameStages { sampler: &mut ir, visibility: &mut vis, shader: &mut shader });
    render_frame(FrameRequest::new(&setup.scene, &far, s(1)), FrameStages { sampler: &mut ir, visibility: &mut vis, shader: &mut shader });
    shader.clamp = Some(c_near);
    let by_hand = render_frame(
        FrameRequest::new(&setup.scene, &near, s(2)),
        FrameStages { sampler: &mut ir, visibility: &mut vis, shader: &mut shader },
    );
    assert!(built.image.data == by_hand.image.data, "the renderer did not shade with the near view's clamp");
}

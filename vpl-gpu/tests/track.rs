//! The device's tracked pixels against `vpl_pathtrace::track_chunk`.
//!
//! Both draw the same samples from the same PCG32 streams (one a chunk of
//! 8 samples), so a pixel's estimate differs only by float rounding (the
//! device adds 64 chunks in `f32` before the host adds in `f64`), which can
//! also move a ray across an edge and so change a path. Tolerances, over
//! 192 pixels of each case at 64 samples each: at least 97 % of the means
//! within 1e-3 relative of the CPU's (a changed path in a pixel of 64
//! samples can move its mean far more), and the mean over all pixels
//! within 0.5 %. Requests of several blocks and submissions, the last
//! chunk short, must add them as the CPU does. (That the chunked estimator
//! is `track_with`'s, over other streams, is the z-test on Table 1's
//! sequences in vpl-bench.)

mod common;

use common::context;
use std::sync::atomic::AtomicBool;
use vpl_core::environment::Sky;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, GeometryClamp, Light, MaterialPolicy, Mode, Purpose, Scene, SceneSetup, stream};
use vpl_gpu::{Gpu, GpuError, GpuTracker};
use vpl_pathtrace::{Accumulator, Footprint, PathTracer, TRACK_CHUNK, TrackRequest, track_chunk};

/// The CPU's estimate of every pixel of `request`, its chunks added in order.
fn cpu(scene: &Scene, camera: &Camera, pt: &PathTracer, request: &TrackRequest) -> Vec<(Vec3, Vec3)> {
    (0..request.pixels.len())
        .map(|p| {
            let mut acc = Accumulator::default();
            for c in 0..request.spp.div_ceil(TRACK_CHUNK) {
                acc.merge(&track_chunk(scene, camera, pt, request, p, c));
            }
            (acc.mean(), acc.stderr())
        })
        .collect()
}

fn check(tracker: &GpuTracker, name: &str, scene: &Scene, camera: &Camera, pt: PathTracer, footprint: Footprint) {
    let (w, h) = camera.resolution;
    let mut rng = stream(5, 0, Purpose::TEST, 0);
    let pixels: Vec<(u32, u32)> = (0..192).map(|_| (rng.below(w), rng.below(h))).collect();
    let request = TrackRequest { pixels: &pixels, spp: 64, seed: 9, frame: 3, footprint };
    let want = cpu(scene, camera, &pt, &request);
    let got = tracker.track(scene, camera, &pt, &request).unwrap();
    let close = want.iter().zip(&got).filter(|((m, _), g)| (*m - g.mean).abs().max_element() <= 1e-3 * m.max_element().max(1e-6)).count();
    let lit = want.iter().filter(|(m, _)| m.max_element() > 0.0).count();
    let mc = want.iter().map(|(m, _)| *m).sum::<Vec3>() / pixels.len() as f32;
    let mg = got.iter().map(|g| g.mean).sum::<Vec3>() / pixels.len() as f32;
    eprintln!("{name}: {close} of {} pixels close, {lit} lit; mean {mc} (CPU) vs {mg} (GPU)", pixels.len());
    assert!(lit > 60, "{name}: too few lit pixels to test");
    assert!(close * 100 >= 97 * pixels.len(), "{name}: {close} of {} close", pixels.len());
    assert!((mc - mg).abs().max_element() <= 5e-3 * mc.max_element(), "{name}: means {mc} vs {mg}");
    assert!(got.iter().all(|g| g.samples == 64));
}

#[test]
fn gpu_tracked_pixels_match_the_cpu_chunks() {
    let Some(ctx) = context() else { return };
    let tracker = GpuTracker::new(Gpu::from_context(ctx));
    let small = |s: &SceneSetup| s.camera.with_resolution((96, 72)).unwrap();
    // Table 1's truth: indirect light through the pixel centres.
    for name in ["cornell", "office", "atrium"] {
        let s = SceneSetup::builtin(name).unwrap();
        check(&tracker, name, &s.scene, &small(&s), PathTracer::new(6, Mode::Indirect), Footprint::Centre);
    }
    // Every path length, emission seen directly, box-filtered pixels, a
    // thin lens.
    let s = SceneSetup::builtin("cornell").unwrap();
    let mut lens = small(&s);
    lens.lens_radius = 0.05;
    check(&tracker, "cornell, full, box, lens", &s.scene, &lens, PathTracer::new(5, Mode::Full), Footprint::Box);
    // The sun and a sky: light sampled toward the sky, the sky seen
    // directly and by paths that leave the scene.
    let s = SceneSetup::builtin("courtyard").unwrap();
    let mut lights = s.scene.extra_lights();
    lights.push(Light::Environment {
        sky: Sky { zenith: Vec3::new(0.2, 0.35, 0.8), horizon: Vec3::new(0.9, 0.9, 0.85), nadir: Vec3::splat(0.1) },
    });
    let sky = s.scene.with_lights(lights).unwrap();
    check(&tracker, "courtyard with a sky, full", &sky, &small(&s), PathTracer::new(5, Mode::Full), Footprint::Centre);
    // The clamp of the segment leaving the primary hit.
    let s = SceneSetup::builtin("office").unwrap();
    let clamped = PathTracer { clamp: Some(GeometryClamp::new(2.0)), ..PathTracer::new(6, Mode::Indirect) };
    check(&tracker, "office, clamped", &s.scene, &small(&s), clamped, Footprint::Centre);
}

/// Several blocks of chunks a pixel, the last chunk short, and more chunks
/// than one submission takes: the sums added in order, as the CPU adds
/// them, and the samples counted.
#[test]
fn gpu_tracked_pixels_add_their_chunks() {
    let Some(ctx) = context() else { return };
    let tracker = GpuTracker::new(Gpu::from_context(ctx));
    let s = SceneSetup::builtin("cornell").unwrap();
    let camera = s.camera.with_resolution((64, 64)).unwrap();
    let pixels = [(32, 40), (10, 20), (50, 12)];
    let pt = PathTracer::new(5, Mode::Full);
    // 3 blocks a pixel; then 25,000 chunks a pixel, 75,072 padded chunks
    // in all, over the 65,536 of a submission.
    for spp in [2 * 64 * TRACK_CHUNK + 13, 200_000 - 3] {
        let request = TrackRequest { pixels: &pixels, spp, seed: 2, frame: 0, footprint: Footprint::Box };
        let want = cpu(&s.scene, &camera, &pt, &request);
        // Progress after each submission, up to every (padded) chunk.
        let calls = std::sync::Mutex::new(Vec::new());
        let got = tracker
            .track_cancellable(&s.scene, &camera, &pt, &request, &|d, t| calls.lock().unwrap().push((d, t)), &AtomicBool::new(false))
            .unwrap();
        let chunks = GpuTracker::chunks(&request);
        assert_eq!(chunks, 3 * (spp.div_ceil(TRACK_CHUNK) as u64).next_multiple_of(64));
        let calls = calls.into_inner().unwrap();
        assert_eq!(calls.last(), Some(&(chunks, chunks)), "{calls:?}");
        assert_eq!(calls.len() as u64, chunks.div_ceil(65_536), "{calls:?}");
        for ((m, se), g) in want.iter().zip(&got) {
            eprintln!("{spp} spp at {:?}: {m} ± {se} (CPU) vs {} ± {} (GPU)", g.pixel, g.mean, g.stderr);
            assert_eq!(g.samples, spp as u64);
            assert!((*m - g.mean).abs().max_element() <= 1e-3 * m.max_element(), "{:?}", g.pixel);
            assert!((*se - g.stderr).abs().max_element() <= 1e-2 * se.max_element(), "{:?}", g.pixel);
        }
    }
    // No counted path: zero, with the samples counted (as the CPU's `li`).
    let request = TrackRequest { pixels: &pixels, spp: 100, seed: 2, frame: 0, footprint: Footprint::Box };
    let none = tracker.track(&s.scene, &camera, &PathTracer::new(1, Mode::Indirect), &request).unwrap();
    assert!(none.iter().all(|g| g.mean == Vec3::ZERO && g.samples == 100));
    // Cancelled before it starts: no samples, and it says so.
    let r = tracker.track_cancellable(&s.scene, &camera, &pt, &request, &|_, _| {}, &AtomicBool::new(true));
    assert!(matches!(r, Err(GpuError::Cancelled)));
}

/// Layered materials and pixels outside the image are refused, not drawn
/// otherwise than the CPU would draw them.
#[test]
fn gpu_tracking_refuses_what_it_cannot_draw() {
    let Some(ctx) = context() else { return };
    let tracker = GpuTracker::new(Gpu::from_context(ctx));
    let s = SceneSetup::builtin("glass").unwrap();
    let camera = s.camera.with_resolution((32, 32)).unwrap();
    let pt = PathTracer::new(5, Mode::Indirect);
    let request = TrackRequest { pixels: &[(3, 3)], spp: 64, seed: 0, frame: 0, footprint: Footprint::Centre };
    assert!(matches!(tracker.track(&s.scene, &camera, &pt, &request), Err(GpuError::Invalid(_))));
    let diffuse = s.scene.with_material_policy(MaterialPolicy::Diffuse);
    assert!(tracker.track(&diffuse, &camera, &pt, &request).is_ok());
    let outside = TrackRequest { pixels: &[(32, 3)], ..request };
    assert!(matches!(tracker.track(&diffuse, &camera, &pt, &outside), Err(GpuError::Invalid(_))));
}

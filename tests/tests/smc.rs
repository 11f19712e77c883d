//! The SMC sampler (Hedman et al. 2017) against what it promises: bounded
//! movement per frame, VPLs only on indirectly visible surfaces, intensities
//! evening out over the warm-up, stable images where IR flickers, energy
//! against the Mitsuba reference falling with the budget, and newly visible
//! rooms filled within a bounded number of frames. Fixed seeds; every bound
//! states its reason.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use vpl_core::glam::Vec3;
use vpl_core::{Camera, GeometryClamp, Image, Scene, SceneSetup, VplSet};
use vpl_ir::{InstantRadiosity, IrConfig, PathSampling};
use vpl_render::metrics::rel_mse;
use vpl_shading::{InterleavedShader, render_gbuffer};
use vpl_smc::{CameraPoint, SmcConfig, SmcSampler, mutually_visible};
use vpl_tests::{exhaustive_rt, mitsuba_indirect_64};
use vpl_visibility::ShadowMaps;

fn smc(vpls: usize, warmup: u32) -> SmcSampler {
    SmcSampler::new(SmcConfig { vpls, warmup, ..SmcConfig::default() }).unwrap()
}

/// Warm-up then `frames` iterations from one camera, as `next_frame` does.
fn warmed(scene: &Scene, camera: &Camera, vpls: usize, warmup: u32, seed: u64) -> SmcSampler {
    let mut s = smc(vpls, warmup);
    for _ in 0..=warmup {
        s.iterate(scene, camera, seed);
    }
    s
}

/// The VPLs of the first frame a renderer draws with `config` (the
/// warm-up and the frame's own iteration, through `next_frame`).
fn first_frame(scene: &Scene, camera: &Camera, gbuffer: &vpl_core::GBuffer, config: SmcConfig, seed: u64) -> VplSet {
    use vpl_core::{Frame, VplSampler};
    let mut s = SmcSampler::new(config).unwrap();
    s.next_frame(&Frame { scene, camera, time: 0.0, index: 0, seed, gbuffer, previous: None }).clone()
}

fn snapshot(set: &VplSet) -> Vec<Option<(Vec3, u64)>> {
    set.slots().iter().map(|v| v.map(|v| (v.y, v.id))).collect()
}

fn config() -> Config {
    Config { cases: 8, rng_seed: RngSeed::Fixed(0x5eed_0404), failure_persistence: None, ..Config::default() }
}

proptest! {
    #![proptest_config(config())]

    /// Over random scenes, cameras (any frame of the scene's sequence, then
    /// a jump to another), M_max and placements: once the set is full, at
    /// most M_max slots move per frame (VPLs that follow their cells'
    /// centroids included), and the slots marked moved are exactly those
    /// whose VPL (position or id) differs from the previous frame.
    #[test]
    fn at_most_m_max_slots_move_per_frame(scene_i in 0usize..4, f0 in 0u32..600, f1 in 0u32..600, m_max in 1usize..40, seed in 0u64..1000, centroid in any::<bool>()) {
        let name = ["cornell", "office", "maze", "atrium"][scene_i];
        let setup = vpl_scene_io::load(name).unwrap();
        let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
        let (placement, flux) = if centroid {
            (vpl_smc::Placement::Centroid, vpl_smc::FluxEstimator::Voronoi)
        } else {
            (vpl_smc::Placement::Site, vpl_smc::FluxEstimator::default())
        };
        let mut s = SmcSampler::new(SmcConfig { vpls: 256, m_max, warmup: 2, placement, flux, ..SmcConfig::default() }).unwrap();
        let mut prev: Option<Vec<Option<(Vec3, u64)>>> = None;
        for (k, f) in [f0 % count, f0 % count, f1 % count, f1 % count, (f1 + 1) % count].into_iter().enumerate() {
            let (scene, camera) = setup.frame(f).unwrap();
            let camera = camera.with_resolution((64, 36)).unwrap();
            let was_full = s.vpls().stored() == 256;
            let set = if k == 0 { for _ in 0..3 { s.iterate(&scene, &camera, seed); } s.vpls() } else { s.iterate(&scene, &camera, seed) };
            let now = snapshot(set);
            if let Some(p) = &prev {
                let differ: Vec<usize> = (0..256).filter(|&i| p[i] != now[i]).collect();
                let marked: Vec<usize> = (0..256).filter(|&i| set.moved(i)).collect();
                prop_assert_eq!(&differ, &marked);
                if was_full {
                    prop_assert!(marked.len() <= m_max, "{}: {} slots moved with M_max = {}", name, marked.len(), m_max);
                }
            }
            prev = Some(now);
        }
    }
}

/// Brute-force indirect visibility: the camera points of every pixel centre
/// of a `w`×`h` G-buffer; a VPL passes when one of them sees it with both
/// cosines positive. Returns the VPLs that none sees.
fn not_indirectly_visible(scene: &Scene, camera: &Camera, set: &VplSet, size: (u32, u32)) -> Vec<usize> {
    let gbuf = render_gbuffer(scene, &camera.with_resolution(size).unwrap());
    let xs: Vec<CameraPoint> = gbuf.samples.iter().filter(|g| g.reflects()).map(|g| CameraPoint { p: g.p, n: g.n, ng: g.ng }).collect();
    // A fixed stride through the points, so that each search spreads over the image.
    let order: Vec<usize> = (0..xs.len()).map(|i| (i * 7919) % xs.len()).collect();
    use rayon::prelude::*;
    set.iter()
        .collect::<Vec<_>>()
        .par_iter()
        .filter(|(_, v)| !order.iter().any(|&i| mutually_visible(scene, &xs[i], v.y, v.n)))
        .map(|(s, _)| *s)
        .collect()
}

/// Every VPL lies on an indirectly visible surface, checked by brute force
/// against every pixel centre of a 1280×720 view (0.9 million camera
/// points) after the 100 warm-up iterations of a 320×180 camera, on
/// `cornell` and on `office` (where most of the scene is hidden behind the
/// corridor walls). Bound: none missed. The brute force must be finer than
/// the view: the sampler's camera points fall anywhere inside a pixel, and on
/// `office` 9 of 512 VPLs are lit only from the far end of the corridor,
/// which the pixel centres of a 320×180 view do not reach.
#[test]
fn every_vpl_is_indirectly_visible() {
    for name in ["cornell", "office"] {
        let setup = vpl_scene_io::load(name).unwrap();
        let camera = setup.camera.with_resolution((320, 180)).unwrap();
        let s = warmed(&setup.scene, &camera, 512, 100, 3);
        let set = s.vpls();
        let bad = not_indirectly_visible(&setup.scene, &camera, set, (1280, 720));
        eprintln!("{name}: {} of {} VPLs not indirectly visible; {}", bad.len(), set.stored(), s.stats().stored);
        assert_eq!(set.stored(), 512);
        assert!(bad.is_empty(), "{name}: {} VPLs are not indirectly visible, e.g. slot {}", bad.len(), bad[0]);
    }
}

/// The distribution moves toward p ∝ L (eq. 4) over the warm-up: the
/// coefficient of variation of the intensities I = L/p falls. `office`,
/// I = 512 (M_max = 16 lets 100 iterations replace up to 1600 VPLs).
#[test]
fn intensities_even_out_over_the_warmup() {
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((160, 90)).unwrap();
    let mut s = smc(512, 100);
    let mut cv = Vec::new();
    for i in 0..=100 {
        s.iterate(&setup.scene, &camera, 4);
        if i % 25 == 0 {
            cv.push(s.stats().intensity_cv);
        }
    }
    eprintln!("intensity CV every 25 iterations: {cv:?}");
    assert!(cv[4] < 0.8 * cv[0], "CV {} -> {}", cv[0], cv[4]);
}

fn luminance_image(img: &Image) -> Vec<f32> {
    img.data.iter().map(|c| vpl_core::image::luminance(*c)).collect()
}

/// Mean over frame pairs of Σ|L_t − L_{t−1}| / Σ L_t (luminance): the
/// relative change of the image from one frame to the next.
fn frame_to_frame_change(frames: &[Image]) -> f64 {
    let l: Vec<Vec<f32>> = frames.iter().map(luminance_image).collect();
    let mut sum = 0.0;
    for w in l.windows(2) {
        let d: f64 = w[0].iter().zip(&w[1]).map(|(a, b)| (a - b).abs() as f64).sum();
        let m: f64 = w[1].iter().map(|&b| b as f64).sum();
        sum += d / m;
    }
    sum / (l.len() - 1) as f64
}

/// Indirect frames of a static `cornell` (96×96, 1024 VPLs, 128² shadow
/// maps, interleaved shading and the filter, the default clamp) rendered by
/// `sampler` for `n` frames.
fn static_frames(sampler: &mut dyn vpl_core::VplSampler, n: u64) -> (Vec<Image>, Vec<usize>) {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((96, 96)).unwrap();
    let clamp = Some(GeometryClamp::for_scene_area(1024, setup.scene.surface_area()));
    let mut vis = ShadowMaps::new(128).unwrap();
    let mut shader = InterleavedShader::new(clamp, 5);
    let s = vpl_render::FrameSettings { mode: vpl_core::Mode::Indirect, seed: 5, ..vpl_render::FrameSettings::default() };
    let mut images = Vec::new();
    let mut rebuilt = Vec::new();
    for index in 0..n {
        let r = vpl_render::render_frame(
            vpl_render::FrameRequest::new(&setup.scene, &camera, vpl_render::FrameSettings { index, ..s }),
            vpl_render::FrameStages { sampler, visibility: &mut vis, shader: &mut shader },
        );
        images.push(r.image);
        rebuilt.push(r.visibility.rebuilt);
    }
    (images, rebuilt)
}

/// A static camera and light give SMC a stable image: its frame-to-frame
/// change is below 1 % (it replaces at most 16 of 1024 VPLs a frame and
/// re-weights the rest by their new kNN densities), while IR with fresh
/// light paths every frame, as the papers compare it, and Metropolis IR,
/// which starts afresh every frame, each change by more than 5 times as
/// much. (IR with fixed paths repeats itself exactly in a static scene:
/// zero change, and zero view adaptation.)
#[test]
fn a_static_view_gives_a_stable_smc_image_and_a_flickering_ir_image() {
    let mut smc_s = smc(1024, 100);
    let (smc_frames, smc_rebuilt) = static_frames(&mut smc_s, 6);
    let mut fresh = InstantRadiosity::new(IrConfig { vpls: 1024, bounces: 3, sampling: PathSampling::Random, fresh_paths: true }).unwrap();
    let (ir_frames, ir_rebuilt) = static_frames(&mut fresh, 6);
    let mut fixed = InstantRadiosity::new(IrConfig { vpls: 1024, bounces: 3, sampling: PathSampling::Random, fresh_paths: false }).unwrap();
    let (fixed_frames, _) = static_frames(&mut fixed, 3);
    let mut mir = vpl_mir::MirSampler::new(vpl_mir::MirConfig { vpls: 1024, ..vpl_mir::MirConfig::default() }).unwrap();
    let (mir_frames, mir_rebuilt) = static_frames(&mut mir, 6);
    let (cs, ci, cf) = (frame_to_frame_change(&smc_frames), frame_to_frame_change(&ir_frames), frame_to_frame_change(&fixed_frames));
    let cm = frame_to_frame_change(&mir_frames);
    eprintln!(
        "frame-to-frame change: SMC {:.4} % (maps rebuilt {smc_rebuilt:?}), IR fresh paths {:.4} % (maps rebuilt {ir_rebuilt:?}), IR fixed paths {:.4} %, MIR {:.4} % (maps rebuilt {mir_rebuilt:?})",
        100.0 * cs,
        100.0 * ci,
        100.0 * cf,
        100.0 * cm
    );
    assert!(cm > 5.0 * cs, "MIR changes by {:.3} %, SMC by {:.3} %", 100.0 * cm, 100.0 * cs);
    assert!(cs < 0.01, "SMC changes by {:.3} % a frame", 100.0 * cs);
    assert!(ci > 5.0 * cs, "IR with fresh paths changes by {:.3} %, SMC by {:.3} %", 100.0 * ci, 100.0 * cs);
    assert!(smc_rebuilt[1..].iter().all(|&r| r <= 16), "SMC rebuilt {smc_rebuilt:?} maps");
}

/// The paper's Fig. 10 on `cornell`: SMC VPLs with ray-traced visibility,
/// exhaustive shading and no clamp against Mitsuba's indirect reference
/// (256×256 box-filtered to 64×64), for I = 2K, 8K, 40K.
/// - Energy: at 40K every channel's image mean is within 3 % of the
///   reference. The estimator is biased by the kNN densities (neighbours
///   across the box's edges shrink r_k), which falls as k grows with I.
/// - relMSE falls with every step of the budget.
///
/// All three budgets warm up for 10 iterations (100 at 40K VPLs would take a
/// minute; with M_max = 16, 100 iterations move at most 4 % of 40K VPLs, so
/// the distribution is the resampled candidates' either way).
#[test]
fn smc_energy_matches_mitsuba_and_error_falls_with_the_budget() {
    let setup = SceneSetup::builtin("cornell").unwrap();
    let camera = setup.camera.with_resolution((64, 64)).unwrap();
    let scene = &setup.scene;
    let gbuf = render_gbuffer(scene, &camera);
    let reference = mitsuba_indirect_64();
    let ref_mean = reference.mean();
    let mut errors = Vec::new();
    for vpls in [2048, 8192, 40_000] {
        let t = std::time::Instant::now();
        let s = warmed(scene, &setup.camera, vpls, 10, 7);
        let img = exhaustive_rt(scene, &gbuf, s.vpls(), None);
        let e = rel_mse(&img, &reference).unwrap();
        let m = img.mean();
        eprintln!(
            "I = {vpls}: relMSE {e:.5}, mean {:.5} {:.5} {:.5} (reference {:.5} {:.5} {:.5}), {:.1} s",
            m[0],
            m[1],
            m[2],
            ref_mean[0],
            ref_mean[1],
            ref_mean[2],
            t.elapsed().as_secs_f32()
        );
        errors.push((vpls, e, m));
    }
    let (_, _, m) = errors[2];
    for c in 0..3 {
        let rel = (m[c] - ref_mean[c]) / ref_mean[c];
        assert!(rel.abs() < 0.03, "channel {c}: 40K-VPL mean differs from the reference by {:.2} %", 100.0 * rel);
    }
    assert!(errors[0].1 > errors[1].1 && errors[1].1 > errors[2].1, "relMSE does not fall with I: {errors:?}");
}

/// Moving into `office`'s corridor: the camera cuts from the corridor's
/// start to a door at z = −30 and looks into the lit room behind it, which
/// the first view did not see. Per frame after the cut: the indirect light
/// on the room's pixels (ray-traced visibility, exhaustive shading, default
/// clamp) against a sampler warmed up at the new view, and the share of VPLs
/// in the room. Before the cut the room holds under a tenth of the VPL
/// share it holds at steady state (measured: 1.5 % of the VPLs against
/// 20–24 %).
///
/// One run is a poor measure of the speed: the frame at which a single seed
/// reaches 80 % of its steady light ranges from 1 to 19 over seeds 8–13
/// (the steady state itself is one noisy run). The test averages the ratio
/// over those six seeds. Bound: the mean reaches 80 % within 18 frames
/// (0.6 s at 30 fps; measured: 14, and 12 before the BVH found hits nearer
/// than 10⁻⁴; the per-seed spread, about 5 frames, puts the standard error
/// of the mean near 2 frames, so the bound is two of them above the
/// measurement). The VPL count in the room grows by at most M_max = 16 a
/// frame; few VPLs suffice for the energy because the kNN density of a
/// sparse region is low, so its VPLs carry large flux.
#[test]
fn newly_visible_rooms_fill_within_frames() {
    let setup = SceneSetup::builtin("office").unwrap();
    let scene = &setup.scene;
    let size = (64, 36);
    let a = setup.camera.looking(Vec3::new(0.0, 1.6, -2.0), Vec3::new(0.0, 1.5, -8.0)).unwrap().with_resolution(size).unwrap();
    let b = setup.camera.looking(Vec3::new(0.9, 1.5, -30.0), Vec3::new(6.0, 1.2, -30.0)).unwrap().with_resolution(size).unwrap();
    let in_room = |p: Vec3| p.x > 1.55 && p.z > -33.3 && p.z < -26.7;
    let gbuf = render_gbuffer(scene, &b);
    let room_px: Vec<usize> = (0..gbuf.samples.len()).filter(|&i| gbuf.samples[i].reflects() && in_room(gbuf.samples[i].p)).collect();
    eprintln!("room pixels: {} of {}", room_px.len(), gbuf.samples.len());
    assert!(room_px.len() > size.0 as usize * size.1 as usize / 5, "the room fills too little of the view");
    let clamp = Some(GeometryClamp::for_scene_area(1024, scene.surface_area()));
    let room_light = |set: &VplSet| {
        let img = exhaustive_rt(scene, &gbuf, set, clamp);
        room_px.iter().map(|&i| vpl_core::image::luminance(img.data[i]) as f64).sum::<f64>()
    };
    let share = |set: &VplSet| set.iter().filter(|(_, v)| in_room(v.y)).count() as f64 / set.stored() as f64;
    let (frames, bound) = (20, 18);
    let seeds = [8u64, 9, 10, 11, 12, 13];
    let mut mean = vec![0.0f64; frames];
    for seed in seeds {
        let target = warmed(scene, &b, 1024, 100, seed);
        let (target_light, target_share) = (room_light(target.vpls()), share(target.vpls()));
        let mut s = warmed(scene, &a, 1024, 100, seed);
        let before = share(s.vpls());
        assert!(
            before < 0.1 * target_share,
            "seed {seed}: the room already held VPLs before the cut: {before}, steady share {target_share}"
        );
        let mut curve = Vec::new();
        for m in mean.iter_mut() {
            let l = room_light(s.iterate(scene, &b, seed)) / target_light;
            *m += l / seeds.len() as f64;
            curve.push(l);
        }
        let first = curve.iter().position(|l| *l >= 0.8).map(|i| i + 1);
        eprintln!(
            "seed {seed}: VPL share {before:.3} before the cut, {target_share:.3} steady; {} after {frames} frames; 80 % of the light at frame {first:?}",
            share(s.vpls())
        );
    }
    let first = mean.iter().position(|l| *l >= 0.8).map(|i| i + 1);
    eprintln!("mean light ratio per frame: {:?}", mean.iter().map(|l| (l * 1000.0).round() / 1000.0).collect::<Vec<_>>());
    let f = first.expect("the room's mean light did not reach 80 % within 20 frames");
    assert!(f <= bound, "the room's mean light reached 80 % only after {f} frames");
}

/// SMC frames give the same VPLs, bit for bit, on one thread and on two.
#[test]
fn smc_is_bit_identical_across_thread_counts() {
    let setup = SceneSetup::builtin("office").unwrap();
    let camera = setup.camera.with_resolution((80, 45)).unwrap();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut s = smc(300, 3);
            for _ in 0..6 {
                s.iterate(&setup.scene, &camera, 11);
            }
            s.vpls()
                .slots()
                .iter()
                .map(|v| v.map(|v| (v.y.to_array().map(f32::to_bits), v.flux.to_array().map(f32::to_bits), v.id)))
                .collect::<Vec<_>>()
        })
    };
    assert!(run(1) == run(2), "1 and 2 threads differ");
}

/// The flux of a VPL uses a radiosity estimate its selection did not see.
/// Algorithm 1 keeps the candidates whose estimated intensity is largest and
/// drops the smallest; rendering with those same 16-path estimates made the
/// kept VPLs too bright (the winner's curse): `office` at frame 600 and
/// `maze` at frame 300, 2048 VPLs after the 100-iteration warm-up,
/// exhaustive ray-traced shading without a clamp, came out 67 % and 69 %
/// above path tracing at 160×120 (office 74 % at this test's 64×48). With
/// independent estimates the image mean is within 10 % of path tracing's
/// (256 spp; its standard error is under 1 %): what is left is the flux
/// estimator's own bias (measured here with the Voronoi-cell flux +2.9 %
/// and +0.9 %; the paper's kNN flux gave +3.9 % and +6.5 %).
#[test]
fn selection_does_not_bias_the_vpl_radiosities() {
    use vpl_core::Mode;
    use vpl_pathtrace::{PathTracer, RenderSettings, render};
    for (name, frame) in [("office", 600), ("maze", 300)] {
        let setup = vpl_scene_io::load(name).unwrap();
        let (scene, camera) = setup.frame(frame).unwrap();
        let camera = camera.with_resolution((64, 48)).unwrap();
        let gbuf = render_gbuffer(&scene, &camera);
        let s = warmed(&scene, &camera, 2048, 100, 5);
        let img = exhaustive_rt(&scene, &gbuf, s.vpls(), None);
        let pt = render(
            &scene,
            &camera,
            &PathTracer::new(5, Mode::Indirect),
            RenderSettings { spp: 256, seed: 5, frame: frame as u64 },
            &|_, _| {},
        )
        .unwrap()
        .image;
        let lum = |i: &Image| i.data.iter().map(|c| vpl_core::image::luminance(*c) as f64).sum::<f64>();
        let ratio = lum(&img) / lum(&pt);
        eprintln!("{name}: SMC / path tracing = {ratio:.3}");
        assert!((ratio - 1.0).abs() < 0.10, "{name}: the SMC image mean is {ratio:.3} of path tracing's");
    }
}

/// The Voronoi-cell flux against path tracing, where the paper's kNN flux
/// is too bright, with the VPLs shining from their own points (the
/// default) and from near their cells' centroids
/// (`Placement::Centroid`), and (printed) from a probe of their cells
/// drawn by area (`Placement::Random`): unclamped, ray-traced, exhaustive indirect
/// light with I = 2048 after the 100-iteration warm-up, at the default
/// cameras of `cornell` (64×64, its square image), `office` and `atrium`
/// (64×48); and the default flux, those cells with the areas near the
/// VPLs (`FluxEstimator::VoronoiNear`), at the VPLs' own points.
///
/// Bound: for each placement, and for the default, the image mean over seeds 0–2 is within 3 %
/// of path tracing's (the target of the flux; at 96×72 through `vpl render`
/// the sites give 0.997, 1.019 and 0.999, the centroids 1.000, 1.018 and
/// 0.996). The path tracer's 512 samples a pixel put its own standard
/// error under 0.2 %, and the seeds' spread (about 1.5 %) puts the mean's
/// under 1 %. The paper's estimator (kNN flux at the sites), one seed, must
/// be more than 8 % too bright on `cornell` and `atrium` (on `office` its
/// errors happen to cancel): the test sees the bias it guards against.
/// Measured for the default: `cornell` 1.002, `office` 0.971 (the cells at
/// the sites 0.990; here the path tracer's rays cover the whole pixel and
/// the VPLs shade its centre, which at 64×48 moves the ratio by a few per
/// cent, see `vpl_bench::energy`, where the same default gives `office`
/// 0.989 ± 0.008 through the pixels' centres), `atrium` 0.981.
#[test]
fn the_cell_flux_matches_path_tracing_where_the_knn_flux_is_too_bright() {
    use vpl_core::Mode;
    use vpl_pathtrace::{PathTracer, RenderSettings, render};
    use vpl_smc::{FluxEstimator, Placement};
    let lum = |i: &Image| i.data.iter().map(|c| vpl_core::image::luminance(*c) as f64).sum::<f64>();
    for (name, size) in [("cornell", (64, 64)), ("office", (64, 48)), ("atrium", (64, 48))] {
        let setup = vpl_scene_io::load(name).unwrap();
        let camera = setup.camera.with_resolution(size).unwrap();
        let scene = &setup.scene;
        let gbuf = render_gbuffer(scene, &camera);
        let settings = RenderSettings { spp: 512, seed: 1, frame: 0 };
        let pt = lum(&render(scene, &camera, &PathTracer::new(5, Mode::Indirect), settings, &|_, _| {}).unwrap().image);
        let ratio = |flux: FluxEstimator, placement: Placement, seed: u64| {
            let set =
                first_frame(scene, &camera, &gbuf, SmcConfig { vpls: 2048, warmup: 100, flux, placement, ..SmcConfig::default() }, seed);
            lum(&exhaustive_rt(scene, &gbuf, &set, None)) / pt
        };
        for placement in Placement::ALL {
            let cells: Vec<f64> = (0..3).map(|seed| ratio(FluxEstimator::Voronoi, placement, seed)).collect();
            let mean = cells.iter().sum::<f64>() / 3.0;
            eprintln!("{name}: SMC / path tracing, cells at {placement} {cells:.3?} (mean {mean:.3})");
            // The random placement renders each cell's light as the cell
            // holds it, so it shows the cells' own errors, which the sites'
            // offset partly hides (office 0.962, seeds 0-2): it is not held
            // to the bound (`vpl_smc::Placement`).
            if placement != Placement::Random {
                assert!((mean - 1.0).abs() < 0.03, "{name}: the cell flux at {placement} gives {mean:.3} of path tracing's image mean");
            }
        }
        let near: Vec<f64> = (0..3).map(|seed| ratio(FluxEstimator::VoronoiNear, Placement::Site, seed)).collect();
        let mean = near.iter().sum::<f64>() / 3.0;
        eprintln!("{name}: SMC / path tracing, the default (cells with the areas near the VPLs) {near:.3?} (mean {mean:.3})");
        assert!((mean - 1.0).abs() < 0.03, "{name}: the default flux gives {mean:.3} of path tracing's image mean");
        let knn = ratio(FluxEstimator::Knn, Placement::Site, 0);
        eprintln!("{name}: kNN {knn:.3}");
        if name != "office" {
            assert!(knn > 1.08, "{name}: the kNN flux gives {knn:.3}: the bias this test guards against is gone");
        }
    }
}

/// A lamp carried from room to room (`building`): where it has just left a
/// cell, the cell's relit light (eq. 1 of `vpl_smc::Relight`'s module) can
/// overshoot below zero, and the sampler takes that part from the nearest
/// cells' light (`vpl_smc::spread_deficits`) instead of holding the cell
/// at zero, which added light (10 % at frame 360 of the job's walk).
/// Stepped every frame from frame 330 to 360 (the lamp passing a doorway;
/// 512 VPLs, a 32×24 G-buffer, the default warm-up at frame 330): some
/// frames have such cells, so the test sees the spreading happen (it fails
/// if eq. 1 is held at zero again); no VPL's flux is negative; and the
/// neighbours take at least 99 % of the negative light over the walk
/// (measured: all of it, 6.0 of the sets' 4,849 in luminance; the nearest
/// 8 cells alone took 94.8 %).
#[test]
fn a_lamp_leaving_a_room_takes_its_overshoot_from_the_neighbours() {
    use vpl_core::{Frame, VplSampler};
    let setup = vpl_scene_io::load("building").unwrap();
    let mut s = smc(512, SmcConfig::default().warmup);
    let (mut negative, mut light, mut unplaced, mut total) = (0usize, 0.0f64, 0.0f64, 0.0f64);
    for f in 330..=360u32 {
        let (scene, camera) = setup.frame(f).unwrap();
        let camera = camera.with_resolution((32, 24)).unwrap();
        let gbuffer = render_gbuffer(&scene, &camera);
        let time = setup.sequence.as_ref().map_or(0.0, |q| q.time(f));
        let set =
            s.next_frame(&Frame { scene: &scene, camera: &camera, time, index: f as u64, seed: 3, gbuffer: &gbuffer, previous: None });
        for v in set.slots().iter().flatten() {
            assert!(v.flux.min_element() >= 0.0, "frame {f}: a VPL's flux is {}", v.flux);
            total += vpl_core::image::luminance(v.flux) as f64;
        }
        let spread = s.stats().negative_cells;
        negative += spread.cells;
        light += spread.light;
        unplaced += spread.unplaced;
    }
    eprintln!("31 frames: {negative} negative cells, their light {light:.4e}, unplaced {unplaced:.4e}, the sets' light {total:.4e}");
    assert!(negative > 0, "no relit cell came out below zero along the lamp's walk");
    assert!(unplaced <= 0.01 * light, "the neighbours took {:.1} % of the negative light", 100.0 * (1.0 - unplaced / light));
}

/// The candidates' relighting estimates (eq. 1 of `vpl_smc::Relight`'s
/// module) are made only at iterations whose lights changed: none while
/// they stand still (a frame of `building` held for 20 iterations), and at
/// the first change both D(t), under the lights the held candidates were
/// made under, and D(now) for the candidates of every iteration held but
/// the newest (about 2 · 15 iterations' candidates). While the lamp keeps
/// moving, D(t) is left to make for one iteration's candidates only, so
/// the next frame makes about half as many (16 iterations' against 30).
#[test]
fn relighting_estimates_are_made_only_when_the_lights_move() {
    use vpl_core::{Frame, VplSampler};
    let setup = vpl_scene_io::load("building").unwrap();
    let mut s = smc(512, SmcConfig::default().warmup);
    let mut step = |f: u32| {
        let (scene, camera) = setup.frame(f).unwrap();
        let camera = camera.with_resolution((32, 24)).unwrap();
        let gbuffer = render_gbuffer(&scene, &camera);
        s.next_frame(&Frame { scene: &scene, camera: &camera, time: 0.0, index: f as u64, seed: 5, gbuffer: &gbuffer, previous: None });
        let st = s.stats();
        (st.relit_candidates, st.candidates)
    };
    let mut held = Vec::new();
    for _ in 0..20 {
        held.push(step(330));
    }
    assert!(held.iter().all(|&(r, _)| r == 0), "estimates made under lights that stand still: {held:?}");
    let per_iteration = held.iter().skip(4).map(|&(_, c)| c).sum::<usize>() as f64 / 16.0;
    let (first, _) = step(331);
    let (next, _) = step(332);
    eprintln!("relighting estimates: {first} at the first change, {next} at the next ({per_iteration:.0} candidates an iteration)");
    let within = |made: usize, iterations: f64| (made as f64 - iterations * per_iteration).abs() <= 0.05 * iterations * per_iteration;
    assert!(within(first, 30.0), "{first} estimates at the first change, not about 30 iterations' candidates");
    assert!(within(next, 16.0), "{next} estimates at the next change, not about 16 iterations' candidates");
}

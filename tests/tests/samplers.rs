//! The view-adaptive samplers against references: Russian-roulette acceptance
//! is unbiased (against IR over seeds, and against Mitsuba's indirect
//! reference), Metropolis IR and its resampling stand-in converge to the
//! indirect reference as I grows, TCAS matches a single-bounce path-traced
//! indirect image, and every sampler is deterministic and survives the
//! degenerate cases. Fixed seeds; every bound is stated with its reason.

use rayon::ThreadPoolBuilder;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, Frame, GBuffer, Image, Light, Material, Mesh, Scene, VplSampler, VplSet};
use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render};
use vpl_render::metrics::rel_mse;
use vpl_rr::{RrConfig, RrSampler};
use vpl_sampling::{Registry, SamplingError};

/// A built-in sampler with its default settings for `vpls` VPLs and depth 5.
fn build(name: &str, vpls: usize) -> Result<Box<dyn VplSampler>, SamplingError> {
    Registry::builtin().build_default(name, vpl_core::Budget::new(vpls, 5))
}
use vpl_shading::render_gbuffer;
use vpl_tests::{exhaustive_rt, mitsuba_indirect_64};

fn setup(name: &str, size: (u32, u32)) -> (Scene, Camera) {
    let s = vpl_scene_io::load(name).unwrap();
    let c = s.camera.with_resolution(size).unwrap();
    (s.scene, c)
}

fn frame<'a>(scene: &'a Scene, camera: &'a Camera, gbuf: &'a GBuffer, index: u64, seed: u64) -> Frame<'a> {
    Frame { scene, camera, time: 0.0, index, seed, gbuffer: gbuf, previous: None }
}

/// Per-pixel mean and standard error of the mean over a stack of images.
fn mean_se(images: &[Image]) -> (Vec<Vec3>, Vec<Vec3>) {
    let n = images.len() as f32;
    let len = images[0].data.len();
    let mut mean = vec![Vec3::ZERO; len];
    let mut se = vec![Vec3::ZERO; len];
    for i in 0..len {
        let m = images.iter().map(|im| im.data[i]).sum::<Vec3>() / n;
        let v = images.iter().map(|im| (im.data[i] - m) * (im.data[i] - m)).sum::<Vec3>() / (n - 1.0);
        mean[i] = m;
        se[i] = (v / n).map(f32::sqrt);
    }
    (mean, se)
}

/// Image means (per channel) of each image, for a z-test of the totals.
fn totals(images: &[Image]) -> Vec<[f64; 3]> {
    images.iter().map(|im| im.mean()).collect()
}

/// RR is unbiased, tested conditionally on its candidates. On `corner`
/// (where it drops most of them), IR with fixed light paths and seed 1 gives
/// the candidate set S (I = 1024); a fresh RR sampler knows no acceptance
/// rate yet, so it asks IR for exactly that budget, and its candidates are S
/// again in every frame, while its roulette and camera samples change with
/// the frame index. Then E[RR image | S] = IR(S) image exactly (eq. 2), and
/// the only noise is the roulette's, bounded by 1/ε per VPL. Over 200
/// frames, with Φ̃_total from IR(S) itself: the image mean's |z| < 4 in each
/// channel, and at most 1 % of the pixel channels have |z| > 3 (0.27 %
/// expected for independent pixels; pixels lit by the same VPLs move
/// together, hence the margin), standard errors floored at f32 rounding.
/// Dropping the 1/p weight fails both (image-mean z ≈ −100).
#[test]
fn rr_is_unbiased_given_its_candidates() {
    let (scene, camera) = setup("corner", (32, 24));
    let gbuf = render_gbuffer(&scene, &camera);
    let mut ir = build("ir", 1024).unwrap();
    let s_set = ir.next_frame(&frame(&scene, &camera, &gbuf, 0, 1)).clone();
    let target = exhaustive_rt(&scene, &gbuf, &s_set, None);
    let frames = 200;
    let mut acceptance = 0.0;
    let rr: Vec<Image> = (0..frames)
        .map(|k| {
            let mut rr = RrSampler::over_ir(RrConfig { vpls: 1024, ..RrConfig::default() }, 3, false).unwrap();
            let set = rr.next_frame(&Frame { previous: Some(&target), ..frame(&scene, &camera, &gbuf, k, 1) }).clone();
            assert_eq!(rr.stats().budget, 1024);
            acceptance += rr.stats().mean_acceptance as f64 / frames as f64;
            exhaustive_rt(&scene, &gbuf, &set, None)
        })
        .collect();
    eprintln!("corner: mean acceptance {acceptance:.3}");
    assert!(acceptance < 0.3, "RR should drop most candidates around the corner (mean acceptance {acceptance:.3})");
    let t = target.mean();
    for c in 0..3 {
        let (m, se) = vpl_tests::mean_se(&totals(&rr).iter().map(|x| x[c]).collect::<Vec<_>>());
        let z = (m - t[c]) / se;
        eprintln!("channel {c}: RR {m:.5} ± {se:.5}, IR(S) {:.5}, z {z:.2}", t[c]);
        assert!(z.abs() < 4.0, "channel {c}: RR mean {m:.5} ± {se:.5} against IR(S) {:.5} (z {z:.2})", t[c]);
    }
    let (m, se) = mean_se(&rr);
    let (mut outliers, mut tested) = (0, 0);
    for p in 0..m.len() {
        for c in 0..3 {
            // Pixels lit almost only by VPLs of p = 1 are exact up to the
            // rounding of a 1024-term f32 sum in another order: standard
            // errors are raised to that, √1024·2⁻²⁴ ≈ 2·10⁻⁶ of the value.
            let se_eff = se[p][c].max(2e-6 * target.data[p][c].abs());
            if se_eff > 0.0 {
                tested += 1;
                if ((m[p][c] - target.data[p][c]) / se_eff).abs() > 3.0 {
                    outliers += 1;
                }
            }
        }
    }
    eprintln!("{outliers} of {tested} pixel channels with |z| > 3");
    assert!(
        tested > 1000 && (outliers as f64) <= 0.01 * tested as f64,
        "{outliers} of {tested} pixel channels differ by more than 3 standard errors"
    );
}

/// RR's mean indirect energy on `cornell` matches Mitsuba's indirect
/// reference as IR's does (test (a) of tests/vpl.rs): 16K stored VPLs after
/// a pilot, ray-traced, exhaustive, no clamp, mean of 2 seeds within 3 % of
/// the reference in each channel (the bound of IR's test; VPL noise of the
/// image mean at 16K is about 1 %).
#[test]
fn rr_energy_matches_the_mitsuba_indirect_reference() {
    let (scene, camera) = setup("cornell", (64, 64));
    let gbuf = render_gbuffer(&scene, &camera);
    let reference = mitsuba_indirect_64().mean();
    let mut mean = [0.0f64; 3];
    for seed in 0..2 {
        let mut rr = RrSampler::over_ir(RrConfig { vpls: 16384, pilot: true, ..RrConfig::default() }, 3, false).unwrap();
        let set = rr.next_frame(&frame(&scene, &camera, &gbuf, 0, 7 + seed)).clone();
        eprintln!("{}", VplSampler::stats(&rr));
        let m = exhaustive_rt(&scene, &gbuf, &set, None).mean();
        (0..3).for_each(|c| mean[c] += m[c] / 2.0);
    }
    for c in 0..3 {
        let rel = (mean[c] - reference[c]) / reference[c];
        eprintln!("channel {c}: RR {:.5}, reference {:.5} ({:+.2} %)", mean[c], reference[c], 100.0 * rel);
        assert!(rel.abs() < 0.03, "channel {c}: RR mean differs from the reference by {:.2} %", 100.0 * rel);
    }
}

/// MIR and mir-resample converge to Mitsuba's indirect reference of
/// `cornell` (64×64) as I grows 1K → 4K → 16K: relMSE at 16K is below half
/// of that at 1K, and at 16K every channel's mean is within 5 % of the
/// reference. (Not "at every step": with the clamp off, one VPL close to a
/// wall makes a single seed's relMSE jump; mir-resample measured 0.0040,
/// 0.0104, 0.0014.) MIR is
/// consistent (its start-up bias is removed by the bootstrap; what remains
/// is chain correlation, falling with I); mir-resample's kNN densities are
/// consistent with k growing with I, and carry SMC's bias at small I
/// (+7 % at 2K in issue 4's figures), hence 5 % rather than IR's 3 %.
#[test]
fn mir_and_mir_resample_converge_to_the_indirect_reference() {
    let (scene, camera) = setup("cornell", (64, 64));
    let gbuf = render_gbuffer(&scene, &camera);
    let reference = mitsuba_indirect_64();
    let ref_mean = reference.mean();
    for name in ["mir", "mir-resample"] {
        let mut errors = Vec::new();
        for vpls in [1024, 4096, 16384] {
            let mut s = build(name, vpls).unwrap();
            let set = s.next_frame(&frame(&scene, &camera, &gbuf, 0, 3)).clone();
            let img = exhaustive_rt(&scene, &gbuf, &set, None);
            let e = rel_mse(&img, &reference).unwrap();
            let m = img.mean();
            eprintln!(
                "{name} I = {vpls}: relMSE {e:.5}, mean {:.5} {:.5} {:.5} (reference {:.5} {:.5} {:.5}); {}",
                m[0],
                m[1],
                m[2],
                ref_mean[0],
                ref_mean[1],
                ref_mean[2],
                s.stats()
            );
            errors.push((e, m));
        }
        assert!(errors[2].0 < 0.5 * errors[0].0, "{name}: relMSE does not fall with I: {errors:?}");
        for (c, r) in ref_mean.iter().enumerate() {
            let rel = (errors[2].1[c] - r) / r;
            assert!(rel.abs() < 0.05, "{name}: channel {c} at 16K differs from the reference by {:.2} %", 100.0 * rel);
        }
    }
}

/// TCAS carries one bounce: on `cornell` (64×64) its image with 16384 VPLs
/// (ray-traced, exhaustive, no clamp) matches the path tracer's indirect
/// image at max depth 3 (paths with exactly two scattering vertices, 512
/// spp): every channel's mean within 3 % (the RSM is a 64² stratified
/// emission quadrature, the path tracer's mean has a standard error under
/// 0.3 %, and the VPL image samples pixel centres where the path tracer
/// averages pixel areas: at 32×32 that alone put IR's own first bounce
/// 3–4 % below the path tracer; 4096 chain-correlated VPLs of one seed
/// left the red mean 3.7 % off, 16K bring it under 1 %), relMSE below 0.02. TCAS against the depth-5 image would
/// miss the second and third bounces: the test also checks that it is at
/// least 15 % below that.
#[test]
fn tcas_matches_a_single_bounce_path_traced_image() {
    let (scene, camera) = setup("cornell", (64, 64));
    let gbuf = render_gbuffer(&scene, &camera);
    let pt = |depth| {
        render(&scene, &camera, &PathTracer::new(depth, Mode::Indirect), RenderSettings { spp: 512, seed: 11, frame: 0 }, &|_, _| {})
            .unwrap()
            .image
    };
    let one = pt(3);
    let three = pt(5);
    let mut tcas = build("tcas", 16384).unwrap();
    let set = tcas.next_frame(&frame(&scene, &camera, &gbuf, 0, 2)).clone();
    assert!(set.iter().all(|(_, v)| v.bounce == 1));
    let img = exhaustive_rt(&scene, &gbuf, &set, None);
    let (m, r1, r3) = (img.mean(), one.mean(), three.mean());
    let e = rel_mse(&img, &one).unwrap();
    eprintln!(
        "tcas: mean {:.5} {:.5} {:.5}, PT depth 3 {:.5} {:.5} {:.5}, depth 5 {:.5}; relMSE {e:.5}; {}",
        m[0],
        m[1],
        m[2],
        r1[0],
        r1[1],
        r1[2],
        r3[0],
        tcas.stats()
    );
    for c in 0..3 {
        let rel = (m[c] - r1[c]) / r1[c];
        assert!(rel.abs() < 0.03, "channel {c}: TCAS differs from the single-bounce image by {:.2} %", 100.0 * rel);
        assert!(m[c] < 0.85 * r3[c], "channel {c}: TCAS {:.5} is not below the three-bounce image {:.5}", m[c], r3[c]);
    }
    assert!(e < 0.02, "relMSE {e}");
}

/// Two frames of `sampler` on `scene`, on a pool of `threads` threads.
fn two_frames(name: &str, scene: &Scene, camera: &Camera, vpls: usize, threads: usize) -> Vec<VplSet> {
    let gbuf = GBuffer::empty();
    let pool = ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        let mut s = build(name, vpls).unwrap();
        (0..2).map(|i| s.next_frame(&frame(scene, camera, &gbuf, i, 9)).clone()).collect()
    })
}

const ADAPTIVE: [&str; 4] = ["rr", "mir", "mir-resample", "tcas"];

/// The same seed gives the same VPLs, bit for bit, on 1 and 2 threads.
#[test]
fn adaptive_samplers_are_deterministic() {
    let (scene, camera) = setup("office", (48, 27));
    for name in ADAPTIVE {
        let a = two_frames(name, &scene, &camera, 128, 1);
        let b = two_frames(name, &scene, &camera, 128, 2);
        assert!(a[0].stored() > 0, "{name} stored nothing");
        for (x, y) in a.iter().zip(&b) {
            assert!(x.slots() == y.slots(), "{name}: 1 and 2 threads differ");
        }
    }
}

/// Degenerate cases give empty or finite sets, never a panic: a camera that
/// sees nothing (no surface is indirectly visible), a scene whose only light
/// has zero power, and a budget of one VPL.
#[test]
fn adaptive_samplers_survive_degenerate_cases() {
    let (scene, camera) = setup("cornell", (16, 16));
    let away = camera.looking(Vec3::new(0.0, 0.0, 50.0), Vec3::new(0.0, 0.0, 100.0)).unwrap();
    let mut mesh = Mesh::default();
    mesh.push_quad(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(-1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, -1.0), 0);
    let dark = Scene::new(
        "dark",
        &mesh,
        vec![Material::diffuse("m", Vec3::splat(0.5))],
        vec![Light::Point { position: Vec3::Y, intensity: Vec3::ZERO }],
        true,
    );
    for name in ADAPTIVE {
        let nothing = two_frames(name, &scene, &away, 32, 2);
        assert!(nothing.iter().all(|s| s.iter().all(|(_, v)| v.flux.is_finite())), "{name}: non-finite flux");
        if name != "rr" {
            // Only RR (over IR) places VPLs without looking at the camera.
            assert_eq!(nothing[1].stored(), 0, "{name} stored VPLs no camera point can see");
        }
        if let Ok(dark) = &dark {
            let down = camera.looking(Vec3::new(0.0, 1.0, 0.5), Vec3::ZERO).unwrap();
            let sets = two_frames(name, dark, &down, 16, 2);
            assert!(sets.iter().all(|s| s.iter().all(|(_, v)| v.flux == Vec3::ZERO || v.flux.is_finite())), "{name}: dark scene");
        }
        let one = two_frames(name, &scene, &camera, 1, 2);
        assert!(
            one.iter().all(|s| s.len() == 1 && s.iter().all(|(_, v)| v.flux.is_finite() && v.flux.min_element() >= 0.0)),
            "{name}: I = 1"
        );
    }
}

/// RR's overflow branch is unbiased: when more candidates are accepted than
/// there are slots, a uniform random I of the A accepted are kept with
/// flux × A/I. Forced here on `cornell` (16×16, I = 64): frame 0 reads a
/// bright previous image (Φ̃_v high: few accepted, so the next candidate
/// budget is many times I), frame 1 a dark one (Φ̃_v tiny: all accepted,
/// then thinned). Frame 1's mean image over 96 seeds equals IR's over 96
/// other seeds: image-mean |z| < 4 in each channel.
#[test]
fn rr_thinning_of_an_overflow_is_unbiased() {
    let (scene, camera) = setup("cornell", (16, 16));
    let gbuf = render_gbuffer(&scene, &camera);
    let bright = Image { width: 16, height: 16, data: vec![Vec3::splat(1e3); 256] };
    let dark = Image { width: 16, height: 16, data: vec![Vec3::splat(1e-12); 256] };
    let seeds = 96;
    let mut thinned = 0;
    let rr: Vec<Image> = (0..seeds)
        .map(|s| {
            let mut rr = RrSampler::over_ir(RrConfig { vpls: 64, ..RrConfig::default() }, 3, false).unwrap();
            rr.next_frame(&Frame { previous: Some(&bright), ..frame(&scene, &camera, &gbuf, 0, 300 + s) });
            let set = rr.next_frame(&Frame { previous: Some(&dark), ..frame(&scene, &camera, &gbuf, 1, 300 + s) }).clone();
            let st = rr.stats();
            if st.accepted > 64 {
                thinned += 1;
            }
            assert!(st.stored <= 64);
            exhaustive_rt(&scene, &gbuf, &set, None)
        })
        .collect();
    assert_eq!(thinned, seeds, "the overflow branch was not taken in every seed");
    let ir: Vec<Image> = (0..seeds)
        .map(|s| {
            let mut ir = build("ir", 64).unwrap();
            let set = ir.next_frame(&frame(&scene, &camera, &gbuf, 0, 900 + s)).clone();
            exhaustive_rt(&scene, &gbuf, &set, None)
        })
        .collect();
    let (tr, ti) = (totals(&rr), totals(&ir));
    for c in 0..3 {
        let (mr, sr) = vpl_tests::mean_se(&tr.iter().map(|t| t[c]).collect::<Vec<_>>());
        let (mi, si) = vpl_tests::mean_se(&ti.iter().map(|t| t[c]).collect::<Vec<_>>());
        let z = (mr - mi) / (sr * sr + si * si).sqrt();
        eprintln!("channel {c}: RR thinned {mr:.5} ± {sr:.5}, IR {mi:.5} ± {si:.5}, z {z:.2}");
        assert!(z.abs() < 4.0, "channel {c}: RR thinned {mr:.5} ± {sr:.5} against IR {mi:.5} ± {si:.5} (z {z:.2})");
    }
}

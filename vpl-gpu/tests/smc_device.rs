//! The device's SMC ([`vpl_gpu::GpuSmcSampler`]) against the CPU's
//! ([`vpl_smc::SmcSampler`], the reference), both with the paper's kNN
//! flux: the same statistics and the same indirect image mean over seeds.
//!
//! The two draw from different streams where the device's work is shaped
//! differently (candidate rays numbered by camera ray, resampling on f32
//! running sums, visibility draws by a float product), so they agree in
//! distribution, not bit for bit: each seed's pair is a paired sample, and
//! the mean of the paired differences must lie within 4 standard errors of
//! zero (a z-test at 4σ: a true twin fails it once in 16 000 runs) and
//! within 1 % of the CPU's image mean.

mod common;

use common::context;
use vpl_core::glam::Vec3;
use vpl_core::{Frame, GBuffer, IndirectShader, Scene, SceneSetup, VplSampler, VplSet, VplVisibility};
use vpl_gpu::{Gpu, GpuSmcSampler};
use vpl_shading::render_gbuffer;
use vpl_smc::{FluxEstimator, SmcConfig, SmcSampler};

/// The indirect image's mean luminance: every VPL at every pixel, shadow rays.
fn indirect_mean(scene: &Scene, gbuf: &GBuffer, set: &VplSet) -> f64 {
    let mut vis = vpl_visibility::RayTraced::default();
    vis.update(scene, set);
    let img = vpl_shading::ExhaustiveShader { clamp: None }.shade(gbuf, set, &vis);
    let m = img.mean();
    vpl_core::image::luminance(Vec3::new(m[0] as f32, m[1] as f32, m[2] as f32)) as f64
}

fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

struct Run {
    mean: f64,
    cv: f64,
    relit: bool,
    ray_valid: f64,
}

/// `frames` of `setup`'s sequence (the camera and the lights where they
/// move) at `size`; the image mean of the last.
fn run(sampler: &mut dyn VplSampler, setup: &SceneSetup, frames: &[u32], size: (u32, u32), seed: u64, m_max: usize) -> Run {
    let empty = GBuffer::empty();
    let (mut last, mut cv, mut relit, mut ray_valid) = (VplSet::new(0), 0.0, false, 0.0);
    let mut at = None;
    for (i, &f) in frames.iter().enumerate() {
        let (scene, camera) = setup.frame(f).unwrap();
        let camera = camera.with_resolution(size).unwrap();
        let frame = Frame { scene: &scene, camera: &camera, time: f as f32 / 30.0, index: f as u64, seed, gbuffer: &empty, previous: None };
        last = sampler.next_frame(&frame).clone();
        if i > 0 {
            assert!(last.moved_count() <= m_max, "{} moved {} VPLs in a frame, over M_max = {m_max}", sampler.name(), last.moved_count());
        }
        let stats = sampler.stats();
        cv = stats.get("intensity_cv").expect("the intensities' CV");
        ray_valid += stats.get("ray_valid").unwrap_or(0.0);
        relit |= stats.get("relit") == Some(1.0);
        at = Some((scene, camera));
    }
    assert_eq!(last.stored(), last.len(), "every slot holds a VPL");
    let (scene, camera) = at.expect("a frame");
    let gbuf = render_gbuffer(&scene, &camera);
    Run { mean: indirect_mean(&scene, &gbuf, &last), cv, relit, ray_valid }
}

/// Paired runs of the two samplers over `seeds`; `frames` of the scene's sequence.
fn twin(gpu: &Gpu, scene: &str, vpls: usize, seeds: u64, frames: &[u32]) -> (f64, f64) {
    let setup = vpl_core::SceneSetup::builtin(scene).unwrap();
    let size = (48, 36);
    let config = SmcConfig { vpls, m_max: vpls / 16, warmup: 20, flux: FluxEstimator::Knn, ..SmcConfig::default() };
    let (mut diffs, mut cpu_means, mut cv_diffs) = (Vec::new(), Vec::new(), Vec::new());
    let mut ray_valid = 0.0;
    for seed in 1..=seeds {
        let d = run(&mut GpuSmcSampler::new(gpu.clone(), config).unwrap(), &setup, frames, size, seed, config.m_max);
        let c = run(&mut SmcSampler::new(config).unwrap(), &setup, frames, size, seed, config.m_max);
        eprintln!(
            "{scene} seed {seed}: image mean {:.5} device, {:.5} CPU; intensity CV {:.3}, {:.3}; VPLs verified by rays {} and {}",
            d.mean, c.mean, d.cv, c.cv, d.ray_valid, c.ray_valid
        );
        assert_eq!(d.relit, c.relit, "{scene}: both samplers see the lights change, or neither");
        diffs.push(d.mean - c.mean);
        cpu_means.push(c.mean);
        cv_diffs.push(d.cv - c.cv);
        ray_valid += d.ray_valid;
    }
    let (dm, dse) = mean_se(&diffs);
    let (cm, _) = mean_se(&cpu_means);
    let (cvm, cvse) = mean_se(&cv_diffs);
    eprintln!("{scene}: device − CPU image mean {dm:+.5} ± {dse:.5} ({:+.2} %), CV {cvm:+.4} ± {cvse:.4}", 100.0 * dm / cm);
    assert!(dm.abs() <= 4.0 * dse + 1e-12, "{scene}: the image means differ by {dm:+.5}, over 4 standard errors ({dse:.5})");
    assert!(dm.abs() <= 0.01 * cm, "{scene}: the image means differ by {:+.2} %, over 1 %", 100.0 * dm / cm);
    assert!(cvm.abs() <= 4.0 * cvse + 1e-6, "{scene}: the intensities' CV differ by {cvm:+.4}, over 4 standard errors ({cvse:.4})");
    (dm / cm, ray_valid)
}

#[test]
fn the_devices_smc_is_the_cpus_twin() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let seeds = std::env::var("SMC_TWIN_SEEDS").ok().and_then(|s| s.parse().ok()).unwrap_or(8);
    // A still camera: three frames of the start.
    twin(&gpu, "cornell", 256, seeds, &[0, 1, 2]);
    twin(&gpu, "office", 256, seeds, &[0, 1, 2]);
    // The camera and the light move: VPLs the camera no longer sees are
    // verified by rays or replaced, and the set is relit every frame.
    let (_, verified) = twin(&gpu, "atrium", 256, seeds, &[0, 40, 80, 120]);
    assert!(verified > 0.0, "the moving camera made VPLs that rays had to verify");
}

/// The device's sampler reports the lights' change as the CPU's does.
#[test]
fn the_devices_smc_reports_relighting() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("atrium").unwrap();
    let config = SmcConfig { vpls: 64, m_max: 4, warmup: 2, flux: FluxEstimator::Knn, ..SmcConfig::default() };
    let mut dev = GpuSmcSampler::new(gpu, config).unwrap();
    let empty = GBuffer::empty();
    let mut relit = Vec::new();
    for f in [0, 0, 60] {
        let (scene, camera) = setup.frame(f).unwrap();
        let camera = camera.with_resolution((32, 24)).unwrap();
        let frame = Frame { scene: &scene, camera: &camera, time: 0.0, index: f as u64, seed: 1, gbuffer: &empty, previous: None };
        dev.next_frame(&frame);
        relit.push(dev.stats().relit);
    }
    assert_eq!(relit, [false, false, true]);
}

/// Where the device writes timestamps, the sampler times its stages there:
/// each stage's time is non-negative and they add up to the device's time
/// of the iteration (the stamps bracket every dispatch), which the frame's
/// wall time bounds.
#[test]
fn the_devices_smc_times_its_stages_on_the_device() {
    let Some(ctx) = context() else { return };
    let gpu = Gpu::from_context(ctx);
    let setup = SceneSetup::builtin("cornell").unwrap();
    let config = SmcConfig { vpls: 128, warmup: 2, flux: FluxEstimator::Knn, ..SmcConfig::default() };
    let mut dev = GpuSmcSampler::new(gpu.clone(), config).unwrap();
    let timed = dev.profile(true);
    eprintln!("timestamps: {timed}");
    let empty = GBuffer::empty();
    let camera = setup.camera.with_resolution((32, 32)).unwrap();
    for f in 0..2 {
        let frame = Frame { scene: &setup.scene, camera: &camera, time: 0.0, index: f, seed: 1, gbuffer: &empty, previous: None };
        dev.next_frame(&frame);
    }
    let t = dev.timings();
    let wall = VplSampler::stats(&dev).get("ms").unwrap();
    eprintln!("{t:?}, wall {wall} ms");
    if !timed {
        assert!(!gpu.ctx().has_timestamps());
        assert_eq!(t.total_ms, wall);
        return;
    }
    let parts = [t.candidates_ms, t.resampling_ms, t.visibility_ms, t.radiosity_ms, t.knn_ms];
    assert!(parts.iter().all(|&p| p >= 0.0 && p.is_finite()), "{t:?}");
    let sum: f64 = parts.iter().sum();
    assert!((sum - t.total_ms).abs() <= 1e-6 * t.total_ms.max(1.0), "the stages add to {sum} ms, the iteration took {} ms", t.total_ms);
    assert!(t.total_ms > 0.0 && t.total_ms <= wall, "{} ms on the device in a frame of {wall} ms", t.total_ms);
    assert!(VplSampler::stats(&dev).get("knn_ms").is_some());
}

/// The backend offers its device twin by the registry entry's name and
/// parameters: `smc-knn` (the paper's flux at the sites) runs on the
/// device, as does `smc` told to use it; the toolkit's default `smc` (the
/// Voronoi flux), `smc-knn` told to place at centroids, other samplers and
/// parameters that do not parse get none (the host entry runs, and reports
/// the parameter's error).
#[test]
fn the_backend_offers_its_smc_for_the_paper_settings_only() {
    let Some(ctx) = context() else { return };
    let backend = vpl_gpu::GpuBackend::new(Gpu::from_context(ctx));
    let services = vpl_render::Backend::services(&backend);
    let twins = services.samplers.clone().expect("the GPU backend runs samplers on its device");
    let budget = vpl_core::Budget::new(64, 5);
    let offered = |name: &str, params: &[&str]| {
        let p = vpl_core::Params::parse(params.iter().copied()).unwrap();
        twins.twin(name, &budget, &p).map(|r| r.is_ok())
    };
    assert_eq!(offered("smc-knn", &[]), Some(true));
    assert_eq!(offered("smc", &["flux=knn"]), Some(true));
    assert_eq!(offered("smc", &[]), None);
    assert_eq!(offered("smc-knn", &["placement=centroid"]), None);
    assert_eq!(offered("smc-knn", &["m-max=many"]), None);
    assert_eq!(offered("ir", &[]), None);
    let err = vpl_sampling::Registry::builtin().build("smc-knn", budget, &services, &vpl_core::Params::parse(["m-max=many"]).unwrap());
    assert!(err.is_err_and(|e| e.to_string().contains("m-max")));
}

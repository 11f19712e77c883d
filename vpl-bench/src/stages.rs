//! Timing the stages of a VPL frame (`vpl bench-vpl`, `cargo xtask bench-vpl`).

use std::time::Instant;
use vpl_core::{CoreError, GeometryClamp, IndirectShader, Vpl, VplVisibility};
use vpl_sampling::{InstantRadiosity, IrConfig, Registry};
use vpl_scene_io::SceneIoError;
use vpl_shading::{InterleavedShader, direct_light, render_gbuffer};
use vpl_visibility::ShadowMaps;

/// Median milliseconds per stage.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageBench {
    /// Camera rays into the G-buffer.
    pub gbuffer: f64,
    /// Direct light, 16 light samples per pixel.
    pub direct: f64,
    /// Instant Radiosity light paths.
    pub sampling: f64,
    /// Shadow maps of all VPLs, from scratch.
    pub shadow_maps_all: f64,
    /// Shadow maps after 16 VPLs moved.
    pub shadow_maps_16: f64,
    /// Interleaved gathering (VPL-major, shadow-map visibility).
    pub gather: f64,
    /// Cross-bilateral filter.
    pub filter: f64,
    /// G-buffer + 16 shadow maps + gather + filter: an indirect frame in
    /// which 16 VPLs changed (what a temporally coherent sampler pays).
    pub indirect_frame: f64,
}

/// The median of `v` (the upper one of an even count; 0 when empty).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

fn time<T>(repeat: u32, mut f: impl FnMut() -> T) -> f64 {
    median(
        (0..repeat)
            .map(|_| {
                let t = Instant::now();
                std::hint::black_box(f());
                t.elapsed().as_secs_f64() * 1e3
            })
            .collect(),
    )
}

/// Times each stage on built-in scene `name` at `size` with `vpls` IR VPLs.
pub fn bench_stages(name: &str, size: (u32, u32), vpls: usize, repeat: u32) -> Result<StageBench, SceneIoError> {
    let setup = vpl_scene_io::load(name)?;
    let scene = &setup.scene;
    let camera = setup.camera.with_resolution(size)?;
    let mut b = StageBench { gbuffer: time(repeat, || render_gbuffer(scene, &camera)), ..StageBench::default() };
    let gbuf = render_gbuffer(scene, &camera);
    b.direct = time(repeat, || direct_light(scene, &gbuf, 16, 0));
    let mut ir = InstantRadiosity::new(IrConfig { vpls, ..IrConfig::default() }).map_err(|e| CoreError::Invalid(e.to_string()))?;
    b.sampling = time(repeat, || ir.sample(scene, 0).stored());
    let mut set = ir.sample(scene, 0).clone();
    b.shadow_maps_all = time(repeat.min(3), || {
        let mut sm = ShadowMaps::new(128).expect("valid resolution");
        sm.update(scene, &set).rebuilt
    });
    let mut sm = ShadowMaps::new(128).expect("valid resolution");
    sm.update(scene, &set);
    let movable: Vec<(usize, Vpl)> = set.iter().map(|(s, v)| (s, *v)).step_by(7).take(16).collect();
    let mut round = 0u32;
    b.shadow_maps_16 = time(repeat, || {
        round += 1;
        set.begin_frame();
        for (s, v) in &movable {
            set.set(*s, Some(Vpl { y: v.y + v.n * (1e-3 * round as f32), ..*v }));
        }
        sm.update(scene, &set).rebuilt
    });
    let mut shader = InterleavedShader::new(Some(GeometryClamp::for_view(vpls, scene, &camera)), 0);
    let mut gathers = Vec::new();
    let mut filters = Vec::new();
    for _ in 0..repeat {
        std::hint::black_box(shader.shade(&gbuf, &set, &sm));
        gathers.push(shader.timings().gather_ms);
        filters.push(shader.timings().filter_ms);
    }
    b.gather = median(gathers);
    b.filter = median(filters);
    b.indirect_frame = b.gbuffer + b.shadow_maps_16 + b.gather + b.filter;
    Ok(b)
}

/// Median milliseconds per step of the SMC sampler, in the columns of the
/// SMC paper's Table 2 ("Sampling VPLs").
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SmcBench {
    /// Camera points, candidate rays, undersampled regions, replacement.
    pub candidates: f64,
    /// Drawing candidates from the weighted hits.
    pub resampling: f64,
    /// Mailboxes and rays toward unverified VPLs.
    pub visibility: f64,
    /// Radiosity estimates (16 NEE paths per candidate).
    pub radiosity: f64,
    /// k-d trees and kNN queries.
    pub knn: f64,
    /// The whole sampler step.
    pub total: f64,
    /// VPLs that moved per frame (median).
    pub moved: f64,
}

/// Times `repeat` SMC frames on built-in scene `name` with budget `vpls`,
/// the camera walking the scene's sequence from frame `start` (one frame a
/// step, so indirect visibility has work), after a 20-iteration warm-up at
/// that frame (not timed).
pub fn bench_smc(name: &str, size: (u32, u32), vpls: usize, start: u32, repeat: u32) -> Result<SmcBench, SceneIoError> {
    let setup = vpl_scene_io::load(name)?;
    let config = vpl_sampling::SmcConfig { vpls, ..vpl_sampling::SmcConfig::default() };
    let mut smc = vpl_sampling::SmcSampler::new(config).map_err(|e| CoreError::Invalid(e.to_string()))?;
    let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
    let frame = |f: u32| -> Result<_, SceneIoError> {
        let (scene, camera) = setup.frame((start + f).min(count - 1))?;
        Ok((scene, camera.with_resolution(size)?))
    };
    let (scene, camera) = frame(0)?;
    for _ in 0..20 {
        smc.iterate(&scene, &camera, 0);
    }
    let mut rows: Vec<[f64; 7]> = Vec::new();
    for f in 1..=repeat {
        let (scene, camera) = frame(f)?;
        let moved = smc.iterate(&scene, &camera, 0).moved_count() as f64;
        let t = smc.timings();
        rows.push([t.candidates_ms, t.resampling_ms, t.visibility_ms, t.radiosity_ms, t.knn_ms, t.total_ms, moved]);
    }
    let col = |i: usize| median(rows.iter().map(|r| r[i]).collect());
    Ok(SmcBench {
        candidates: col(0),
        resampling: col(1),
        visibility: col(2),
        radiosity: col(3),
        knn: col(4),
        total: col(5),
        moved: col(6),
    })
}

/// One sampler's cost per frame ([`bench_samplers`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SamplerBench {
    /// Registry name.
    pub name: String,
    /// Milliseconds of the first frame (warm-up, RSMs, pilot).
    pub first_ms: f64,
    /// Median milliseconds of the following frames.
    pub frame_ms: f64,
    /// Median VPL slots moved per frame.
    pub moved: f64,
    /// Median VPLs stored.
    pub stored: f64,
}

/// Every sampler of `registry` on `name`'s sequence from frame `start`
/// (the camera walking one frame at a time): `next_frame` time of the first
/// frame, and the median over the next `repeat` frames. RR reads its own
/// estimate of the image (no images are rendered here); IR draws fresh paths.
pub fn bench_samplers(
    registry: &Registry,
    name: &str,
    size: (u32, u32),
    vpls: usize,
    start: u32,
    repeat: u32,
) -> Result<Vec<SamplerBench>, SceneIoError> {
    let setup = vpl_scene_io::load(name)?;
    let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
    let gbuf = vpl_core::GBuffer::empty();
    let mut out = Vec::new();
    let mut params = vpl_core::Params::new();
    params.offer("fresh-paths", true);
    for entry in registry.entries() {
        let mut s = registry
            .build(&entry.name, vpl_core::Budget::new(vpls, 5), &vpl_core::Services::cpu(), &params)
            .map_err(|e| CoreError::Invalid(e.to_string()))?;
        let mut rows: Vec<[f64; 3]> = Vec::new();
        let mut first_ms = 0.0;
        for f in 0..=repeat {
            let (scene, camera) = setup.frame((start + f).min(count - 1))?;
            let camera = camera.with_resolution(size)?;
            let frame =
                vpl_core::Frame { scene: &scene, camera: &camera, time: 0.0, index: f as u64, seed: 0, gbuffer: &gbuf, previous: None };
            let t = std::time::Instant::now();
            let set = s.next_frame(&frame);
            let ms = t.elapsed().as_secs_f64() * 1e3;
            if f == 0 {
                first_ms = ms;
            } else {
                rows.push([ms, set.moved_count() as f64, set.stored() as f64]);
            }
        }
        let col = |i: usize| median(rows.iter().map(|r| r[i]).collect());
        out.push(SamplerBench { name: entry.name.clone(), first_ms, frame_ms: col(0), moved: col(1), stored: col(2) });
    }
    Ok(out)
}

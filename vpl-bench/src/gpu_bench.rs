//! `vpl bench-gpu` (`cargo xtask bench-gpu`): milliseconds per kernel and
//! per indirect frame of the GPU backend, SMC sampling with its rays and
//! radiosity estimates on the GPU.

use crate::error::BenchError;
pub use crate::smc_step::SmcPlace;
use crate::smc_step::SmcStep;
use crate::stages::median;
use serde::Serialize;
use std::fmt::Write as _;
use std::time::Instant;
use vpl_core::{Frame, GeometryClamp, IndirectShader, VplVisibility};
use vpl_gpu::{Gpu, GpuInterleavedShader, GpuShadowMaps, Traffic};
use vpl_sampling::SmcConfig;

/// Medians of one scene's timed frames, milliseconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GpuBenchRow {
    /// Built-in scene.
    pub scene: String,
    /// Triangles.
    pub triangles: usize,
    /// VPL budget.
    pub vpls: usize,
    /// Image size.
    pub size: (u32, u32),
    /// G-buffer kernel (camera rays over the device BVH).
    pub gbuffer: f64,
    /// Reading the G-buffer back for the CPU sampler.
    pub gbuffer_read: f64,
    /// The SMC sampler's step (CPU, its rays on the GPU).
    pub sampling: f64,
    /// Of which: camera points, candidate rays and indirect visibility
    /// (on the host: rays on the device, bookkeeping on the host).
    pub smc_rays: f64,
    /// Of which: radiosity estimates (16 NEE paths per candidate and new
    /// VPL, on the device either way).
    pub smc_radiosity: f64,
    /// Of which: kNN densities (and on the host the cells; on the device
    /// the grids, their queries, the densities and fluxes).
    pub smc_knn: f64,
    /// Shadow maps of the moved VPLs (one dispatch).
    pub shadow_maps: f64,
    /// Median VPLs moved per frame.
    pub moved: f64,
    /// All maps at once (the first frame: every slot is new), and how many.
    pub all_maps: f64,
    /// Maps rendered in the first frame.
    pub all_maps_count: usize,
    /// Uploading the VPLs.
    pub upload: f64,
    /// Interleaved gathering with shadow-map lookups and the clamp.
    pub gather: f64,
    /// Cross-bilateral filter and albedo.
    pub filter: f64,
    /// Reading the image back.
    pub image_read: f64,
    /// The device kernels of a frame: G-buffer + shadow maps + gather + filter.
    pub kernels: f64,
    /// The whole indirect frame as run: sampling, kernels, uploads and read-backs.
    pub frame: f64,
    /// Whether the frame stayed on the device (G-buffer and image not read
    /// back), as a renderer under `ReadBack::Nothing` runs it.
    pub resident: bool,
    /// Where SMC's iteration ran.
    pub smc: SmcPlace,
    /// Host↔device traffic of a frame (medians of each count).
    pub traffic: Traffic,
    /// Of which: the SMC sampler's step.
    pub sampling_traffic: Traffic,
}

/// Per-field medians of traffic readings.
fn median_traffic(t: &[Traffic]) -> Traffic {
    let m = |f: fn(&Traffic) -> u64| median(t.iter().map(|x| f(x) as f64).collect()).round() as u64;
    Traffic {
        bytes_up: m(|x| x.bytes_up),
        bytes_down: m(|x| x.bytes_down),
        writes: m(|x| x.writes),
        reads: m(|x| x.reads),
        submissions: m(|x| x.submissions),
    }
}

/// One scene's benchmark.
#[derive(Clone, Copy, Debug)]
pub struct GpuBenchSpec<'a> {
    /// Built-in scene or scene file.
    pub scene: &'a str,
    /// Image size.
    pub size: (u32, u32),
    /// VPL budget.
    pub vpls: usize,
    /// First frame of the scene's sequence.
    pub start: u32,
    /// Timed frames (after one untimed warm-up frame).
    pub frames: u32,
    /// Whether the frame stays on the device (the G-buffer and the image
    /// not read back), as a renderer under `ReadBack::Nothing` runs it.
    pub resident: bool,
    /// Where SMC runs.
    pub smc: SmcPlace,
}

/// Times `frames` frames (after one untimed warm-up frame, which compiles
/// the kernels and renders every map) of `scene`'s sequence from frame
/// `start` at `size` with `vpls` SMC VPLs, 128² maps, 4×4 interleaved
/// shading with the filter and G_max = I / A_view. Every step is waited for on
/// the device, so the times add up. With `resident` the frame stays on the
/// device (the G-buffer and the image are not read back); without, both are
/// read back as a host-side renderer needs them.
pub fn bench_scene(gpu: &Gpu, spec: &GpuBenchSpec) -> Result<GpuBenchRow, BenchError> {
    let GpuBenchSpec { scene, size, vpls, start, frames, resident, smc: place } = *spec;
    let setup = vpl_scene_io::load(scene)?;
    let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
    let services = vpl_render::Backend::services(&vpl_gpu::GpuBackend::new(gpu.clone()));
    let config = SmcConfig { vpls, ..SmcConfig::default() };
    let mut smc = match place {
        SmcPlace::Host => SmcStep::host(config, &services)?,
        SmcPlace::Device => SmcStep::device(gpu, config)?,
    };
    let mut maps = GpuShadowMaps::new(gpu.clone(), vpl_visibility::DEFAULT_RESOLUTION)?;
    let clamp = GeometryClamp::for_view(vpls, &setup.scene, &setup.camera);
    let mut shader = GpuInterleavedShader::new(gpu.clone(), Some(clamp), 0);
    // The gather and the filter timed apart (one more submission a frame).
    shader.profile(true);
    shader.keep_on_device(resident);
    let mut rows: Vec<[f64; 14]> = Vec::new();
    let mut traffic = Vec::new();
    let mut first = (0.0, 0);
    for k in 0..=frames {
        let f = (start + k).min(count - 1);
        let (sc, camera) = setup.frame(f)?;
        let camera = camera.with_resolution(size)?;
        let t_frame = Instant::now();
        let tr0 = gpu.traffic();
        let gbuf = if resident { gpu.render_gbuffer_on_device(&sc, &camera)? } else { gpu.render_gbuffer(&sc, &camera)? };
        let (g_ms, g_read) = gpu.gbuffer_timings();
        let frame = Frame { scene: &sc, camera: &camera, time: f as f32 / 30.0, index: f as u64, seed: 0, gbuffer: &gbuf, previous: None };
        let t0 = Instant::now();
        let tr1 = gpu.traffic();
        let set = smc.next_frame(&frame).clone();
        let tr2 = gpu.traffic();
        let s_ms = t0.elapsed().as_secs_f64() * 1e3;
        let st = smc.timings();
        let t0 = Instant::now();
        let u = maps.update(&sc, &set);
        let m_ms = t0.elapsed().as_secs_f64() * 1e3;
        std::hint::black_box(shader.shade(&gbuf, &set, &maps));
        let total = t_frame.elapsed().as_secs_f64() * 1e3;
        let tr3 = gpu.traffic();
        let d = shader.device_timings();
        if k == 0 {
            first = (m_ms, u.rebuilt);
        } else {
            traffic.push((tr3 - tr0, tr2 - tr1));
            rows.push([
                g_ms,
                g_read,
                s_ms,
                m_ms,
                set.moved_count() as f64,
                d.upload_ms,
                d.gather_ms,
                d.filter_ms,
                d.read_ms,
                g_ms + m_ms + d.gather_ms + d.filter_ms,
                total,
                st.candidates_ms + st.visibility_ms,
                st.radiosity_ms,
                st.knn_ms,
            ]);
        }
    }
    let col = |i: usize| median(rows.iter().map(|r| r[i]).collect());
    Ok(GpuBenchRow {
        scene: scene.into(),
        triangles: setup.scene.geometry.triangles.len(),
        vpls,
        size,
        gbuffer: col(0),
        gbuffer_read: col(1),
        sampling: col(2),
        smc_rays: col(11),
        smc_radiosity: col(12),
        smc_knn: col(13),
        shadow_maps: col(3),
        moved: col(4),
        all_maps: first.0,
        all_maps_count: first.1,
        upload: col(5),
        gather: col(6),
        filter: col(7),
        image_read: col(8),
        kernels: col(9),
        frame: col(10),
        resident,
        smc: place,
        traffic: median_traffic(&traffic.iter().map(|t| t.0).collect::<Vec<_>>()),
        sampling_traffic: median_traffic(&traffic.iter().map(|t| t.1).collect::<Vec<_>>()),
    })
}

/// The report: a Markdown table, one row per scene, and the adapter.
pub fn report(adapter: &str, rows: &[GpuBenchRow], frames: u32, threads: usize) -> String {
    let mut md = String::from("# GPU backend: milliseconds per kernel and per indirect frame\n\n");
    let _ = writeln!(
        md,
        "Adapter: **{adapter}**. Medians over {frames} frames after a warm-up frame; SMC sampling with its rays (camera points, candidates, indirect visibility) and radiosity estimates on the GPU, the rest (kNN, bookkeeping) on the CPU ({threads} threads); \
         128² paraboloid shadow maps of the moved VPLs by ray casting; 4×4 interleaved shading with the clamp; the cross-bilateral \
         filter. Each step is waited for, so the columns add up: *kernels* = G-buffer + shadow maps + gather + filter, *frame* = \
         everything including sampling, uploads and read-backs.\n"
    );
    md.push_str("*SMC*: `host` is the default SMC (Voronoi flux) on the host with its rays and radiosities on the device; `device` is SMC with the paper's kNN flux, every line of Algorithm 1 on the device.\n\n");
    md.push_str("| scene | SMC | triangles | VPLs | size | G-buffer | G-buffer read | SMC sampling | shadow maps (moved) | upload | gather | filter | image read | kernels | frame | all maps (first frame) |\n");
    md.push_str("| --- | --- | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for r in rows {
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {} | {}×{} | {:.2} | {:.2} | {:.2} | {:.2} ({:.0}) | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} ({}) |",
            r.scene,
            r.smc.name(),
            r.triangles,
            r.vpls,
            r.size.0,
            r.size.1,
            r.gbuffer,
            r.gbuffer_read,
            r.sampling,
            r.shadow_maps,
            r.moved,
            r.upload,
            r.gather,
            r.filter,
            r.image_read,
            r.kernels,
            r.frame,
            r.all_maps,
            r.all_maps_count
        );
    }
    md.push_str("\nSMC sampling by step (ms). *host*: rays and radiosity on the device, kNN and the cells on the host; *device*: every stage on the device, timed there by timestamps (0 where the adapter has none):\n\n| scene | SMC | camera, candidate and visibility rays | radiosity (16 NEE paths per candidate and new VPL) | kNN | total |\n| --- | --- | ---: | ---: | ---: | ---: |\n");
    for r in rows {
        let _ = writeln!(
            md,
            "| `{}` | {} | {:.2} | {:.2} | {:.2} | {:.2} |",
            r.scene,
            r.smc.name(),
            r.smc_rays,
            r.smc_radiosity,
            r.smc_knn,
            r.sampling
        );
    }
    md.push_str("\nHost↔device traffic per frame (medians; the counts do not depend on the device's speed). *Resident*: the G-buffer and the image stay on the device; otherwise both are read back every frame:\n\n| scene | SMC | resident | up (KiB) | writes | down (KiB) | reads | submissions | of which SMC: up (KiB) | down (KiB) | submissions |\n| --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    let kib = |b: u64| b as f64 / 1024.0;
    for r in rows {
        let (t, s) = (r.traffic, r.sampling_traffic);
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {:.1} | {} | {:.1} | {} | {} | {:.1} | {:.1} | {} |",
            r.scene,
            r.smc.name(),
            if r.resident { "yes" } else { "no" },
            kib(t.bytes_up),
            t.writes,
            kib(t.bytes_down),
            t.reads,
            t.submissions,
            kib(s.bytes_up),
            kib(s.bytes_down),
            s.submissions
        );
    }
    md
}

/// Table 1's ground truth on the CPU and on the device, side by side
/// ([`bench_truth`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TruthBench {
    /// Table 1 sequence (its scene, first quick-profile frame, tracked pixels).
    pub row: String,
    /// Tracked pixels.
    pub pixels: usize,
    /// Samples per pixel.
    pub spp: u32,
    /// Seconds of the CPU truth's sampling (`vpl_pathtrace::track_with`, all
    /// CPU threads of the pool).
    pub cpu_seconds: f64,
    /// Seconds of the device truth's sampling ([`vpl_gpu::GpuTracker::track`],
    /// its kernels compiled and the scene uploaded beforehand).
    pub gpu_seconds: f64,
}

impl TruthBench {
    /// Paths a second on the CPU and on the device.
    pub fn paths_per_second(&self) -> (f64, f64) {
        let n = self.pixels as f64 * self.spp as f64;
        (n / self.cpu_seconds.max(1e-9), n / self.gpu_seconds.max(1e-9))
    }
}

/// One truth frame of Table 1's sequence `row` (its first quick-profile
/// frame, the quick profile's size and depth, `spp` samples at each tracked
/// pixel) as the harness makes it ([`crate::table1::truth::Truth`]), on the
/// CPU and then on `gpu`, each after a warm-up unit of 1/16 of the samples;
/// the time is the unit's sampling, without its set-up.
pub fn bench_truth(gpu: &Gpu, row: &str, spp: u32) -> Result<TruthBench, BenchError> {
    use crate::pipeline::BackendKind;
    use crate::table1::truth::Truth;
    use crate::table1::{Table1Error, Table1Spec};
    let r = crate::table1::rows::row(row).ok_or_else(|| vpl_core::CoreError::Invalid(format!("no Table 1 sequence '{row}'")))?;
    let quick = Table1Spec::quick();
    let time = |truth: &mut Truth, backend: BackendKind| -> Result<(f64, usize), Table1Error> {
        let spec = |truth_spp: u32| Table1Spec { truth_spp, backend, ..quick.clone() };
        truth.unit(&spec((spp / 16).max(1)), &r, r.quick_frames.start)?;
        let u = truth.unit(&spec(spp), &r, r.quick_frames.start)?;
        Ok((u.seconds - u.setup_seconds, u.mean.len()))
    };
    let bench = |e: Table1Error| vpl_core::CoreError::Invalid(e.to_string());
    let (cpu_seconds, pixels) = time(&mut Truth::new(), BackendKind::Cpu).map_err(bench)?;
    let (gpu_seconds, _) = time(&mut Truth::on(gpu.clone()), BackendKind::Gpu).map_err(bench)?;
    Ok(TruthBench { row: row.into(), pixels, spp, cpu_seconds, gpu_seconds })
}

/// A Markdown table of [`bench_truth`] rows.
pub fn truth_report(adapter: &str, rows: &[TruthBench], threads: usize) -> String {
    let mut md = format!(
        "\n## Table 1's ground truth, CPU ({threads} threads) and {adapter}\n\nOne truth frame each (320×240, indirect light, depth 5, rays through the tracked pixels' centres), timed one after the other in this run.\n\n| sequence | pixels | samples | CPU s | GPU s | CPU M paths/s | GPU M paths/s | GPU speed-up |\n| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n"
    );
    for r in rows {
        let (c, g) = r.paths_per_second();
        let _ = writeln!(
            md,
            "| `{}` | {} | {} | {:.3} | {:.3} | {:.2} | {:.2} | {:.2}× |",
            r.row,
            r.pixels,
            r.spp,
            r.cpu_seconds,
            r.gpu_seconds,
            c / 1e6,
            g / 1e6,
            r.cpu_seconds / r.gpu_seconds.max(1e-9)
        );
    }
    md
}

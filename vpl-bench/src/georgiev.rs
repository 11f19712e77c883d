//! Reproduces Georgiev & Slusallek's claims (EG 2010, §4): on the `corner`
//! scene (their EG scene: a point light around the corner behind the
//! camera) Russian-roulette acceptance discards most VPL candidates
//! (paper: mean acceptance 0.07) and is more than an order of magnitude more
//! efficient than plain IR at the same number of stored VPLs. Also the mean
//! acceptance on `cornell` and `office`.
//!
//! Efficiency is 1 / (MSE · cost), with the cost in CPU seconds of the
//! process (which do not move with the machine's load) and, beside it, in
//! wall seconds of the frame's sampling, visibility and shading. MSE is a
//! frame's indirect image against the path tracer's, traced through the
//! same pixel centres that VPL shading sees and clamped by the same rule as
//! the VPLs, with the reference's own variance (from its per-pixel standard
//! errors) subtracted. Both methods use ray-traced visibility and exhaustive
//! shading, so only the VPLs differ.

use crate::error::BenchError;
use crate::metrics::{mse, reference_variance};
use crate::pipeline::{BackendKind, PipelineSpec, ShadingSpec, VisibilitySpec};
use rayon::prelude::*;
use std::fmt::Write as _;
use vpl_core::glam::Vec3;
use vpl_core::{Budget, Camera, GeometryClamp, Image, Mode, Params, Purpose, Scene, SceneSetup, stream};
use vpl_pathtrace::PathTracer;
use vpl_sampling::{Registry, RrConfig};

/// Settings of the experiment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeorgievSettings {
    /// Image size.
    pub size: (u32, u32),
    /// Stored VPLs I of both methods.
    pub vpls: usize,
    /// Frames before measuring (RR learns Φ̃_total from them).
    pub warmup_frames: u32,
    /// Frames measured.
    pub frames: u32,
    /// Samples per pixel of the path-traced reference.
    pub reference_spp: u32,
    /// Seed.
    pub seed: u64,
    /// RR's settings (its budget is `vpls`).
    pub rr: RrConfig,
}

/// What [`georgiev`] produced.
#[derive(Clone, Debug)]
pub struct GeorgievReport {
    /// The Markdown report.
    pub markdown: String,
    /// CSV rows: scene, method, epsilon, stored, acceptance, mse, ms.
    pub csv: String,
    /// The path-traced reference of `corner` (pixel centres).
    pub reference: Image,
    /// IR's last measured frame.
    pub ir: Image,
    /// RR's last measured frame (the settings' ε).
    pub rr: Image,
}

/// One method's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MethodFigures {
    /// Mean MSE of a frame against the reference, its noise removed.
    pub mse: f64,
    /// Mean milliseconds of a frame (sampling + visibility + shading), wall time.
    pub ms: f64,
    /// Mean CPU milliseconds of the process per frame (the whole frame, all
    /// threads; [`crate::cpu_time`]): a cost that does not move with the
    /// machine's load. 0 where the CPU time cannot be read.
    pub cpu_ms: f64,
    /// Mean VPLs stored.
    pub stored: f64,
    /// Mean acceptance probability (1 for IR).
    pub acceptance: f64,
}

impl MethodFigures {
    /// 1 / (MSE · seconds), the seconds of wall time.
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.mse * self.ms * 1e-3)
    }

    /// 1 / (MSE · seconds), the seconds of CPU time.
    pub fn efficiency_cpu(&self) -> f64 {
        1.0 / (self.mse * self.cpu_ms * 1e-3)
    }
}

fn spec(sampler: &str, s: &GeorgievSettings, clamp: GeometryClamp) -> PipelineSpec {
    let mut params = Params::new();
    params.offer("fresh-paths", true);
    params.offer("rr-epsilon", s.rr.epsilon).offer("camera-samples", s.rr.camera_samples).offer("rr-pilot", s.rr.pilot);
    params.offer("rr-max-candidates", s.rr.max_candidates_factor);
    PipelineSpec {
        sampler: sampler.into(),
        params,
        budget: Budget::new(s.vpls, 5),
        visibility: VisibilitySpec::RayTraced,
        shading: ShadingSpec::Exhaustive,
        clamp: vpl_render::Clamp::Value(clamp),
        compensation: 0,
        mode: Mode::Indirect,
        direct_samples: 1,
        seed: s.seed,
        backend: BackendKind::Cpu.name().into(),
    }
}

/// Runs `sampler` on `scene` frame 0 for warm-up + measured frames; with a
/// reference, measures relMSE. Returns the figures of the measured frames.
/// The path tracer's image through the pixel centres (the points VPL
/// shading lights), `spp` paths a pixel, with per-pixel standard errors.
pub fn centre_reference(scene: &Scene, camera: &Camera, pt: &PathTracer, spp: u32, seed: u64) -> (Image, Image) {
    let (w, h) = camera.resolution;
    let px: Vec<(Vec3, Vec3)> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let ray = camera.ray((i % w) as f32 + 0.5, (i / w) as f32 + 0.5, (0.5, 0.5));
            let mut rng = stream(seed, 0, Purpose::PIXEL, i as u64);
            let (mut sum, mut sq) = (Vec3::ZERO, Vec3::ZERO);
            for _ in 0..spp {
                let l = pt.li(scene, ray, &mut rng);
                sum += l;
                sq += l * l;
            }
            let n = spp as f32;
            let mean = sum / n;
            let var = if spp > 1 { ((sq - sum * mean) / (n - 1.0)).max(Vec3::ZERO) } else { Vec3::ZERO };
            (mean, (var / n).map(f32::sqrt))
        })
        .collect();
    let img = |f: fn(&(Vec3, Vec3)) -> Vec3| Image { width: w, height: h, data: px.iter().map(f).collect() };
    (img(|p| p.0), img(|p| p.1))
}

fn run(
    scene_name: &str,
    sampler: &str,
    s: &GeorgievSettings,
    reference: Option<(&Image, f64)>,
    progress: &dyn Fn(&str),
) -> Result<(MethodFigures, Image), BenchError> {
    let setup = vpl_scene_io::load(scene_name)?;
    let camera = setup.camera.with_resolution(s.size)?;
    let clamp = GeometryClamp::for_view(s.vpls, &setup.scene, &camera);
    let mut p = spec(sampler, s, clamp).build(&Registry::builtin(), &crate::pipeline::backends(), &setup.scene)?;
    let mut f = MethodFigures::default();
    let mut last = Image::new(s.size.0, s.size.1);
    for i in 0..s.warmup_frames + s.frames {
        let cpu0 = crate::cpu_time::process_cpu_seconds();
        let out = p.render(&setup.scene, &camera, i as u64, 0.0)?;
        let cpu = crate::cpu_time::process_cpu_seconds().zip(cpu0).map_or(0.0, |(b, a)| (b - a) * 1e3);
        progress(&format!("{scene_name} {sampler} frame {i}: {}", out.sampler_stats));
        if i < s.warmup_frames {
            continue;
        }
        let n = s.frames as f64;
        if let Some((r, var)) = reference {
            f.mse += (mse(&out.image, r)? - var) / n;
        }
        f.ms += (out.timings.sampling_ms + out.timings.visibility_ms + out.timings.shading_ms) / n;
        f.cpu_ms += cpu / n;
        let acc = out.sampler_stats.get("acceptance").unwrap_or(1.0);
        f.acceptance += acc / n;
        f.stored += out.stored as f64 / n;
        last = out.image;
    }
    Ok((f, last))
}

/// The experiment; returns the Markdown report and the CSV rows. Besides
/// `s.rr`, RR runs on `corner` with each ε of `sweep` (the rest of its
/// settings as `s.rr`), to show how the gain depends on ε.
pub fn georgiev(s: &GeorgievSettings, sweep: &[f32], progress: &dyn Fn(&str)) -> Result<GeorgievReport, BenchError> {
    let setup = SceneSetup::builtin("corner")?;
    let camera = setup.camera.with_resolution(s.size)?;
    let clamp = GeometryClamp::for_view(s.vpls, &setup.scene, &camera);
    let mut pt = PathTracer::new(5, Mode::Indirect);
    pt.clamp = Some(clamp);
    progress(&format!("corner reference: path tracer, indirect, {} spp", s.reference_spp));
    // The reference draws the materials as the VPL methods do.
    let truth_scene = setup.scene.with_material_policy(vpl_core::MaterialPolicy::Diffuse);
    let (reference, stderr) = centre_reference(&truth_scene, &camera, &pt, s.reference_spp, s.seed ^ 0xEF);
    let var = reference_variance(&stderr);
    let (ir, ir_image) = run("corner", "ir", s, Some((&reference, var)), progress)?;
    let (rr, rr_image) = run("corner", "rr", s, Some((&reference, var)), progress)?;
    let gain = rr.efficiency() / ir.efficiency();
    let gain_cpu = rr.efficiency_cpu() / ir.efficiency_cpu();
    let mut swept = Vec::new();
    for &epsilon in sweep.iter().filter(|&&e| e != s.rr.epsilon) {
        let t = GeorgievSettings { rr: RrConfig { epsilon, ..s.rr }, ..*s };
        swept.push((epsilon, run("corner", "rr", &t, Some((&reference, var)), progress)?.0));
    }
    let mut acc = Vec::new();
    for scene in ["cornell", "office", "corner"] {
        let f = if scene == "corner" { rr } else { run(scene, "rr", s, None, progress)?.0 };
        acc.push((scene, f.acceptance, f.stored));
    }
    let mut md = String::new();
    let _ = writeln!(md, "# Georgiev & Slusallek (EG 2010): Russian-roulette VPL acceptance\n");
    let _ = writeln!(
        md,
        "`corner` (the paper's EG scene), frame 0, {}x{}, I = {} stored VPLs, ray-traced visibility, exhaustive shading, clamp G_max = I/A_view = {:.2} m^-2 for both; {} warm-up frames (RR learns Phi_total from the previous frame's indirect image), then {} measured frames; reference: path tracer through the pixel centres, indirect, same clamp, {} spp; MSE is against it with its own variance ({:.3e}, from its per-pixel standard errors) subtracted. IR uses fresh light paths every frame. Seed {}.\n",
        s.size.0, s.size.1, s.vpls, clamp.g_max, s.warmup_frames, s.frames, s.reference_spp, var, s.seed
    );
    let _ = writeln!(
        md,
        "| method | stored VPLs | mean acceptance | MSE | wall ms / frame | CPU ms / frame | efficiency 1/(MSE·s), CPU | efficiency 1/(MSE·s), wall |"
    );
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- | --- | --- |");
    let rr_name = format!("RR (eps {}, N_C {})", s.rr.epsilon, s.rr.camera_samples);
    for (name, f) in [("IR", ir), (rr_name.as_str(), rr)] {
        let _ = writeln!(
            md,
            "| {name} | {:.0} | {:.3} | {:.3e} | {:.1} | {:.1} | {:.3e} | {:.3e} |",
            f.stored,
            f.acceptance,
            f.mse,
            f.ms,
            f.cpu_ms,
            f.efficiency_cpu(),
            f.efficiency()
        );
    }
    let _ = writeln!(
        md,
        "\n**Efficiency gain of RR over IR: {gain_cpu:.1}x in CPU time** ({gain:.1}x in wall time; paper: more than an order of magnitude). CPU time is the process's user and system time over the whole frame on all threads: it does not move with the machine's load as wall time does, so it is the figure to compare across runs. Mean acceptance on `corner`: {:.3} (paper: 0.07, i.e. 93 % discarded).\n",
        rr.acceptance
    );
    if !swept.is_empty() {
        let _ = writeln!(
            md,
            "RR with other values of epsilon (same frames and reference):\n\n| epsilon | stored VPLs | mean acceptance | MSE | wall ms / frame | CPU ms / frame | gain over IR, CPU | gain over IR, wall |\n| --- | --- | --- | --- | --- | --- | --- | --- |"
        );
        let mut rows: Vec<(f32, MethodFigures)> = swept.clone();
        rows.push((s.rr.epsilon, rr));
        rows.sort_by(|a, b| a.0.total_cmp(&b.0));
        for (e, f) in rows {
            let _ = writeln!(
                md,
                "| {e} | {:.0} | {:.3} | {:.3e} | {:.1} | {:.1} | {:.1}x | {:.1}x |",
                f.stored,
                f.acceptance,
                f.mse,
                f.ms,
                f.cpu_ms,
                f.efficiency_cpu() / ir.efficiency_cpu(),
                f.efficiency() / ir.efficiency()
            );
        }
        let _ = writeln!(md);
    }
    let _ = writeln!(
        md,
        "Mean acceptance probability of RR over the measured frames (same settings):\n\n| scene | mean acceptance | stored VPLs |\n| --- | --- | --- |"
    );
    for (scene, a, st) in &acc {
        let _ = writeln!(md, "| {scene} | {a:.3} | {st:.0} |");
    }
    let mut csv = String::from("scene,method,epsilon,stored,acceptance,mse,ms,cpu_ms\n");
    let _ = writeln!(csv, "corner,ir,,{:.1},{:.4},{:.6e},{:.2},{:.2}", ir.stored, ir.acceptance, ir.mse, ir.ms, ir.cpu_ms);
    for (e, f) in std::iter::once((s.rr.epsilon, rr)).chain(swept.iter().copied()) {
        let _ = writeln!(csv, "corner,rr,{e},{:.1},{:.4},{:.6e},{:.2},{:.2}", f.stored, f.acceptance, f.mse, f.ms, f.cpu_ms);
    }
    for (scene, a, st) in &acc {
        if *scene != "corner" {
            let _ = writeln!(csv, "{scene},rr,{},{st:.1},{a:.4},,,", s.rr.epsilon);
        }
    }
    let _ = writeln!(
        md,
        "\nPictures (indirect light, same exposure): the reference `corner_reference.png`, IR's last measured frame `corner_ir.png`, RR's `corner_rr.png`; EXRs beside them.\n\n![reference](corner_reference.png) ![IR](corner_ir.png) ![RR](corner_rr.png)"
    );
    Ok(GeorgievReport { markdown: md, csv, reference, ir: ir_image, rr: rr_image })
}

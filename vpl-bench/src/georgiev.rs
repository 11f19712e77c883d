//! Reproduces Georgiev & Slusallek's claims (EG 2010, §4): on the `corner`
//! scene (their EG scene: a point light around the corner behind the
//! camera) Russian-roulette acceptance discards most VPL candidates
//! (paper: mean acceptance 0.07) and is more than an order of magnitude more
//! efficient than plain IR at the same number of stored VPLs. Also the mean
//! acceptance on `cornell` and `office`.
//!
//! Efficiency is 1 / (relMSE · time): relMSE of a frame's indirect image
//! against the path tracer's (clamped by the same rule as the VPLs), time
//! the frame's sampling, visibility and shading. Both methods use
//! ray-traced visibility and exhaustive shading, so only the VPLs differ.

use crate::metrics::rel_mse;
use crate::pipeline::{Pipeline, PipelineSpec, ShadingSpec, VisibilitySpec};
use std::fmt::Write as _;
use vpl_core::{GeometryClamp, Mode, SceneSetup};
use vpl_pathtrace::{render, PathTracer, RenderSettings};
use vpl_sampling::{RrConfig, SamplerConfig};

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
}

/// One method's figures.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MethodFigures {
    /// Mean relMSE of a frame against the reference.
    pub rel_mse: f64,
    /// Mean milliseconds of a frame (sampling + visibility + shading).
    pub ms: f64,
    /// Mean VPLs stored.
    pub stored: f64,
    /// Mean acceptance probability (1 for IR).
    pub acceptance: f64,
}

impl MethodFigures {
    /// 1 / (relMSE · seconds).
    pub fn efficiency(&self) -> f64 {
        1.0 / (self.rel_mse * self.ms * 1e-3)
    }
}

fn spec(sampler: &str, vpls: usize, clamp: GeometryClamp, seed: u64) -> PipelineSpec {
    PipelineSpec {
        sampler: sampler.into(),
        config: SamplerConfig { vpls, fresh_paths: true, rr: RrConfig { vpls, ..RrConfig::default() }, ..SamplerConfig::default() },
        visibility: VisibilitySpec::RayTraced,
        shading: ShadingSpec::Exhaustive,
        clamp: Some(clamp),
        mode: Mode::Indirect,
        direct_samples: 1,
        seed,
    }
}

/// Runs `sampler` on `scene` frame 0 for warm-up + measured frames; with a
/// reference, measures relMSE. Returns the figures of the measured frames.
fn run(scene_name: &str, sampler: &str, s: &GeorgievSettings, reference: Option<&vpl_core::Image>, progress: &dyn Fn(&str)) -> Result<MethodFigures, String> {
    let setup = SceneSetup::load(scene_name).map_err(|e| e.to_string())?;
    let camera = setup.camera.with_resolution(s.size).map_err(|e| e.to_string())?;
    let clamp = GeometryClamp::for_budget(s.vpls, setup.scene.surface_area());
    let mut p = Pipeline::new(spec(sampler, s.vpls, clamp, s.seed))?;
    let mut f = MethodFigures::default();
    for i in 0..s.warmup_frames + s.frames {
        let out = p.render(&setup.scene, &camera, i as u64, 0.0);
        progress(&format!("{scene_name} {sampler} frame {i}: {}", out.sampler_report));
        if i < s.warmup_frames {
            continue;
        }
        let n = s.frames as f64;
        if let Some(r) = reference {
            f.rel_mse += rel_mse(&out.image, r).map_err(|e| e.to_string())? / n;
        }
        f.ms += (out.timings.sampling_ms + out.timings.visibility_ms + out.timings.shading_ms) / n;
        let acc = p.sampler.acceptance().map_or(1.0, |a| a as f64);
        f.acceptance += acc / n;
        f.stored += out.stored as f64 / n;
    }
    Ok(f)
}

/// The experiment; returns the Markdown report and the CSV rows.
pub fn georgiev(s: &GeorgievSettings, progress: &dyn Fn(&str)) -> Result<(String, String), String> {
    let setup = SceneSetup::load("corner").map_err(|e| e.to_string())?;
    let camera = setup.camera.with_resolution(s.size).map_err(|e| e.to_string())?;
    let clamp = GeometryClamp::for_budget(s.vpls, setup.scene.surface_area());
    let mut pt = PathTracer::new(5, Mode::Indirect);
    pt.clamp = Some(clamp);
    progress(&format!("corner reference: path tracer, indirect, {} spp", s.reference_spp));
    let reference = render(&setup.scene, &camera, &pt, RenderSettings { spp: s.reference_spp, seed: s.seed ^ 0xEF, frame: 0 }, &|_, _| {}).map_err(|e| e.to_string())?.image;
    let ir = run("corner", "ir", s, Some(&reference), progress)?;
    let rr = run("corner", "rr", s, Some(&reference), progress)?;
    let gain = rr.efficiency() / ir.efficiency();
    let mut acc = Vec::new();
    for scene in ["cornell", "office", "corner"] {
        let f = if scene == "corner" { rr } else { run(scene, "rr", s, None, progress)? };
        acc.push((scene, f.acceptance, f.stored));
    }
    let mut md = String::new();
    let _ = writeln!(md, "# Georgiev & Slusallek (EG 2010): Russian-roulette VPL acceptance\n");
    let _ = writeln!(md, "`corner` (the paper's EG scene), frame 0, {}x{}, I = {} stored VPLs, ray-traced visibility, exhaustive shading, clamp G_max = I/A = {:.2} m^-2 for both; {} warm-up frames (RR learns Phi_total from the previous frame's indirect image), then {} measured frames; reference: path tracer, indirect, same clamp, {} spp. IR uses fresh light paths every frame. Seed {}.\n",
        s.size.0, s.size.1, s.vpls, clamp.g_max, s.warmup_frames, s.frames, s.reference_spp, s.seed);
    let _ = writeln!(md, "| method | stored VPLs | mean acceptance | relMSE | ms / frame | efficiency 1/(relMSE·s) |");
    let _ = writeln!(md, "| --- | --- | --- | --- | --- | --- |");
    for (name, f) in [("IR", ir), ("RR (eps 0.05, N_C 100)", rr)] {
        let _ = writeln!(md, "| {name} | {:.0} | {:.3} | {:.5} | {:.1} | {:.1} |", f.stored, f.acceptance, f.rel_mse, f.ms, f.efficiency());
    }
    let _ = writeln!(md, "\n**Efficiency gain of RR over IR: {gain:.1}x** (paper: more than an order of magnitude). Mean acceptance on `corner`: {:.3} (paper: 0.07, i.e. 93 % discarded).\n", rr.acceptance);
    let _ = writeln!(md, "Mean acceptance probability of RR over the measured frames (same settings):\n\n| scene | mean acceptance | stored VPLs |\n| --- | --- | --- |");
    for (scene, a, st) in &acc {
        let _ = writeln!(md, "| {scene} | {a:.3} | {st:.0} |");
    }
    let mut csv = String::from("scene,method,stored,acceptance,rel_mse,ms\n");
    let _ = writeln!(csv, "corner,ir,{:.1},{:.4},{:.6},{:.2}", ir.stored, ir.acceptance, ir.rel_mse, ir.ms);
    let _ = writeln!(csv, "corner,rr,{:.1},{:.4},{:.6},{:.2}", rr.stored, rr.acceptance, rr.rel_mse, rr.ms);
    for (scene, a, st) in &acc {
        if *scene != "corner" {
            let _ = writeln!(csv, "{scene},rr,{st:.1},{a:.4},,");
        }
    }
    Ok((md, csv))
}

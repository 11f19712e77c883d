//! `vpl view`: the interactive viewer (crate vpl-viewer) on a scene.

use super::*;

/// Open a window that renders VPL frames continuously: fly, switch samplers, split two of them.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scene: a built-in name or a scene file (.toml, .obj, .gltf, .glb, Mitsuba .xml).
    #[arg(long, default_value = "office")]
    scene: String,
    /// Let the scene's files name files under this folder too (repeatable).
    #[arg(long, value_name = "PATH")]
    allow_outside: Vec<PathBuf>,
    /// The left (or only) side's pipeline: its sampler, that sampler's parameters, visibility,
    /// shading and backend.
    #[command(flatten)]
    v: VplArgs,
    /// Split view with this sampler on the right.
    #[arg(long)]
    split: Option<String>,
    /// VPL budget of each side.
    #[arg(long, default_value_t = 256)]
    vpls: usize,
    /// Which light paths to include.
    #[arg(long, value_enum, default_value_t = ModeArg::Full)]
    mode: ModeArg,
    /// Render resolution over the view's size (default 0.5 on the GPU, 0.25 on the CPU).
    #[arg(long, allow_hyphen_values = true)]
    scale: Option<f32>,
    /// Window size.
    #[arg(long, default_value = "1280x720")]
    window: Size,
    /// Seed of the renderers.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Exposure of the tone mapping.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    exposure: f32,
    /// Accumulate a path-traced reference while the camera stands still (also on the panel).
    #[arg(long)]
    reference: bool,
    /// Run a scripted session from this file and close (see the vpl-viewer crate's `script`
    /// module: frames, sampler, split, overlay, show, mode, vpls, orbit, reference, pick, record,
    /// screenshot, quit).
    #[arg(long)]
    script: Option<PathBuf>,
    /// No summary line at the end.
    #[arg(long)]
    quiet: bool,
}

impl Args {
    /// The pipeline's settings, for the sampler flags made at parse time.
    pub(super) fn vpl_args(&mut self) -> &mut VplArgs {
        &mut self.v
    }
}

/// Runs `vpl view`.
#[cfg(feature = "viewer")]
pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args { scene, v, split, vpls, mode, scale, window, seed, exposure, reference, script, quiet, allow_outside } = args;
    let script = match script {
        Some(p) => {
            let text = std::fs::read_to_string(&p).map_err(|e| format!("cannot read {}: {e}", p.display()))?;
            Some(vpl_viewer::Script::parse(&text).map_err(|e| format!("{}: {e}", p.display()))?)
        }
        None => None,
    };
    if !exposure.is_finite() || exposure <= 0.0 {
        return Err(format!("--exposure must be positive, got {exposure}"));
    }
    let defaults = vpl_viewer::ViewerOptions::new(scene);
    // The viewer's defaults where the command line is silent: its depth,
    // the view's clamp, and the first device that opens.
    let mut pipeline = pipeline_spec(&v, vpls, defaults.pipeline.budget.max_depth, mode, defaults.pipeline.clamp, seed)?;
    if v.backend.is_none() {
        pipeline.backend = vpl_render::AUTO.into();
    }
    let options = vpl_viewer::ViewerOptions {
        window: (window.0, window.1),
        pipeline,
        scale,
        split,
        exposure,
        reference,
        script,
        load: vpl_scene_io::LoadOptions { allow_outside, memory_limit: None },
        ..defaults
    };
    // The viewer checks the sampler's keys before any window opens; its
    // refusal is said in the command line's words (keys as flags).
    let s = vpl_viewer::run(options, registry).map_err(|e| match e {
        vpl_viewer::ViewerError::Sampler { name, source } => sampling_line(&name, &source),
        e => e.to_string(),
    })?;
    if !quiet {
        eprintln!(
            "vpl: view: {} frames shown, {:.2} frames/s after the first, {} of them composed on the device, render {}x{}; {}",
            s.frames, s.fps, s.device_frames, s.resolution.0, s.resolution.1, s.renderer
        );
    }
    Ok(())
}

/// Runs `vpl view` in a build without the viewer.
#[cfg(not(feature = "viewer"))]
pub(super) fn run(_args: Args, _registry: &Registry) -> Res<()> {
    Err("this vpl was built without the viewer (feature `viewer` of vpl-bench)".into())
}

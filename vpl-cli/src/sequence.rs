//! `vpl sequence`: Render frames of a scene's sequence with VPLs, the sampler keeping its state from frame to
//! frame: one EXR (and PNG preview) per frame, tracked.csv (tracked pixels) and frames.csv (timings).

use super::*;
use vpl_scene_io::ImageFile;

/// Render frames of a scene's sequence with VPLs, the sampler keeping its state from frame to
/// frame: one EXR (and PNG preview) per frame, tracked.csv (tracked pixels) and frames.csv (timings).
#[derive(clap::Args)]
pub(super) struct Args {
    #[command(flatten)]
    s: SceneArgs,
    /// Frames A..B (B not included), A.. (to the end) or one frame N. Default: the whole sequence.
    #[arg(long)]
    frames: Option<FramesArg>,
    /// Which light paths to include.
    #[arg(long, value_enum, default_value_t = ModeArg::Full)]
    mode: ModeArg,
    #[command(flatten)]
    v: VplArgs,
    /// A tracked pixel X,Y (repeat for more; default: 8 pixels spread over the image).
    #[arg(long = "pixel")]
    pixels: Vec<PixelArg>,
    /// Output folder (created if missing).
    #[arg(long)]
    out: PathBuf,
    /// Exposure applied to the PNG previews.
    #[arg(long, default_value_t = 1.0)]
    exposure: f32,
    /// No progress bar or summary.
    #[arg(long)]
    quiet: bool,
}

/// Runs `vpl sequence`.
impl Args {
    /// The VPL settings, for the sampler flags made at parse time.
    pub(super) fn vpl_args(&mut self) -> &mut VplArgs {
        &mut self.v
    }
}

pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args {
        s: SceneArgs { scene, frame, max_depth, clamp, vpls, size, seed, threads, memory_limit, allow_outside },
        frames,
        mode,
        v,
        pixels,
        out,
        exposure,
        quiet,
    } = args;
    if frame != 0 {
        return Err("--frame is for render; a sequence takes --frames A..B".into());
    }
    check_depth(max_depth, vpls)?;
    if !(exposure.is_finite() && exposure > 0.0) {
        return Err("--exposure must be positive".into());
    }
    if out.exists() && !out.is_dir() {
        return Err(format!("--out {} is not a directory", out.display()));
    }
    if out.is_dir() {
        check_writable(&out.join("frames.csv"))?;
    }
    let pool = pool(threads)?;
    let setup = SceneSource::new(scene, allow_outside, memory_limit).load()?;
    for w in &setup.warnings {
        eprintln!("vpl: warning: {w}");
    }
    let count = setup.sequence.as_ref().map_or(1, |q| q.frame_count());
    let range = frames.unwrap_or(FramesArg { start: 0, end: None }).range(count);
    vpl_bench::sequence::check_frames(&setup, &range).map_err(|e| format!("--{e}"))?;
    let res = match size {
        Some(Size(w, h)) => (w, h),
        None => setup.camera.resolution,
    };
    let maps = (v.visibility == VisibilityArg::Shadowmap).then_some(v.shadowmap_res);
    // The first frame's camera, for the warnings below.
    let first = setup.camera_at_frame(range.start).map_err(|e| e.to_string())?.with_resolution(res).map_err(|e| e.to_string())?;
    if let Some(note) = setup
        .scene
        .material_policy_note(vpl_core::MaterialPolicy::Diffuse, "the VPL pipeline (compare with --method path --materials diffuse)")
    {
        eprintln!("vpl: warning: {note}");
    }
    if let Some(w) = vpl_core::view::check_view(&setup.scene, &first) {
        eprintln!("vpl: warning: frame {}: {w}", range.start);
    }
    // The clamp's rule goes to the renderer: the view rule follows the camera.
    let spec = pipeline_spec(&v, vpls, max_depth, mode, clamp.unwrap_or(vpl_render::Clamp::Auto), seed)?;
    let estimate = with_sampler_memory(vpl_render::MemoryEstimate::vpl_frame(&setup.scene, res, vpls, maps), &spec, registry);
    check_memory(&estimate, memory_limit)?;
    let mut p = build_renderer(&spec, registry, &setup.scene)?;
    if let (Some(a), false) = (p.backend().device(), quiet) {
        eprintln!("vpl: GPU: {a}");
    }
    p.backend().check_size(res).map_err(vpl_bench::pipeline::backend_line)?;
    let tracked: Vec<(u32, u32)> = if pixels.is_empty() {
        vpl_bench::sequence::default_tracked_pixels(res.0, res.1)
    } else {
        pixels.iter().map(|p| (p.0, p.1)).collect()
    };
    let dir = OutDir::create("--out", &out)?;
    let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(range.len() as u64) };
    bar.set_style(
        ProgressStyle::with_template("{elapsed_precise} [{bar:40}] frame {pos}/{len} {msg}, eta {eta}").unwrap().progress_chars("=> "),
    );
    let start = Instant::now();
    let done = pool
        .install(|| {
            vpl_bench::sequence::run_sequence(
                &setup,
                range.clone(),
                size.map(|s| (s.0, s.1)),
                &mut p,
                &tracked,
                Some(dir.path()),
                &mut |f, image| {
                    let path = dir.path().join(format!("frame_{:04}.exr", f.index));
                    image.write_exr(&path)?;
                    image.write_png(vpl_core::image::preview_path(&path), exposure)?;
                    bar.set_message(format!("{:.0} ms, {} VPLs moved", f.timings.total_ms, f.moved));
                    bar.inc(1);
                    Ok(())
                },
            )
        })
        .map_err(vpl_bench::pipeline::backend_line)?;
    bar.finish_and_clear();
    dir.keep()?;
    if !quiet {
        let mean_ms = done.iter().map(|f| f.timings.total_ms).sum::<f64>() / done.len() as f64;
        let moved = done.iter().skip(1).map(|f| f.moved).max().unwrap_or(0);
        eprintln!(
            "vpl: {} frames {}..{} with {} in {:.1} s ({mean_ms:.0} ms a frame; at most {moved} VPLs moved between frames), {} -> {}",
            setup.scene.name,
            range.start,
            range.end,
            v.sampler,
            start.elapsed().as_secs_f64(),
            memory_line(&estimate),
            out.display()
        );
    }
    Ok(())
}

//! `vpl track`: Many path-traced samples at a few pixels: ground truth with standard errors, as CSV.

use super::*;

/// Many path-traced samples at a few pixels: ground truth with standard errors, as CSV.
#[derive(clap::Args)]
pub(super) struct Args {
    #[command(flatten)]
    s: SceneArgs,
    /// Which light paths to include.
    #[arg(long, value_enum, default_value_t = ModeArg::Indirect)]
    mode: ModeArg,
    /// A pixel X,Y (repeat for more).
    #[arg(long = "pixel", required = true)]
    pixels: Vec<PixelArg>,
    /// Samples per pixel.
    #[arg(long, default_value_t = 65536)]
    spp: u32,
    /// Write the CSV here instead of standard output.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Runs `vpl track`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args {
        s: SceneArgs { scene, frame, max_depth, clamp, vpls, size, seed, threads, memory_limit, allow_outside },
        mode,
        pixels,
        spp,
        out,
    } = args;
    if spp == 0 {
        return Err("--spp must be at least 1".into());
    }
    check_depth(max_depth, vpls)?;
    if let Some(p) = &out {
        check_writable(p)?;
    }
    let pool = pool(threads)?;
    let (sc, camera) = load_frame(&SceneSource::new(scene, allow_outside, memory_limit), frame, size)?;
    check_memory(&vpl_render::MemoryEstimate::scene(&sc), memory_limit)?;
    let pt = tracer(max_depth, mode, clamp, vpls, &sc, &camera);
    let (w, h) = camera.resolution;
    if let Some(p) = pixels.iter().find(|p| p.0 >= w || p.1 >= h) {
        return Err(format!("--pixel {},{} is outside the {w}x{h} image", p.0, p.1));
    }
    let px: Vec<(u32, u32)> = pixels.iter().map(|p| (p.0, p.1)).collect();
    let ts = pool.install(|| vpl_pathtrace::track(&sc, &camera, &pt, &px, spp, seed, frame as u64));
    if let Some(t) = ts.iter().find(|t| !(t.mean.is_finite() && t.stderr.is_finite())) {
        return Err(format!("path tracing produced a non-finite value at pixel {},{}; nothing written", t.pixel.0, t.pixel.1));
    }
    let mut csv = String::from("x,y,r,g,b,stderr_r,stderr_g,stderr_b,samples\n");
    for t in ts {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{}\n",
            t.pixel.0, t.pixel.1, t.mean.x, t.mean.y, t.mean.z, t.stderr.x, t.stderr.y, t.stderr.z, t.samples
        ));
    }
    emit(out.as_deref(), &csv)
}

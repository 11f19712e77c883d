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
    /// Which materials to draw: as-is (default) or diffuse (each material's albedo only, as the
    /// VPL pipeline draws it).
    #[arg(long, value_enum, default_value_t = MaterialsArg::AsIs)]
    materials: MaterialsArg,
    /// Where to sample: the CPU, or the GPU (`vpl_gpu::GpuTracker`, the same estimator over other
    /// streams; diffuse materials only, so with --materials diffuse on scenes with layered ones).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
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
        materials,
        backend,
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
    let sc = sc.with_material_policy(materials.policy());
    check_memory(&vpl_render::MemoryEstimate::scene(&sc), memory_limit)?;
    let pt = tracer(max_depth, mode, clamp, vpls, &sc, &camera);
    let (w, h) = camera.resolution;
    if let Some(p) = pixels.iter().find(|p| p.0 >= w || p.1 >= h) {
        return Err(format!("--pixel {},{} is outside the {w}x{h} image", p.0, p.1));
    }
    let px: Vec<(u32, u32)> = pixels.iter().map(|p| (p.0, p.1)).collect();
    let request = vpl_pathtrace::TrackRequest { pixels: &px, spp, seed, frame: frame as u64, footprint: vpl_pathtrace::Footprint::Box };
    let ts = match backend {
        BackendArg::Cpu => pool.install(|| vpl_pathtrace::track_with(&sc, &camera, &pt, &request)),
        BackendArg::Gpu => {
            let layered = sc.layered_materials();
            if !layered.is_empty() {
                return Err(format!(
                    "--backend gpu draws diffuse materials only (layered here: {}); add --materials diffuse to draw their albedo, as VPLs do",
                    layered.join(", ")
                ));
            }
            track_on_device(&sc, &camera, &pt, &request)?
        }
    };
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

/// `--backend gpu`: the tracked pixels on the default adapter.
#[cfg(feature = "gpu")]
fn track_on_device(
    scene: &vpl_core::Scene,
    camera: &vpl_core::Camera,
    pt: &vpl_pathtrace::PathTracer,
    request: &vpl_pathtrace::TrackRequest,
) -> Res<Vec<vpl_pathtrace::TrackedPixel>> {
    let gpu = vpl_gpu::Gpu::new().map_err(|e| format!("--backend gpu: {e}"))?;
    vpl_gpu::GpuTracker::new(gpu).track(scene, camera, pt, request).map_err(|e| format!("--backend gpu: {e}"))
}

#[cfg(not(feature = "gpu"))]
fn track_on_device(
    _: &vpl_core::Scene,
    _: &vpl_core::Camera,
    _: &vpl_pathtrace::PathTracer,
    _: &vpl_pathtrace::TrackRequest,
) -> Res<Vec<vpl_pathtrace::TrackedPixel>> {
    Err("--backend gpu: this vpl was built without the GPU backend (feature `gpu`)".into())
}

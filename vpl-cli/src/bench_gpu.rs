//! `vpl bench-gpu`: Milliseconds per GPU kernel and per indirect frame (SMC on the host or wholly on the device), and the adapter:
//! G-buffer, shadow maps of moved VPLs, interleaved gathering, filter, uploads and read-backs.

use super::*;

/// Milliseconds per GPU kernel and per indirect frame (SMC on the host or wholly on the device), and the adapter:
/// G-buffer, shadow maps of moved VPLs, interleaved gathering, filter, uploads and read-backs.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scenes (comma-separated).
    #[arg(long = "scene", value_delimiter = ',', default_value = "office,atrium")]
    scenes: Vec<String>,
    /// Image size.
    #[arg(long, default_value = "1920x1080")]
    size: Size,
    /// VPL budget.
    #[arg(long, default_value_t = 2048)]
    vpls: usize,
    /// Timed frames per scene (after one warm-up frame); medians are reported.
    #[arg(long, default_value_t = 5)]
    frames: u32,
    /// Worker threads of the CPU sampler (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Also write gpu_bench.md and gpu_bench.json into this folder.
    #[arg(long)]
    out: Option<PathBuf>,
    /// Read the G-buffer and the image back every frame, as a host-side
    /// renderer does (default: the frame stays on the device).
    #[arg(long)]
    read_back: bool,
    /// Where SMC runs, one row each (comma-separated): `host` (the default
    /// SMC, its rays and radiosities on the device) and `device` (the
    /// paper's kNN flux, every line on the device).
    #[arg(long, value_delimiter = ',', default_value = "host,device")]
    smc: Vec<String>,
    /// Samples per tracked pixel of the ground-truth comparison (one truth frame of
    /// each --scene that is a Table 1 sequence, CPU and GPU side by side; 0: none).
    #[arg(long, default_value_t = 65536)]
    truth_spp: u32,
}

/// Runs `vpl bench-gpu`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    bench_gpu(args)
}

/// `vpl bench-gpu`.
#[cfg(feature = "gpu")]
fn bench_gpu(args: Args) -> Res<()> {
    let Args { scenes, size: Size(w, h), vpls, frames, threads, out, read_back, smc, truth_spp } = args;
    let (size, resident, out) = ((w, h), !read_back, out.as_deref());
    if frames == 0 || vpls == 0 {
        return Err("--frames and --vpls must be at least 1".into());
    }
    let places: Vec<vpl_bench::gpu_bench::SmcPlace> =
        smc.iter().map(|s| s.parse().map_err(|e| format!("--smc: {e}"))).collect::<Result<_, _>>()?;
    for s in &scenes {
        vpl_scene_io::load(s).map_err(|e| format!("--scene: {e}"))?;
    }
    let pool = pool(threads)?;
    let gpu = vpl_gpu::Gpu::new().map_err(|e| e.to_string())?;
    let adapter = gpu.ctx().describe();
    eprintln!("vpl: bench-gpu on {adapter}");
    let mut rows = Vec::new();
    for s in &scenes {
        eprintln!("vpl: bench-gpu: {s} ({vpls} VPLs, {}x{}, {frames} frames)", size.0, size.1);
        let start = vpl_bench::table1::rows::row(s).map_or(0, |r| r.quick_frames.start);
        for &place in &places {
            let spec = vpl_bench::gpu_bench::GpuBenchSpec { scene: s, size, vpls, start, frames, resident, smc: place };
            let row = pool.install(|| vpl_bench::gpu_bench::bench_scene(&gpu, &spec));
            rows.push(row.map_err(|e| e.to_string())?);
        }
    }
    let mut truth = Vec::new();
    for s in scenes.iter().filter(|s| truth_spp > 0 && vpl_bench::table1::rows::row(s).is_some()) {
        eprintln!("vpl: bench-gpu: {s} ground truth ({truth_spp} samples a pixel)");
        truth.push(pool.install(|| vpl_bench::gpu_bench::bench_truth(&gpu, s, truth_spp)).map_err(|e| e.to_string())?);
    }
    let mut md = vpl_bench::gpu_bench::report(&adapter, &rows, frames, pool.current_num_threads());
    if !truth.is_empty() {
        md.push_str(&vpl_bench::gpu_bench::truth_report(&adapter, &truth, pool.current_num_threads()));
    }
    println!("{md}");
    if let Some(dir) = out {
        let out = super::OutDir::create("--out", dir)?;
        vpl_core::image::write_atomic(&out.path().join("gpu_bench.md"), md.as_bytes()).map_err(|e| e.to_string())?;
        let json = serde_json::json!({ "adapter": adapter, "frames": frames, "threads": pool.current_num_threads(), "rows": rows, "truth": truth });
        let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
        vpl_core::image::write_atomic(&out.path().join("gpu_bench.json"), text.as_bytes()).map_err(|e| e.to_string())?;
        out.keep()?;
    }
    Ok(())
}

/// `vpl bench-gpu` without the GPU backend.
#[cfg(not(feature = "gpu"))]
fn bench_gpu(_: Args) -> Res<()> {
    Err("bench-gpu: this build has no GPU backend (build vpl-bench with its default feature `gpu`)".into())
}

//! `vpl table2`: Table 2 of the SMC paper: milliseconds per stage of an SMC frame on courtyard, office, atrium
//! (2048 VPLs) and maze (512); table2.md, .csv, .json.

use super::*;

/// Table 2 of the SMC paper: milliseconds per stage of an SMC frame on courtyard, office, atrium
/// (2048 VPLs) and maze (512); table2.md, .csv, .json.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Image size.
    #[arg(long, default_value = "640x360")]
    size: Size,
    /// Frames timed per scene (after one warm-up frame).
    #[arg(long, default_value_t = 10)]
    frames: u32,
    /// Where the G-buffer, shadow maps and shading run.
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// Where SMC runs: `host` (the default SMC, with the backend's rays and
    /// radiosities) or `device` (the paper's kNN flux, every stage on the
    /// GPU, timed there; needs `--backend gpu`). Default: `device` with
    /// the GPU backend, else `host`.
    #[arg(long)]
    smc: Option<String>,
    /// Scenes (comma-separated; default the paper's four: courtyard, office, atrium, maze).
    #[arg(long = "scene", value_delimiter = ',')]
    scenes: Vec<String>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `vpl table2`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { size: Size(w, h), frames, backend, scenes, threads, out, smc } = args;
    if frames == 0 {
        return Err("--frames must be at least 1".into());
    }
    let gpu = backend.backend() == vpl_bench::pipeline::BackendKind::Gpu;
    let smc: vpl_bench::smc_step::SmcPlace = match smc {
        Some(s) => s.parse().map_err(|e| format!("--smc: {e}"))?,
        None if gpu => vpl_bench::smc_step::SmcPlace::Device,
        None => vpl_bench::smc_step::SmcPlace::Host,
    };
    if smc == vpl_bench::smc_step::SmcPlace::Device && !gpu {
        return Err("--smc device needs --backend gpu".into());
    }
    let pool = pool(threads)?;
    if let Some(bad) = scenes.iter().find(|s| !vpl_bench::table2::PAPER.iter().any(|p| p.1 == s.as_str())) {
        return Err(format!("--scene: '{bad}' is not a Table 2 scene (courtyard, office, atrium, maze)"));
    }
    let dir = OutDir::create("--out", &out)?;
    let mut rows = Vec::new();
    let mut device = format!("this machine's CPU ({} threads)", pool.current_num_threads());
    for (paper, scene, _, vpls, _) in vpl_bench::table2::PAPER {
        if !scenes.is_empty() && !scenes.iter().any(|s| s == scene) {
            continue;
        }
        eprintln!("vpl: table2: {scene} ({vpls} VPLs, {w}x{h}, {frames} frames)");
        let start = vpl_bench::table1::rows::row(scene).map_or(0, |r| r.quick_frames.start);
        let spec =
            vpl_bench::table2::Table2Spec { scene, paper_scene: paper, size: (w, h), vpls, start, frames, backend: backend.backend(), smc };
        let (row, adapter) = pool.install(|| vpl_bench::table2::time_scene(&spec)).map_err(|e| e.to_string())?;
        if let Some(a) = adapter {
            device = match smc {
                vpl_bench::smc_step::SmcPlace::Device => format!(
                    "{a}: SMC with the paper's kNN flux wholly on the device (its columns timed there by timestamps), the G-buffer, shadow maps and shading"
                ),
                vpl_bench::smc_step::SmcPlace::Host => format!(
                    "{a} for the G-buffer, shadow maps, shading and SMC's rays and radiosities; the rest of sampling on the CPU ({} threads)",
                    pool.current_num_threads()
                ),
            };
        }
        rows.push(row);
    }
    vpl_bench::table2::write(dir.path(), &rows, (w, h), frames, &device).map_err(|e| e.to_string())?;
    dir.keep()?;
    eprintln!("vpl: table2 -> {}", out.join("table2.md").display());
    Ok(())
}

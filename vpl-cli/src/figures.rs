//! `vpl figures`: Figs. 8, 9 and 10 of the SMC paper: one frame by path tracing, clamped path tracing and three
//! ways of shading the same VPLs; shadow-map resolutions against ray tracing; error against the
//! VPL budget. fig8.md, fig10.md with images, CSV, JSON and a plot.

use super::*;

/// Figs. 8, 9 and 10 of the SMC paper: one frame by path tracing, clamped path tracing and three
/// ways of shading the same VPLs; shadow-map resolutions against ray tracing; error against the
/// VPL budget. fig8.md, fig10.md with images, CSV, JSON and a plot.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scenes of Figs. 8 and 9 (comma-separated; frame 0 of each).
    #[arg(long, value_delimiter = ',', default_value = "office")]
    scenes: Vec<String>,
    /// Scenes of Fig. 10.
    #[arg(long, value_delimiter = ',', default_value = "atrium")]
    fig10_scenes: Vec<String>,
    /// Image size of Figs. 8 and 9.
    #[arg(long, default_value = "320x240")]
    size: Size,
    /// Image size of Fig. 10.
    #[arg(long, default_value = "160x120")]
    fig10_size: Size,
    /// Samples per pixel of the path-traced references of Figs. 8 and 9.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Samples per pixel of the path-traced references of Fig. 10.
    #[arg(long, default_value_t = 1024)]
    fig10_spp: u32,
    /// Shadow-map sides of Fig. 9.
    #[arg(long, value_delimiter = ',', default_value = "128,256")]
    shadow_maps: Vec<u32>,
    /// VPL budgets of Fig. 10.
    #[arg(long, value_delimiter = ',', default_value = "2000,8000,40000")]
    budgets: Vec<usize>,
    /// SMC warm-up iterations in Fig. 10.
    #[arg(long, default_value_t = 20)]
    fig10_warmup: u32,
    /// Which figures: 8 (with 9), 10 or both.
    #[arg(long, value_delimiter = ',', default_value = "8,10")]
    only: Vec<u32>,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `vpl figures`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args {
        scenes,
        fig10_scenes,
        size: Size(w, h),
        fig10_size: Size(w10, h10),
        spp,
        fig10_spp,
        shadow_maps,
        budgets,
        fig10_warmup,
        only,
        seed,
        threads,
        out,
    } = args;
    use vpl_bench::figures;
    if spp == 0 || fig10_spp == 0 || budgets.contains(&0) || shadow_maps.is_empty() {
        return Err("--spp and --budgets must be positive and --shadow-maps not empty".into());
    }
    if let Some(bad) = only.iter().find(|f| **f != 8 && **f != 10) {
        return Err(format!("--only: no figure {bad} (8 or 10)"));
    }
    for sc in scenes.iter().chain(&fig10_scenes) {
        vpl_scene_io::load(sc).map_err(|e| e.to_string())?;
    }
    let pool = pool(threads)?;
    let dir = OutDir::create("--out", &out)?;
    // Where the files go until the command succeeds (see OutDir).
    let to = dir.path().to_path_buf();
    let settings = figures::FigureSettings {
        size: (w, h),
        reference_spp: spp,
        shadow_map_sides: shadow_maps,
        budgets,
        fig10_size: (w10, h10),
        fig10_spp,
        fig10_warmup,
        seed,
    };
    if only.contains(&8) {
        let mut figs = Vec::new();
        for sc in &scenes {
            eprintln!("vpl: figures: Figs. 8 and 9 on {sc}");
            let (a, b) = pool.install(|| figures::fig8_9(&to, sc, 0, &settings)).map_err(|e| e.to_string())?;
            figs.push((sc.clone(), a, b));
        }
        figures::write_fig8(&to, &figs, &settings).map_err(|e| e.to_string())?;
    }
    if only.contains(&10) {
        let mut figs = Vec::new();
        for sc in &fig10_scenes {
            eprintln!("vpl: figures: Fig. 10 on {sc}");
            figs.push((sc.clone(), pool.install(|| figures::fig10(&to, sc, &settings)).map_err(|e| e.to_string())?));
        }
        figures::write_fig10(&to, &figs, &settings).map_err(|e| e.to_string())?;
    }
    dir.keep()?;
    eprintln!("vpl: figures -> {}", out.display());
    Ok(())
}

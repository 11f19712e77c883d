//! `vpl progressive-figures`: Figs. 6-8 of the progressive renderer (Dammertz et al. 2010): error against passes on a
//! scene, and an equal-time comparison with path tracing on diffuse scenes.

use super::*;

/// Figs. 6-8 of the progressive renderer (Dammertz et al. 2010): error against passes on a
/// scene, and an equal-time comparison with path tracing on diffuse scenes.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scene of Fig. 7.
    #[arg(long, default_value = "glass")]
    fig7_scene: String,
    /// Image size of Fig. 7.
    #[arg(long, default_value = "160x120")]
    fig7_size: Size,
    /// Passes of the Fig. 7 curve.
    #[arg(long, default_value_t = 512)]
    passes: u64,
    /// Passes between points of the curve.
    #[arg(long, default_value_t = 16)]
    step: u64,
    /// Passes of the converged image.
    #[arg(long, default_value_t = 2048)]
    converged: u64,
    /// Caustic photon paths per pass in Fig. 7.
    #[arg(long, default_value_t = 100_000)]
    caustic_paths: usize,
    /// Scenes of Fig. 8 (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "cornell,office")]
    fig8_scenes: Vec<String>,
    /// Image size of Fig. 8 (cornell keeps the Mitsuba reference's 256x256).
    #[arg(long, default_value = "160x120")]
    fig8_size: Size,
    /// Seconds per method in Fig. 8.
    #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
    seconds: f64,
    /// Samples per pixel of the path-traced references.
    #[arg(long, default_value_t = 1024)]
    reference_spp: u32,
    /// Folder of the Mitsuba cornell references.
    #[arg(long, default_value = "tests/data/cornell-box")]
    mitsuba: PathBuf,
    /// Which figures: 7, 8 or both.
    #[arg(long, value_delimiter = ',', default_value = "7,8")]
    only: Vec<u32>,
    /// VPL budget I of the progressive renderer's geometry clamp G ≤ I / A_view.
    #[arg(long, default_value_t = 2048)]
    vpls: usize,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder (progressive.md, fig7.*, fig8_*).
    #[arg(long)]
    out: PathBuf,
}

/// Runs `vpl progressive-figures`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args {
        fig7_scene,
        fig7_size: Size(w7, h7),
        passes,
        step,
        converged,
        caustic_paths,
        fig8_scenes,
        fig8_size: Size(w8, h8),
        seconds,
        reference_spp,
        mitsuba,
        only,
        vpls,
        seed,
        threads,
        out,
    } = args;
    use vpl_bench::progressive as pf;
    if vpls == 0 {
        return Err("--vpls must be at least 1".into());
    }
    if passes == 0 || step == 0 || converged == 0 || reference_spp == 0 {
        return Err("--passes, --step, --converged and --reference-spp must be at least 1".into());
    }
    if !(seconds.is_finite() && seconds > 0.0) {
        return Err("--seconds must be positive".into());
    }
    if let Some(bad) = only.iter().find(|f| **f != 7 && **f != 8) {
        return Err(format!("--only: no figure {bad} (7 or 8)"));
    }
    for sc in std::iter::once(&fig7_scene).chain(&fig8_scenes) {
        vpl_scene_io::load(sc).map_err(|e| e.to_string())?;
    }
    let pool = pool(threads)?;
    let dir = OutDir::create("--out", &out)?;
    // Where the files go until the command succeeds (see OutDir).
    let to = dir.path().to_path_buf();
    let say = |m: &str| eprintln!("vpl: progressive figures: {m}");
    let fig7 = if only.contains(&7) {
        let s = pf::Fig7Settings {
            scene: fig7_scene,
            size: (w7, h7),
            passes,
            step,
            converged,
            reference_spp,
            caustic_paths,
            clamp_budget: Some(vpls),
            seed,
        };
        Some(pool.install(|| pf::fig7(&to, &s, &say)).map_err(|e| e.to_string())?)
    } else {
        None
    };
    let mut rows = Vec::new();
    if only.contains(&8) {
        let s = pf::Fig8Settings {
            scenes: fig8_scenes.clone(),
            size: (w8, h8),
            seconds,
            reference_spp,
            mitsuba: Some(mitsuba),
            clamp_budget: vpls,
            seed,
        };
        for sc in &fig8_scenes {
            rows.push(pool.install(|| pf::fig8_scene(&to, sc, &s, &say)).map_err(|e| e.to_string())?);
        }
        let json = serde_json::to_string_pretty(&rows).map_err(|e| e.to_string())?;
        write_atomic(&to.join("fig8.json"), json.as_bytes()).map_err(|e| e.to_string())?;
    }
    let md = format!("# Progressive point-light rendering (Dammertz et al. 2010)\n\n{}", pf::report(fig7.as_ref(), &rows, seconds, ""));
    write_atomic(&to.join("progressive.md"), md.as_bytes()).map_err(|e| e.to_string())?;
    dir.keep()?;
    eprintln!("vpl: progressive figures -> {}", out.join("progressive.md").display());
    Ok(())
}

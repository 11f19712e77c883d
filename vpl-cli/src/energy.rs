//! `vpl energy`: a sampler's unclamped indirect image mean against the path tracer's, at frame 0 and
//! over checkpoints of each scene's sequence, with the share the default clamp removes;
//! energy.md and energy.json.

use super::*;
use vpl_bench::energy::{EnergySettings, markdown, measure};

/// A sampler's unclamped indirect image mean against the path tracer's, at frame 0 and over
/// checkpoints of each scene's sequence (the sampler stepped along it), with the share of its light
/// the default clamp removes; energy.md and energy.json.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scenes (comma-separated): Table 1 sequences by id (office, courtyard, maze, atrium,
    /// courtyard-sun, sponza, munich), built-in names, or scene files.
    #[arg(long = "scene", value_delimiter = ',', required = true)]
    scenes: Vec<String>,
    /// VPL sampler: a registry name.
    #[arg(long, default_value = "smc")]
    sampler: String,
    /// A sampler parameter KEY=VALUE (repeat for more).
    #[arg(long = "set", value_name = "KEY=VALUE")]
    set: Vec<String>,
    /// VPL budget I.
    #[arg(long, default_value_t = 2048)]
    vpls: usize,
    /// Image size.
    #[arg(long, default_value = "64x48")]
    size: Size,
    /// Seeds of the sampler.
    #[arg(long, default_value_t = 3)]
    seeds: u32,
    /// Seeds rendered at frame 0 (at least --seeds; those past --seeds render frame 0 alone):
    /// one frame's image mean varies more between seeds than a sequence's.
    #[arg(long = "frame0-seeds", default_value_t = 16)]
    frame0_seeds: u32,
    /// Stop adding seeds at frame 0 once their ratio's standard error is at most this (after at
    /// least 8 and --seeds; 0: all of --frame0-seeds run).
    #[arg(long = "frame0-se", default_value_t = 0.0)]
    frame0_se: f64,
    /// First seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Checkpoints spread over each sequence.
    #[arg(long, default_value_t = 6)]
    checkpoints: u32,
    /// Step the sampler at every N-th frame (1: every frame, as a renderer does) and at each of
    /// the --settle frames before a checkpoint.
    #[arg(long, default_value_t = 1)]
    stride: u32,
    /// Frames stepped one by one before each checkpoint when --stride is above 1 (32 = 2T lets
    /// the area probes come from consecutive frames).
    #[arg(long, default_value_t = 32)]
    settle: u32,
    /// Path-traced samples a pixel of the truth.
    #[arg(long, default_value_t = 512)]
    spp: u32,
    /// Longest path in segments (5: three indirect bounces).
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Let scene files name files under this folder too (repeatable).
    #[arg(long = "allow-outside")]
    allow_outside: Vec<PathBuf>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
}

/// Runs `vpl energy`.
pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args {
        scenes,
        sampler,
        set,
        vpls,
        size: Size(w, h),
        seeds,
        frame0_seeds,
        frame0_se,
        seed,
        checkpoints,
        stride,
        settle,
        spp,
        max_depth,
        allow_outside,
        threads,
        out,
    } = args;
    if seeds == 0 || vpls == 0 || spp == 0 || stride == 0 {
        return Err("--seeds, --vpls, --spp and --stride must be at least 1".into());
    }
    if !(frame0_se >= 0.0 && frame0_se.is_finite()) {
        return Err(format!("--frame0-se {frame0_se}: expected a standard error of 0 or more"));
    }
    let mut params = vpl_core::Params::new();
    for item in &set {
        let (k, value) = item.split_once('=').ok_or_else(|| format!("--set {item}: expected KEY=VALUE"))?;
        params.insert(k, value).map_err(|e| format!("--set {e}"))?;
    }
    let settings = EnergySettings {
        sampler,
        params,
        vpls,
        size: (w, h),
        seeds,
        frame0_seeds,
        frame0_se,
        seed,
        checkpoints,
        stride,
        settle,
        truth_spp: spp,
        max_depth,
    };
    let (setups, skipped) = study_scenes(&scenes, allow_outside)?;
    let pool = pool(threads)?;
    let dir = OutDir::create("--out", &out)?;
    let mut runs = Vec::new();
    for (name, setup) in &setups {
        let name = name.as_str();
        eprintln!("vpl: energy: {name}");
        // Params marks the keys it was asked for, so each scene takes its own copy.
        let settings = settings.clone();
        let run = pool
            .install(move || measure(registry, name, setup, &settings, &mut |what| eprintln!("vpl: energy: {name}: {what}")))
            .map_err(|e| e.to_string())?;
        let (a, b, c) = (run.frame0_ratio(), run.sequence_ratio(), run.clamp_removed());
        eprintln!(
            "vpl: energy: {name}: frame 0 {:.3} ± {:.3}, sequence {:.3} ± {:.3}, clamp removes {:.1} % ± {:.1} ({:.0} s)",
            a.mean,
            a.se,
            b.mean,
            b.se,
            100.0 * c.mean,
            100.0 * c.se,
            run.seconds
        );
        runs.push(run);
    }
    let mut md = markdown(&runs, &settings);
    for why in &skipped {
        eprintln!("vpl: energy: skipped {why}");
        md.push_str(&format!("\nSkipped {why}\n"));
    }
    let json = serde_json::json!({
        "sampler": settings.sampler,
        "set": set,
        "vpls": vpls,
        "size": [w, h],
        "seeds": seeds,
        "frame0_seeds": seeds.max(frame0_seeds),
        "frame0_se": frame0_se,
        "seed": seed,
        "stride": stride,
        "settle": settle,
        "spp": spp,
        "max_depth": max_depth,
        "scenes": runs.iter().map(|r| serde_json::json!({
            "scene": r.scene,
            "seconds": r.seconds,
            "frame0_ratio": [r.frame0_ratio().mean, r.frame0_ratio().se],
            "sequence_ratio": [r.sequence_ratio().mean, r.sequence_ratio().se],
            "clamp_removed": [r.clamp_removed().mean, r.clamp_removed().se],
            "frames": r.frames.iter().map(|c| serde_json::json!({
                "frame": c.frame, "truth": c.truth, "truth_se": c.truth_se, "unclamped": c.unclamped, "clamped": c.clamped,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
    });
    vpl_core::image::write_atomic(&dir.path().join("energy.md"), md.as_bytes()).map_err(|e| e.to_string())?;
    let text = serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?;
    vpl_core::image::write_atomic(&dir.path().join("energy.json"), text.as_bytes()).map_err(|e| e.to_string())?;
    dir.keep()?;
    print!("{md}");
    Ok(())
}

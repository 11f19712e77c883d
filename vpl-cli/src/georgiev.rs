//! `vpl georgiev`: Reproduce Georgiev & Slusallek's claims on `corner`: RR's mean acceptance and its
//! efficiency gain over IR at equal stored VPLs (and RR's acceptance on cornell, office).

use super::*;
use vpl_scene_io::ImageFile;

/// Reproduce Georgiev & Slusallek's claims on `corner`: RR's mean acceptance and its
/// efficiency gain over IR at equal stored VPLs (and RR's acceptance on cornell, office).
#[derive(clap::Args)]
pub(super) struct Args {
    /// Image size.
    #[arg(long, default_value = "160x120")]
    size: Size,
    /// Stored VPLs of both methods.
    #[arg(long, default_value_t = 1024)]
    vpls: usize,
    /// Frames measured (after 4 warm-up frames).
    #[arg(long, default_value_t = 8)]
    frames: u32,
    /// Samples per pixel of the path-traced reference.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Seed.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// RR's epsilon of eq. (3).
    #[arg(long, default_value_t = 0.05)]
    rr_epsilon: f32,
    /// RR's camera samples per frame.
    #[arg(long, default_value_t = 100)]
    camera_samples: usize,
    /// Further values of epsilon to run RR with on corner (comma-separated; a value equal to
    /// --rr-epsilon is skipped, so `--sweep 0.05` runs none).
    #[arg(long, default_value = "0.02,0.2", value_delimiter = ',')]
    sweep: Vec<f32>,
    /// Output folder (georgiev.md, georgiev.csv).
    #[arg(long)]
    out: PathBuf,
}

/// Runs `vpl georgiev`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { size, vpls, frames, spp, seed, rr_epsilon, camera_samples, sweep, out } = args;
    if vpls == 0 || frames == 0 || spp == 0 {
        return Err("--vpls, --frames and --spp must be at least 1".into());
    }
    let rr = vpl_sampling::RrConfig { vpls, epsilon: rr_epsilon, camera_samples, ..vpl_sampling::RrConfig::default() };
    rr.validate().map_err(|e| e.to_string())?;
    if out.exists() && !out.is_dir() {
        return Err(format!("--out {} is not a directory", out.display()));
    }
    let settings =
        vpl_bench::georgiev::GeorgievSettings { size: (size.0, size.1), vpls, warmup_frames: 4, frames, reference_spp: spp, seed, rr };
    let bar = ProgressBar::new_spinner();
    bar.set_style(ProgressStyle::with_template("{elapsed_precise} {spinner} {msg}").unwrap());
    if let Some(bad) = sweep.iter().find(|e| !(**e > 0.0 && **e <= 1.0)) {
        return Err(format!("--sweep: epsilon {bad} is outside (0, 1]"));
    }
    let r = vpl_bench::georgiev::georgiev(&settings, &sweep, &|m| {
        let short: String = m.chars().take(100).collect();
        bar.set_message(short);
        bar.tick();
    })
    .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    let dir = OutDir::create("--out", &out)?;
    // Where the files go until the command succeeds (see OutDir).
    let to = dir.path().to_path_buf();
    // One exposure for all three pictures: the reference's mean luminance at 0.18.
    let mean = r.reference.data.iter().map(|c| vpl_core::image::luminance(*c) as f64).sum::<f64>() / r.reference.data.len().max(1) as f64;
    let exposure = if mean > 0.0 { (0.18 / mean) as f32 } else { 1.0 };
    for (name, img) in [("reference", &r.reference), ("ir", &r.ir), ("rr", &r.rr)] {
        check_finite(img, &format!("the {name} image"))?;
        img.write_exr(to.join(format!("corner_{name}.exr"))).map_err(|e| e.to_string())?;
        img.write_png(to.join(format!("corner_{name}.png")), exposure).map_err(|e| e.to_string())?;
    }
    write_atomic(&to.join("georgiev.md"), r.markdown.as_bytes()).map_err(|e| e.to_string())?;
    write_atomic(&to.join("georgiev.csv"), r.csv.as_bytes()).map_err(|e| e.to_string())?;
    dir.keep()?;
    print!("{}", r.markdown);
    Ok(())
}

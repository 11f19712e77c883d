//! `vpl validate-cornell`: Compare the path tracer with the Mitsuba 3 references of `cornell`; write a Markdown report.

use super::*;
use vpl_scene_io::ImageFile;

/// Compare the path tracer with the Mitsuba 3 references of `cornell`; write a Markdown report.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Samples per pixel.
    #[arg(long, default_value_t = 1024)]
    spp: u32,
    /// Folder holding the reference EXRs.
    #[arg(long, default_value = "tests/data/cornell-box")]
    data: PathBuf,
    /// Folder for the report and difference images.
    #[arg(long, default_value = "results")]
    out: PathBuf,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs `vpl validate-cornell`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { spp, data, out, seed } = args;
    if spp == 0 {
        return Err("--spp must be at least 1".into());
    }
    let bar = ProgressBar::new(3 * 256 * 256);
    bar.set_style(
        ProgressStyle::with_template("{msg:>9} {elapsed_precise} [{bar:40}] {percent}%, eta {eta}").unwrap().progress_chars("=> "),
    );
    let vs = vpl_bench::validation::validate_cornell(&data, spp, seed, &|m, d, t| {
        let k = vpl_bench::validation::MODES.iter().position(|x| x.0 == m).unwrap_or(0) as u64;
        bar.set_message(m.to_string());
        bar.set_position(k * t + d);
    })
    .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    let dir = OutDir::create("--out", &out)?;
    // Where the files go until the command succeeds (see OutDir).
    let to = dir.path().to_path_buf();
    for v in &vs {
        vpl_bench::validation::write_difference(v, &to).map_err(|e| e.to_string())?;
        v.ours.0.write_png(to.join(format!("cornell_{}_ours.png", v.mode)), 1.0).map_err(|e| e.to_string())?;
        v.theirs.0.write_png(to.join(format!("cornell_{}_mitsuba.png", v.mode)), 1.0).map_err(|e| e.to_string())?;
    }
    let md = vpl_bench::validation::report_markdown(&vs, spp);
    write_atomic(&to.join("cornell_validation.md"), md.as_bytes()).map_err(|e| e.to_string())?;
    dir.keep()?;
    print!("{md}");
    Ok(())
}

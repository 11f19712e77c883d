//! `vpl bench-pt`: Path-tracing throughput on `cornell` 256×256, max-depth 5, all cores.

use super::*;

/// Path-tracing throughput on `cornell` 256×256, max-depth 5, all cores.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Samples per pixel of each timed render.
    #[arg(long, default_value_t = 64)]
    spp: u32,
    /// Timed renders (the best and the median are reported).
    #[arg(long, default_value_t = 5)]
    repeat: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// Runs `vpl bench-pt`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { spp, repeat, threads } = args;
    if spp == 0 || repeat == 0 {
        return Err("--spp and --repeat must be at least 1".into());
    }
    let pool = pool(threads)?;
    let setup = SceneSetup::builtin("cornell").map_err(|e| e.to_string())?;
    let pt = PathTracer::new(5, Mode::Full);
    let mut rates = Vec::new();
    // One warm-up render, then the timed ones.
    for i in 0..=repeat {
        let r = pool
            .install(|| {
                vpl_pathtrace::render(&setup.scene, &setup.camera, &pt, RenderSettings { spp, seed: i as u64, frame: 0 }, &|_, _| {})
            })
            .map_err(|e| e.to_string())?;
        if i > 0 {
            rates.push(r.paths as f64 / r.seconds);
        }
    }
    rates.sort_by(f64::total_cmp);
    println!(
        "bench-pt: cornell 256x256, max-depth 5, {spp} spp, {} threads: best {:.3} M paths/s, median {:.3} M paths/s over {repeat} renders",
        pool.current_num_threads(),
        rates[rates.len() - 1] / 1e6,
        rates[rates.len() / 2] / 1e6
    );
    Ok(())
}

//! `vpl bench-vpl`: Milliseconds per VPL stage at 640×360 with 2048 IR VPLs on `cornell` and `office`, and the
//! SMC sampler's steps (Table 2 of Hedman et al.) on `office` (I VPLs) and `maze` (I/4).

use super::*;

/// Milliseconds per VPL stage at 640×360 with 2048 IR VPLs on `cornell` and `office`, and the
/// SMC sampler's steps (Table 2 of Hedman et al.) on `office` (I VPLs) and `maze` (I/4).
#[derive(clap::Args)]
pub(super) struct Args {
    /// Timed repetitions of each stage (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeat: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Image size.
    #[arg(long, default_value = "640x360")]
    size: Size,
    /// VPL budget.
    #[arg(long, default_value_t = 2048)]
    vpls: usize,
}

/// Runs `vpl bench-vpl`.
pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args { repeat, threads, size, vpls } = args;
    if repeat == 0 || vpls == 0 {
        return Err("--repeat and --vpls must be at least 1".into());
    }
    let pool = pool(threads)?;
    println!(
        "bench-vpl: {}x{}, {vpls} IR VPLs, 128x128 shadow maps, {} threads, median of {repeat} (ms)",
        size.0,
        size.1,
        pool.current_num_threads()
    );
    println!(
        "| scene | G-buffer | direct (16 spp) | IR sampling | shadow maps, all | shadow maps, 16 changed | interleaved gather | filter | indirect frame, 16 changed |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for name in ["cornell", "office"] {
        let b = pool.install(|| vpl_bench::stages::bench_stages(name, (size.0, size.1), vpls, repeat)).map_err(|e| e.to_string())?;
        println!(
            "| {name} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | **{:.1}** |",
            b.gbuffer, b.direct, b.sampling, b.shadow_maps_all, b.shadow_maps_16, b.gather, b.filter, b.indirect_frame
        );
    }
    println!();
    println!(
        "SMC sampling (Table 2 of Hedman et al.), camera walking the sequence from frame 300, median of {} frames (ms):",
        repeat.max(15)
    );
    println!("| scene | VPLs | cand. sampling | cand. resampling | indirect visibility | radiosity | kNN | **total** | VPLs moved |");
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (name, budget) in [("office", vpls), ("maze", (vpls / 4).max(1))] {
        let b = pool
            .install(|| vpl_bench::stages::bench_smc(name, (size.0, size.1), budget, 300, repeat.max(15)))
            .map_err(|e| e.to_string())?;
        println!(
            "| {name} | {budget} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | **{:.1}** | {:.0} |",
            b.candidates, b.resampling, b.visibility, b.radiosity, b.knn, b.total, b.moved
        );
    }
    println!();
    println!(
        "Every sampler on office, I = {vpls}, camera walking the sequence from frame 300: next_frame of the first frame, then the median of {} frames (ms):",
        repeat.max(8)
    );
    println!("| sampler | first frame | **per frame** | VPLs moved per frame | VPLs stored |");
    println!("| --- | --- | --- | --- | --- |");
    let rows = pool
        .install(|| vpl_bench::stages::bench_samplers(registry, "office", (size.0, size.1), vpls, 300, repeat.max(8)))
        .map_err(|e| e.to_string())?;
    for b in rows {
        println!("| {} | {:.1} | **{:.1}** | {:.0} | {:.0} |", b.name, b.first_ms, b.frame_ms, b.moved, b.stored);
    }
    Ok(())
}

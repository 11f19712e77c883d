//! `vpl table1`: Table 1 of the SMC paper (|E| and |E′| of eight tracked pixels over seven sequences, with
//! confidence intervals over seeds and pixels): run the units of a shard into --out; without --shard,
//! also merge them into table1.md, .csv, .json and the Fig. 7 plots.

use super::*;

/// Table 1 of the SMC paper (|E| and |E′| of eight tracked pixels over seven sequences, with
/// confidence intervals over seeds and pixels): run the units of a shard into --out; without
/// --shard, also merge them into table1.md, .csv, .json and the Fig. 7 plots.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Settings: quick (8 frames a sequence, 65 536 truth samples, 3 seeds) or full (whole
    /// sequences, 692 100 truth samples: the paper's; 3 seeds).
    #[arg(long, value_enum, default_value_t = ProfileArg::Quick)]
    profile: ProfileArg,
    /// Sequences (comma-separated; default all: office, courtyard, maze, atrium, courtyard-sun, and
    /// sponza and munich where their models are in ../shared/scenes).
    #[arg(long = "scene", value_delimiter = ',')]
    scenes: Vec<String>,
    /// Methods (comma-separated registry names; default ir, rr, mir-resample, tcas, smc).
    #[arg(long, value_delimiter = ',')]
    methods: Vec<String>,
    /// Frames A..B (or A.. to the end) of every sequence instead of the profile's.
    #[arg(long)]
    frames: Option<FramesArg>,
    /// Image size (default 320x240).
    #[arg(long)]
    size: Option<Size>,
    /// Path-traced samples per tracked pixel and frame of ground truth.
    #[arg(long)]
    truth_spp: Option<u32>,
    /// Seed of the first run of each method (the others take the next ones).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Runs of each method with seeds --seed, --seed + 1, … (default: the profile's, 3).
    #[arg(long)]
    seeds: Option<u32>,
    /// Run only shard I of N (units k with k mod N = I); merge later with `vpl merge`.
    #[arg(long)]
    shard: Option<vpl_bench::table1::Shard>,
    /// Where the VPL stages and the ground truth run (on the GPU the truth is
    /// `vpl_gpu::GpuTracker`: the CPU path tracer's estimator over other streams).
    #[arg(long, value_enum, default_value_t = BackendArg::Cpu)]
    backend: BackendArg,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Output folder (unit files under units/, the tables beside).
    #[arg(long)]
    out: PathBuf,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// Runs `vpl table1`.
pub(super) fn run(args: Args, registry: &Registry) -> Res<()> {
    let Args { profile, scenes, methods, frames, size, truth_spp, seed, seeds, shard, backend, threads, out, quiet } = args;
    use vpl_bench::table1::{self, Table1Spec};
    let mut spec = match profile {
        ProfileArg::Quick => Table1Spec::quick(),
        ProfileArg::Full => Table1Spec::full().map_err(|e| e.to_string())?,
    };
    let custom = !scenes.is_empty()
        || !methods.is_empty()
        || frames.is_some()
        || size.is_some()
        || truth_spp.is_some()
        || seed != 0
        || seeds.is_some();
    if !scenes.is_empty() {
        let ids = table1::row_ids();
        if let Some(bad) = scenes.iter().find(|s| !ids.contains(&s.as_str())) {
            return Err(format!("--scene: unknown sequence '{bad}' (sequences: {})", ids.join(", ")));
        }
        if let Some((id, why)) = table1::skipped_rows().into_iter().find(|(id, _)| scenes.iter().any(|s| s == id)) {
            return Err(format!("--scene {id}: {why}"));
        }
        spec.rows.retain(|r| scenes.contains(&r.id));
    }
    if !methods.is_empty() {
        spec.methods = methods;
    }
    if let Some(f) = frames {
        for r in &mut spec.rows {
            let n = table1::rows::row(&r.id).map(|row| row.frame_count()).transpose().map_err(|e| e.to_string())?.unwrap_or(1);
            let range = f.range(n);
            r.start = range.start;
            r.end = range.end;
        }
    }
    if let Some(Size(w, h)) = size {
        spec.size = (w, h);
    }
    if let Some(n) = truth_spp {
        spec.truth_spp = n;
    }
    spec.seed = seed;
    if let Some(n) = seeds {
        spec.seeds = n;
    }
    spec.backend = backend.backend();
    if custom {
        spec.profile = format!("{}+custom", spec.profile);
    }
    spec.validate(registry).map_err(|e| e.to_string())?;
    if out.exists() && !out.is_dir() {
        return Err(format!("--out {} is not a directory", out.display()));
    }
    std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let pool = pool(threads)?;
    let shard_arg = shard.unwrap_or(table1::Shard::ALL);
    let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::with_draw_target(Some(0), ProgressDrawTarget::stderr()) };
    bar.set_style(
        ProgressStyle::with_template("table1 {elapsed_precise} [{bar:40}] {pos}/{len} frames {msg}, eta {eta}")
            .unwrap()
            .progress_chars("=> "),
    );
    let summary = pool
        .install(|| {
            table1::run(registry, &spec, &out, shard_arg, &mut |p| {
                bar.set_length(p.total);
                bar.set_position(p.done);
                if !p.message.is_empty() {
                    bar.set_message(p.message.clone());
                }
            })
        })
        .map_err(|e| e.to_string())?;
    bar.finish_and_clear();
    if !quiet {
        eprintln!(
            "vpl: table1 shard {}/{}: {} units run, {} already done, of {} in the run; {:.0} s",
            shard_arg.index, shard_arg.count, summary.ran, summary.kept, summary.total_units, summary.seconds
        );
    }
    if shard.is_none() {
        let (_, cost) = pool.install(|| table1::merge_with_cost(&out)).map_err(|e| e.to_string())?;
        if !quiet {
            if let Some(e) = &cost {
                eprintln!("vpl: table1: estimated {}", table1::report::estimate_line(e));
            }
            eprintln!("vpl: table1 -> {}", out.join("table1.md").display());
        }
    }
    Ok(())
}

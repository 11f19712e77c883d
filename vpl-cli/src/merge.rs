//! `vpl merge`: Merge the unit files of a sharded Table 1 run (all shards done) into its tables and plots.

use super::*;

/// Merge the unit files of a sharded Table 1 run (all shards done) into its tables and plots.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The run's output folder.
    dir: PathBuf,
    /// Only report the units done per shard (of --shards), merging nothing.
    #[arg(long)]
    status: bool,
    /// Shards of the run, for --status.
    #[arg(long, default_value_t = 1)]
    shards: u32,
}

/// Runs `vpl merge`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { dir, status, shards } = args;
    if !dir.join("spec.json").exists() {
        return Err(format!("{} holds no Table 1 run (no spec.json)", dir.display()));
    }
    if status {
        let all = vpl_bench::table1::status(&dir, shards).map_err(|e| e.to_string())?;
        let (done, total) = all.iter().fold((0, 0), |(d, t), s| (d + s.done, t + s.total));
        for s in &all {
            println!("shard {}/{}: {} of {} units", s.shard.index, s.shard.count, s.done, s.total);
        }
        println!("all: {done} of {total} units{}", if done == total { ", ready to merge" } else { "" });
        return Ok(());
    }
    vpl_bench::table1::merge(&dir).map_err(|e| e.to_string())?;
    eprintln!("vpl: merged -> {}", dir.join("table1.md").display());
    Ok(())
}

//! `vpl merge`: Merge the unit files of a sharded Table 1 run (all shards done) into its tables and plots.

use super::*;

/// Merge the unit files of a sharded Table 1 run (all shards done) into its tables and plots.
#[derive(clap::Args)]
pub(super) struct Args {
    /// The run's output folder.
    dir: PathBuf,
}

/// Runs `vpl merge`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { dir } = args;
    if !dir.join("spec.json").exists() {
        return Err(format!("{} holds no Table 1 run (no spec.json)", dir.display()));
    }
    vpl_bench::table1::merge(&dir).map_err(|e| e.to_string())?;
    eprintln!("vpl: merged -> {}", dir.join("table1.md").display());
    Ok(())
}

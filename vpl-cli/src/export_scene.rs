//! `vpl export-scene`: Print a built-in scene (or any scene) as a TOML scene file.

use super::*;

/// Print a built-in scene (or any scene) as a TOML scene file.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Built-in name or scene file.
    name: String,
    /// Write to this file instead of standard output.
    #[arg(long)]
    out: Option<PathBuf>,
}

/// Runs `vpl export-scene`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { name, out } = args;
    let setup = vpl_scene_io::load(&name).map_err(|e| e.to_string())?;
    emit(out.as_deref(), &vpl_scene_io::scene_toml(&setup.description))
}

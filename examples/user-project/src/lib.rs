//! A user's experiment: the uniform-by-area sampler of the toolkit's
//! `user_sampler` example, registered beside the built-in samplers, run
//! through the renderer library (`src/main.rs`), and, with
//! `--features cli`, through the toolkit's command line (`src/bin/vpl.rs`).
//!
//! `cargo run` renders three frames of `office` with it and with SMC;
//! `cargo run --features cli --bin vpl -- render --scene cornell --method vpl --sampler uniform-area`
//! is the `vpl` command with this project's registry.

#[path = "../../../vpl-cli/examples/user_sampler/uniform_area.rs"]
mod uniform_area;

use vpl_render::Registry;

/// The built-in samplers and this project's own.
pub fn registry() -> Registry {
    Registry::builtin().with(uniform_area::UniformArea::entry()).expect("the name is free")
}

//! A user's experiment: the uniform-by-area sampler of the toolkit's
//! `user_sampler` example, registered beside the built-in samplers, run
//! through the renderer library, and, with `--features cli`, through the
//! toolkit's command line.
//!
//! `cargo run` renders three frames of `office` with it and with SMC;
//! `cargo run --features cli -- render --scene cornell --method vpl --sampler uniform-area`
//! is the `vpl` command with this project's registry.

#[path = "../../../vpl-bench/examples/user_sampler/uniform_area.rs"]
mod uniform_area;

use vpl_render::Registry;

fn registry() -> Registry {
    Registry::builtin().with(uniform_area::UniformArea::entry()).expect("the name is free")
}

#[cfg(feature = "cli")]
fn main() {
    vpl_bench::cli::main(&registry())
}

#[cfg(not(feature = "cli"))]
fn main() -> Result<(), Box<dyn std::error::Error>> {
    use vpl_render::vpl_core::{Mode, SceneSetup};
    use vpl_render::{Renderer, VisibilitySpec};

    let registry = registry();
    let setup = SceneSetup::load("office")?;
    for sampler in ["uniform-area", "smc"] {
        let mut renderer = Renderer::builder(&setup.scene)
            .registry(&registry)
            .vpls(128)
            .sampler(sampler)
            .visibility(VisibilitySpec::RayTraced)
            .mode(Mode::Indirect)
            .build()?;
        for f in 0..3u32 {
            let (scene, camera) = setup.frame(f * 15)?;
            let out = renderer.render(&scene, &camera.with_resolution((48, 27))?, f as u64, f as f32 / 2.0)?;
            let m = out.image.mean();
            println!(
                "{sampler:>12} frame {f}: {:3} moved, mean indirect {:.4}, {:.1} ms",
                out.moved,
                (m[0] + m[1] + m[2]) / 3.0,
                out.timings.total_ms
            );
        }
    }
    Ok(())
}

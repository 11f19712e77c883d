//! Three frames of `office` rendered with this project's uniform-by-area
//! sampler and with SMC, through the renderer library.

fn main() -> Result<(), Box<dyn std::error::Error>> {
    use vpl_render::vpl_core::{Mode, SceneSetup};
    use vpl_render::{Renderer, VisibilitySpec};

    let registry = my_vpl_experiment::registry();
    let setup = SceneSetup::builtin("office")?;
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

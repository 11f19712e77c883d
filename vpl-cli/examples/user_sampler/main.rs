//! A sampler of your own, everywhere the toolkit's go: registered once, then
//! rendered through the library (alone and as the candidate source of
//! Russian-roulette acceptance) and through every subcommand of the `vpl`
//! command (`render`, `sequence`, a small Table 1), by calling
//! `vpl_cli::run` with your registry.
//!
//! Run: `cargo run -p vpl-bench --example user_sampler`

mod uniform_area;

use uniform_area::UniformArea;
use vpl_render::vpl_core::{Mode, Params, SceneSetup};
use vpl_render::{Registry, Renderer, ShadingSpec, VisibilitySpec};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let registry = Registry::builtin().with(UniformArea::entry())?;

    // Through the library: four frames of office's walk, 256 VPLs, shadow maps.
    let setup = SceneSetup::builtin("office")?;
    for (sampler, params) in [("uniform-area", vec![]), ("rr", vec!["candidates=uniform-area", "rr-pilot=true"])] {
        let mut renderer = Renderer::builder(&setup.scene)
            .registry(&registry)
            .vpls(256)
            .sampler(sampler)
            .params(Params::parse(params)?)
            .visibility(VisibilitySpec::ShadowMaps(32))
            .shader(ShadingSpec::Interleaved { filter: true })
            .mode(Mode::Indirect)
            .build()?;
        for f in 0..4u32 {
            let (scene, camera) = setup.frame(f * 10)?;
            let camera = camera.with_resolution((64, 36))?;
            let out = renderer.render(&scene, &camera, f as u64, f as f32 / 3.0)?;
            let mean = out.image.mean();
            println!(
                "{sampler} frame {f}: {} stored, {} moved, mean {:.4}  [{}]",
                out.stored,
                out.moved,
                (mean[0] + mean[1] + mean[2]) / 3.0,
                out.sampler_stats
            );
        }
    }

    // Through the command line, with the same registry.
    let dir = std::env::temp_dir().join(format!("vpl-user-sampler-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let runs = [
        ("render.exr", "vpl render --scene cornell --method vpl --sampler uniform-area --radiosity-paths 8 --vpls 256 --size 64x64"),
        ("sequence", "vpl sequence --scene office --sampler uniform-area --vpls 128 --frames 0..3 --size 32x18 --shadowmap-res 16"),
        ("table1", "vpl table1 --scene maze --methods ir,uniform-area --frames 300..302 --size 32x24 --truth-spp 16"),
    ]
    .map(|(out, line)| {
        let mut args: Vec<String> = line.split_whitespace().map(String::from).collect();
        args.extend(["--quiet".into(), "--out".into(), dir.join(out).to_string_lossy().into_owned()]);
        args
    });
    for args in runs {
        println!("$ {}", args.join(" "));
        let code = vpl_cli::run(&registry, &args);
        if code != 0 {
            let _ = std::fs::remove_dir_all(&dir);
            return Err(format!("{} exited with {code}", args[1]).into());
        }
    }
    println!("{}", std::fs::read_to_string(dir.join("table1/table1.md"))?);
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}

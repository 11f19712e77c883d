//! `vpl bench-rays`: BVH build time and memory, and rays per second for
//! closest hits and occlusion, on scenes of growing size.

use super::*;
use vpl_bench::rays::{RaySets, closest_rate, fan_rate, occluded_rate, side_by_side, timed_build};

/// BVH build time and memory, and M rays/s for primary and diffuse closest hits and shadow
/// occlusion, on `cornell` (36 triangles), Dabrovic's Sponza (66K) and five Sponzas side by
/// side (330K), or the scenes given.
#[derive(clap::Args)]
pub(super) struct Args {
    /// Scenes (built-in names, .toml, .obj, .gltf, .glb or Mitsuba .xml files); default: cornell, Sponza and its copies.
    #[arg(long, value_delimiter = ',')]
    scene: Vec<String>,
    /// Copies side by side of the last scene given (or of Sponza), as one more row (1: none).
    #[arg(long, default_value_t = 5)]
    copies: usize,
    /// Primary rays: one per pixel of an image of this size (diffuse and shadow rays from their hits).
    #[arg(long, default_value = "512x512")]
    size: Size,
    /// Least seconds each figure is measured over (the fastest pass is reported).
    #[arg(long, default_value_t = 1.0)]
    seconds: f64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// The default scenes: `cornell` and, where its model is present, Sponza.
fn default_scenes() -> Vec<String> {
    let mut s = vec!["cornell".to_string()];
    match vpl_bench::scenes::locate("sponza-dabrovic.toml") {
        Ok(sponza) => match vpl_bench::scenes::model_missing(&sponza) {
            None => s.push(sponza.display().to_string()),
            Some(why) => eprintln!("bench-rays: Dabrovic's Sponza: {why}; cornell only"),
        },
        Err(why) => eprintln!("bench-rays: {why}; cornell only"),
    }
    s
}

/// Runs `vpl bench-rays`.
pub(super) fn run(args: Args, _registry: &Registry) -> Res<()> {
    let Args { scene, copies, size, seconds, threads } = args;
    if copies == 0 || size.0 == 0 || size.1 == 0 || !(0.0..=600.0).contains(&seconds) {
        return Err("--copies and --size must be at least 1, --seconds within 0..600".into());
    }
    let pool = pool(threads)?;
    let scenes = if scene.is_empty() { default_scenes() } else { scene };
    println!(
        "bench-rays: {}x{} primary rays (one diffuse and one shadow ray from each hit), {} threads, fastest pass of at least {seconds} s, traversal for {}",
        size.0,
        size.1,
        pool.current_num_threads(),
        if vpl_core::bvh::Bvh::build(&[]).is_ok_and(|b| b.uses_avx2()) { "AVX2 and FMA" } else { "SSE2" }
    );
    println!(
        "| scene | triangles | build (ms) | BVH (MiB) | nodes | primary (M rays/s) | primary, 8×8 bundles (M rays/s) | diffuse (M rays/s) | shadow (M rays/s) |"
    );
    println!("| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |");
    let last = scenes.len() - 1;
    for (i, spec) in scenes.iter().enumerate() {
        let setup = vpl_scene_io::load(spec).map_err(|e| e.to_string())?;
        let name = setup.scene.name.clone();
        let tris = &setup.scene.geometry.triangles;
        let sets = pool.install(|| RaySets::new(&setup.scene, &setup.camera, (size.0, size.1), 1));
        let mut rows = vec![(name.clone(), tris.clone())];
        if i == last && copies > 1 {
            rows.push((format!("{name} ×{copies}"), side_by_side(tris, copies)));
        }
        for (label, tris) in rows {
            let (bvh, build) = pool.install(|| timed_build(&tris, seconds.min(2.0))).map_err(|e| e.to_string())?;
            let (p, f, d, s) = pool.install(|| {
                (
                    closest_rate(&bvh, &sets.primary, seconds),
                    sets.eye.map(|eye| fan_rate(&bvh, eye, &sets.primary_tiles, seconds)),
                    closest_rate(&bvh, &sets.diffuse, seconds),
                    occluded_rate(&bvh, &sets.shadow, seconds),
                )
            });
            println!(
                "| {label} | {} | {:.2} | {:.2} | {} | {:.2} | {} | {:.2} | {:.2} |",
                tris.len(),
                build * 1e3,
                bvh.memory_bytes() as f64 / (1 << 20) as f64,
                bvh.node_count(),
                p.rays_per_second() / 1e6,
                f.map_or("–".to_string(), |f| format!("{:.2}", f.rays_per_second() / 1e6)),
                d.rays_per_second() / 1e6,
                s.rays_per_second() / 1e6
            );
        }
    }
    Ok(())
}

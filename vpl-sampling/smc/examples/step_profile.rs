//! The cost of SMC's step where it runs: `office` at I = 2048 after 20
//! iterations, the camera walking from frame 300; prints each frame's
//! milliseconds (a target for `perf record`).
//!
//! Run: `cargo run --release -p vpl-smc --example step_profile [flux] [frames] [probes-per-vpl] [probe-iterations]`

use vpl_core::SceneSetup;
use vpl_smc::{FluxEstimator, SmcConfig, SmcSampler};

fn main() {
    let mut args = std::env::args().skip(1);
    let flux = match args.next().as_deref() {
        Some("knn") => FluxEstimator::Knn,
        _ => FluxEstimator::Voronoi,
    };
    let frames: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(40);
    let d = SmcConfig::default();
    let probes_per_vpl = args.next().and_then(|a| a.parse().ok()).unwrap_or(d.probes_per_vpl);
    let probe_iterations = args.next().and_then(|a| a.parse().ok()).unwrap_or(d.probe_iterations);
    let setup = SceneSetup::builtin("office").expect("a built-in scene");
    let mut smc = SmcSampler::new(SmcConfig { flux, probes_per_vpl, probe_iterations, ..d }).expect("valid settings");
    let frame = |f: u32| {
        let (scene, camera) = setup.frame(300 + f).expect("a frame of the sequence");
        (scene, camera.with_resolution((640, 360)).expect("a valid size"))
    };
    let (scene, camera) = frame(0);
    for _ in 0..20 {
        smc.iterate(&scene, &camera, 0);
    }
    let mut ms = Vec::new();
    for f in 1..=frames {
        let (scene, camera) = frame(f);
        smc.iterate(&scene, &camera, 0);
        ms.push(smc.timings().total_ms);
    }
    ms.sort_by(f64::total_cmp);
    println!(
        "{flux}, {probes_per_vpl} probes a VPL, T = {probe_iterations}: median {:.1} ms a step over {frames} frames",
        ms[ms.len() / 2]
    );
}

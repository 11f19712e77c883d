//! SMC's step, stage by stage, on a scene's sequence: the loop to profile
//! (`perf record`) when the step's cost changes.
//!
//! ```text
//! cargo run --release -p vpl-bench --example smc_step -- [SCENE] [FRAMES] [KEY=VALUE ...]
//! ```
//!
//! The sampler (I = 2048, the scene's own budget otherwise; `KEY=VALUE` are
//! SMC's parameters, e.g. `flux=knn`) takes 20 steps at frame 300 of the
//! sequence, then walks FRAMES frames (default 60) from there at 640×360;
//! the medians of each stage's milliseconds over those frames are printed,
//! as `vpl bench-vpl` reports them, with a hash of the last frame's VPLs
//! (positions, normals, fluxes and ids, bit for bit): a change meant only
//! to make the step faster keeps it.

use vpl_core::{Budget, Params};
use vpl_sampling::{SmcConfig, SmcSampler};

fn main() {
    if let Err(e) = run() {
        eprintln!("smc_step: {e}");
        std::process::exit(2);
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let name = args.first().map_or("office", String::as_str);
    let frames: u32 = args.get(1).map_or(Ok(60), |s| s.parse())?;
    let params = Params::parse(args.iter().skip(2))?;
    let config = SmcConfig::from_params(&Budget::default(), &params)?;
    params.check_used("smc")?;
    let setup = vpl_scene_io::load(name)?;
    let count = setup.sequence.as_ref().map_or(1, |s| s.frame_count());
    let mut smc = SmcSampler::new(config)?;
    let mut rows: Vec<[f64; 6]> = Vec::new();
    let mut hash = 0xcbf2_9ce4_8422_2325u64;
    for f in 0..frames.max(1) + 20 {
        let (scene, camera) = setup.frame((300 + f.saturating_sub(20)).min(count - 1))?;
        let camera = camera.with_resolution((640, 360))?;
        let set = smc.iterate(&scene, &camera, 0);
        if f == frames.max(1) + 19 {
            // FNV-1a over the bits of every VPL of the last frame.
            for (slot, v) in set.iter() {
                let words = [v.y.to_array(), v.n.to_array(), v.flux.to_array()].concat().into_iter().map(|x| x.to_bits() as u64);
                for w in [slot as u64, v.id].into_iter().chain(words) {
                    hash = (hash ^ w).wrapping_mul(0x0100_0000_01b3);
                }
            }
        }
        if f >= 20 {
            let t = smc.timings();
            rows.push([t.candidates_ms, t.resampling_ms, t.visibility_ms, t.radiosity_ms, t.knn_ms, t.total_ms]);
        }
    }
    let median = |i: usize| {
        let mut v: Vec<f64> = rows.iter().map(|r| r[i]).collect();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{name}: cand. sampling {:.1} | cand. resampling {:.1} | indirect visibility {:.1} | radiosity {:.1} | kNN {:.1} | total {:.1} ms (median of {} frames), VPLs {hash:016x}",
        median(0),
        median(1),
        median(2),
        median(3),
        median(4),
        median(5),
        rows.len()
    );
    Ok(())
}

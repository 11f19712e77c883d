//! SMC's indirect light against the path tracer's along whole sequences:
//! the default clamp's removed share within 5 %, and (not met yet: the
//! ignored test says where) the default estimator's unclamped image mean
//! within 3 % at frame 0 and over each sequence,
//! on every built-in scene (the two of heavy occlusion, `building` and
//! `colonnade`, among them) and the real scenes of `../shared/scenes`
//! (when their models are there). Measured by `vpl_bench::energy`, the
//! code behind `vpl energy`.

use vpl_bench::energy::{EnergyRun, EnergySettings, Estimate, measure};
use vpl_core::SceneSetup;
use vpl_sampling::Registry;

/// The scenes: every built-in, then the real ones that are here.
fn scenes() -> Vec<(String, SceneSetup)> {
    let mut scenes: Vec<(String, SceneSetup)> =
        vpl_core::builtin::NAMES.iter().map(|n| (n.to_string(), vpl_scene_io::load(n).unwrap())).collect();
    for file in ["sponza-dabrovic.toml", "city-munich.toml"] {
        if let Some(path) = vpl_tests::real_scene(file) {
            scenes.push((file.to_string(), vpl_scene_io::load(&path.to_string_lossy()).unwrap()));
        }
    }
    scenes
}

/// `e` with the truth's relative standard error added to its own (the
/// ratios share the truth's image, so its error is not in the seeds' spread).
fn with_truth(e: Estimate, run: &EnergyRun) -> Estimate {
    Estimate { mean: e.mean, se: (e.se * e.se + (e.mean * run.truth_rel_se()).powi(2)).sqrt() }
}

/// Standard errors past the bound at which a mean fails (one-sided z at
/// 2.5: a mean that meets its bound fails under 1 % of the time).
const Z: f64 = 2.5;

/// The test's settings: the sampler's defaults (I = 2048, its warm-up),
/// 3 seeds, 48×36 pixels, the truth at 256 paths a pixel through the pixel
/// centres; 3 checkpoints at the centres of the sequence's thirds, the
/// sampler stepped every 8th frame and then at each of the 32 frames (2T)
/// before a checkpoint, so that the probes a checkpoint's cells hold come
/// from consecutive frames at 30 fps (their lag as a renderer has it).
fn settings(sampler: &str) -> EnergySettings {
    EnergySettings {
        sampler: sampler.into(),
        size: (48, 36),
        seeds: 3,
        checkpoints: 3,
        stride: 8,
        settle: 32,
        truth_spp: 256,
        ..EnergySettings::default()
    }
}

/// Standard error past which a mean is too uncertain to judge (and fails).
const MAX_SE: f64 = 0.02;

/// Each scene's run with `s`, its figures printed.
fn runs(s: &EnergySettings) -> Vec<EnergyRun> {
    let registry = Registry::builtin();
    scenes()
        .into_iter()
        .map(|(name, setup)| {
            let run = measure(&registry, &name, &setup, s, &mut |_| {}).unwrap();
            let (f0, seq, clamp) = (with_truth(run.frame0_ratio(), &run), with_truth(run.sequence_ratio(), &run), run.clamp_removed());
            eprintln!(
                "{name}: frame 0 {:.3} ± {:.3}, sequence {:.3} ± {:.3}, clamp removes {:.2} % ± {:.2} ({:.0} s)",
                f0.mean,
                f0.se,
                seq.mean,
                seq.se,
                100.0 * clamp.mean,
                100.0 * clamp.se,
                run.seconds
            );
            run
        })
        .collect()
}

/// The default clamp (G_max = I / A_view of each checkpoint's own view)
/// removes at most 5 % of the default SMC's indirect light on every scene,
/// averaged over the checkpoints of its sequence (the same VPLs shaded
/// with and without it: ray-traced, exhaustive, indirect only). The image
/// means against path tracing are printed beside.
///
/// Bound: the share fails when it lies past 5 % by more than 2.5 of its
/// standard errors over the seeds (one-sided z: a share that meets the
/// bound fails under 1 % of the time), or when that standard error is
/// above 2 % and the comparison too weak to judge. Measured: at most
/// 2.7 % ± 0.8 (the Munich blocks), under 1 % on every other scene.
#[test]
fn the_default_clamp_takes_at_most_5_percent_along_every_sequence() {
    let mut failures = Vec::new();
    for run in runs(&settings("smc")) {
        let clamp = run.clamp_removed();
        if clamp.se > MAX_SE || clamp.mean - 0.05 > Z * clamp.se {
            failures.push(format!("{}: the clamp removes {:.1} % ± {:.1}", run.scene, 100.0 * clamp.mean, 100.0 * clamp.se));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("; "));
}

/// The default SMC (Voronoi-cell flux at the VPLs' own points),
/// unclamped, ray-traced, exhaustive, indirect only: its image mean over
/// the path tracer's within 3 % of 1 at frame 0 and averaged over the
/// checkpoints of every sequence, 3 seeds (same bound and standard-error
/// limit as the clamp's).
///
/// Not met yet, measured at these settings: the Munich blocks at frame 0
/// 1.109 ± 0.016 (16 seeds; 8 seeds with every hit a probe and equal
/// weights gave 1.173 ± 0.033, so the thinned probes are not the cause:
/// the sites' offset from their cells' centroids is, and a heavy tail of
/// huge far cells whose light a point cannot stand for; see
/// `vpl_smc::Placement`); and on `office`, `corner` and Sponza 3 seeds
/// leave standard errors of 2.2–3.1 % at frame 0 (1.032, 1.003, 1.021),
/// too wide to judge 3 %. Every other mean passes: `building`'s sequence,
/// whose lamp is carried from room to room, is 1.030 ± 0.007 with the
/// cells brought to the lights of now ([`vpl_smc::Relight`]; 1.063 ±
/// 0.008 when each cell followed its VPL's change), and `maze`'s 0.989 ±
/// 0.009 with every candidate's first estimate in its cell (0.967 ± 0.008
/// when the candidates that joined the set took their second). With
/// `placement=random` the Munich blocks' frame 0 is 1.023 ± 0.024 over
/// 16 seeds, but `atrium`'s 0.949 ± 0.011 (`vpl_smc::Placement`).
#[test]
#[ignore = "Munich's frame 0 (1.109 ± 0.016) is past 3 %; office, corner and Sponza need more than 3 seeds"]
fn smc_keeps_the_light_at_frame_0_and_along_every_sequence() {
    let mut failures = Vec::new();
    for run in runs(&settings("smc")) {
        for (what, e) in [("frame 0", with_truth(run.frame0_ratio(), &run)), ("sequence", with_truth(run.sequence_ratio(), &run))] {
            if e.se > MAX_SE || e.z_past(1.0, 0.03) > Z {
                failures.push(format!("{}: {what} image mean {:.3} ± {:.3} of the path tracer's", run.scene, e.mean, e.se));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("; "));
}

/// The same measure sees the bias it guards against: the paper's kNN flux
/// (`smc-knn`) at frame 0 of `cornell` and `atrium` lies past 3 % too
/// bright by more than 2.5 standard errors.
#[test]
fn the_measure_sees_the_knn_flux_too_bright() {
    let registry = Registry::builtin();
    let s = EnergySettings { checkpoints: 0, ..settings("smc-knn") };
    for name in ["cornell", "atrium"] {
        let setup = vpl_scene_io::load(name).unwrap();
        let run = measure(&registry, name, &setup, &s, &mut |_| {}).unwrap();
        let f0 = with_truth(run.frame0_ratio(), &run);
        eprintln!("{name}: kNN flux, frame 0 {:.3} ± {:.3}", f0.mean, f0.se);
        assert!(f0.mean > 1.03 && f0.z_past(1.0, 0.03) > Z, "{name}: the kNN flux gives {:.3} ± {:.3}", f0.mean, f0.se);
    }
}

//! The many-light study on tiny settings: frames are averaged (the error
//! falls as independent frames come in), every configuration is reported,
//! and the temporal table measures a Table 1 sequence.

use vpl_bench::manylights::{ManyLightsSettings, Source, markdown, measure, plot, temporal};
use vpl_bench::pipeline::ShadingSpec;
use vpl_core::SceneSetup;
use vpl_render::Clamp;
use vpl_sampling::Registry;

fn tiny() -> ManyLightsSettings {
    ManyLightsSettings {
        sources: vec![Source { sampler: "ir".into(), vpls: 256 }, Source { sampler: "ir".into(), vpls: 64 }],
        gathers: vec![ShadingSpec::Exhaustive, ShadingSpec::Lightcuts { cut: 4 }],
        size: (24, 18),
        // Frames, not time, end these runs: the test's numbers do not
        // depend on the machine's speed.
        seconds: 1e9,
        max_frames: 12,
        reference_spp: 256,
        truth_spp: 256,
        max_depth: 3,
        clamp: Clamp::Off,
        ..ManyLightsSettings::default()
    }
}

#[test]
fn averaged_frames_approach_the_reference_and_every_configuration_is_reported() {
    let registry = Registry::builtin();
    let setup = SceneSetup::builtin("cornell").unwrap();
    let s = tiny();
    let study = measure(&registry, "cornell", &setup, &s, &mut |_| {}).unwrap();
    // Sources run smallest first, each with every gather.
    let order: Vec<(usize, &str)> = study.curves.iter().map(|c| (c.source.vpls, c.gather.as_str())).collect();
    assert_eq!(order, [(64, "exhaustive"), (64, "lightcuts:4"), (256, "exhaustive"), (256, "lightcuts:4")]);
    for c in &study.curves {
        assert_eq!(c.predicted_s, None, "nothing is predicted over a budget of 1e9 s");
        assert_eq!(c.points.len(), 12, "{} {}", c.source.label(), c.gather);
        assert!(c.points.windows(2).all(|p| p[1].seconds > p[0].seconds && p[1].frames == p[0].frames + 1));
        // Unclamped IR frames are independent and unbiased: the mean of 12
        // has a quarter of one frame's variance beside the same (small)
        // reference noise, so its error must fall clearly (a run that kept
        // the last frame instead of the mean would not).
        let (first, last) = (c.points[0].rmse, c.points[11].rmse);
        assert!(last < 0.75 * first, "{} {}: RMSE {first} after one frame, {last} after 12", c.source.label(), c.gather);
    }
    // Four lights a pixel are noisier than every light.
    let at = |vpls, g: &str| study.curves.iter().find(|c| c.source.vpls == vpls && c.gather == g).unwrap().points[0].rmse;
    assert!(at(256, "lightcuts:4") > at(256, "exhaustive"));
    let md = markdown(std::slice::from_ref(&study), None, &s);
    for label in ["| IR 64 | exhaustive |", "| IR 256 | lightcuts:4 |", "Lowest error at"] {
        assert!(md.contains(label), "{label} missing from\n{md}");
    }
    let dir = std::env::temp_dir().join(format!("vpl-manylights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    plot(&dir, &study).unwrap();
    assert!(std::fs::metadata(dir.join("manylights_cornell.png")).unwrap().len() > 1000);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_gather_that_grows_with_the_vpls_is_not_run_past_the_budget() {
    let registry = Registry::builtin();
    let setup = SceneSetup::builtin("cornell").unwrap();
    // A 1M-VPL exhaustive frame at 24×18 is 4.5·10⁸ shadow rays: predicted
    // from the 64-VPL frame, it is over a budget of 0.5 s on any machine
    // this runs on, and must not be rendered (it would take minutes).
    let s = ManyLightsSettings {
        sources: vec![Source { sampler: "ir".into(), vpls: 64 }, Source { sampler: "ir".into(), vpls: 1 << 20 }],
        gathers: vec![ShadingSpec::Exhaustive],
        seconds: 0.5,
        max_frames: 2,
        ..tiny()
    };
    let study = measure(&registry, "cornell", &setup, &s, &mut |_| {}).unwrap();
    let big = &study.curves[1];
    assert!(big.points.is_empty() && big.predicted_s.is_some_and(|p| p > 0.5), "{big:?}");
    let md = markdown(std::slice::from_ref(&study), None, &s);
    assert!(md.contains("| IR 1M | exhaustive | — | ≈"), "{md}");
}

#[test]
fn the_temporal_table_measures_a_table1_sequence() {
    let registry = Registry::builtin();
    let row = vpl_bench::table1::rows::row("office").unwrap();
    let s = ManyLightsSettings {
        sources: vec![Source { sampler: "smc".into(), vpls: 64 }],
        gathers: vec![ShadingSpec::Exhaustive, ShadingSpec::Lightcuts { cut: 4 }],
        truth_spp: 64,
        ..tiny()
    };
    let t = temporal(&registry, &row, &s, &mut |_| {}).unwrap();
    assert_eq!((t.row.as_str(), t.pixels, t.rows.len()), ("office", row.tracked.len(), 2));
    for r in &t.rows {
        let e = r.error.expect("run");
        assert_eq!(e.count, row.tracked.len() * row.quick_frames.len());
        assert!(e.e.is_finite() && e.e > 0.0 && e.e_prime.is_finite(), "{e:?}");
    }
    let md = markdown(&[], Some(&t), &s);
    assert!(md.contains("Temporal error on Table 1's `office`") && md.contains("| SMC 64 | lightcuts:4 |"), "{md}");
}

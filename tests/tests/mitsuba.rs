//! The path tracer against Mitsuba 3.9.1 on `cornell`, in the three modes.
//!
//! Reference: 32768 spp with per-pixel standard errors. Ours: [`SPP`] spp with
//! per-pixel standard errors. Criteria (each can fail):
//! - image mean within 4 combined standard errors in every channel; the test
//!   checks that a 0.1 % bias of our image would fail this;
//! - a per-pixel test at α = 0.01 (three channel z-tests at α/3, Bonferroni)
//!   passes for ≥ 99 % of pixels. A correct renderer fails at most 1 % in
//!   expectation; the skew of path-traced samples pushes failures up at low
//!   spp, which is why [`SPP`] is well above the 256 floor.
//!
//! On failure the difference and |z| images are written to
//! `target/test-output/mitsuba/`.

use vpl_bench::validation::{validate_cornell, write_difference};
use vpl_render::compare::compare;
use vpl_scene_io::ImageFile;
use vpl_tests::{data_dir, scratch_dir};

/// Samples per pixel of our renders.
const SPP: u32 = 2048;

#[test]
fn path_tracer_matches_mitsuba_full_direct_indirect() {
    let vs = validate_cornell(&data_dir().join("cornell-box"), SPP, 1, &|_, _, _| {}).unwrap();
    let mut failures = Vec::new();
    for v in &vs {
        let c = &v.comparison;
        let line = format!(
            "{}: {:.3} % of pixels pass, mean z = ({:+.2}, {:+.2}, {:+.2})",
            v.mode,
            100.0 * c.pass_rate,
            c.mean_z[0],
            c.mean_z[1],
            c.mean_z[2]
        );
        eprintln!("{line}");
        if c.pass_rate < 0.99 || c.mean_z.iter().any(|z| z.abs() > 4.0) {
            write_difference(v, &scratch_dir("mitsuba")).unwrap();
            failures.push(line);
        }
    }
    assert!(failures.is_empty(), "differs from Mitsuba (difference images in target/test-output/mitsuba): {failures:?}");
    // Power: a 0.1 % bias in our image must fail the mean criterion in every mode.
    for v in &vs {
        let mut biased = v.ours.0.clone();
        for p in biased.data.iter_mut() {
            *p *= 1.001;
        }
        let c = compare(&biased, &v.ours.1, &v.theirs.0, &v.theirs.1, 0.01).unwrap();
        eprintln!("{} with a 0.1 % bias: mean z = ({:+.1}, {:+.1}, {:+.1})", v.mode, c.mean_z[0], c.mean_z[1], c.mean_z[2]);
        assert!(c.mean_z.iter().any(|z| z.abs() > 4.0), "{}: a 0.1 % bias went undetected", v.mode);
    }
}

/// Mitsuba's Cornell box written as a Mitsuba XML scene
/// (`data/cornell-box/cornell.xml`: rectangles and cubes placed by
/// `to_world` steps, as `mitsuba.cornell_box()` builds it) is the built-in
/// `cornell` (same area per material, same bounds) and renders Mitsuba's
/// reference: the image mean of 512 spp (full light, depth 5) within 4
/// combined standard errors of the 32768-spp reference in every channel
/// (P ≈ 6e-5 per channel for a correct renderer), and a 0.5 % bias of the
/// same image fails that.
#[test]
fn cornell_written_as_mitsuba_xml_renders_the_reference() {
    use vpl_core::{Image, SceneSetup};
    use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render};
    let dir = data_dir().join("cornell-box");
    let xml = vpl_scene_io::load(dir.join("cornell.xml").to_str().unwrap()).unwrap();
    let builtin = SceneSetup::builtin("cornell").unwrap();
    let area_by_material = |s: &vpl_core::Scene| {
        let mut v: Vec<(String, f64)> = s
            .materials
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let a: f64 = s.geometry.triangles.iter().filter(|t| t.material as usize == i).map(|t| t.area as f64).sum();
                // The XML's light material is "white+emitter", the built-in's "light".
                (if m.is_emissive() { "light".to_string() } else { m.name.clone() }, a)
            })
            .collect();
        v.sort_by(|a, b| a.0.cmp(&b.0));
        v
    };
    let (a, b) = (area_by_material(&xml.scene), area_by_material(&builtin.scene));
    assert_eq!(a.len(), b.len(), "{a:?} {b:?}");
    for ((na, aa), (nb, ab)) in a.iter().zip(&b) {
        assert_eq!(na, nb);
        assert!((aa / ab - 1.0).abs() < 1e-4, "{na}: area {aa} vs {ab}");
    }
    let (lo, hi) = (xml.scene.geometry.bounds, builtin.scene.geometry.bounds);
    assert!((lo.0 - hi.0).abs().max_element() < 1e-4 && (lo.1 - hi.1).abs().max_element() < 1e-4, "{lo:?} {hi:?}");
    assert_eq!(xml.scene.two_sided, builtin.scene.two_sided);
    assert_eq!(xml.camera.resolution, (256, 256));

    let r = render(&xml.scene, &xml.camera, &PathTracer::new(5, Mode::Full), RenderSettings { spp: 512, seed: 11, frame: 0 }, &|_, _| {})
        .unwrap();
    let reference = Image::read_exr(dir.join("reference_path_d5.exr")).unwrap();
    let reference_se = Image::read_exr(dir.join("reference_path_d5_stderr.exr")).unwrap();
    let c = compare(&r.image, &r.stderr, &reference, &reference_se, 0.01).unwrap();
    eprintln!(
        "cornell.xml: mean z = ({:+.2}, {:+.2}, {:+.2}), {:.2} % of pixels pass",
        c.mean_z[0],
        c.mean_z[1],
        c.mean_z[2],
        100.0 * c.pass_rate
    );
    assert!(c.mean_z.iter().all(|z| z.abs() <= 4.0), "cornell.xml differs from Mitsuba's reference: {:?}", c.mean_z);
    let mut biased = r.image.clone();
    for p in biased.data.iter_mut() {
        *p *= 1.005;
    }
    let cb = compare(&biased, &r.stderr, &reference, &reference_se, 0.01).unwrap();
    assert!(cb.mean_z.iter().any(|z| z.abs() > 4.0), "a 0.5 % bias went undetected: {:?}", cb.mean_z);
}

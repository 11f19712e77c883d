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

//! Validation of the path tracer against Mitsuba 3.9.1 on `cornell`.
//!
//! The references (32768 spp, box filter, with per-pixel standard errors) are
//! in `tests/data/cornell-box/`. For each mode (full d5, direct d2, indirect
//! d5 − d2) the toolkit renders `cornell` and compares with [`compare`].

use crate::compare::{Comparison, compare, difference};
use std::path::Path;
use vpl_core::{CoreError, Image, SceneSetup};
use vpl_pathtrace::{Mode, PathTracer, RenderSettings, render};
use vpl_scene_io::ImageFile;
use vpl_scene_io::SceneIoError;

/// One mode's validation result.
#[derive(Clone, Debug)]
pub struct ModeValidation {
    /// "full", "direct" or "indirect".
    pub mode: &'static str,
    /// Reference file stem.
    pub reference: &'static str,
    /// The comparison.
    pub comparison: Comparison,
    /// Our image and standard error.
    pub ours: (Image, Image),
    /// The reference and its standard error.
    pub theirs: (Image, Image),
    /// Render time (s).
    pub seconds: f64,
}

/// The three modes and the Mitsuba files they are checked against.
pub const MODES: [(&str, Mode, u32, &str); 3] = [
    ("full", Mode::Full, 5, "reference_path_d5"),
    ("direct", Mode::Direct, 5, "reference_direct_d2"),
    ("indirect", Mode::Indirect, 5, "reference_indirect"),
];

/// Renders `cornell` at `spp` in the three modes and compares with the
/// references in `data_dir`. `progress(mode, pixels_done, pixels_total)` is
/// called as the renders advance.
pub fn validate_cornell(
    data_dir: &Path,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(&str, u64, u64) + Sync),
) -> Result<Vec<ModeValidation>, SceneIoError> {
    let setup = SceneSetup::builtin("cornell")?;
    // Every reference is read (and checked) before any rendering starts.
    let mut references = Vec::new();
    for (_, _, _, stem) in MODES {
        let reference = Image::read_exr(data_dir.join(format!("{stem}.exr")))?;
        let reference_se = Image::read_exr(data_dir.join(format!("{stem}_stderr.exr")))?;
        references.push((reference, reference_se));
    }
    let mut out = Vec::new();
    for ((name, mode, depth, stem), (reference, reference_se)) in MODES.into_iter().zip(references) {
        let pt = PathTracer::new(depth, mode);
        let r = render(&setup.scene, &setup.camera, &pt, RenderSettings { spp, seed, frame: 0 }, &|d, t| progress(name, d, t))
            .map_err(|e| CoreError::Invalid(e.to_string()))?;
        let comparison = compare(&r.image, &r.stderr, &reference, &reference_se, 0.01)?;
        out.push(ModeValidation {
            mode: name,
            reference: stem,
            comparison,
            ours: (r.image, r.stderr),
            theirs: (reference, reference_se),
            seconds: r.seconds,
        });
    }
    Ok(out)
}

/// Writes the difference image (ours − reference, EXR), the |z| image (EXR)
/// and a PNG of it (grey: |z| up to the critical value, red: failing pixels) into `dir`.
pub fn write_difference(v: &ModeValidation, dir: &Path) -> Result<(), SceneIoError> {
    difference(&v.ours.0, &v.theirs.0).write_exr(dir.join(format!("cornell_{}_difference.exr", v.mode)))?;
    v.comparison.z_image.write_exr(dir.join(format!("cornell_{}_z.exr", v.mode)))?;
    let zc = crate::compare::z_critical(v.comparison.alpha / 3.0) as f32;
    let mut map = v.comparison.z_image.clone();
    for p in map.data.iter_mut() {
        *p = if p.x > zc { vpl_core::glam::Vec3::new(8.0, 0.0, 0.0) } else { vpl_core::glam::Vec3::splat(0.4 * p.x / zc) };
    }
    Ok(map.write_png(dir.join(format!("cornell_{}_z.png", v.mode)), 1.0)?)
}

/// The Markdown report of a validation run.
pub fn report_markdown(vs: &[ModeValidation], spp: u32) -> String {
    let mut s = String::new();
    s.push_str("# Path tracer vs Mitsuba 3.9.1 on `cornell`\n\n");
    s.push_str(&format!(
        "Ours: {spp} spp, box filter, 256×256, max-depth 5. Reference: Mitsuba 3.9.1 `llvm_ad_rgb`, 32768 spp. \
         Per-pixel test at α = 0.01 with both images' standard errors (each channel a two-sided z-test at α/3, \
         Bonferroni, so a correct renderer fails at most 1 % of pixels in expectation); \
         image means compared in units of the combined standard error of the two means.\n\n"
    ));
    s.push_str("| mode | reference | pixels passing | mean ours (R, G, B) | mean Mitsuba (R, G, B) | mean difference / σ (R, G, B) | relMSE | render s |\n");
    s.push_str("| --- | --- | --- | --- | --- | --- | --- | --- |\n");
    for v in vs {
        let c = &v.comparison;
        s.push_str(&format!(
            "| {} | `{}` | {:.2} % | {:.6}, {:.6}, {:.6} | {:.6}, {:.6}, {:.6} | {:+.2}, {:+.2}, {:+.2} | {:.2e} | {:.1} |\n",
            v.mode,
            v.reference,
            100.0 * c.pass_rate,
            c.mean_a[0],
            c.mean_a[1],
            c.mean_a[2],
            c.mean_b[0],
            c.mean_b[1],
            c.mean_b[2],
            c.mean_z[0],
            c.mean_z[1],
            c.mean_z[2],
            c.rel_mse,
            v.seconds
        ));
    }
    s.push_str("\nPass criteria (tests/tests/mitsuba.rs): ≥ 99 % of pixels pass and |mean difference| ≤ 4 σ in every channel.\n");
    s
}

//! # vpl-tests
//!
//! Workspace-level tests of the VPL toolkit: statistical image tests against
//! Mitsuba 3 references, furnace tests with closed forms, loader and
//! determinism tests. This library holds the helpers they share.
//!
//! ```
//! assert!(vpl_tests::data_dir().join("cornell-box/cbox.obj").exists());
//! ```

#![warn(missing_docs)]

pub mod fuzz;

use std::path::PathBuf;
use vpl_core::{GBuffer, GeometryClamp, Image, IndirectShader, Scene, VplSet, VplVisibility};

/// The folder of test data shipped with the repository (`tests/data`).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// A scratch folder for files a test writes (difference images of failed
/// comparisons, malformed inputs); kept under `target/` so CI can collect it.
pub fn scratch_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/test-output").join(name);
    std::fs::create_dir_all(&d).expect("create scratch dir");
    d
}

/// Every VPL of `set` at every pixel of `gbuf`, with exact (ray-traced)
/// visibility: the reference form of VPL shading.
pub fn exhaustive_rt(scene: &Scene, gbuf: &GBuffer, set: &VplSet, clamp: Option<GeometryClamp>) -> Image {
    let mut vis = vpl_visibility::RayTraced::default();
    vis.update(scene, set);
    vpl_shading::ExhaustiveShader { clamp }.shade(gbuf, set, &vis)
}

/// Mean of `xs` and the standard error of that mean (sample variance with
/// n − 1; at least two values).
pub fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (var / n).sqrt())
}

/// Mitsuba's indirect reference of `cornell` (256×256) box-filtered to 64×64.
pub fn mitsuba_indirect_64() -> Image {
    let full = Image::read_exr(data_dir().join("cornell-box/reference_indirect.exr")).expect("the Mitsuba indirect reference");
    vpl_render::metrics::downsample(&full, 4).expect("256 is a multiple of 4")
}

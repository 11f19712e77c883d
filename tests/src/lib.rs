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
use vpl_scene_io::ImageFile;

/// The folder of test data shipped with the repository (`tests/data`).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// The scene file `file` of the repository's `scenes/` when the model it
/// names (kept outside the repository, in `../shared/scenes`) is there;
/// otherwise `None`, after saying which test skips it and why.
pub fn real_scene(file: &str) -> Option<PathBuf> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let path = root.join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let obj = text.lines().find_map(|l| l.strip_prefix("obj = ")).unwrap_or_else(|| panic!("{file} names no obj")).trim_matches('"');
    if root.join(obj).is_file() {
        Some(path)
    } else {
        eprintln!("skipped {file}: {obj} is not there");
        None
    }
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

/// Image means of one scene by the path tracer and by the VPL renderer,
/// each with its standard error (see [`vpl_against_path_tracer`]).
#[derive(Clone, Copy, Debug)]
pub struct MeanComparison {
    /// Path tracer's mean luminance and its standard error.
    pub path: (f64, f64),
    /// VPL renderer's mean luminance over the seeds and its standard error.
    pub vpl: (f64, f64),
}

impl MeanComparison {
    /// (VPL − path) over the combined standard error, plus `rounding` of
    /// the path tracer's mean (for scenes where both are nearly exact).
    pub fn z(&self, rounding: f64) -> f64 {
        let (m_pt, se_pt) = self.path;
        let (m, se) = self.vpl;
        (m - m_pt) / ((se * se + se_pt * se_pt).sqrt() + rounding * m_pt)
    }
}

/// The image mean of `scene` through `camera` by the path tracer (depth 5,
/// full light, `paths` paths through each pixel centre, the point the
/// G-buffer shades) and by the VPL renderer (IR, an unbiased sampler, with
/// `vpls` VPLs, ray-traced, exhaustive, unclamped) over `seeds` seeds. The
/// path tracer's error is the luminance of the per-pixel channel errors
/// (pixels independent; this bounds the luminance's error, so it is
/// conservative); the VPL renderer's is the spread over seeds.
pub fn vpl_against_path_tracer(scene: &Scene, camera: &vpl_core::Camera, vpls: usize, seeds: u64, paths: u32) -> MeanComparison {
    sampler_against_path_tracer(scene, camera, &Comparison { sampler: "ir", mode: vpl_core::Mode::Full, depth: 5, vpls, seeds, paths })
}

/// The settings of [`sampler_against_path_tracer`].
#[derive(Clone, Copy, Debug)]
pub struct Comparison<'a> {
    /// The built-in sampler.
    pub sampler: &'a str,
    /// The light paths both renderers include.
    pub mode: vpl_core::Mode,
    /// Both renderers' depth (Mitsuba's convention: 3 = direct light and
    /// one indirect bounce).
    pub depth: u32,
    /// VPL budget.
    pub vpls: usize,
    /// Seeds of the VPL renderer.
    pub seeds: u64,
    /// Path tracer's paths a pixel.
    pub paths: u32,
}

/// [`vpl_against_path_tracer`] with the settings of `c`.
pub fn sampler_against_path_tracer(scene: &Scene, camera: &vpl_core::Camera, c: &Comparison) -> MeanComparison {
    let &Comparison { sampler, mode, depth, vpls, seeds, paths } = c;
    use vpl_core::image::luminance;
    let (w, h) = camera.resolution;
    let pixels: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
    let pt = vpl_pathtrace::PathTracer::new(depth, mode);
    let tracked = vpl_pathtrace::track_with(
        scene,
        camera,
        &pt,
        &vpl_pathtrace::TrackRequest { pixels: &pixels, spp: paths, seed: 3, frame: 0, footprint: vpl_pathtrace::Footprint::Centre },
    );
    let n = tracked.len() as f64;
    let m_pt = tracked.iter().map(|t| luminance(t.mean) as f64).sum::<f64>() / n;
    let se_pt = tracked.iter().map(|t| (luminance(t.stderr) as f64).powi(2)).sum::<f64>().sqrt() / n;
    let means: Vec<f64> = (0..seeds)
        .map(|seed| {
            let mut r = vpl_render::Renderer::builder(scene)
                .sampler(sampler)
                .max_depth(depth)
                .vpls(vpls)
                .seed(seed)
                .visibility(vpl_render::VisibilitySpec::RayTraced)
                .shader(vpl_render::ShadingSpec::Exhaustive)
                .mode(mode)
                .clamp(vpl_render::Clamp::Off)
                .build()
                .expect("an IR renderer");
            let out = r.render(scene, camera, 0, 0.0).expect("a VPL render");
            out.image.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / out.image.data.len() as f64
        })
        .collect();
    MeanComparison { path: (m_pt, se_pt), vpl: mean_se(&means) }
}

//! The figures of Dammertz, Keller and Lensch (2010) for the progressive
//! renderer: Fig. 7, the error of the image against a converged one as
//! passes accumulate, and Fig. 8, an equal-time comparison with path tracing
//! on diffuse scenes.
//!
//! Errors against a path-traced reference subtract the reference's own
//! noise (its per-pixel variance, [`reference_variance`]), so they estimate
//! the error against the noise-free image; the Mitsuba reference of
//! `cornell` is used where given.

use crate::figures::exposure_for;
use crate::metrics::{mse, reference_variance};
use crate::plot::{Chart, Series, line_chart};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::{Camera, CoreError, GeometryClamp, Image, Mode, Scene};
use vpl_pathtrace::{PathTracer, RenderSettings, render};
use vpl_progressive::{Progressive, ProgressiveConfig};
use vpl_scene_io::ImageFile;
use vpl_scene_io::SceneIoError;

fn err(e: impl std::fmt::Display) -> CoreError {
    CoreError::Invalid(e.to_string())
}

/// RMSE of `a` against reference `r` with standard errors `se`, the reference's noise removed.
pub fn rmse_vs(a: &Image, r: &Image, se: &Image) -> Result<f64, SceneIoError> {
    Ok((mse(a, r)? - reference_variance(se)).max(0.0).sqrt())
}

/// Pixels that see no light source directly: none of the rays through the
/// pixel's centre and corners meets an emissive surface. A light seen
/// directly is 10–100 times brighter than the rest of the image, so its
/// anti-aliased edge pixels (where the estimate is the fraction of the pixel
/// the light covers) would dominate an RMSE; they measure pixel sampling,
/// the same for every method per eye sample, not light transport.
pub fn non_emitter_mask(scene: &Scene, camera: &Camera) -> Vec<bool> {
    let (w, h) = camera.resolution;
    let mut mask = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let sees = [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].iter().any(|&(dx, dy)| {
                let ray = camera.ray(x as f32 + dx, y as f32 + dy, (0.5, 0.5));
                scene.intersect(&ray).is_some_and(|hit| scene.material(&hit.point).is_emissive())
            });
            mask.push(!sees);
        }
    }
    mask
}

/// [`rmse_vs`] over the pixels of `mask`.
pub fn rmse_masked(a: &Image, r: &Image, se: &Image, mask: &[bool]) -> f64 {
    let (mut s, mut v, mut n) = (0.0f64, 0.0f64, 0usize);
    for (((x, y), e), _) in a.data.iter().zip(&r.data).zip(&se.data).zip(mask).filter(|(_, m)| **m) {
        s += (*x - *y).length_squared() as f64;
        v += e.length_squared() as f64;
        n += 1;
    }
    ((s - v) / (3 * n.max(1)) as f64).max(0.0).sqrt()
}

/// RMSE between two images over the pixels of `mask` (no reference noise to remove).
fn rmse_plain(a: &Image, b: &Image, mask: &[bool]) -> f64 {
    let zero = Image::new(a.width, a.height);
    rmse_masked(a, b, &zero, mask)
}

fn save(dir: &Path, stem: &str, img: &Image, exposure: f32) -> Result<(), SceneIoError> {
    img.write_exr(dir.join(format!("{stem}.exr")))?;
    Ok(img.write_png(dir.join(format!("{stem}.png")), exposure)?)
}

/// Fig. 6's "inverse difference image scaled by 8": 1 − 8·|a − b| per
/// channel, white where the images agree.
pub fn inverse_difference(a: &Image, b: &Image, scale: f32) -> Image {
    Image {
        width: a.width,
        height: a.height,
        data: a.data.iter().zip(&b.data).map(|(x, y)| (Vec3::ONE - (*x - *y).abs() * scale).max(Vec3::ZERO)).collect(),
    }
}

/// Writes an image of values in [0, 1] as an 8-bit PNG as they are (no tone mapping).
fn write_unit_png(img: &Image, path: &Path) -> Result<(), SceneIoError> {
    let rgb: Vec<u8> = img.data.iter().flat_map(|p| [p.x, p.y, p.z].map(|v| (v.clamp(0.0, 1.0) * 255.0 + 0.5) as u8)).collect();
    Ok(vpl_scene_io::write_png_rgb8(path, img.width, img.height, &rgb)?)
}

/// A path-traced full reference (max depth 5): image, standard error, seconds.
fn pt_reference(scene: &Scene, camera: &Camera, spp: u32, seed: u64) -> Result<(Image, Image, f64), SceneIoError> {
    let r = render(scene, camera, &PathTracer::new(5, Mode::Full), RenderSettings { spp, seed, frame: 0 }, &|_, _| {}).map_err(err)?;
    Ok((r.image, r.stderr, r.seconds))
}

/// Settings of Fig. 7.
#[derive(Clone, Debug, Serialize)]
pub struct Fig7Settings {
    /// Scene.
    pub scene: String,
    /// Image size.
    pub size: (u32, u32),
    /// Passes of the curve.
    pub passes: u64,
    /// Passes between curve points (the paper: 16).
    pub step: u64,
    /// Passes of the converged image (the paper: 11 456).
    pub converged: u64,
    /// Samples per pixel of the path-traced reference.
    pub reference_spp: u32,
    /// Caustic photon paths per pass.
    pub caustic_paths: usize,
    /// VPL budget I of the geometry clamp G ≤ I / A_view (`None`: unclamped).
    pub clamp_budget: Option<usize>,
    /// Seed.
    pub seed: u64,
}

/// One point of Fig. 7.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Fig7Point {
    /// Passes accumulated.
    pub passes: u64,
    /// Seconds of rendering so far.
    pub seconds: f64,
    /// RMSE against the converged progressive image.
    pub rmse_converged: f64,
    /// RMSE against the path-traced reference (its noise removed).
    pub rmse_reference: f64,
}

/// What Fig. 7 measured.
#[derive(Clone, Debug, Serialize)]
pub struct Fig7 {
    /// The settings.
    pub settings: Fig7Settings,
    /// The curve.
    pub points: Vec<Fig7Point>,
    /// Passes per second of the curve's render.
    pub passes_per_second: f64,
    /// Mean RGB of the converged image.
    pub converged_mean: [f64; 3],
    /// Mean RGB of the path-traced reference.
    pub reference_mean: [f64; 3],
    /// RMSE of the converged image against the reference (its noise removed): bias plus the converged image's own noise.
    pub converged_rmse_reference: f64,
}

/// Fig. 7 (with Fig. 6's snapshots): renders the curve, a converged image
/// with another seed and a path-traced reference, and writes
/// `fig7.csv`, `fig7.png`, `fig7_<passes>.png` snapshots with their inverse
/// difference images and `fig7.json` into `dir`.
pub fn fig7(dir: &Path, s: &Fig7Settings, progress: &dyn Fn(&str)) -> Result<Fig7, SceneIoError> {
    let setup = vpl_scene_io::load(&s.scene)?;
    let camera = setup.camera.with_resolution(s.size)?;
    let scene = &setup.scene;
    let clamp = s.clamp_budget.map(|i| GeometryClamp::for_view(i, scene, &camera));
    let config = |seed: u64| ProgressiveConfig { seed, caustic_paths: s.caustic_paths, clamp, ..ProgressiveConfig::default() };
    progress(&format!("path-traced reference, {} spp", s.reference_spp));
    let (reference, reference_se, _) = pt_reference(scene, &camera, s.reference_spp, s.seed ^ 0x5eed)?;
    progress(&format!("converged image, {} passes", s.converged));
    let mut conv = Progressive::new(scene, camera.clone(), config(s.seed + 1_000_003)).map_err(err)?;
    for _ in 0..s.converged {
        conv.pass();
    }
    let converged = conv.image();
    let exposure = exposure_for(&reference);
    save(dir, "fig7_converged", &converged, exposure)?;
    save(dir, "fig7_reference", &reference, exposure)?;
    let mask = non_emitter_mask(scene, &camera);
    progress(&format!("curve, {} passes", s.passes));
    let mut r = Progressive::new(scene, camera, config(s.seed)).map_err(err)?;
    let mut points = Vec::new();
    let mut seconds = 0.0;
    let snapshots = [16u64, 128, 512, 2048];
    let mut csv = String::from("passes,seconds,rmse_converged,rmse_reference\n");
    while r.passes() < s.passes {
        let t = Instant::now();
        r.pass();
        seconds += t.elapsed().as_secs_f64();
        let k = r.passes();
        if k % s.step == 0 || k == s.passes {
            let img = r.image();
            let p = Fig7Point {
                passes: k,
                seconds,
                rmse_converged: rmse_plain(&img, &converged, &mask),
                rmse_reference: rmse_masked(&img, &reference, &reference_se, &mask),
            };
            csv.push_str(&format!("{},{:.3},{:.6e},{:.6e}\n", p.passes, p.seconds, p.rmse_converged, p.rmse_reference));
            points.push(p);
            if snapshots.contains(&k) {
                save(dir, &format!("fig7_{k}"), &img, exposure)?;
                write_unit_png(&inverse_difference(&img, &converged, 8.0), &dir.join(format!("fig7_{k}_difference.png")))?;
            }
        }
    }
    vpl_core::image::write_atomic(&dir.join("fig7.csv"), csv.as_bytes())?;
    let series = vec![
        Series {
            label: "against the converged image".into(),
            points: points.iter().map(|p| (p.passes as f64, p.rmse_converged)).collect(),
            color: (0, 114, 178),
            bold: true,
            markers: false,
        },
        Series {
            label: "against the path tracer".into(),
            points: points.iter().map(|p| (p.passes as f64, p.rmse_reference)).collect(),
            color: (213, 94, 0),
            bold: false,
            markers: false,
        },
    ];
    let title = format!("Fig. 7: RMSE vs passes, {} {}x{}", s.scene, s.size.0, s.size.1);
    line_chart(
        &dir.join("fig7.png"),
        &Chart { title: &title, x_label: "rendering passes", y_label: "RMSE", log: (false, false), size: (720, 440) },
        &series,
    )
    .map_err(err)?;
    let fig = Fig7 {
        settings: s.clone(),
        passes_per_second: s.passes as f64 / seconds.max(1e-9),
        converged_mean: converged.mean(),
        reference_mean: reference.mean(),
        converged_rmse_reference: rmse_masked(&converged, &reference, &reference_se, &mask),
        points,
    };
    let json = serde_json::to_string_pretty(&fig).map_err(err)?;
    vpl_core::image::write_atomic(&dir.join("fig7.json"), json.as_bytes())?;
    Ok(fig)
}

/// Settings of Fig. 8.
#[derive(Clone, Debug, Serialize)]
pub struct Fig8Settings {
    /// Scenes (frame 0 of each).
    pub scenes: Vec<String>,
    /// Image size (`cornell` with a Mitsuba reference keeps 256×256).
    pub size: (u32, u32),
    /// Seconds each method gets.
    pub seconds: f64,
    /// Samples per pixel of the path-traced references.
    pub reference_spp: u32,
    /// Folder of the Mitsuba `cornell` references (`reference_path_d5.exr`), if any.
    pub mitsuba: Option<PathBuf>,
    /// The VPL budget I of the progressive renderer's geometry clamp
    /// G ≤ I / A_view (the toolkit's rule, [`GeometryClamp::for_view`]); the
    /// unclamped renderer runs too.
    pub clamp_budget: usize,
    /// Seed.
    pub seed: u64,
}

/// One scene of Fig. 8.
#[derive(Clone, Debug, Serialize)]
pub struct Fig8Row {
    /// Scene.
    pub scene: String,
    /// Image size.
    pub size: (u32, u32),
    /// Where the reference comes from.
    pub reference: String,
    /// Passes the progressive renderer completed.
    pub passes: u64,
    /// Its seconds.
    pub progressive_seconds: f64,
    /// Samples per pixel the path tracer completed.
    pub spp: u32,
    /// Its seconds.
    pub path_seconds: f64,
    /// RMSE of the progressive image (geometry term clamped).
    pub rmse_progressive: f64,
    /// Passes of the unclamped progressive renderer.
    pub passes_unclamped: u64,
    /// RMSE of the unclamped progressive image.
    pub rmse_unclamped: f64,
    /// The clamp's G_max (1/m²).
    pub g_max: f32,
    /// RMSE of the path-traced image.
    pub rmse_path: f64,
    /// rmse_path / rmse_progressive (> 1: the progressive renderer wins).
    pub ratio: f64,
}

/// Fig. 8 on one scene: both methods for `seconds` each, RMSE against the reference.
pub fn fig8_scene(dir: &Path, scene_name: &str, s: &Fig8Settings, progress: &dyn Fn(&str)) -> Result<Fig8Row, SceneIoError> {
    let setup = vpl_scene_io::load(scene_name)?;
    let mitsuba = s.mitsuba.as_ref().filter(|_| scene_name == "cornell").map(|d| d.join("reference_path_d5.exr")).filter(|p| p.exists());
    let (camera, reference, reference_se, source) = match mitsuba {
        Some(p) => {
            let img = Image::read_exr(&p)?;
            let se = Image::read_exr(p.with_file_name("reference_path_d5_stderr.exr"))?;
            (setup.camera.with_resolution((img.width, img.height))?, img, se, "Mitsuba 3.9.1, 32768 spp".to_string())
        }
        None => {
            let camera = setup.camera.with_resolution(s.size)?;
            progress(&format!("{scene_name}: path-traced reference, {} spp", s.reference_spp));
            let (img, se, _) = pt_reference(&setup.scene, &camera, s.reference_spp, s.seed ^ 0x5eed)?;
            (camera, img, se, format!("path tracer, {} spp", s.reference_spp))
        }
    };
    let scene = &setup.scene;
    let clamp = GeometryClamp::for_view(s.clamp_budget, scene, &camera);
    let run = |clamp: Option<GeometryClamp>| -> Result<(Image, u64, f64), SceneIoError> {
        progress(&format!("{scene_name}: progressive ({}), {} s", if clamp.is_some() { "clamped" } else { "unclamped" }, s.seconds));
        let mut r = Progressive::new(scene, camera.clone(), ProgressiveConfig { seed: s.seed, clamp, ..ProgressiveConfig::default() })
            .map_err(err)?;
        let t = Instant::now();
        while t.elapsed().as_secs_f64() < s.seconds {
            r.pass();
        }
        Ok((r.image(), r.passes(), t.elapsed().as_secs_f64()))
    };
    let (prog, passes, progressive_seconds) = run(Some(clamp))?;
    let (unclamped, passes_unclamped, _) = run(None)?;
    progress(&format!("{scene_name}: path tracer, {} s", s.seconds));
    let pt = PathTracer::new(5, Mode::Full);
    let (w, h) = camera.resolution;
    let mut sum = vec![Vec3::ZERO; (w * h) as usize];
    let mut spp = 0u32;
    let t = Instant::now();
    while t.elapsed().as_secs_f64() < s.seconds {
        // One sample per pixel at a time, each with its own stream (frame = sample number).
        let o = render(scene, &camera, &pt, RenderSettings { spp: 1, seed: s.seed, frame: spp as u64 }, &|_, _| {}).map_err(err)?;
        for (a, b) in sum.iter_mut().zip(&o.image.data) {
            *a += *b;
        }
        spp += 1;
    }
    let path_seconds = t.elapsed().as_secs_f64();
    let path = Image { width: w, height: h, data: sum.iter().map(|v| *v / spp as f32).collect() };
    let exposure = exposure_for(&reference);
    save(dir, &format!("fig8_{scene_name}_progressive"), &prog, exposure)?;
    save(dir, &format!("fig8_{scene_name}_unclamped"), &unclamped, exposure)?;
    save(dir, &format!("fig8_{scene_name}_path"), &path, exposure)?;
    reference.write_png(dir.join(format!("fig8_{scene_name}_reference.png")), exposure)?;
    write_unit_png(&inverse_difference(&prog, &reference, 8.0), &dir.join(format!("fig8_{scene_name}_progressive_difference.png")))?;
    write_unit_png(&inverse_difference(&path, &reference, 8.0), &dir.join(format!("fig8_{scene_name}_path_difference.png")))?;
    let mask = non_emitter_mask(scene, &camera);
    let rmse_progressive = rmse_masked(&prog, &reference, &reference_se, &mask);
    let rmse_path = rmse_masked(&path, &reference, &reference_se, &mask);
    Ok(Fig8Row {
        scene: scene_name.to_string(),
        size: (w, h),
        reference: source,
        passes,
        progressive_seconds,
        passes_unclamped,
        rmse_unclamped: rmse_masked(&unclamped, &reference, &reference_se, &mask),
        g_max: clamp.g_max,
        spp,
        path_seconds,
        rmse_progressive,
        rmse_path,
        ratio: rmse_path / rmse_progressive.max(1e-30),
    })
}

/// The Markdown report of Figs. 7 and 8 (image links relative to `prefix`).
pub fn report(fig7: Option<&Fig7>, fig8: &[Fig8Row], seconds: f64, prefix: &str) -> String {
    let mut md = String::new();
    if let Some(f) = fig7 {
        let s = &f.settings;
        let last = f.points.last();
        md.push_str(&format!(
            "### Fig. 7: error against passes\n\n`{}` at {}x{}, default settings (16 VPL paths, {} caustic paths, unbiased culling, projection maps, max depth 5, {}), \
             {:.2} passes/s. RMSE over the pixels that see no light directly (see below) against a converged image of {} passes with another seed (the paper's curve) and against a path-traced reference of {} spp \
             (its noise removed), every {} passes. After {} passes: {:.4e} against the converged image, {:.4e} against the path tracer; the converged image \
             itself is {:.4e} from the path tracer (bias plus its own noise). Mean RGB converged {:.5} {:.5} {:.5}, path tracer {:.5} {:.5} {:.5}.\n\n\
             ![Fig. 7]({prefix}fig7.png)\n\nData: `{prefix}fig7.csv`, `{prefix}fig7.json`.\n\n",
            s.scene,
            s.size.0,
            s.size.1,
            s.caustic_paths,
            match s.clamp_budget {
                Some(i) => format!("geometry term clamped at I / A_view with I = {i}"),
                None => "no clamp".to_string(),
            },
            f.passes_per_second,
            s.converged,
            s.reference_spp,
            s.step,
            last.map_or(0, |p| p.passes),
            last.map_or(0.0, |p| p.rmse_converged),
            last.map_or(0.0, |p| p.rmse_reference),
            f.converged_rmse_reference,
            f.converged_mean[0],
            f.converged_mean[1],
            f.converged_mean[2],
            f.reference_mean[0],
            f.reference_mean[1],
            f.reference_mean[2],
        ));
        let snaps: Vec<u64> = [16u64, 128, 512, 2048].into_iter().filter(|k| *k <= s.passes).collect();
        if !snaps.is_empty() {
            md.push_str("Fig. 6: the image after each number of passes, and 1 − 8·|image − converged|:\n\n| passes | image | inverse difference ×8 |\n| ---: | --- | --- |\n");
            for k in snaps {
                md.push_str(&format!("| {k} | ![]({prefix}fig7_{k}.png) | ![]({prefix}fig7_{k}_difference.png) |\n"));
            }
            md.push_str(&format!("| converged | ![]({prefix}fig7_converged.png) | path tracer: ![]({prefix}fig7_reference.png) |\n\n"));
        }
    }
    if !fig8.is_empty() {
        md.push_str(&format!(
            "### Fig. 8: equal time against path tracing\n\nEach method renders for {seconds} s on the same threads: the path tracer (NEE + MIS, max depth 5) \
             one sample per pixel at a time, the progressive renderer pass after pass, once with the geometry term clamped at G ≤ I / A_view (its default; the paper \
             bounds G, §8) and once unclamped (unbiased). RMSE against the reference, its noise removed, over the pixels that see no light source directly \
             (a light seen directly is 10-100 times brighter than the rest, and its anti-aliased edge pixels, which measure pixel sampling rather than light \
             transport, would dominate the RMSE). Ratio = RMSE of path tracing / RMSE of the progressive renderer (above 1: the progressive renderer is closer).\n\n\
             | scene | size | reference | progressive passes | path tracer spp | RMSE progressive (clamped) | RMSE progressive (unclamped) | RMSE path tracer | ratio (clamped) | ratio (unclamped) |\n\
             | --- | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n"
        ));
        for r in fig8 {
            md.push_str(&format!(
                "| `{}` | {}x{} | {} | {} | {} | {:.4e} | {:.4e} | {:.4e} | **{:.2}** | {:.2} |\n",
                r.scene,
                r.size.0,
                r.size.1,
                r.reference,
                r.passes,
                r.spp,
                r.rmse_progressive,
                r.rmse_unclamped,
                r.rmse_path,
                r.ratio,
                r.rmse_path / r.rmse_unclamped.max(1e-30)
            ));
        }
        md.push_str("\nThe clamped column's G_max (1/m²): ");
        md.push_str(&fig8.iter().map(|r| format!("`{}` {:.2}", r.scene, r.g_max)).collect::<Vec<_>>().join(", "));
        md.push_str(".\n");
        md.push_str("\n| scene | progressive (clamped) | 1 − 8·error | progressive (unclamped) | path tracer | 1 − 8·error | reference |\n| --- | --- | --- | --- | --- | --- | --- |\n");
        for r in fig8 {
            let s = &r.scene;
            md.push_str(&format!(
                "| `{s}` | ![]({prefix}fig8_{s}_progressive.png) | ![]({prefix}fig8_{s}_progressive_difference.png) | ![]({prefix}fig8_{s}_unclamped.png) | ![]({prefix}fig8_{s}_path.png) | ![]({prefix}fig8_{s}_path_difference.png) | ![]({prefix}fig8_{s}_reference.png) |\n"
            ));
        }
        md.push('\n');
    }
    md
}

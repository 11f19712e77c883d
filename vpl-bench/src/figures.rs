//! The SMC paper's single-frame figures (`vpl figures`):
//!
//! - Fig. 8: one frame by path tracing, clamped path tracing, interleaved
//!   shadow maps, all VPLs with shadow maps and all VPLs ray traced (the
//!   same 2048 SMC VPLs in the three VPL images);
//! - Fig. 9: the same VPLs, every VPL at every pixel, with shadow maps of
//!   128² to 1024² against ray-traced visibility;
//! - Fig. 10: absolute-error images and RMSE against the VPL budget (2K,
//!   8K, 40K SMC VPLs, ray-traced visibility).
//!
//! Errors against a path-traced reference subtract the reference's own
//! variance ([`crate::metrics::reference_variance`]).

use crate::metrics::{mse, reference_variance, rel_mse};
use crate::plot::{Chart, Series, line_chart};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;
use vpl_core::image::{luminance, write_atomic};
use vpl_core::{Camera, CoreError, Frame, GBuffer, GeometryClamp, Image, IndirectShader, Mode, Scene, VplSampler, VplSet, VplVisibility};
use vpl_pathtrace::{PathTracer, RenderSettings, render};
use vpl_sampling::{SmcConfig, SmcSampler};
use vpl_scene_io::ImageFile;
use vpl_scene_io::SceneIoError;
use vpl_shading::{ExhaustiveShader, InterleavedShader, render_gbuffer};
use vpl_visibility::{RayTraced, ShadowMaps};

/// One image of a figure with its errors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Panel {
    /// File stem (`<scene>_<name>.exr` / `.png`).
    pub name: String,
    /// What it shows.
    pub label: String,
    /// RMSE against the path-traced reference, its noise removed.
    pub rmse: f64,
    /// Relative MSE against the reference.
    pub rel_mse: f64,
    /// RMSE against the second comparison image of the figure (clamped path
    /// tracing in Fig. 8, ray-traced visibility in Fig. 9), if any.
    pub rmse_second: Option<f64>,
    /// Mean luminance over the reference's: 1 when no energy is lost or gained.
    pub mean_ratio: f64,
    /// Seconds it took.
    pub seconds: f64,
}

/// One line of fig8.csv / fig9.csv for panel `p` of `scene`.
fn csv_row(csv: &mut String, fig: &str, scene: &str, p: &Panel) {
    let second = p.rmse_second.map_or(String::new(), |v| v.to_string());
    let _ = writeln!(csv, "{fig},{scene},{},\"{}\",{},{},{second},{},{}", p.name, p.label, p.rmse, p.rel_mse, p.mean_ratio, p.seconds);
}

/// Settings of the figures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FigureSettings {
    /// Image size.
    pub size: (u32, u32),
    /// Samples per pixel of the path-traced references.
    pub reference_spp: u32,
    /// Shadow-map sides of Fig. 9.
    pub shadow_map_sides: Vec<u32>,
    /// VPL budgets of Fig. 10.
    pub budgets: Vec<usize>,
    /// Image size of Fig. 10.
    pub fig10_size: (u32, u32),
    /// Samples per pixel of Fig. 10's references.
    pub fig10_spp: u32,
    /// SMC warm-up iterations (Fig. 10 uses fewer for its large budgets: see the report).
    pub fig10_warmup: u32,
    /// Seed.
    pub seed: u64,
}

fn err(e: impl std::fmt::Display) -> CoreError {
    CoreError::Invalid(e.to_string())
}

/// RMSE of `a` against the reference `r` with standard errors `se`, the reference's noise removed (at least 0).
fn rmse_vs(a: &Image, r: &Image, se: &Image) -> Result<f64, SceneIoError> {
    Ok((mse(a, r)? - reference_variance(se)).max(0.0).sqrt())
}

/// The exposure that puts the mean luminance of `img` at 0.18 (middle grey).
pub fn exposure_for(img: &Image) -> f32 {
    let m = img.data.iter().map(|c| luminance(*c) as f64).sum::<f64>() / img.data.len().max(1) as f64;
    if m > 0.0 { (0.18 / m) as f32 } else { 1.0 }
}

fn save(dir: &Path, stem: &str, img: &Image, exposure: f32) -> Result<(), SceneIoError> {
    img.write_exr(dir.join(format!("{stem}.exr")))?;
    Ok(img.write_png(dir.join(format!("{stem}.png")), exposure)?)
}

/// A path-traced indirect reference (image, standard error) of `spp` samples.
fn reference(
    scene: &Scene,
    camera: &Camera,
    clamp: Option<GeometryClamp>,
    spp: u32,
    seed: u64,
) -> Result<(Image, Image, f64), SceneIoError> {
    let mut pt = PathTracer::new(5, Mode::Indirect);
    pt.clamp = clamp;
    // The reference draws the materials as the VPL renders it is set beside do.
    let scene = &scene.with_material_policy(vpl_core::MaterialPolicy::Diffuse);
    let r = render(scene, camera, &pt, RenderSettings { spp, seed, frame: 0 }, &|_, _| {}).map_err(err)?;
    Ok((r.image, r.stderr, r.seconds))
}

/// SMC's VPLs for one frame, after `warmup` iterations.
fn smc_vpls(scene: &Scene, camera: &Camera, gbuf: &GBuffer, vpls: usize, warmup: u32, seed: u64) -> Result<(VplSet, f64), SceneIoError> {
    let t = Instant::now();
    let mut smc = SmcSampler::new(SmcConfig { vpls, warmup, ..SmcConfig::default() }).map_err(err)?;
    let frame = Frame { scene, camera, time: 0.0, index: 0, seed, gbuffer: gbuf, previous: None };
    let set = smc.next_frame(&frame).clone();
    Ok((set, t.elapsed().as_secs_f64()))
}

fn shade(gbuf: &GBuffer, set: &VplSet, scene: &Scene, vis: &mut dyn VplVisibility, shader: &mut dyn IndirectShader) -> (Image, f64) {
    let t = Instant::now();
    vis.update(scene, set);
    let img = shader.shade(gbuf, set, vis);
    (img, t.elapsed().as_secs_f64())
}

/// Figs. 8 and 9 on frame `frame` of `scene_name`: writes the images and
/// returns the panels of each figure.
pub fn fig8_9(dir: &Path, scene_name: &str, frame: u32, s: &FigureSettings) -> Result<(Vec<Panel>, Vec<Panel>), SceneIoError> {
    let setup = vpl_scene_io::load(scene_name)?;
    let (scene, camera) = setup.frame(frame)?;
    let camera = camera.with_resolution(s.size)?;
    let vpls = 2048;
    let clamp = GeometryClamp::for_view(vpls, &scene, &camera);
    let (pt, pt_se, pt_s) = reference(&scene, &camera, None, s.reference_spp, s.seed)?;
    let (cpt, cpt_se, cpt_s) = reference(&scene, &camera, Some(clamp), s.reference_spp, s.seed ^ 1)?;
    let exposure = exposure_for(&pt);
    let gbuf = render_gbuffer(&scene, &camera);
    let (set, smc_s) = smc_vpls(&scene, &camera, &gbuf, vpls, SmcConfig::default().warmup, s.seed)?;
    let panel =
        |name: &str, label: &str, img: &Image, second: Option<(&Image, Option<&Image>)>, seconds: f64| -> Result<Panel, SceneIoError> {
            save(dir, &format!("{scene_name}_{name}"), img, exposure)?;
            let rmse_second = match second {
                Some((b, Some(se))) => Some(rmse_vs(img, b, se)?),
                Some((b, None)) => Some(mse(img, b)?.sqrt()),
                None => None,
            };
            Ok(Panel {
                name: format!("{scene_name}_{name}"),
                label: label.into(),
                rmse: rmse_vs(img, &pt, &pt_se)?,
                rel_mse: rel_mse(img, &pt)?,
                rmse_second,
                mean_ratio: mean_luminance(img) / mean_luminance(&pt),
                seconds,
            })
        };
    let mut f8 = Vec::new();
    f8.push(panel("pt", &format!("path tracing, {} spp", s.reference_spp), &pt, None, pt_s)?);
    let mut clamped =
        panel("pt_clamped", "clamped path tracing (G ≤ I / A_view after the primary hit)", &cpt, Some((&cpt, Some(&cpt_se))), cpt_s)?;
    // Both images are noisy: remove the variance of each.
    clamped.rmse = (mse(&cpt, &pt)? - reference_variance(&pt_se) - reference_variance(&cpt_se)).max(0.0).sqrt();
    f8.push(clamped);
    let mut sm = ShadowMaps::new(vpl_visibility::DEFAULT_RESOLUTION).map_err(err)?;
    let (img, t) = shade(&gbuf, &set, &scene, &mut sm, &mut InterleavedShader::new(Some(clamp), s.seed));
    f8.push(panel("vpl_interleaved_sm", "VPLs, interleaved, 128² shadow maps (the method)", &img, Some((&cpt, Some(&cpt_se))), t + smc_s)?);
    let (img, t) = shade(&gbuf, &set, &scene, &mut sm, &mut ExhaustiveShader { clamp: Some(clamp) });
    f8.push(panel("vpl_all_sm", "all VPLs, 128² shadow maps", &img, Some((&cpt, Some(&cpt_se))), t)?);
    let (rt, t) = shade(&gbuf, &set, &scene, &mut RayTraced::default(), &mut ExhaustiveShader { clamp: Some(clamp) });
    f8.push(panel("vpl_all_rt", "all VPLs, ray traced", &rt, Some((&cpt, Some(&cpt_se))), t)?);
    let mut f9 = vec![Panel {
        name: format!("{scene_name}_vpl_all_rt"),
        label: "ray traced".into(),
        rmse: rmse_vs(&rt, &pt, &pt_se)?,
        rel_mse: rel_mse(&rt, &pt)?,
        rmse_second: Some(0.0),
        mean_ratio: mean_luminance(&rt) / mean_luminance(&pt),
        seconds: t,
    }];
    for &side in &s.shadow_map_sides {
        let mut sm = ShadowMaps::new(side).map_err(err)?;
        let (img, t) = shade(&gbuf, &set, &scene, &mut sm, &mut ExhaustiveShader { clamp: Some(clamp) });
        let mib = sm.memory_bytes() as f64 / (1u64 << 20) as f64;
        f9.push(panel(&format!("sm{side}"), &format!("{side}² shadow maps ({mib:.0} MiB)"), &img, Some((&rt, None)), t)?);
    }
    Ok((f8, f9))
}

/// One budget of Fig. 10.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BudgetPoint {
    /// VPLs.
    pub vpls: usize,
    /// Clamp G_max = I / A_view.
    pub g_max: f32,
    /// RMSE of the VPL image against path tracing.
    pub rmse: f64,
    /// RMSE of clamped path tracing (same G_max) against path tracing: the
    /// part of the error the clamp alone causes.
    pub clamp_rmse: f64,
    /// Relative MSE against path tracing.
    pub rel_mse: f64,
    /// Mean luminance over path tracing's.
    pub mean_ratio: f64,
    /// Seconds (sampling and shading).
    pub seconds: f64,
}

/// Fig. 10 on frame 0 of `scene_name`.
pub fn fig10(dir: &Path, scene_name: &str, s: &FigureSettings) -> Result<Vec<BudgetPoint>, SceneIoError> {
    let setup = vpl_scene_io::load(scene_name)?;
    let (scene, camera) = setup.frame(0)?;
    let camera = camera.with_resolution(s.fig10_size)?;
    let (pt, pt_se, _) = reference(&scene, &camera, None, s.fig10_spp, s.seed)?;
    let exposure = exposure_for(&pt);
    save(dir, &format!("{scene_name}_reference"), &pt, exposure)?;
    let gbuf = render_gbuffer(&scene, &camera);
    let mut out = Vec::new();
    for &b in &s.budgets {
        let clamp = GeometryClamp::for_view(b, &scene, &camera);
        let (set, smc_s) = smc_vpls(&scene, &camera, &gbuf, b, s.fig10_warmup, s.seed)?;
        let (img, t) = shade(&gbuf, &set, &scene, &mut RayTraced::default(), &mut ExhaustiveShader { clamp: Some(clamp) });
        let (cpt, _, _) = reference(&scene, &camera, Some(clamp), s.fig10_spp, s.seed ^ 1)?;
        let k = b / 1000;
        save(dir, &format!("{scene_name}_{k}k"), &img, exposure)?;
        // 2× absolute error, shown at the reference's exposure (as the paper's Fig. 10).
        let abs = Image { data: img.data.iter().zip(&pt.data).map(|(a, r)| (*a - *r).abs() * 2.0).collect(), ..img.clone() };
        save(dir, &format!("{scene_name}_{k}k_error"), &abs, exposure)?;
        // The clamp's own bias: clamped against unclamped path tracing, both noisy.
        let clamp_rmse = (mse(&cpt, &pt)? - 2.0 * reference_variance(&pt_se)).max(0.0).sqrt();
        out.push(BudgetPoint {
            vpls: b,
            g_max: clamp.g_max,
            rmse: rmse_vs(&img, &pt, &pt_se)?,
            clamp_rmse,
            rel_mse: rel_mse(&img, &pt)?,
            mean_ratio: mean_luminance(&img) / mean_luminance(&pt),
            seconds: smc_s + t,
        });
    }
    Ok(out)
}

/// Writes `fig8.md` (with Fig. 9) and its CSV/JSON.
pub fn write_fig8(dir: &Path, figs: &[(String, Vec<Panel>, Vec<Panel>)], s: &FigureSettings) -> Result<(), SceneIoError> {
    let mut md = String::from("# Figs. 8 and 9: one frame, path tracing against VPLs\n\n");
    let _ = writeln!(
        md,
        "Indirect light only, {}×{} pixels, max depth 5. The three VPL images of a scene use the same 2048 SMC VPLs (100 warm-up \
         iterations) and the clamp G_max = I / A_view; clamped path tracing applies that clamp to the segment leaving the primary hit \
         (except connections to a light), which is the limit of infinitely many clamped VPLs. RMSE against path tracing ({} spp) \
         has the reference's noise removed. PNGs at one exposure per scene.\n",
        s.size.0, s.size.1, s.reference_spp
    );
    let mut csv = String::from("figure,scene,panel,label,rmse,rel_mse,rmse_second,mean_ratio,seconds\n");
    for (scene, f8, f9) in figs {
        let _ = writeln!(
            md,
            "## Fig. 8: `{scene}`\n\n| image | RMSE vs path tracing | relMSE | RMSE vs clamped path tracing | mean / path tracing's | seconds |\n| --- | ---: | ---: | ---: | ---: | ---: |"
        );
        for p in f8 {
            let _ = writeln!(
                md,
                "| {} | {:.5} | {:.4} | {} | {:.3} | {:.1} |",
                p.label,
                p.rmse,
                p.rel_mse,
                p.rmse_second.map_or("–".into(), |v| format!("{v:.5}")),
                p.mean_ratio,
                p.seconds
            );
            csv_row(&mut csv, "fig8", scene, p);
        }
        md.push('\n');
        for p in f8 {
            let _ = write!(md, "![{}]({}.png) ", p.label, p.name);
        }
        let _ = writeln!(
            md,
            "\n\n## Fig. 9: `{scene}`, shadow-map resolution (all VPLs at every pixel)\n\n| visibility | RMSE vs path tracing | RMSE vs ray tracing | seconds |\n| --- | ---: | ---: | ---: |"
        );
        for p in f9 {
            let _ = writeln!(
                md,
                "| {} | {:.5} | {} | {:.1} |",
                p.label,
                p.rmse,
                p.rmse_second.map_or("–".into(), |v| format!("{v:.5}")),
                p.seconds
            );
            csv_row(&mut csv, "fig9", scene, p);
        }
        md.push('\n');
        for p in f9 {
            let _ = write!(md, "![{}]({}.png) ", p.label, p.name);
        }
        md.push_str("\n\n");
    }
    write_atomic(&dir.join("fig8.md"), md.as_bytes())?;
    write_atomic(&dir.join("fig8.csv"), csv.as_bytes())?;
    let json = serde_json::to_string_pretty(&figs.iter().map(|(s, a, b)| (s, a, b)).collect::<Vec<_>>()).map_err(err)?;
    Ok(write_atomic(&dir.join("fig8.json"), json.as_bytes())?)
}

/// Writes `fig10.md`, its CSV/JSON and the error-vs-budget plot.
pub fn write_fig10(dir: &Path, figs: &[(String, Vec<BudgetPoint>)], s: &FigureSettings) -> Result<(), crate::plot::PlotError> {
    let mut md = String::from("# Fig. 10: error against the VPL budget\n\n");
    let _ = writeln!(
        md,
        "SMC VPLs ({} warm-up iterations), every VPL at every pixel with ray-traced visibility, clamp G_max = I / A_view, {}×{} pixels, \
         against path tracing ({} spp; its noise removed from the RMSE). \"Clamp alone\" is clamped path tracing with the same G_max \
         against path tracing: the energy the clamp removes, which more VPLs (a looser clamp) give back. Error images: 2× |VPL − \
         path tracing| at the reference's exposure.\n",
        s.fig10_warmup, s.fig10_size.0, s.fig10_size.1, s.fig10_spp
    );
    let mut csv = String::from("scene,vpls,g_max,rmse,clamp_rmse,rel_mse,mean_ratio,seconds\n");
    let mut series = Vec::new();
    let palette = [(213, 94, 0), (0, 114, 178), (0, 158, 115)];
    for (i, (scene, pts)) in figs.iter().enumerate() {
        let _ = writeln!(
            md,
            "## `{scene}`\n\n| VPLs | G_max (1/m²) | RMSE | clamp alone | relMSE | mean / path tracing's | seconds |\n| ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
        );
        for p in pts {
            let _ = writeln!(
                md,
                "| {} | {:.1} | {:.5} | {:.5} | {:.4} | {:.3} | {:.1} |",
                p.vpls, p.g_max, p.rmse, p.clamp_rmse, p.rel_mse, p.mean_ratio, p.seconds
            );
            let _ =
                writeln!(csv, "{scene},{},{},{},{},{},{},{}", p.vpls, p.g_max, p.rmse, p.clamp_rmse, p.rel_mse, p.mean_ratio, p.seconds);
        }
        let _ = write!(md, "\n![reference]({scene}_reference.png) ");
        for p in pts {
            let _ = write!(md, "![{0}K error]({scene}_{0}k_error.png) ", p.vpls / 1000);
        }
        md.push_str("\n\n");
        let c = palette[i % palette.len()];
        series.push(Series {
            label: format!("{scene}: SMC VPLs"),
            points: pts.iter().map(|p| (p.vpls as f64, p.rmse)).collect(),
            color: c,
            bold: true,
            markers: true,
        });
        series.push(Series {
            label: format!("{scene}: clamp alone"),
            points: pts.iter().map(|p| (p.vpls as f64, p.clamp_rmse)).collect(),
            color: (c.0 / 2, c.1 / 2, c.2 / 2),
            bold: false,
            markers: true,
        });
    }
    md.push_str("![RMSE against VPLs](fig10_error.png)\n");
    let chart = Chart {
        title: "Fig. 10: RMSE against the VPL budget",
        x_label: "VPLs",
        y_label: "RMSE (indirect radiance)",
        log: (true, true),
        size: (800, 500),
    };
    line_chart(&dir.join("fig10_error.png"), &chart, &series)?;
    write_atomic(&dir.join("fig10.md"), md.as_bytes())?;
    write_atomic(&dir.join("fig10.csv"), csv.as_bytes())?;
    let json = serde_json::to_string_pretty(figs).map_err(|e| CoreError::Invalid(e.to_string()))?;
    write_atomic(&dir.join("fig10.json"), json.as_bytes())?;
    Ok(())
}

/// Mean of an image's luminance (a quick check that a panel is not black).
pub fn mean_luminance(img: &Image) -> f64 {
    img.data.iter().map(|c| luminance(*c) as f64).sum::<f64>() / img.data.len().max(1) as f64
}

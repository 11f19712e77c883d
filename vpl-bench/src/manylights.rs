//! The many-light study (`vpl manylights`): is a well-placed set of 2K
//! VPLs better than 64K or 1M VPLs gathered by a light tree, at equal
//! time?
//!
//! **Error over wall time.** For each scene, each VPL source (a sampler
//! and its budget) and each gather (a [`ShadingSpec`]: interleaved with
//! its filter, exhaustive, stochastic lightcuts of cut N) one renderer
//! renders the view of frame 0 again and again, frame index 0, 1, 2, …:
//! ray-traced visibility (shadow rays, no shadow maps), indirect light
//! only, the clamp of the settings (by default the view's, G_max = I /
//! A_view, which loosens as I grows). After each frame the running mean
//! of its images is compared with a path-traced reference of the same
//! view (rays through the pixel centres, the materials as the VPLs draw
//! them): the RMSE over pixels and channels with the reference's own
//! variance removed ([`reference_variance`]), against the wall time of
//! the frames so far (G-buffer, sampling, tree building and shading).
//! The first frame is rendered before the clock starts and is not
//! averaged: it holds SMC's warm-up iterations, which a renderer pays once
//! a sequence; its time is reported apart. A configuration stops
//! when its time reaches the budget or after `max_frames` frames. IR draws
//! new paths every frame, so its frames are independent; SMC moves at
//! most M_max VPLs a frame, so its frames are not, which is its nature.
//!
//! **What does not fit.** A gather whose cost grows with the VPL count
//! (exhaustive; interleaved, which shades I/16 VPLs a pixel) is not run for
//! a source when its first frame, predicted from the same gather's median
//! frame on the largest smaller source of the same scene scaled by the VPL
//! count, would take longer than the whole budget: the table gives the
//! predicted time instead.
//!
//! **Temporal error.** The same configurations render a Table 1 sequence's
//! frames from a fresh renderer; |E| and |E′| (the SMC paper's eq. 10) of
//! the row's tracked pixels against the path tracer's truth there, as
//! Table 1 measures them (tone-mapped luminance), one seed.

use crate::metrics::{TemporalError, mse, reference_variance, temporal_error, tone_mapped_luminance};
use crate::pipeline::{BackendKind, PipelineSpec, ShadingSpec, VisibilitySpec};
use crate::plot::{Chart, Series, line_chart};
use serde::Serialize;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;
use vpl_core::glam::Vec3;
use vpl_core::{Budget, Image, MaterialPolicy, Mode, Params, SceneSetup};
use vpl_pathtrace::{Footprint, PathTracer, TrackRequest, track_with};
use vpl_render::{Clamp, Renderer, run_sequence};
use vpl_sampling::Registry;

/// Where a study's VPLs come from: a sampler and its budget.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Source {
    /// The sampler's registry name.
    pub sampler: String,
    /// Its VPL budget I.
    pub vpls: usize,
}

impl Source {
    /// `SMC 2K`, `IR 64K`, `IR 1M`: the sampler in capitals and I in
    /// binary thousands or millions.
    pub fn label(&self) -> String {
        let n = self.vpls;
        let count = if n >= 1 << 20 && n % (1 << 20) == 0 {
            format!("{}M", n >> 20)
        } else if n >= 1 << 10 && n % (1 << 10) == 0 {
            format!("{}K", n >> 10)
        } else {
            n.to_string()
        };
        format!("{} {count}", self.sampler.to_uppercase())
    }
}

/// What a study measures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ManyLightsSettings {
    /// VPL sources, smallest budget first.
    pub sources: Vec<Source>,
    /// Gathers of every source.
    #[serde(serialize_with = "display_all")]
    pub gathers: Vec<ShadingSpec>,
    /// Image size.
    pub size: (u32, u32),
    /// Wall-time budget of each configuration, seconds.
    pub seconds: f64,
    /// Most frames a configuration renders.
    pub max_frames: u32,
    /// Path-traced samples a pixel of the reference.
    pub reference_spp: u32,
    /// Path-traced samples a tracked pixel and frame of the temporal truth.
    pub truth_spp: u32,
    /// Longest path in segments.
    pub max_depth: u32,
    /// The geometry clamp of every renderer.
    #[serde(serialize_with = "display")]
    pub clamp: Clamp,
    /// Where the VPL stages run.
    pub backend: BackendKind,
    /// Seed of every stream.
    pub seed: u64,
}

fn display<S: serde::Serializer, T: std::fmt::Display>(v: &T, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&v.to_string())
}

fn display_all<S: serde::Serializer, T: std::fmt::Display>(v: &[T], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(v.iter().map(|x| x.to_string()))
}

impl Default for ManyLightsSettings {
    /// {SMC 2K, IR 64K, IR 1M} × {interleaved, exhaustive, lightcuts 8,
    /// 32, 128} at 96×72, 8 s a configuration, the view's clamp.
    fn default() -> Self {
        ManyLightsSettings {
            sources: vec![
                Source { sampler: "smc".into(), vpls: 2048 },
                Source { sampler: "ir".into(), vpls: 1 << 16 },
                Source { sampler: "ir".into(), vpls: 1 << 20 },
            ],
            gathers: vec![
                ShadingSpec::Interleaved { filter: true },
                ShadingSpec::Exhaustive,
                ShadingSpec::Lightcuts { cut: 8 },
                ShadingSpec::Lightcuts { cut: 32 },
                ShadingSpec::Lightcuts { cut: 128 },
            ],
            size: (96, 72),
            seconds: 8.0,
            max_frames: 256,
            reference_spp: 4096,
            truth_spp: 16384,
            max_depth: 5,
            clamp: Clamp::Auto,
            backend: BackendKind::Cpu,
            seed: 0,
        }
    }
}

/// Errors of a study.
#[derive(Debug, thiserror::Error)]
pub enum ManyLightsError {
    /// The scene or a frame of it.
    #[error(transparent)]
    Core(#[from] vpl_core::CoreError),
    /// The sampler or renderer.
    #[error(transparent)]
    Render(#[from] vpl_render::RenderError),
    /// A scene file.
    #[error(transparent)]
    SceneIo(#[from] vpl_scene_io::SceneIoError),
    /// A plot.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
    /// A setting.
    #[error("{0}")]
    Invalid(String),
}

/// The running mean after `frames` frames.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Point {
    /// Frames averaged.
    pub frames: u32,
    /// Their wall time, seconds.
    pub seconds: f64,
    /// RMSE of their mean against the reference, its noise removed.
    pub rmse: f64,
}

/// One configuration's error over time, or why it did not run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Curve {
    /// The VPL source.
    pub source: Source,
    /// The gather (its [`ShadingSpec`] name).
    pub gather: String,
    /// After each frame.
    pub points: Vec<Point>,
    /// Median milliseconds a frame after the first (NaN when not run).
    pub frame_ms: f64,
    /// Seconds of the first frame, which warms up and is not counted.
    pub warmup_s: f64,
    /// Not run: its first frame's predicted seconds.
    pub predicted_s: Option<f64>,
    /// The mean of its frames at the end (not in the JSON).
    #[serde(skip)]
    pub image: Option<Image>,
}

impl Curve {
    /// The final mean image's mean over the reference's (1: no light lost
    /// or gained); NaN when not run.
    pub fn mean_ratio(&self, reference_mean: f64) -> f64 {
        self.image.as_ref().map_or(f64::NAN, |i| {
            let m = i.mean();
            (m[0] + m[1] + m[2]) / 3.0 / reference_mean
        })
    }

    /// The RMSE of the frames done by `t` seconds (`None` before the first).
    pub fn rmse_at(&self, t: f64) -> Option<f64> {
        self.points.iter().take_while(|p| p.seconds <= t).last().map(|p| p.rmse)
    }
}

/// A scene's curves.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SceneStudy {
    /// The scene as named.
    pub scene: String,
    /// The reference's mean over pixels and channels.
    pub reference_mean: f64,
    /// The reference's own RMSE (the square root of its mean variance).
    pub reference_noise: f64,
    /// Every configuration, sources outer, gathers inner.
    pub curves: Vec<Curve>,
    /// The reference (not in the JSON).
    #[serde(skip)]
    pub reference: Image,
    /// Seconds the scene took.
    pub seconds: f64,
}

/// The renderer of one configuration.
fn renderer(
    registry: &Registry,
    setup: &SceneSetup,
    s: &ManyLightsSettings,
    source: &Source,
    gather: ShadingSpec,
) -> Result<Renderer, ManyLightsError> {
    let mut params = Params::new();
    // IR draws new paths every frame (independent frames), as in Table 1.
    params.offer("fresh-paths", true);
    let spec = PipelineSpec {
        sampler: source.sampler.clone(),
        params,
        budget: Budget::new(source.vpls, s.max_depth),
        visibility: VisibilitySpec::RayTraced,
        shading: gather,
        clamp: s.clamp,
        compensation: 0,
        mode: Mode::Indirect,
        direct_samples: 1,
        seed: s.seed,
        backend: s.backend.name().into(),
    };
    Ok(spec.build(registry, &crate::pipeline::backends(), &setup.scene)?)
}

/// Whether a gather's cost grows with the VPL count (so a larger source's
/// frame may be predicted from a smaller one's).
fn grows_with_vpls(g: ShadingSpec) -> bool {
    matches!(g, ShadingSpec::Exhaustive | ShadingSpec::Interleaved { .. } | ShadingSpec::Culled { .. })
}

/// The predicted first-frame seconds of `gather` on `source`, from the
/// configurations already measured, each (VPLs, gather, median ms a frame;
/// NaN where it did not run): `None` when there is no prediction (run it).
fn predict<'a>(measured: impl IntoIterator<Item = (usize, &'a str, f64)>, source: &Source, gather: &str, grows: bool) -> Option<f64> {
    if !grows {
        return None;
    }
    measured
        .into_iter()
        .filter(|&(vpls, g, ms)| g == gather && ms.is_finite() && vpls < source.vpls)
        .max_by_key(|&(vpls, _, _)| vpls)
        .map(|(vpls, _, ms)| ms / 1e3 * source.vpls as f64 / vpls as f64)
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn check(s: &ManyLightsSettings) -> Result<(), ManyLightsError> {
    if s.sources.is_empty() || s.gathers.is_empty() {
        return Err(ManyLightsError::Invalid("the study needs a source and a gather".into()));
    }
    if s.sources.iter().any(|x| x.vpls == 0) || s.reference_spp == 0 || s.truth_spp == 0 || s.max_frames == 0 {
        return Err(ManyLightsError::Invalid("VPL budgets, samples and frames must be at least 1".into()));
    }
    if !(s.seconds.is_finite() && s.seconds > 0.0) {
        return Err(ManyLightsError::Invalid(format!("the budget must be a positive number of seconds, not {}", s.seconds)));
    }
    Ok(())
}

/// Measures every configuration of `s` on frame 0 of `setup` (named
/// `scene`); `progress` hears each finished configuration and skip.
pub fn measure(
    registry: &Registry,
    scene: &str,
    setup: &SceneSetup,
    s: &ManyLightsSettings,
    progress: &mut dyn FnMut(&str),
) -> Result<SceneStudy, ManyLightsError> {
    check(s)?;
    let start = Instant::now();
    let (frame_scene, camera) = setup.frame(0)?;
    let camera = camera.with_resolution(s.size)?;
    let (w, h) = camera.resolution;
    // The reference: the path tracer through the pixel centres, the
    // materials as the VPL pipeline draws them.
    let truth_scene = frame_scene.clone().with_material_policy(MaterialPolicy::Diffuse);
    let pixels: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
    let tracked = track_with(
        &truth_scene,
        &camera,
        &PathTracer::new(s.max_depth, Mode::Indirect),
        &TrackRequest { pixels: &pixels, spp: s.reference_spp, seed: s.seed ^ 0x6d61_6e79, frame: 0, footprint: Footprint::Centre },
    );
    let reference = Image { width: w, height: h, data: tracked.iter().map(|t| t.mean).collect() };
    let reference_se = Image { width: w, height: h, data: tracked.iter().map(|t| t.stderr).collect() };
    let floor = reference_variance(&reference_se);
    let m = reference.mean();
    let reference_mean = (m[0] + m[1] + m[2]) / 3.0;
    progress(&format!("reference, {} spp", s.reference_spp));
    let mut curves: Vec<Curve> = Vec::new();
    let mut sources = s.sources.clone();
    sources.sort_by_key(|x| x.vpls);
    for source in &sources {
        for &gather in &s.gathers {
            let name = gather.to_string();
            if let Some(p) =
                predict(curves.iter().map(|c| (c.source.vpls, c.gather.as_str(), c.frame_ms)), source, &name, grows_with_vpls(gather))
                    .filter(|&p| p > s.seconds)
            {
                progress(&format!("{} {name}: skipped, a frame would take about {p:.0} s", source.label()));
                curves.push(Curve {
                    source: source.clone(),
                    gather: name,
                    points: Vec::new(),
                    frame_ms: f64::NAN,
                    warmup_s: f64::NAN,
                    predicted_s: Some(p),
                    image: None,
                });
                continue;
            }
            let mut r = renderer(registry, setup, s, source, gather)?;
            // The first frame warms up (SMC's iterations from nothing): timed
            // apart, neither averaged nor counted.
            let t = Instant::now();
            r.render(&frame_scene, &camera, 0, 0.0)?;
            let warmup_s = t.elapsed().as_secs_f64();
            let mut sum = vec![Vec3::ZERO; (w * h) as usize];
            let (mut points, mut ms, mut spent) = (Vec::new(), Vec::new(), 0.0);
            for k in 0..s.max_frames {
                let t = Instant::now();
                let out = r.render(&frame_scene, &camera, k as u64 + 1, 0.0)?;
                let dt = t.elapsed().as_secs_f64();
                spent += dt;
                ms.push(dt * 1e3);
                for (a, b) in sum.iter_mut().zip(&out.image.data) {
                    *a += *b;
                }
                let n = (k + 1) as f32;
                let mean = Image { width: w, height: h, data: sum.iter().map(|v| *v / n).collect() };
                let rmse = (mse(&mean, &reference)? - floor).max(0.0).sqrt();
                points.push(Point { frames: k + 1, seconds: spent, rmse });
                if spent >= s.seconds {
                    break;
                }
            }
            let n = points.len().max(1) as f32;
            let image = Image { width: w, height: h, data: sum.iter().map(|v| *v / n).collect() };
            let c = Curve {
                source: source.clone(),
                gather: name,
                points,
                frame_ms: median(ms),
                warmup_s,
                predicted_s: None,
                image: Some(image),
            };
            let last = c.points.last().copied();
            progress(&format!(
                "{} {}: {} frames, {:.0} ms a frame, relative RMSE {:.3}",
                source.label(),
                c.gather,
                last.map_or(0, |p| p.frames),
                c.frame_ms,
                last.map_or(f64::NAN, |p| p.rmse / reference_mean)
            ));
            curves.push(c);
        }
    }
    Ok(SceneStudy {
        scene: scene.into(),
        reference_mean,
        reference_noise: floor.sqrt(),
        curves,
        reference,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// One configuration's temporal error on a sequence.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TemporalRow {
    /// The VPL source.
    pub source: Source,
    /// The gather.
    pub gather: String,
    /// |E|, |E′| and the mean signed error (`None`: not run).
    pub error: Option<TemporalError>,
    /// Median milliseconds a frame (NaN when not run).
    pub frame_ms: f64,
    /// Not run: the sequence's predicted seconds.
    pub predicted_s: Option<f64>,
}

/// The configurations on a Table 1 sequence.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TemporalStudy {
    /// The Table 1 row.
    pub row: String,
    /// Its frames.
    pub frames: std::ops::Range<u32>,
    /// Tracked pixels.
    pub pixels: usize,
    /// Every configuration, as [`SceneStudy::curves`].
    pub rows: Vec<TemporalRow>,
    /// Seconds it took.
    pub seconds: f64,
}

/// |E| and |E′| of every configuration of `s` on the Table 1 row `row`
/// (its quick window of frames, its tracked pixels at `s.size`).
pub fn temporal(
    registry: &Registry,
    row: &crate::table1::rows::Row,
    s: &ManyLightsSettings,
    progress: &mut dyn FnMut(&str),
) -> Result<TemporalStudy, ManyLightsError> {
    check(s)?;
    let start = Instant::now();
    let setup = row.setup()?;
    let frames = row.quick_frames.clone();
    let pixels = row.pixels(s.size);
    let mut truth = Vec::new();
    for f in frames.clone() {
        let (scene, camera) = setup.frame(f)?;
        let scene = scene.with_material_policy(MaterialPolicy::Diffuse);
        let camera = camera.with_resolution(s.size)?;
        let t = track_with(
            &scene,
            &camera,
            &PathTracer::new(s.max_depth, Mode::Indirect),
            &TrackRequest {
                pixels: &pixels,
                spp: s.truth_spp,
                seed: s.seed ^ 0x0074_7275_7468,
                frame: f as u64,
                footprint: Footprint::Centre,
            },
        );
        truth.push(t.iter().map(|p| tone_mapped_luminance(p.mean)).collect::<Vec<f64>>());
    }
    progress(&format!("{}: truth of {} frames, {} spp", row.id, frames.len(), s.truth_spp));
    let budget = s.seconds;
    let mut rows: Vec<TemporalRow> = Vec::new();
    let mut sources = s.sources.clone();
    sources.sort_by_key(|x| x.vpls);
    for source in &sources {
        for &gather in &s.gathers {
            let name = gather.to_string();
            // As the still study: a gather that grows with I is not run when
            // its frames would take longer than the budget.
            let n = frames.len() as f64;
            if let Some(p) =
                predict(rows.iter().map(|r| (r.source.vpls, r.gather.as_str(), r.frame_ms)), source, &name, grows_with_vpls(gather))
                    .map(|p| p * n)
                    .filter(|&p| p > budget)
            {
                progress(&format!("{} {name}: skipped, the sequence would take about {p:.0} s", source.label()));
                rows.push(TemporalRow { source: source.clone(), gather: name, error: None, frame_ms: f64::NAN, predicted_s: Some(p) });
                continue;
            }
            let mut r = renderer(registry, &setup, s, source, gather)?;
            let done = run_sequence(&setup, frames.clone(), Some(s.size), &mut r, &pixels, None, &mut |_, _| Ok(()))?;
            let estimate: Vec<Vec<f64>> = done.iter().map(|f| f.tracked.iter().map(|&c| tone_mapped_luminance(c)).collect()).collect();
            let error = temporal_error(&estimate, &truth)?;
            let frame_ms = median(done.iter().map(|f| f.timings.total_ms).collect());
            progress(&format!("{} {name}: |E| {:.4}, |E′| {:.4}", source.label(), error.e, error.e_prime));
            rows.push(TemporalRow { source: source.clone(), gather: name, error: Some(error), frame_ms, predicted_s: None });
        }
    }
    Ok(TemporalStudy { row: row.id.into(), frames, pixels: pixels.len(), rows, seconds: start.elapsed().as_secs_f64() })
}

/// The times of the table's columns: the budget's 1/8, 1/2 and whole.
pub fn checkpoints(s: &ManyLightsSettings) -> [f64; 3] {
    [s.seconds / 8.0, s.seconds / 2.0, s.seconds]
}

fn cell(v: Option<f64>) -> String {
    v.map_or("—".into(), |v| format!("{v:.3}"))
}

/// The configuration with the lowest RMSE at `t`, if any ran by then.
pub fn best_at(study: &SceneStudy, t: f64) -> Option<&Curve> {
    study.curves.iter().filter_map(|c| c.rmse_at(t).map(|e| (c, e))).min_by(|a, b| a.1.total_cmp(&b.1)).map(|(c, _)| c)
}

/// The study's Markdown: one table a scene (relative RMSE, the RMSE over
/// the reference's mean, at equal times), its plot, and the temporal table.
pub fn markdown(studies: &[SceneStudy], temporal: Option<&TemporalStudy>, s: &ManyLightsSettings) -> String {
    let [t1, t2, t3] = checkpoints(s);
    let mut md = format!(
        "Each configuration renders frame 0's view again and again ({}×{}, ray-traced visibility, indirect light, clamp `{}`, {} backend) and averages its frames after the first \
         (which warms up, SMC's iterations from nothing, and is timed apart); its error is the RMSE of that mean against a path-traced reference ({} spp through the pixel centres, its own noise removed), over the reference's mean, \
         after the wall time given. Budget {} s a configuration. Gathers whose cost grows with the VPL count are not run where their first frame, \
         predicted from the next smaller source's frame scaled by the VPL count, would exceed the budget (the predicted time is given).\n\n",
        s.size.0,
        s.size.1,
        s.clamp,
        s.backend.name(),
        s.reference_spp,
        s.seconds
    );
    for st in studies {
        let _ = write!(
            md,
            "### {}\n\n![{0}](manylights_{0}.png)\n\nReference mean {:.4}, its own relative RMSE {:.4}; {:.0} s.\n\n\
             | VPLs | gather | first frame, s | ms a frame | frames | rel. RMSE, 1 frame | at {t1:.1} s | at {t2:.1} s | at {t3:.1} s | mean / reference |\n| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n",
            st.scene,
            st.reference_mean,
            st.reference_noise / st.reference_mean,
            st.seconds
        );
        let rel = |v: Option<f64>| v.map(|v| v / st.reference_mean);
        for c in &st.curves {
            match c.predicted_s {
                Some(p) => {
                    let _ =
                        writeln!(md, "| {} | {} | — | ≈ {:.0} (predicted) | 0 | — | — | — | — | — |", c.source.label(), c.gather, p * 1e3);
                }
                None => {
                    let _ = writeln!(
                        md,
                        "| {} | {} | {:.2} | {:.0} | {} | {} | {} | {} | {} | {:.3} |",
                        c.source.label(),
                        c.gather,
                        c.warmup_s,
                        c.frame_ms,
                        c.points.last().map_or(0, |p| p.frames),
                        cell(rel(c.points.first().map(|p| p.rmse))),
                        cell(rel(c.rmse_at(t1))),
                        cell(rel(c.rmse_at(t2))),
                        cell(rel(c.rmse_at(t3))),
                        c.mean_ratio(st.reference_mean)
                    );
                }
            }
        }
        md.push('\n');
        for t in [t1, t3] {
            if let Some(b) = best_at(st, t) {
                let _ = writeln!(md, "Lowest error at {t:.1} s: {} {}.  ", b.source.label(), b.gather);
            }
        }
        if let Some(b) = best_at(st, t3) {
            let _ = writeln!(
                md,
                "\nThe reference and the lowest error at {t3:.1} s ({} {}): ![reference](manylights_{}_reference.png) ![best]({}.png)",
                b.source.label(),
                b.gather,
                st.scene,
                image_stem(&st.scene, b)
            );
        }
        md.push('\n');
    }
    if let Some(tp) = temporal {
        let _ = write!(
            md,
            "### Temporal error on Table 1's `{}` (frames {}..{}, {} tracked pixels)\n\n\
             |E| and |E′| (eq. 10) of the tracked pixels' tone-mapped luminance against the path tracer's ({} spp), one seed, each configuration from a fresh renderer.\n\n\
             | VPLs | gather | ms a frame | abs(E) | abs(E′) | mean signed error |\n| --- | --- | ---: | ---: | ---: | ---: |\n",
            tp.row, tp.frames.start, tp.frames.end, tp.pixels, s.truth_spp
        );
        for r in &tp.rows {
            match (&r.error, r.predicted_s) {
                (Some(e), _) => {
                    let _ = writeln!(
                        md,
                        "| {} | {} | {:.0} | {:.4} | {:.4} | {:+.4} |",
                        r.source.label(),
                        r.gather,
                        r.frame_ms,
                        e.e,
                        e.e_prime,
                        e.bias
                    );
                }
                (None, p) => {
                    let _ = writeln!(
                        md,
                        "| {} | {} | sequence ≈ {:.0} s (predicted) | — | — | — |",
                        r.source.label(),
                        r.gather,
                        p.unwrap_or(f64::NAN)
                    );
                }
            }
        }
        md.push('\n');
    }
    md
}

/// The file stem of a configuration's image: `manylights_<scene>_<sampler><I>_<gather>`,
/// the gather's colon as a dash.
pub fn image_stem(scene: &str, c: &Curve) -> String {
    format!("manylights_{scene}_{}{}_{}", c.source.sampler, c.source.vpls, c.gather.replace(':', "-"))
}

/// Writes into `dir` the reference (`manylights_<scene>_reference`) and
/// every configuration's final mean image ([`image_stem`]) as EXR and PNG,
/// all PNGs at the reference's exposure.
pub fn write_images(dir: &Path, st: &SceneStudy) -> Result<(), ManyLightsError> {
    use vpl_scene_io::ImageFile as _;
    let exposure = crate::figures::exposure_for(&st.reference);
    let save = |stem: &str, img: &Image| -> Result<(), ManyLightsError> {
        img.write_exr(dir.join(format!("{stem}.exr")))?;
        Ok(img.write_png(dir.join(format!("{stem}.png")), exposure)?)
    };
    save(&format!("manylights_{}_reference", st.scene), &st.reference)?;
    for c in &st.curves {
        if let Some(img) = &c.image {
            save(&image_stem(&st.scene, c), img)?;
        }
    }
    Ok(())
}

/// Colour of a gather in the plots (Okabe–Ito).
fn gather_color(g: &str) -> (u8, u8, u8) {
    match g {
        "interleaved" => (230, 159, 0),
        "exhaustive" => (0, 0, 0),
        "lightcuts:8" => (86, 180, 233),
        "lightcuts:32" => (0, 114, 178),
        "lightcuts:128" => (0, 158, 115),
        g if g.starts_with("culled") => (204, 121, 167),
        _ => (213, 94, 0),
    }
}

/// `manylights_<scene>.png` in `dir`: relative RMSE over seconds, log–log;
/// a colour per gather, sources by line (smallest thin, next with markers,
/// largest bold).
pub fn plot(dir: &Path, st: &SceneStudy) -> Result<(), ManyLightsError> {
    let mut budgets: Vec<usize> = st.curves.iter().map(|c| c.source.vpls).collect();
    budgets.sort_unstable();
    budgets.dedup();
    let series: Vec<Series> = st
        .curves
        .iter()
        .filter(|c| !c.points.is_empty())
        .map(|c| {
            let rank = budgets.iter().position(|&b| b == c.source.vpls).unwrap_or(0);
            Series {
                label: format!("{} {}", c.source.label(), c.gather),
                points: c.points.iter().map(|p| (p.seconds, p.rmse / st.reference_mean)).collect(),
                color: gather_color(&c.gather),
                bold: rank + 1 == budgets.len() && budgets.len() > 1,
                markers: rank == 1,
            }
        })
        .collect();
    let title = format!("{}: error over wall time", st.scene);
    line_chart(
        &dir.join(format!("manylights_{}.png", st.scene)),
        &Chart { title: &title, x_label: "seconds", y_label: "RMSE / reference mean", log: (true, true), size: (900, 560) },
        &series,
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sources_are_labelled_by_sampler_and_binary_size() {
        assert_eq!(Source { sampler: "smc".into(), vpls: 2048 }.label(), "SMC 2K");
        assert_eq!(Source { sampler: "ir".into(), vpls: 1 << 20 }.label(), "IR 1M");
        assert_eq!(Source { sampler: "ir".into(), vpls: 1000 }.label(), "IR 1000");
    }

    #[test]
    fn a_growing_gather_is_predicted_from_the_largest_smaller_source() {
        // A smaller source that did not run (NaN) predicts nothing.
        let measured = [(1024, "exhaustive", 100.0), (4096, "exhaustive", 300.0), (8192, "exhaustive", f64::NAN)];
        let big = Source { sampler: "ir".into(), vpls: 16384 };
        assert_eq!(predict(measured, &big, "exhaustive", true), Some(1.2));
        assert_eq!(predict(measured, &big, "exhaustive", false), None);
        assert_eq!(predict(measured, &big, "lightcuts:8", true), None);
    }

    #[test]
    fn the_error_at_a_time_is_that_of_the_frames_done_by_then() {
        let curve = Curve {
            source: Source { sampler: "ir".into(), vpls: 1 },
            gather: "exhaustive".into(),
            points: vec![Point { frames: 1, seconds: 1.0, rmse: 4.0 }, Point { frames: 2, seconds: 2.0, rmse: 3.0 }],
            frame_ms: 1e3,
            warmup_s: 0.0,
            predicted_s: None,
            image: None,
        };
        assert_eq!(curve.rmse_at(0.5), None);
        assert_eq!(curve.rmse_at(1.5), Some(4.0));
        assert_eq!(curve.rmse_at(9.0), Some(3.0));
    }
}

//! Energy along a sequence: a sampler's indirect image mean against the
//! path tracer's, at frame 0 and at checkpoints spread over the scene's
//! sequence, and the share of its indirect light the default clamp removes.
//!
//! The sampler runs the sequence as a renderer would: it is stepped at
//! every frame from frame 0 (after its own warm-up), keeping its state, so
//! an estimator that lags behind moving lights (SMC's area probes live T
//! iterations) is measured with its lag. To save time it may instead be
//! stepped at every `stride`-th frame and then at each of the `settle`
//! frames before a checkpoint: a stride alone would make a light move
//! `stride` times as far in the T iterations the probes live (on
//! `building`, with its lamp carried from room to room, stride 8 put the
//! sequence's image mean at 3 times the path tracer's). At frame 0 and at
//! each checkpoint its VPLs are shaded exhaustively with ray-traced
//! visibility, once without a clamp and once with G_max = I / A_view of
//! that frame's view ([`GeometryClamp::for_view`]), and the path tracer
//! renders the same view's indirect light (depth `max_depth`, materials by
//! their albedo as the VPL pipeline draws them) through the same points,
//! the pixels' centres. (With paths through the whole pixel, edges inside
//! the pixels of a small image move the ratio: `cornell` at 48×36 came
//! out 0.948 against 0.99 at 64×64.)
//!
//! Per seed the sequence's figure is the mean over the checkpoints of the
//! per-frame ratios (every frame counts alike, however bright); the seeds
//! give its standard error.

use std::time::Instant;
use vpl_core::image::luminance;
use vpl_core::{Budget, Frame, GeometryClamp, Image, MaterialPolicy, Mode, Params, SceneSetup, VplVisibility as _};
use vpl_pathtrace::{Footprint, PathTracer, TrackRequest, track_with};
use vpl_render::{Clamp, Renderer, ShadingSpec, VisibilitySpec};
use vpl_sampling::Registry;
use vpl_shading::{ExhaustiveShader, render_gbuffer};
use vpl_visibility::RayTraced;

/// What an energy run measures.
#[derive(Clone, Debug)]
pub struct EnergySettings {
    /// The sampler's registry name.
    pub sampler: String,
    /// Its settings (`--set`).
    pub params: Params,
    /// The VPL budget I.
    pub vpls: usize,
    /// Image size of every render.
    pub size: (u32, u32),
    /// Seeds `seed`, `seed + 1`, … of the sampler (the path tracer uses `seed`).
    pub seeds: u32,
    /// Seeds rendered at frame 0, at least `seeds`: those past `seeds`
    /// render frame 0 alone (after the warm-up). One seed's image mean
    /// varies more at one frame than over a sequence's checkpoints, and
    /// frame 0 costs no walk along the sequence.
    pub frame0_seeds: u32,
    /// With `frame0_se` above 0, the seeds past `seeds` stop once frame
    /// 0's ratio over the seeds so far has a standard error of at most
    /// `frame0_se` (after at least [`FRAME0_MIN_SEEDS`]), so that a scene
    /// whose seeds agree takes few and one that varies takes up to
    /// `frame0_seeds`. The rule looks at the seeds' spread alone, never
    /// at their mean: for normally distributed ratios the sample mean is
    /// independent of the sample variance, so stopping on the one leaves
    /// the other unbiased. 0: every one of `frame0_seeds` runs.
    pub frame0_se: f64,
    /// First seed.
    pub seed: u64,
    /// Checkpoints spread over the sequence (the centres of as many equal
    /// parts); 0: frame 0 alone.
    pub checkpoints: u32,
    /// The sampler is stepped at every `stride`-th frame (1: every frame;
    /// more moves the lights and camera further between its iterations).
    pub stride: u32,
    /// Frames stepped one by one before each checkpoint (with a stride
    /// above 1): 2T or more lets the sampler catch up with the sequence at
    /// its own pace, so that the probes the checkpoint's cells hold come
    /// from consecutive frames, lag and all.
    pub settle: u32,
    /// Path-traced samples a pixel of the truth.
    pub truth_spp: u32,
    /// Longest path in segments.
    pub max_depth: u32,
}

impl Default for EnergySettings {
    fn default() -> Self {
        EnergySettings {
            sampler: "smc".into(),
            params: Params::new(),
            vpls: 2048,
            size: (64, 48),
            seeds: 3,
            frame0_seeds: 3,
            frame0_se: 0.0,
            seed: 0,
            checkpoints: 6,
            stride: 1,
            settle: 0,
            truth_spp: 512,
            max_depth: 5,
        }
    }
}

/// The fewest seeds at frame 0 that [`EnergySettings::frame0_se`] stops
/// at: below that the seeds' own standard error is too uncertain to stop
/// on (from 8 seeds, 7 degrees of freedom, it is under 0.56 of the true
/// one 5 % of the time; from 4, 3 degrees, 18 % of the time: 5 seeds of
/// `colonnade` that happened to agree once stopped at 0.961 ± 0.007 in
/// the energy test, where 16 gave 0.973 ± 0.007).
pub const FRAME0_MIN_SEEDS: usize = 8;

/// One rendered frame: the truth and every seed's images.
#[derive(Clone, Debug, PartialEq)]
pub struct Checkpoint {
    /// Frame index.
    pub frame: u32,
    /// The path tracer's indirect image mean (luminance).
    pub truth: f64,
    /// Its standard error (from the per-pixel errors, pixels independent).
    pub truth_se: f64,
    /// The sampler's unclamped image mean, per seed.
    pub unclamped: Vec<f64>,
    /// The same VPLs' image mean under the view's default clamp, per seed.
    pub clamped: Vec<f64>,
}

/// A scene's measurements: frame 0 first, then the checkpoints.
#[derive(Clone, Debug, PartialEq)]
pub struct EnergyRun {
    /// The scene as named.
    pub scene: String,
    /// Frame 0, then the checkpoints in order.
    pub frames: Vec<Checkpoint>,
    /// Seconds the run took.
    pub seconds: f64,
    /// The seeds that walked the sequence (the first ones of frame 0's).
    pub walked: usize,
}

/// A mean over seeds and its standard error (0 with one seed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// The mean.
    pub mean: f64,
    /// Its standard error.
    pub se: f64,
}

impl Estimate {
    /// The mean and standard error of `xs` (sample variance with n − 1).
    pub fn of(xs: &[f64]) -> Estimate {
        let n = xs.len() as f64;
        if xs.is_empty() {
            return Estimate { mean: f64::NAN, se: f64::NAN };
        }
        let mean = xs.iter().sum::<f64>() / n;
        let se = if xs.len() < 2 { 0.0 } else { (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt() };
        Estimate { mean, se }
    }

    /// Standard errors by which the mean lies more than `tolerance` from
    /// `target` (negative when inside; infinite when outside with no spread).
    pub fn z_past(&self, target: f64, tolerance: f64) -> f64 {
        let d = (self.mean - target).abs() - tolerance;
        if self.se > 0.0 {
            d / self.se
        } else if d > 0.0 {
            f64::INFINITY
        } else {
            f64::NEG_INFINITY
        }
    }
}

impl EnergyRun {
    /// Per seed that rendered every one of `frames`, the mean of
    /// `f(checkpoint, seed)` over them.
    fn per_seed(&self, frames: &[Checkpoint], f: impl Fn(&Checkpoint, usize) -> f64) -> Vec<f64> {
        let seeds = frames.iter().map(|c| c.unclamped.len()).min().unwrap_or(0);
        (0..seeds).map(|s| frames.iter().map(|c| f(c, s)).sum::<f64>() / frames.len() as f64).collect()
    }

    /// The checkpoints; frame 0 where there are none (with the seeds that
    /// walked the sequence, not those that rendered frame 0 alone).
    fn sequence(&self) -> &[Checkpoint] {
        if self.frames.len() > 1 { &self.frames[1..] } else { &self.frames }
    }

    /// The sequence's figure per seed: over the checkpoints, or frame 0's
    /// first `walked` seeds where there are none.
    fn sequence_per_seed(&self, f: impl Fn(&Checkpoint, usize) -> f64) -> Vec<f64> {
        let mut v = self.per_seed(self.sequence(), f);
        if self.frames.len() == 1 {
            v.truncate(self.walked);
        }
        v
    }

    /// The unclamped image mean over the truth's at frame 0, over seeds.
    pub fn frame0_ratio(&self) -> Estimate {
        Estimate::of(&self.per_seed(&self.frames[..1], |c, s| c.unclamped[s] / c.truth))
    }

    /// The mean over the checkpoints of that ratio, over seeds.
    pub fn sequence_ratio(&self) -> Estimate {
        Estimate::of(&self.sequence_per_seed(|c, s| c.unclamped[s] / c.truth))
    }

    /// The share of the indirect light the clamp removes, mean over the
    /// checkpoints, over seeds.
    pub fn clamp_removed(&self) -> Estimate {
        Estimate::of(&self.sequence_per_seed(|c, s| 1.0 - c.clamped[s] / c.unclamped[s]))
    }

    /// The largest relative standard error of the truth over the frames.
    pub fn truth_rel_se(&self) -> f64 {
        self.frames.iter().map(|c| c.truth_se / c.truth).fold(0.0, f64::max)
    }

    /// The relative standard error that frame 0's truth gives its ratio.
    pub fn frame0_truth_rel_se(&self) -> f64 {
        self.frames.first().map_or(0.0, |c| c.truth_se / c.truth)
    }

    /// The relative standard error that the truths give the sequence's
    /// ratio, a mean over its checkpoints of ratios to independent truths:
    /// √(Σ_k (σ_k / t_k)²) / K.
    pub fn sequence_truth_rel_se(&self) -> f64 {
        let frames = self.sequence();
        (frames.iter().map(|c| (c.truth_se / c.truth).powi(2)).sum::<f64>()).sqrt() / frames.len().max(1) as f64
    }
}

/// Errors of an energy run.
#[derive(Debug, thiserror::Error)]
pub enum EnergyError {
    /// The scene or a frame of it.
    #[error(transparent)]
    Core(#[from] vpl_core::CoreError),
    /// The sampler or renderer.
    #[error(transparent)]
    Render(#[from] vpl_render::RenderError),
    /// The path tracer.
    #[error(transparent)]
    Path(#[from] vpl_pathtrace::RenderError),
    /// A setting.
    #[error("{0}")]
    Invalid(String),
    /// The truth is black at a frame, so no ratio exists.
    #[error("{scene}: the path tracer's indirect light is black at frame {frame}")]
    Black {
        /// The scene.
        scene: String,
        /// The frame.
        frame: u32,
    },
}

/// The frames [`measure`] renders for a sequence of `count` frames: 0, then
/// the centres of `checkpoints` equal parts, on the stride.
pub fn checkpoint_frames(count: u32, checkpoints: u32, stride: u32) -> Vec<u32> {
    let stride = stride.max(1);
    let mut frames = vec![0];
    for k in 0..checkpoints {
        let f = ((2 * k + 1) as u64 * count as u64 / (2 * checkpoints as u64)) as u32;
        frames.push(f / stride * stride);
    }
    frames
}

fn mean_luminance(img: &Image) -> f64 {
    img.data.iter().map(|&c| luminance(c) as f64).sum::<f64>() / img.data.len().max(1) as f64
}

/// Measures `spec` (a built-in name or scene file, loaded by the caller
/// as `setup`) under `s`; `progress` hears each finished (seed, frame).
pub fn measure(
    registry: &Registry,
    scene_name: &str,
    setup: &SceneSetup,
    s: &EnergySettings,
    progress: &mut dyn FnMut(&str),
) -> Result<EnergyRun, EnergyError> {
    if s.seeds == 0 || s.vpls == 0 || s.truth_spp == 0 {
        return Err(EnergyError::Invalid("seeds, VPLs and samples must be at least 1".into()));
    }
    let start = Instant::now();
    let count = setup.sequence.as_ref().map_or(1, |q| q.frame_count());
    let frames = checkpoint_frames(count, if count > 1 { s.checkpoints } else { 0 }, s.stride);
    let stride = s.stride.max(1);
    let last = *frames.iter().max().unwrap_or(&0);
    // The frames the sampler steps through, in order: the stride's and
    // the settling runs before each checkpoint.
    let mut steps: Vec<u32> = (0..=last).step_by(stride as usize).collect();
    for &c in &frames {
        steps.extend(c.saturating_sub(s.settle)..=c);
    }
    steps.sort_unstable();
    steps.dedup();
    // The truth at every rendered frame.
    let mut out: Vec<Checkpoint> = Vec::with_capacity(frames.len());
    for &f in &frames {
        let (scene, camera) = setup.frame(f)?;
        let scene = scene.with_material_policy(MaterialPolicy::Diffuse);
        let camera = camera.with_resolution(s.size)?;
        // Rays through the pixel centres: the one point a G-buffer shades
        // per pixel, so that edges inside a pixel count for neither.
        let (w, h) = camera.resolution;
        let pixels: Vec<(u32, u32)> = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).collect();
        let pt = PathTracer::new(s.max_depth, Mode::Indirect);
        let tracked = track_with(
            &scene,
            &camera,
            &pt,
            &TrackRequest { pixels: &pixels, spp: s.truth_spp, seed: s.seed, frame: f as u64, footprint: Footprint::Centre },
        );
        let n = tracked.len().max(1) as f64;
        let truth = tracked.iter().map(|t| luminance(t.mean) as f64).sum::<f64>() / n;
        let truth_se = tracked.iter().map(|t| (luminance(t.stderr) as f64).powi(2)).sum::<f64>().sqrt() / n;
        if truth.is_nan() || truth <= 0.0 {
            return Err(EnergyError::Black { scene: scene_name.into(), frame: f });
        }
        out.push(Checkpoint { frame: f, truth, truth_se, unclamped: Vec::new(), clamped: Vec::new() });
        progress(&format!("truth of frame {f}"));
    }
    for k in 0..s.seeds.max(s.frame0_seeds) {
        let seed = s.seed + k as u64;
        // Seeds past `seeds` render frame 0 alone.
        let steps = if k < s.seeds { &steps[..] } else { &steps[..1.min(steps.len())] };
        let mut renderer = Renderer::builder(&setup.scene)
            .registry(registry)
            .sampler(s.sampler.as_str())
            .params(s.params.clone())
            .budget(Budget { vpls: s.vpls, max_depth: s.max_depth })
            .seed(seed)
            .visibility(VisibilitySpec::RayTraced)
            .shader(ShadingSpec::Exhaustive)
            .clamp(Clamp::Off)
            .mode(Mode::Indirect)
            .build()?;
        for &f in steps {
            let (scene, camera) = setup.frame(f)?;
            let camera = camera.with_resolution(s.size)?;
            let gbuffer = render_gbuffer(&scene, &camera);
            let time = setup.sequence.as_ref().map_or(0.0, |q| q.time(f));
            let frame = Frame { scene: &scene, camera: &camera, time, index: f as u64, seed, gbuffer: &gbuffer, previous: None };
            let set = renderer.sampler_mut().next_frame(&frame).clone();
            for c in out.iter_mut().filter(|c| c.frame == f) {
                let mut vis = RayTraced::default();
                vis.update(&scene, &set);
                // Both images from one pass over the pairs: the same
                // visibility queries serve the clamped and the unclamped.
                let clamp = GeometryClamp::for_view(s.vpls, &scene, &camera);
                let (unclamped, clamped) = ExhaustiveShader::default().shade_free_and_clamped(&gbuffer, &set, &vis, clamp);
                c.unclamped.push(mean_luminance(&unclamped));
                c.clamped.push(mean_luminance(&clamped));
                progress(&format!("seed {seed}, frame {f}"));
            }
        }
        // Frame 0 (always `out[0]`) precise enough: the later seeds are skipped.
        if let Some(f0) = out.first()
            && s.frame0_se > 0.0
            && k + 1 >= s.seeds
            && f0.unclamped.len() >= FRAME0_MIN_SEEDS
        {
            let ratios: Vec<f64> = f0.unclamped.iter().map(|u| u / f0.truth).collect();
            if Estimate::of(&ratios).se <= s.frame0_se {
                break;
            }
        }
    }
    Ok(EnergyRun { scene: scene_name.into(), frames: out, seconds: start.elapsed().as_secs_f64(), walked: s.seeds as usize })
}

/// A Markdown table of `runs`: the frame-0 and sequence ratios and the
/// clamp's removed share, each ± its standard error over seeds.
pub fn markdown(runs: &[EnergyRun], s: &EnergySettings) -> String {
    let mut md = format!(
        "{} with I = {}, {}×{}, {} seeds ({} at frame 0), stepped {}, {} checkpoints; path tracer {} spp through the pixel centres, depth {}; unclamped, ray-traced, exhaustive, indirect only.\n\n",
        s.sampler,
        s.vpls,
        s.size.0,
        s.size.1,
        s.seeds,
        if s.frame0_se > 0.0 {
            format!("up to {}, until their standard error is at most {},", s.seeds.max(s.frame0_seeds), s.frame0_se)
        } else {
            s.seeds.max(s.frame0_seeds).to_string()
        },
        if s.stride <= 1 {
            "at every frame".to_string()
        } else {
            format!("every {} frames and at each of the {} before a checkpoint", s.stride, s.settle)
        },
        s.checkpoints,
        s.truth_spp,
        s.max_depth
    );
    md.push_str(
        "| scene | frame 0: image mean / path tracer | sequence mean | clamp removes (sequence) | truth's largest rel. SE | seconds |\n",
    );
    md.push_str("| --- | ---: | ---: | ---: | ---: | ---: |\n");
    for r in runs {
        let (a, b, c) = (r.frame0_ratio(), r.sequence_ratio(), r.clamp_removed());
        md.push_str(&format!(
            "| {} | {:.3} ± {:.3} | {:.3} ± {:.3} | {:.1} % ± {:.1} | {:.1} % | {:.0} |\n",
            r.scene,
            a.mean,
            a.se,
            b.mean,
            b.se,
            100.0 * c.mean,
            100.0 * c.se,
            100.0 * r.truth_rel_se(),
            r.seconds
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checkpoints_sit_at_the_centres_of_equal_parts_on_the_stride() {
        assert_eq!(checkpoint_frames(720, 4, 1), vec![0, 90, 270, 450, 630]);
        assert_eq!(checkpoint_frames(720, 4, 4), vec![0, 88, 268, 448, 628]);
        assert_eq!(checkpoint_frames(1, 0, 1), vec![0]);
    }

    #[test]
    fn estimates_and_their_distance_past_a_tolerance() {
        let e = Estimate::of(&[1.0, 1.02, 1.04]);
        assert!((e.mean - 1.02).abs() < 1e-12 && (e.se - 0.02 / 3f64.sqrt()).abs() < 1e-12);
        assert!(e.z_past(1.0, 0.03) < 0.0);
        assert!((Estimate::of(&[1.1, 1.1]).z_past(1.0, 0.03)).is_infinite());
    }

    /// Frame 0's seeds stop at the first count from [`FRAME0_MIN_SEEDS`]
    /// whose standard error is at most `frame0_se`: all of them with a
    /// bound no spread meets, the fewest with one every spread meets, and
    /// with the rule off.
    #[test]
    fn frame_0_takes_seeds_until_its_standard_error_is_small_enough() {
        let registry = Registry::builtin();
        let setup = SceneSetup::builtin("cornell").unwrap();
        let s = |frame0_se: f64| EnergySettings {
            sampler: "ir".into(),
            vpls: 16,
            size: (8, 6),
            seeds: 2,
            frame0_seeds: 10,
            frame0_se,
            truth_spp: 4,
            ..EnergySettings::default()
        };
        let seeds = |frame0_se: f64| measure(&registry, "cornell", &setup, &s(frame0_se), &mut |_| {}).unwrap().frames[0].unclamped.len();
        assert_eq!(seeds(0.0), 10);
        assert_eq!(seeds(1e-12), 10);
        assert_eq!(seeds(1e9), FRAME0_MIN_SEEDS);
    }
}

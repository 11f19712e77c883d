//! One frame of VPL rendering, stage by stage, timed.

use crate::compensation::{Compensation, compensate};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use vpl_core::{Camera, Frame, GBuffer, Image, IndirectShader, Mode, Scene, Stats, VisibilityUpdate, VplSampler, VplSet, VplVisibility};
use vpl_shading::{direct_light, render_gbuffer};

/// What a frame renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameSettings {
    /// Which paths: `indirect` (VPLs only), `direct` (emission and direct
    /// light), `full` (both).
    pub mode: Mode,
    /// Longest path in segments (Mitsuba's convention); the sampler must
    /// have been built for the same depth.
    pub max_depth: u32,
    /// Light samples per pixel of the direct light.
    pub direct_samples: u32,
    /// Seed of all streams.
    pub seed: u64,
    /// Frame index.
    pub index: u64,
    /// Time in seconds.
    pub time: f32,
    /// Bias compensation of the shader's clamp (`None`: the clamped image as
    /// it is); see [`crate::compensation`].
    pub compensation: Option<Compensation>,
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings { mode: Mode::Full, max_depth: 5, direct_samples: 16, seed: 0, index: 0, time: 0.0, compensation: None }
    }
}

/// Milliseconds per stage of a frame (zero for stages the mode skips).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StageTimings {
    /// Camera rays into the G-buffer.
    pub gbuffer_ms: f64,
    /// The sampler's `next_frame`.
    pub sampling_ms: f64,
    /// Visibility update (shadow maps of changed VPLs).
    pub visibility_ms: f64,
    /// Indirect shading (filter included).
    pub shading_ms: f64,
    /// Bias compensation of the clamp.
    pub compensation_ms: f64,
    /// Direct light.
    pub direct_ms: f64,
    /// The whole frame.
    pub total_ms: f64,
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct FrameOutput {
    /// Radiance per pixel.
    pub image: Image,
    /// The G-buffer the frame used.
    pub gbuffer: GBuffer,
    /// Stage timings.
    pub timings: StageTimings,
    /// What the visibility update did.
    pub visibility: VisibilityUpdate,
    /// VPL slots that moved since the previous frame (see `VplSet::moved`).
    pub moved: usize,
    /// VPLs stored in the frame's set.
    pub stored: usize,
    /// The VPL set the frame was shaded with (positions, normals, fluxes and
    /// which slots moved; no slots when the mode needs no VPLs): what a
    /// viewer splats over the image or a study logs per frame.
    pub vpls: VplSet,
    /// The sampler's statistics of the frame (empty when the mode needs no VPLs).
    pub sampler_stats: Stats,
    /// The indirect light the VPLs gave (`None` when the mode needs no
    /// VPLs): what adaptive samplers read as the previous frame's image.
    pub indirect: Option<Image>,
    /// The first stage that produced NaN or infinite values, and how many
    /// (VPL fluxes or pixels); `None` for a finite frame.
    /// [`crate::Renderer::render`] turns it into [`crate::RenderError::NonFinite`].
    pub non_finite: Option<(&'static str, usize)>,
    /// The frame stopped at a stage boundary because its cancel flag was set
    /// ([`render_frame_cancellable_on`]): the image lacks the stages not run.
    /// [`crate::Renderer::render_cancellable`] turns it into
    /// [`crate::RenderError::Cancelled`].
    pub cancelled: bool,
}

/// Counts the non-finite pixels of `img`.
pub fn count_non_finite(img: &Image) -> usize {
    img.data.iter().filter(|p| !p.is_finite()).count()
}

/// Records `bad` non-finite values of `stage` unless an earlier stage already had some.
fn note(first: &mut Option<(&'static str, usize)>, stage: &'static str, bad: usize) {
    if bad > 0 && first.is_none() {
        *first = Some((stage, bad));
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// Renders one frame: the G-buffer; then, when the mode and depth keep paths
/// with ≥ 2 scattering vertices, the sampler's VPLs, the visibility update,
/// indirect shading and the clamp's bias compensation if asked for; then directly seen emission (k = 0) and direct
/// light (k = 1) where the mode keeps them. `previous` is the indirect
/// image of the previous frame ([`FrameOutput::indirect`]), which samplers
/// that adapt to the image (Russian-roulette acceptance) read.
#[allow(clippy::too_many_arguments)]
pub fn render_frame(
    scene: &Scene,
    camera: &Camera,
    s: FrameSettings,
    previous: Option<&Image>,
    sampler: &mut dyn VplSampler,
    vis: &mut dyn VplVisibility,
    shader: &mut dyn IndirectShader,
) -> FrameOutput {
    let t0 = Instant::now();
    let gbuffer = render_gbuffer(scene, camera);
    render_frame_on(gbuffer, ms(t0), scene, camera, s, previous, sampler, vis, shader)
}

/// [`render_frame`] from a G-buffer rendered elsewhere (on a GPU) in
/// `gbuffer_ms` milliseconds.
#[allow(clippy::too_many_arguments)]
pub fn render_frame_on(
    gbuffer: GBuffer,
    gbuffer_ms: f64,
    scene: &Scene,
    camera: &Camera,
    s: FrameSettings,
    previous: Option<&Image>,
    sampler: &mut dyn VplSampler,
    vis: &mut dyn VplVisibility,
    shader: &mut dyn IndirectShader,
) -> FrameOutput {
    render_frame_cancellable_on(gbuffer, gbuffer_ms, scene, camera, s, previous, sampler, vis, shader, &AtomicBool::new(false))
}

/// [`render_frame_on`] that stops at the next stage boundary once `cancel`
/// is set (from another thread: a Ctrl-C handler, a viewer's camera move),
/// with [`FrameOutput::cancelled`] set. The boundaries are before the
/// sampler, after the visibility update, after shading and after the bias
/// compensation: the sampler's step and the visibility update it calls for
/// run together or not at all, so that the visibility always matches the
/// sampler's set. A frame that is not cancelled is [`render_frame_on`]'s,
/// bit for bit.
#[allow(clippy::too_many_arguments)]
pub fn render_frame_cancellable_on(
    gbuffer: GBuffer,
    gbuffer_ms: f64,
    scene: &Scene,
    camera: &Camera,
    s: FrameSettings,
    previous: Option<&Image>,
    sampler: &mut dyn VplSampler,
    vis: &mut dyn VplVisibility,
    shader: &mut dyn IndirectShader,
    cancel: &AtomicBool,
) -> FrameOutput {
    let stop = || cancel.load(Ordering::Relaxed);
    let start = Instant::now();
    let mut t = StageTimings { gbuffer_ms, ..StageTimings::default() };
    let mut image = Image::new(camera.resolution.0, camera.resolution.1);
    let mut visibility = VisibilityUpdate::default();
    let mut sampler_stats = Stats::default();
    let mut moved = 0;
    let mut stored = 0;
    let mut vpl_set = VplSet::new(0);
    let mut indirect = None;
    let mut non_finite = None;
    let (_, max_k) = s.mode.k_range(s.max_depth);
    let mut cancelled = stop();
    if !cancelled && s.mode != Mode::Direct && max_k >= 2 {
        let frame = Frame { scene, camera, time: s.time, index: s.index, seed: s.seed, gbuffer: &gbuffer, previous };
        let t0 = Instant::now();
        let vpls = sampler.next_frame(&frame);
        t.sampling_ms = ms(t0);
        moved = vpls.moved_count();
        stored = vpls.stored();
        vpl_set = vpls.clone();
        let bad = vpls.iter().filter(|(_, v)| !(v.flux.is_finite() && v.y.is_finite() && v.n.is_finite())).count();
        note(&mut non_finite, "the VPL sampler", bad);
        let t0 = Instant::now();
        visibility = vis.update(scene, vpls);
        t.visibility_ms = ms(t0);
        cancelled = stop();
        if !cancelled {
            let t0 = Instant::now();
            image = shader.shade(&gbuffer, vpls, vis);
            t.shading_ms = ms(t0);
            note(&mut non_finite, "indirect shading", count_non_finite(&image));
            cancelled = stop();
        }
        if let Some(c) = s.compensation.filter(|_| !cancelled) {
            let t0 = Instant::now();
            let added = compensate(scene, &gbuffer, c, s.max_depth, s.seed, s.index);
            t.compensation_ms = ms(t0);
            note(&mut non_finite, "bias compensation", count_non_finite(&added));
            for (o, a) in image.data.iter_mut().zip(&added.data) {
                *o += *a;
            }
            cancelled = stop();
        }
        sampler_stats = sampler.stats();
        if !cancelled {
            indirect = Some(image.clone());
        }
    }
    if cancelled {
        t.total_ms = ms(start) + gbuffer_ms;
        return FrameOutput {
            image,
            gbuffer,
            timings: t,
            visibility,
            moved,
            stored,
            vpls: vpl_set,
            sampler_stats,
            indirect,
            non_finite,
            cancelled,
        };
    }
    // A frame left on the device is finished there: emission and direct
    // light added by the shader's device (the renderer keeps a frame there
    // only when it can).
    let emission = s.mode.includes(0, s.max_depth);
    let direct = s.mode.includes(1, s.max_depth);
    if !image.on_host() {
        if emission || direct {
            let t0 = Instant::now();
            let done = shader.finish_on_device(scene, emission, direct.then_some((s.direct_samples, s.seed)));
            t.direct_ms = ms(t0);
            if !done {
                note(&mut non_finite, "the frame's emission and direct light (not added on the device)", 1);
            }
        }
    } else {
        if emission {
            note(&mut non_finite, "the G-buffer's emission", gbuffer.samples.iter().filter(|g| !g.emitted.is_finite()).count());
            for (o, g) in image.data.iter_mut().zip(&gbuffer.samples) {
                *o += g.emitted;
            }
        }
        if direct {
            let t0 = Instant::now();
            let d = direct_light(scene, &gbuffer, s.direct_samples, s.seed);
            t.direct_ms = ms(t0);
            note(&mut non_finite, "direct light", count_non_finite(&d));
            for (o, d) in image.data.iter_mut().zip(&d.data) {
                *o += *d;
            }
        }
    }
    t.total_ms = ms(start) + gbuffer_ms;
    note(&mut non_finite, "the frame's sum", count_non_finite(&image));
    FrameOutput { image, gbuffer, timings: t, visibility, moved, stored, vpls: vpl_set, sampler_stats, indirect, non_finite, cancelled }
}

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
    /// ([`FrameRequest::cancel`]): the image lacks the stages not run.
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

/// The stages that make a frame's VPL light, each keeping its state from
/// frame to frame.
pub struct FrameStages<'a> {
    /// The VPL sampler.
    pub sampler: &'a mut dyn VplSampler,
    /// The visibility structure, updated with the sampler's set.
    pub visibility: &'a mut dyn VplVisibility,
    /// The indirect shader.
    pub shader: &'a mut dyn IndirectShader,
}

/// One frame asked of [`render_frame`]: the scene and camera, the settings,
/// and what a caller may bring ([`FrameRequest::new`] brings none of it).
#[derive(Clone, Debug)]
pub struct FrameRequest<'a> {
    /// The scene at this frame's time.
    pub scene: &'a Scene,
    /// The camera, at the image's resolution.
    pub camera: &'a Camera,
    /// Mode, depth, seed, index, time, compensation.
    pub settings: FrameSettings,
    /// The indirect image of the previous frame ([`FrameOutput::indirect`]),
    /// which samplers that adapt to the image (Russian-roulette acceptance)
    /// read.
    pub previous: Option<&'a Image>,
    /// A G-buffer rendered elsewhere (on a GPU) and the milliseconds it
    /// took; `None`: rendered here on the CPU.
    pub gbuffer: Option<(GBuffer, f64)>,
    /// Set from another thread (a Ctrl-C handler, a viewer's camera move),
    /// it stops the frame at the next stage boundary with
    /// [`FrameOutput::cancelled`] set. The boundaries are before the
    /// sampler, after the visibility update, after shading and after the
    /// bias compensation: the sampler's step and the visibility update it
    /// calls for run together or not at all, so that the visibility always
    /// matches the sampler's set. A frame that is not cancelled is the same,
    /// bit for bit, as one without a flag.
    pub cancel: Option<&'a AtomicBool>,
}

impl<'a> FrameRequest<'a> {
    /// Frame `settings` of `scene` seen by `camera`, with no previous
    /// image, the G-buffer rendered here and no cancel flag.
    pub fn new(scene: &'a Scene, camera: &'a Camera, settings: FrameSettings) -> FrameRequest<'a> {
        FrameRequest { scene, camera, settings, previous: None, gbuffer: None, cancel: None }
    }

    /// The same request with the previous frame's indirect image.
    pub fn previous(mut self, previous: Option<&'a Image>) -> FrameRequest<'a> {
        self.previous = previous;
        self
    }

    /// The same request with a G-buffer rendered elsewhere in `ms` milliseconds.
    pub fn gbuffer(mut self, gbuffer: GBuffer, ms: f64) -> FrameRequest<'a> {
        self.gbuffer = Some((gbuffer, ms));
        self
    }

    /// The same request, stopped at a stage boundary once `cancel` is set.
    pub fn cancel(mut self, cancel: &'a AtomicBool) -> FrameRequest<'a> {
        self.cancel = Some(cancel);
        self
    }
}

/// Renders one frame: the G-buffer (unless the request brings one); then,
/// when the mode and depth keep paths with ≥ 2 scattering vertices, the
/// sampler's VPLs, the visibility update, indirect shading and the clamp's
/// bias compensation if asked for; then directly seen emission (k = 0) and
/// direct light (k = 1) where the mode keeps them.
pub fn render_frame(request: FrameRequest<'_>, stages: FrameStages<'_>) -> FrameOutput {
    let FrameRequest { scene, camera, settings: s, previous, gbuffer, cancel } = request;
    let FrameStages { sampler, visibility: vis, shader } = stages;
    let (gbuffer, gbuffer_ms) = match gbuffer {
        Some(g) => g,
        None => {
            let t0 = Instant::now();
            let g = render_gbuffer(scene, camera);
            (g, ms(t0))
        }
    };
    let stop = || cancel.is_some_and(|c| c.load(Ordering::Relaxed));
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

//! The render thread: it owns one [`Renderer`] per side of the view (each
//! keeps its sampler's, visibility's and shader's state from frame to
//! frame), renders the frames the window asks for, and stops a frame at
//! its next stage boundary when the window asks for another (the camera
//! moved). The window never waits on it. While the camera stands still it
//! also accumulates a reference with the path tracer, a pass of one path
//! per pixel at a time, after each frame's sides.

use crate::view::temporal_change;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use std::time::{Duration, Instant};
use vpl_core::glam::Vec3;
use vpl_core::{Camera, Image, Mode, Params, Scene};
use vpl_pathtrace::{PathTracer, RenderSettings};
use vpl_render::{Backend, FrameOutput, PipelineSpec, ReadBack, RenderError, Renderer};
use vpl_sampling::Registry;

/// What a side renders with: a change rebuilds its renderer (and restarts
/// its sampler's state).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SideSpec {
    /// Registry name of the sampler.
    pub sampler: String,
    /// VPL budget I.
    pub vpls: usize,
    /// Which light paths the frame includes.
    pub mode: Mode,
    /// Render resolution: a new size is a new renderer, so no stage ever
    /// sees state kept for another size.
    pub resolution: (u32, u32),
}

/// A frame the window asks for.
pub struct Job {
    /// The scene at this frame (animated lights, a light moved by hand).
    pub scene: Arc<Scene>,
    /// The camera, at the render resolution.
    pub camera: Camera,
    /// Scene time in seconds.
    pub time: f32,
    /// One side, or two for a split view (the same camera and lights).
    pub sides: Vec<SideSpec>,
    /// Set by the window to stop this frame at its next stage boundary.
    pub cancel: Arc<AtomicBool>,
    /// Accumulate the reference after the sides.
    pub reference: Option<ReferenceSpec>,
    /// Leave GPU frames on the device (the window shows them from there,
    /// on the same device) instead of reading them back.
    pub resident: bool,
}

/// The reference a job asks for: the path tracer's estimate of what the
/// sides converge to, accumulated pass by pass while the camera, the lights
/// and the mode stay as they are (any change starts it afresh).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ReferenceSpec {
    /// Which light paths it includes (the sides' mode).
    pub mode: Mode,
    /// Longest path in segments (the VPL budget's, 5 by default).
    pub max_depth: u32,
    /// Passes run after the sides until this much time has gone (at least one).
    pub budget: Duration,
}

/// The reference accumulated so far.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Mean of the passes.
    pub image: Image,
    /// Passes of one path per pixel in the mean.
    pub passes: u32,
}

/// One side's frame.
#[derive(Clone)]
pub struct SideResult {
    /// What it was rendered with.
    pub spec: SideSpec,
    /// The side's whole pipeline, as a [`PipelineSpec`] reads it (the
    /// backend by the name of the one made).
    pub pipeline: String,
    /// The frame.
    pub out: FrameOutput,
    /// The camera it was rendered from.
    pub camera: Camera,
    /// Σ|ΔL|/ΣL against this side's previous frame (`None` on its first).
    pub change: Option<f64>,
    /// The side's frame number (its renderer's count).
    pub index: u64,
    /// The frame left on the device, when the job asked for resident frames
    /// and every stage of the frame ran there (`out.image` then holds no
    /// pixels, unless the job's reference needed them on the host).
    #[cfg(feature = "gpu")]
    pub device: Option<vpl_gpu::DeviceFrame>,
    /// The device `device` is on.
    #[cfg(feature = "gpu")]
    pub gpu: Option<vpl_gpu::Gpu>,
}

/// What the render thread answers.
pub enum Reply {
    /// Every side of the job, rendered.
    Frame {
        /// The sides, in the job's order.
        sides: Vec<SideResult>,
        /// The reference, when the job asked for one (an error line when a
        /// pass failed).
        reference: Option<Result<Reference, String>>,
    },
    /// The job was cancelled.
    Cancelled,
    /// A side could not be built or rendered (the side's sampler name, the
    /// error). The window shows it; the next job tries again.
    Failed(String),
}

/// Where the renderers run.
pub enum BackendChoice {
    /// A registered backend, made anew for each side by its entry.
    Entry(vpl_render::BackendEntry),
    /// vpl-gpu's backend on this device (shared by both sides and the
    /// window, which presents the frames they leave there).
    #[cfg(feature = "gpu")]
    Gpu(vpl_gpu::Gpu),
}

impl BackendChoice {
    /// A backend for one side, and where its frames left on the device appear.
    fn make(&self) -> Result<(Box<dyn Backend>, Published), String> {
        match self {
            BackendChoice::Entry(e) => Ok(((e.factory)().map_err(|e| e.to_string())?, Published::default())),
            #[cfg(feature = "gpu")]
            BackendChoice::Gpu(gpu) => {
                let backend = vpl_gpu::GpuBackend::new(gpu.clone());
                let frames = backend.frames();
                Ok((Box::new(backend), Published { gpu: Some((gpu.clone(), frames)) }))
            }
        }
    }
}

/// Where a side's GPU backend publishes the frames it leaves on the device.
#[derive(Default)]
struct Published {
    #[cfg(feature = "gpu")]
    gpu: Option<(vpl_gpu::Gpu, vpl_gpu::Frames)>,
}

/// A side's previous frame, for the frame-to-frame change.
enum Previous {
    Host(Image),
    #[cfg(feature = "gpu")]
    Device(vpl_gpu::DeviceFrame),
}

/// The path tracer's running sum, and what it is a sum for.
struct Accumulation {
    camera: Camera,
    scene: Arc<Scene>,
    spec: (Mode, u32),
    sum: Vec<Vec3>,
    passes: u32,
}

impl Accumulation {
    fn matches(&self, job: &Job, spec: &ReferenceSpec) -> bool {
        self.camera == job.camera && Arc::ptr_eq(&self.scene, &job.scene) && self.spec == (spec.mode, spec.max_depth)
    }
}

struct Side {
    spec: SideSpec,
    /// [`SideResult::pipeline`].
    pipeline: String,
    renderer: Renderer,
    index: u64,
    previous: Option<Previous>,
    // Read by the GPU path alone.
    #[cfg_attr(not(feature = "gpu"), allow(dead_code))]
    published: Published,
}

/// Runs jobs from `jobs` until the window hangs up; calls `wake` after each
/// reply so the window redraws.
pub fn run(
    jobs: Receiver<Job>,
    replies: Sender<Reply>,
    registry: Registry,
    backend: BackendChoice,
    pipeline: PipelineSpec,
    wake: impl Fn(),
) {
    let seed = pipeline.seed;
    let mut sides: Vec<Option<Side>> = Vec::new();
    let mut accumulation: Option<Accumulation> = None;
    // One reply per job: the window sends the next job when this one is answered.
    while let Ok(job) = jobs.recv() {
        // A panic in a stage must not leave the window waiting for a reply
        // that never comes: it is a failed frame, and the sides start afresh.
        let reply = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let frame = render_job(&job, &mut sides, &registry, &backend, &pipeline)?;
            let reference = job.reference.map(|spec| accumulate(&job, &spec, &mut accumulation, seed));
            Ok((frame, reference))
        }));
        let reply = match reply {
            Ok(Ok((sides, reference))) => Reply::Frame { sides, reference },
            Ok(Err(None)) => Reply::Cancelled,
            Ok(Err(Some(e))) => Reply::Failed(e),
            Err(panic) => {
                sides.clear();
                accumulation = None;
                let what = panic
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_default();
                Reply::Failed(format!("internal error in a render stage: {what}"))
            }
        };
        if replies.send(reply).is_err() {
            return;
        }
        wake();
    }
}

/// Runs reference passes for `job` until its budget is spent or it is
/// cancelled (a pass cut short is dropped), and answers the mean so far.
fn accumulate(job: &Job, spec: &ReferenceSpec, acc: &mut Option<Accumulation>, seed: u64) -> Result<Reference, String> {
    if acc.as_ref().is_none_or(|a| !a.matches(job, spec)) {
        let pixels = (job.camera.resolution.0 * job.camera.resolution.1) as usize;
        *acc = Some(Accumulation {
            camera: job.camera.clone(),
            scene: job.scene.clone(),
            spec: (spec.mode, spec.max_depth),
            sum: vec![Vec3::ZERO; pixels],
            passes: 0,
        });
    }
    let a = acc.as_mut().expect("made above");
    let pt = PathTracer::new(spec.max_depth, spec.mode);
    let start = Instant::now();
    loop {
        // Pass p draws the streams of frame p: the mean after n passes is
        // the same bits however the passes fell between frames.
        let settings = RenderSettings { spp: 1, seed, frame: a.passes as u64 };
        match vpl_pathtrace::render_cancellable(&job.scene, &job.camera, &pt, settings, &|_, _| {}, &job.cancel) {
            Ok(out) => {
                for (s, v) in a.sum.iter_mut().zip(&out.image.data) {
                    *s += *v;
                }
                a.passes += 1;
            }
            Err(vpl_pathtrace::RenderError::Cancelled) => break,
            Err(e) => {
                *acc = None;
                return Err(format!("reference: {e}"));
            }
        }
        if start.elapsed() >= spec.budget || job.cancel.load(Ordering::Relaxed) {
            break;
        }
    }
    let mut image = Image::new(job.camera.resolution.0, job.camera.resolution.1);
    let inv = 1.0 / a.passes.max(1) as f32;
    for (p, s) in image.data.iter_mut().zip(&a.sum) {
        *p = *s * inv;
    }
    Ok(Reference { image, passes: a.passes })
}

/// The frame `side` just left on the device, with its device; `None` when
/// the frame came back to the host.
#[cfg(feature = "gpu")]
fn frame_on_device(side: &Side, on_device: bool) -> Option<(vpl_gpu::Gpu, vpl_gpu::DeviceFrame)> {
    let (gpu, frames) = side.published.gpu.as_ref().filter(|_| on_device)?;
    frames.latest().map(|f| (gpu.clone(), f))
}

#[cfg(not(feature = "gpu"))]
fn frame_on_device(_: &Side, _: bool) -> Option<std::convert::Infallible> {
    None
}

/// The window composes a view on the device only when every side is
/// there: a side that is (a sampler that reads the previous image, say,
/// keeps its frame on the host) beside one that is not comes back.
#[cfg(feature = "gpu")]
fn bring_back_if_mixed(sides: &mut [SideResult]) -> Result<(), String> {
    if sides.iter().all(|s| s.device.is_some()) || sides.iter().all(|s| s.device.is_none()) {
        return Ok(());
    }
    for s in sides.iter_mut() {
        let Some(d) = s.device.take() else { continue };
        // The frames share the renderer's device; the read needs its context.
        let gpu = s.gpu.take().ok_or("a frame on the device without its device")?;
        let why = |e: vpl_gpu::GpuError| format!("{}: {e}", s.spec.sampler);
        s.out.image = d.read_image(gpu.ctx()).map_err(why)?;
        s.out.gbuffer = d.read_gbuffer(gpu.ctx()).map_err(why)?;
    }
    Ok(())
}

/// `Err(None)`: cancelled; `Err(Some(line))`: failed.
fn render_job(
    job: &Job,
    sides: &mut Vec<Option<Side>>,
    registry: &Registry,
    backend: &BackendChoice,
    pipeline: &PipelineSpec,
) -> Result<Vec<SideResult>, Option<String>> {
    sides.resize_with(job.sides.len().max(sides.len()), || None);
    let mut out = Vec::new();
    for (k, spec) in job.sides.iter().enumerate() {
        if job.cancel.load(Ordering::Relaxed) {
            return Err(None);
        }
        let slot = &mut sides[k];
        if slot.as_ref().is_none_or(|s| s.spec != *spec) {
            let (backend, published) = backend.make().map_err(|e| Some(format!("{}: {e}", spec.sampler)))?;
            // The pipeline with the panel's sampler, budget and light paths.
            let mut side = pipeline.clone();
            if side.sampler != spec.sampler {
                side.params = Params::default();
            }
            side.sampler = spec.sampler.clone();
            side.budget.vpls = spec.vpls;
            side.mode = spec.mode;
            side.backend = backend.name().to_string();
            let described = side.to_string();
            let renderer =
                side.builder(registry, &job.scene).boxed_backend(backend).build().map_err(|e| Some(format!("{}: {e}", spec.sampler)))?;
            *slot = Some(Side { spec: spec.clone(), pipeline: described, renderer, index: 0, previous: None, published });
        }
        let side = slot.as_mut().expect("built above");
        side.renderer.set_read_back(if job.resident { ReadBack::Nothing } else { ReadBack::All });
        let frame = side.renderer.render_cancellable(&job.scene, &job.camera, side.index, job.time, &job.cancel);
        let frame = match frame {
            Ok(f) => f,
            Err(RenderError::Cancelled { .. }) => return Err(None),
            Err(e) => {
                // A failed frame leaves no state worth keeping.
                *slot = None;
                return Err(Some(format!("{}: {e}", spec.sampler)));
            }
        };
        let on_device = !frame.image.on_host();
        let (change, previous, host_image) = match frame_on_device(side, on_device) {
            #[cfg(feature = "gpu")]
            Some((gpu, device)) => {
                let change = match &side.previous {
                    Some(Previous::Device(p)) => gpu.temporal_change(p, &device).map_err(|e| Some(format!("{}: {e}", spec.sampler)))?,
                    _ => None,
                };
                // The reference is compared on the host: its frames come back.
                let host = job.reference.and_then(|_| side.renderer.read_image());
                (change, Previous::Device(device), host)
            }
            _ => {
                let change = match &side.previous {
                    Some(Previous::Host(p)) => temporal_change(p, &frame.image),
                    _ => None,
                };
                (change, Previous::Host(frame.image.clone()), None)
            }
        };
        let frame = match host_image {
            Some(image) => FrameOutput { image, ..frame },
            None => frame,
        };
        #[cfg(feature = "gpu")]
        let (device, gpu) = match &previous {
            Previous::Device(d) => (Some(d.clone()), side.published.gpu.as_ref().map(|g| g.0.clone())),
            Previous::Host(_) => (None, None),
        };
        side.previous = Some(previous);
        out.push(SideResult {
            spec: spec.clone(),
            pipeline: side.pipeline.clone(),
            out: frame,
            camera: job.camera.clone(),
            change,
            index: side.index,
            #[cfg(feature = "gpu")]
            device,
            #[cfg(feature = "gpu")]
            gpu,
        });
        side.index += 1;
    }
    #[cfg(feature = "gpu")]
    bring_back_if_mixed(&mut out).map_err(Some)?;
    Ok(out)
}

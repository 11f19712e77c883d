//! The render thread: it owns one [`Renderer`] per side of the view (each
//! keeps its sampler's, visibility's and shader's state from frame to
//! frame), renders the frames the window asks for, and stops a frame at
//! its next stage boundary when the window asks for another (the camera
//! moved). The window never waits on it.

use crate::view::temporal_change;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender};
use vpl_core::{Camera, Image, Mode, Scene};
use vpl_render::{Backend, FrameOutput, RenderError, Renderer};
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
}

/// One side's frame.
pub struct SideResult {
    /// What it was rendered with.
    pub spec: SideSpec,
    /// The frame.
    pub out: FrameOutput,
    /// The camera it was rendered from.
    pub camera: Camera,
    /// Σ|ΔL|/ΣL against this side's previous frame (`None` on its first).
    pub change: Option<f64>,
    /// The side's frame number (its renderer's count).
    pub index: u64,
}

/// What the render thread answers.
pub enum Reply {
    /// Every side of the job, rendered.
    Frame {
        /// The sides, in the job's order.
        sides: Vec<SideResult>,
    },
    /// The job was cancelled.
    Cancelled,
    /// A side could not be built or rendered (the side's sampler name, the
    /// error). The window shows it; the next job tries again.
    Failed(String),
}

/// Where the renderers run.
pub enum BackendChoice {
    /// The CPU backend.
    Cpu,
    /// The GPU backend on this device (shared by both sides).
    #[cfg(feature = "gpu")]
    Gpu(vpl_gpu::Gpu),
}

impl BackendChoice {
    fn make(&self) -> Box<dyn Backend> {
        match self {
            BackendChoice::Cpu => Box::new(vpl_render::CpuBackend),
            #[cfg(feature = "gpu")]
            BackendChoice::Gpu(gpu) => Box::new(vpl_gpu::GpuBackend::new(gpu.clone())),
        }
    }
}

struct Side {
    spec: SideSpec,
    renderer: Renderer,
    index: u64,
    previous: Option<Image>,
}

/// Runs jobs from `jobs` until the window hangs up; calls `wake` after each
/// reply so the window redraws.
pub fn run(jobs: Receiver<Job>, replies: Sender<Reply>, registry: Registry, backend: BackendChoice, seed: u64, wake: impl Fn()) {
    let mut sides: Vec<Option<Side>> = Vec::new();
    // One reply per job: the window sends the next job when this one is answered.
    while let Ok(job) = jobs.recv() {
        // A panic in a stage must not leave the window waiting for a reply
        // that never comes: it is a failed frame, and the sides start afresh.
        let reply = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| render_job(&job, &mut sides, &registry, &backend, seed)));
        let reply = match reply {
            Ok(Ok(sides)) => Reply::Frame { sides },
            Ok(Err(None)) => Reply::Cancelled,
            Ok(Err(Some(e))) => Reply::Failed(e),
            Err(panic) => {
                sides.clear();
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

/// `Err(None)`: cancelled; `Err(Some(line))`: failed.
fn render_job(
    job: &Job,
    sides: &mut Vec<Option<Side>>,
    registry: &Registry,
    backend: &BackendChoice,
    seed: u64,
) -> Result<Vec<SideResult>, Option<String>> {
    sides.resize_with(job.sides.len().max(sides.len()), || None);
    let mut out = Vec::new();
    for (k, spec) in job.sides.iter().enumerate() {
        if job.cancel.load(Ordering::Relaxed) {
            return Err(None);
        }
        let slot = &mut sides[k];
        if slot.as_ref().is_none_or(|s| s.spec != *spec) {
            let renderer = Renderer::builder(&job.scene)
                .vpls(spec.vpls)
                .sampler(spec.sampler.as_str())
                .registry(registry)
                .mode(spec.mode)
                .seed(seed)
                .boxed_backend(backend.make())
                .build()
                .map_err(|e| Some(format!("{}: {e}", spec.sampler)))?;
            *slot = Some(Side { spec: spec.clone(), renderer, index: 0, previous: None });
        }
        let side = slot.as_mut().expect("built above");
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
        let change = side.previous.as_ref().and_then(|p| temporal_change(p, &frame.image));
        side.previous = Some(frame.image.clone());
        out.push(SideResult { spec: spec.clone(), out: frame, camera: job.camera.clone(), change, index: side.index });
        side.index += 1;
    }
    Ok(out)
}

//! `vpl.render_path`: the path-traced reference as NumPy arrays.

use crate::arrays::{image, vectors};
use crate::error::vpl_err;
use crate::interrupt::interruptible;
use crate::progress::Progress;
use crate::scene::PyScene;
use numpy::{PyArray2, PyArray3};
use pyo3::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use vpl_pathtrace::{Footprint, PathTracer, RenderSettings, TrackRequest, render_cancellable, track_cancellable};
use vpl_render::vpl_core::{MaterialPolicy, Mode};

/// An image and its per-pixel standard errors, (height, width, 3) each.
pub(crate) type ImageAndError<'py> = (Bound<'py, PyArray3<f32>>, Bound<'py, PyArray3<f32>>);

/// Means and standard errors of tracked pixels, (n, 3) each.
type MeansAndErrors<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<f32>>);

/// Reads a mode name.
pub(crate) fn mode(name: &str) -> PyResult<Mode> {
    name.parse::<Mode>().map_err(vpl_err)
}

/// Reads a material policy name.
pub(crate) fn policy(name: &str) -> PyResult<MaterialPolicy> {
    match name {
        "as-is" => Ok(MaterialPolicy::AsIs),
        "diffuse" => Ok(MaterialPolicy::Diffuse),
        _ => Err(vpl_err(format!("unknown materials '{name}' (as-is, diffuse)"))),
    }
}

/// Path-traces `scene` through its camera and returns `(image, stderr)`,
/// float32 arrays of shape (height, width, 3): each pixel's mean radiance
/// over `spp` paths (box filter) and the standard error of that mean.
///
/// `mode` is `"full"`, `"direct"` (emission and direct light) or
/// `"indirect"` (paths with two or more scattering vertices), `max_depth`
/// the longest path in segments (Mitsuba's convention), `size` (width,
/// height) overrides the camera's, `materials="diffuse"` draws every
/// material by its albedo as the VPL renderers do. The same arguments give
/// the same bits on any thread count, and as `vpl_pathtrace::render`. Releases the GIL; Ctrl-C stops it (raising KeyboardInterrupt);
/// `progress=True` shows a tqdm bar when tqdm is installed.
#[pyfunction]
#[pyo3(signature = (scene, spp = 64, mode = "full", max_depth = 5, size = None, seed = 0, materials = "as-is", progress = false))]
#[allow(clippy::too_many_arguments)] // the Python signature: keyword arguments with defaults
pub fn render_path<'py>(
    py: Python<'py>,
    scene: &PyScene,
    spp: u32,
    mode: &str,
    max_depth: u32,
    size: Option<(u32, u32)>,
    seed: u64,
    materials: &str,
    progress: bool,
) -> PyResult<ImageAndError<'py>> {
    if spp == 0 {
        return Err(vpl_err("spp must be at least 1"));
    }
    if max_depth == 0 {
        return Err(vpl_err("max_depth must be at least 1"));
    }
    let pt = PathTracer::new(max_depth, self::mode(mode)?);
    let camera = scene.camera_at(size)?;
    // The geometry is shared: the copy is of the materials and lights.
    let sc = &scene.scene.with_material_policy(policy(materials)?);
    let (w, h) = camera.resolution;
    let settings = RenderSettings { spp, seed, frame: scene.frame as u64 };
    let done = AtomicU64::new(0);
    let mut bar = Progress::new(py, progress, (w as u64) * (h as u64), "path tracing")?;
    let out = interruptible(
        py,
        |cancel| render_cancellable(sc, &camera, &pt, settings, &|d, _| _ = done.fetch_max(d, Ordering::Relaxed), cancel),
        |py| bar.update(py, done.load(Ordering::Relaxed)),
    )?;
    bar.close(py);
    let out = out.map_err(vpl_err)?;
    Ok((image(py, &out.image), image(py, &out.stderr)))
}

/// What `track` on the device takes: the scene (materials as asked), the
/// camera, the path tracer and the request.
type TrackJob<'a> = (&'a vpl_render::vpl_core::Scene, &'a vpl_render::vpl_core::Camera, &'a PathTracer, &'a TrackRequest<'a>);

/// `track(backend="gpu")`: the same estimator on the device
/// (`vpl_gpu::GpuTracker`, opened once a process), interruptible between
/// its submissions.
#[cfg(feature = "gpu")]
fn track_on_device<'py>(py: Python<'py>, (scene, camera, pt, request): TrackJob<'_>, progress: bool) -> PyResult<MeansAndErrors<'py>> {
    static TRACKER: std::sync::OnceLock<Result<vpl_gpu::GpuTracker, String>> = std::sync::OnceLock::new();
    let tracker =
        TRACKER.get_or_init(|| vpl_gpu::Gpu::new().map(vpl_gpu::GpuTracker::new).map_err(|e| e.to_string())).as_ref().map_err(vpl_err)?;
    let done = AtomicU64::new(0);
    let mut bar = Progress::new(py, progress, vpl_gpu::GpuTracker::chunks(request), "tracking on the GPU")?;
    let out = interruptible(
        py,
        |cancel| tracker.track_cancellable(scene, camera, pt, request, &|d, _| _ = done.fetch_max(d, Ordering::Relaxed), cancel),
        |py| bar.update(py, done.load(Ordering::Relaxed)),
    )?;
    bar.close(py);
    let out = out.map_err(|e| vpl_err(format!("backend gpu: {e}")))?;
    Ok((vectors(py, out.iter().map(|t| t.mean)), vectors(py, out.iter().map(|t| t.stderr))))
}

#[cfg(not(feature = "gpu"))]
fn track_on_device<'py>(_: Python<'py>, _: TrackJob<'_>, _: bool) -> PyResult<MeansAndErrors<'py>> {
    Err(vpl_err("backend gpu: this build of vpl has no GPU backend (build vpl-python with its default feature `gpu`)"))
}

/// Many paths through a few pixels (the papers' per-pixel ground truth):
/// `pixels` is a list of (x, y); returns `(mean, stderr)`, float32 arrays of
/// shape (n, 3). `footprint="box"` spreads the camera rays over each
/// pixel's square (as `render_path`); `"centre"` sends them through its
/// centre, the one point a VPL renderer's G-buffer shades. Deterministic
/// for any thread count. Releases the GIL; Ctrl-C stops it (each thread
/// ends its batch of 4096 paths) and raises KeyboardInterrupt;
/// `progress=True` shows a tqdm bar over the batches when tqdm is installed.
/// `backend="gpu"` samples on the GPU (`vpl_gpu::GpuTracker`: the same
/// estimator over other streams, diffuse materials only, so with
/// `materials="diffuse"` on scenes with layered ones); Ctrl-C stops it
/// between its submissions.
#[pyfunction]
#[pyo3(signature = (scene, pixels, spp = 4096, mode = "full", max_depth = 5, size = None, seed = 0, footprint = "box", materials = "as-is", progress = false, backend = "cpu"))]
#[allow(clippy::too_many_arguments)] // the Python signature: keyword arguments with defaults
pub fn track<'py>(
    py: Python<'py>,
    scene: &PyScene,
    pixels: Vec<(u32, u32)>,
    spp: u32,
    mode: &str,
    max_depth: u32,
    size: Option<(u32, u32)>,
    seed: u64,
    footprint: &str,
    materials: &str,
    progress: bool,
    backend: &str,
) -> PyResult<MeansAndErrors<'py>> {
    if spp == 0 || max_depth == 0 {
        return Err(vpl_err("spp and max_depth must be at least 1"));
    }
    let footprint = match footprint {
        "box" => Footprint::Box,
        "centre" | "center" => Footprint::Centre,
        other => return Err(vpl_err(format!("unknown footprint '{other}' (box, centre)"))),
    };
    let pt = PathTracer::new(max_depth, self::mode(mode)?);
    let camera = scene.camera_at(size)?;
    let (w, h) = camera.resolution;
    if let Some(&(x, y)) = pixels.iter().find(|&&(x, y)| x >= w || y >= h) {
        return Err(vpl_err(format!("pixel ({x}, {y}) lies outside the {w}x{h} image")));
    }
    let policy = policy(materials)?;
    let sc = scene.scene.with_material_policy(policy);
    let frame = scene.frame as u64;
    let request = TrackRequest { pixels: &pixels, spp, seed, frame, footprint };
    let done = AtomicU64::new(0);
    if backend == "gpu" {
        return track_on_device(py, (&sc, &camera, &pt, &request), progress);
    }
    if backend != "cpu" {
        return Err(vpl_err(format!("unknown backend '{backend}' (cpu, gpu)")));
    }
    let mut bar = Progress::new(py, progress, pixels.len() as u64 * spp.div_ceil(vpl_pathtrace::TRACK_BATCH) as u64, "tracking")?;
    let out = interruptible(
        py,
        |cancel| track_cancellable(&sc, &camera, &pt, &request, &|d, _| _ = done.fetch_max(d, Ordering::Relaxed), cancel),
        |py| bar.update(py, done.load(Ordering::Relaxed)),
    )?;
    bar.close(py);
    let out = out.map_err(vpl_err)?;
    Ok((vectors(py, out.iter().map(|t| t.mean)), vectors(py, out.iter().map(|t| t.stderr))))
}

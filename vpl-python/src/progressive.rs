//! `vpl.render_progressive`: the progressive point-light renderer
//! (Dammertz, Keller and Lensch 2010) from Python.

use crate::arrays::image;
use crate::error::vpl_err;
use crate::interrupt::interruptible;
use crate::pathtrace::ImageAndError;
use crate::progress::Progress;
use crate::scene::PyScene;
use pyo3::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use vpl_progressive::{Progressive, ProgressiveConfig};

/// Runs `passes` passes of the progressive renderer on `scene` (its
/// κ-layered materials: glass, mirrors, glossy coats and caustics) and
/// returns `(image, stderr)`, float32 (height, width, 3): the accumulation
/// buffer's mean and its per-pixel standard error over passes.
/// `vpl_paths` and `caustic_paths` are per pass (the paper's 16 and
/// 100,000). `gather="lightcuts:N"` gathers the VPLs at each eye vertex
/// by a stochastic lightcut of N (unbiased; for many `vpl_paths`) instead
/// of every VPL (`"exhaustive"`). Releases the GIL; Ctrl-C stops between passes (raising
/// KeyboardInterrupt); `progress=True` shows a tqdm bar over passes.
#[pyfunction]
#[pyo3(signature = (scene, passes = 64, size = None, max_depth = 5, vpl_paths = 16, caustic_paths = 100_000, gather = "exhaustive", seed = 0, progress = false))]
#[allow(clippy::too_many_arguments)] // the Python signature: keyword arguments with defaults
pub fn render_progressive<'py>(
    py: Python<'py>,
    scene: &PyScene,
    passes: u64,
    size: Option<(u32, u32)>,
    max_depth: u32,
    vpl_paths: usize,
    caustic_paths: usize,
    gather: &str,
    seed: u64,
    progress: bool,
) -> PyResult<ImageAndError<'py>> {
    if passes == 0 {
        return Err(vpl_err("passes must be at least 1"));
    }
    let camera = scene.camera_at(size)?;
    let gathering = gather.parse().map_err(vpl_err)?;
    let config = ProgressiveConfig { max_depth, vpl_paths, caustic_paths, gathering, seed, ..Default::default() };
    let sc = scene.scene.clone();
    let mut r = Progressive::new(&sc, camera, config).map_err(vpl_err)?;
    let done = AtomicU64::new(0);
    let mut bar = Progress::new(py, progress, passes, "passes")?;
    let cancelled = interruptible(
        py,
        |cancel| {
            for _ in 0..passes {
                if cancel.load(Ordering::Relaxed) {
                    return true;
                }
                r.pass();
                done.fetch_add(1, Ordering::Relaxed);
            }
            false
        },
        |py| bar.update(py, done.load(Ordering::Relaxed)),
    )?;
    bar.close(py);
    if cancelled {
        return Err(vpl_err("the render was cancelled"));
    }
    Ok((image(py, &r.image()), image(py, &r.stderr())))
}

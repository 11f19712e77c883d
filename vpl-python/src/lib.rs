//! # vpl-python
//!
//! The Python package `vpl`: the toolkit's scenes, path tracer, VPL samplers
//! and renderer from Python, with NumPy arrays, and VPL samplers written in
//! Python that plug into the same renderer. Built with PyO3 and maturin as
//! one abi3 wheel for CPython ≥ 3.9, on the library crates only
//! (`vpl-render`, `vpl-sampling`, `vpl-pathtrace`, `vpl-progressive`, and
//! `vpl-gpu` behind the default feature `gpu`).
//!
//! ```python
//! import vpl
//!
//! scene = vpl.Scene.load("cornell")
//! image, stderr = vpl.render_path(scene, spp=64, mode="indirect", size=(64, 64))
//! r = vpl.Renderer(scene, sampler="smc", vpls=1024, mode="indirect", size=(64, 64), m_max=16)
//! first = r.frame(0)
//! print(r.stats()["sampling_ms"], r.vpls()["flux"].sum(axis=0))
//! ```
//!
//! Install from a checkout with `pip install ./vpl-python` (or `maturin
//! develop -m vpl-python/Cargo.toml` in a virtual environment); the tests
//! are `pytest vpl-python/tests`. The Rust side is this crate's modules:
//! one per Python class or function family.

mod arrays;
mod error;
mod interrupt;
mod metrics;
mod pathtrace;
mod progress;
mod progressive;
mod renderer;
mod sampler;
mod scene;

use pyo3::prelude::*;

/// The registry's samplers: a list of dicts with `name`, `about` and
/// `keys` (each `key`, `default`, `about`).
#[pyfunction]
fn samplers(py: Python<'_>) -> PyResult<Vec<Bound<'_, pyo3::types::PyDict>>> {
    vpl_sampling::Registry::builtin()
        .entries()
        .iter()
        .map(|e| {
            let d = pyo3::types::PyDict::new(py);
            d.set_item("name", &e.name)?;
            d.set_item("about", &e.about)?;
            let keys = e
                .keys
                .iter()
                .map(|k| {
                    let kd = pyo3::types::PyDict::new(py);
                    kd.set_item("key", k.key)?;
                    kd.set_item("default", k.default)?;
                    kd.set_item("about", k.about)?;
                    Ok(kd)
                })
                .collect::<PyResult<Vec<_>>>()?;
            d.set_item("keys", keys)?;
            Ok(d)
        })
        .collect()
}

/// The SMC paper's eight tracked pixels of a `width`×`height` image, as
/// `vpl sequence` and Table 1 follow them: the centre, a point low in the
/// image, and six around the centre.
#[pyfunction]
fn default_tracked_pixels(width: u32, height: u32) -> PyResult<Vec<(u32, u32)>> {
    if width == 0 || height == 0 {
        return Err(error::vpl_err("the image must be at least 1x1"));
    }
    Ok(vpl_render::default_tracked_pixels(width, height))
}

/// The native module `vpl._vpl`; the package `vpl` re-exports it.
#[pymodule]
fn _vpl(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("VplError", m.py().get_type::<error::VplError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::PyScene>()?;
    m.add_class::<renderer::PyRenderer>()?;
    m.add_class::<sampler::FrameInfo>()?;
    m.add_function(wrap_pyfunction!(samplers, m)?)?;
    m.add_function(wrap_pyfunction!(pathtrace::render_path, m)?)?;
    m.add_function(wrap_pyfunction!(pathtrace::track, m)?)?;
    m.add_function(wrap_pyfunction!(progressive::render_progressive, m)?)?;
    m.add_function(wrap_pyfunction!(default_tracked_pixels, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::rel_mse, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::rmse, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::temporal_error, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::compare, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::tone_mapped_luminance, m)?)?;
    Ok(())
}

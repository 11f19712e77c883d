//! The toolkit's image metrics on NumPy arrays (`vpl-render`'s `metrics`
//! and `compare`).

use crate::arrays::{as_f32, read_image};
use crate::error::vpl_err;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArrayDyn, PyReadonlyArray2, PyReadonlyArrayDyn, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use vpl_render::vpl_core::glam::Vec3;

/// Relative MSE of `a` against `b`: the mean over pixels and channels of
/// (a − b)² / (b² + 0.01). Both float arrays of shape (height, width, 3).
#[pyfunction]
pub fn rel_mse(a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>) -> PyResult<f64> {
    vpl_render::metrics::rel_mse(&read_image(a, "a")?, &read_image(b, "b")?).map_err(vpl_err)
}

/// Root-mean-square error of `a` against `b` over pixels and channels.
#[pyfunction]
pub fn rmse(a: &Bound<'_, PyAny>, b: &Bound<'_, PyAny>) -> PyResult<f64> {
    vpl_render::metrics::rmse(&read_image(a, "a")?, &read_image(b, "b")?).map_err(vpl_err)
}

/// The SMC paper's |E| and |E′| (eq. 10) of `estimate` against `truth`,
/// arrays of shape (frames, pixels) of tone-mapped luminances over
/// consecutive frames: a dict of `e`, `e_prime`, `bias` (the mean signed
/// error), `count` and `count_prime`.
#[pyfunction]
pub fn temporal_error<'py>(
    py: Python<'py>,
    estimate: PyReadonlyArray2<'py, f64>,
    truth: PyReadonlyArray2<'py, f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let rows = |a: &PyReadonlyArray2<f64>| -> Vec<Vec<f64>> { a.as_array().rows().into_iter().map(|r| r.to_vec()).collect() };
    let t = vpl_render::metrics::temporal_error(&rows(&estimate), &rows(&truth)).map_err(vpl_err)?;
    let d = PyDict::new(py);
    d.set_item("e", t.e)?;
    d.set_item("e_prime", t.e_prime)?;
    d.set_item("bias", t.bias)?;
    d.set_item("count", t.count)?;
    d.set_item("count_prime", t.count_prime)?;
    Ok(d)
}

/// Per-pixel z-tests of image `a` (standard errors `a_se`) against `b`
/// (`b_se`) at level `alpha`: a dict of `pixels`, `pass_rate`, `alpha`,
/// `mean_a`, `mean_b`, `mean_z` and `mean_se` (per channel), `rel_mse`, and
/// `z`, the |z| image (largest channel) as float32 (height, width).
#[pyfunction]
#[pyo3(signature = (a, a_se, b, b_se, alpha = 0.01))]
pub fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    a_se: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    b_se: &Bound<'py, PyAny>,
    alpha: f64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(alpha > 0.0 && alpha < 1.0) {
        return Err(vpl_err(format!("alpha must lie in (0, 1), not {alpha}")));
    }
    let c = vpl_render::compare::compare(
        &read_image(a, "a")?,
        &read_image(a_se, "a_se")?,
        &read_image(b, "b")?,
        &read_image(b_se, "b_se")?,
        alpha,
    )
    .map_err(vpl_err)?;
    let d = PyDict::new(py);
    d.set_item("pixels", c.pixels)?;
    d.set_item("pass_rate", c.pass_rate)?;
    d.set_item("alpha", c.alpha)?;
    d.set_item("mean_a", c.mean_a)?;
    d.set_item("mean_b", c.mean_b)?;
    d.set_item("mean_z", c.mean_z)?;
    d.set_item("mean_se", c.mean_se)?;
    d.set_item("rel_mse", c.rel_mse)?;
    let (w, h) = (c.z_image.width as usize, c.z_image.height as usize);
    let z: Vec<f32> = c.z_image.data.iter().map(|p| p.max_element()).collect();
    d.set_item("z", Array2::from_shape_vec((h, w), z).map_err(vpl_err)?.into_pyarray(py))?;
    Ok(d)
}

/// Reinhard's L/(1 + L) of the luminance of RGB values (the SMC paper
/// measures |E| and |E′| after it): an array whose last axis is RGB (…, 3)
/// becomes float64 of shape (…).
#[pyfunction]
pub fn tone_mapped_luminance<'py>(py: Python<'py>, rgb: &Bound<'py, PyAny>) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let rgb: PyReadonlyArrayDyn<'py, f32> = as_f32(rgb, "rgb")?.extract()?;
    let shape = rgb.shape().to_vec();
    if shape.last() != Some(&3) {
        return Err(vpl_err(format!("rgb must have a last axis of 3, not shape {shape:?}")));
    }
    let view = rgb.as_array();
    let flat: Vec<f32> = view.iter().copied().collect();
    let out: Vec<f64> = flat.chunks_exact(3).map(|c| vpl_render::metrics::tone_mapped_luminance(Vec3::new(c[0], c[1], c[2]))).collect();
    let dims = numpy::ndarray::IxDyn(&shape[..shape.len() - 1]);
    Ok(numpy::ndarray::ArrayD::from_shape_vec(dims, out).map_err(vpl_err)?.into_pyarray(py))
}

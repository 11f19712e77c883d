//! NumPy arrays from and to the toolkit's images and vectors: each a single
//! copy in Rust into an array NumPy then owns, never a Python loop.

use crate::error::vpl_err;
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3, PyReadonlyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use vpl_render::vpl_core::Image;
use vpl_render::vpl_core::glam::Vec3;

/// An image as a `float32` array of shape (height, width, 3), row 0 at the top.
pub fn image<'py>(py: Python<'py>, img: &Image) -> Bound<'py, PyArray3<f32>> {
    let flat: Vec<f32> = img.data.iter().flat_map(|v| v.to_array()).collect();
    // The shape matches the data by construction (width × height pixels).
    Array3::from_shape_vec((img.height as usize, img.width as usize, 3), flat).unwrap_or_else(|_| Array3::zeros((0, 0, 3))).into_pyarray(py)
}

/// Vectors as a `float32` array of shape (n, 3).
pub fn vectors<'py>(py: Python<'py>, v: impl ExactSizeIterator<Item = Vec3>) -> Bound<'py, PyArray2<f32>> {
    let n = v.len();
    let flat: Vec<f32> = v.flat_map(|v| v.to_array()).collect();
    Array2::from_shape_vec((n, 3), flat).unwrap_or_else(|_| Array2::zeros((0, 3))).into_pyarray(py)
}

/// `value` as a C-contiguous float32 NumPy array (any array-like NumPy can
/// cast); `what` names the argument in the error.
pub fn as_f32<'py>(value: &Bound<'py, PyAny>, what: &str) -> PyResult<Bound<'py, PyAny>> {
    let np = value.py().import("numpy")?;
    np.call_method1("ascontiguousarray", (value, "float32")).map_err(|e| vpl_err(format!("{what}: {e}")))
}

/// An (n, 3) array of numbers (any float or int dtype NumPy can cast) as
/// vectors; `what` names the argument in the error.
pub fn read_vectors(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<Vec3>> {
    let arr = as_f32(value, what)?;
    let arr: PyReadonlyArray2<f32> =
        arr.extract().map_err(|_| vpl_err(format!("{what} must be an array of shape (n, 3), not of {} dimension(s)", ndim(&arr))))?;
    if arr.shape()[1] != 3 {
        return Err(vpl_err(format!("{what} must be an array of shape (n, 3), not {:?}", arr.shape())));
    }
    let view = arr.as_array();
    Ok(view.rows().into_iter().map(|r| Vec3::new(r[0], r[1], r[2])).collect())
}

fn ndim(a: &Bound<'_, PyAny>) -> usize {
    a.getattr("ndim").and_then(|n| n.extract()).unwrap_or(0)
}

/// Whether an (h, w, 3) array is readable as an image, and the image.
pub fn read_image(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Image> {
    let arr = as_f32(value, what)?;
    let arr: PyReadonlyArray3<f32> = arr
        .extract()
        .map_err(|_| vpl_err(format!("{what} must be an array of shape (height, width, 3), not of {} dimension(s)", ndim(&arr))))?;
    let s = arr.shape();
    if s[2] != 3 || s[0] == 0 || s[1] == 0 {
        return Err(vpl_err(format!("{what} must be an array of shape (height, width, 3), not {s:?}")));
    }
    let (h, w) = (s[0] as u32, s[1] as u32);
    let mut img = Image::new(w, h);
    let flat = arr.as_slice().map_err(vpl_err)?;
    for (px, c) in img.data.iter_mut().zip(flat.chunks_exact(3)) {
        *px = Vec3::new(c[0], c[1], c[2]);
    }
    Ok(img)
}

//! Samplers as the Python renderer holds them: any sampler wrapped so that
//! its last VPL set can be read out, and samplers written in Python.

use crate::arrays::read_vectors;
use crate::error::vpl_err;
use crate::scene::PyScene;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use std::sync::{Arc, Mutex, MutexGuard};
use vpl_render::vpl_core::rng::mix64;
use vpl_render::vpl_core::{Frame, Stats, Vpl, VplSampler, VplSet};

/// What the renderer and its sampler share across the GIL boundary: the
/// last frame's VPL set, the first error a Python sampler raised, and the
/// scene of the frame being rendered.
#[derive(Default)]
pub struct Shared {
    /// The set the sampler returned for the last frame.
    pub last: VplSet,
    /// The exception a Python sampler raised during the frame.
    pub error: Option<PyErr>,
    /// The frame's scene, handed to a Python sampler.
    pub scene: Option<Py<PyScene>>,
}

/// A handle on [`Shared`].
pub type Hooks = Arc<Mutex<Shared>>;

/// Locks the shared state (a poisoned lock still holds valid data: every
/// writer replaces whole fields).
pub fn lock(h: &Hooks) -> MutexGuard<'_, Shared> {
    h.lock().unwrap_or_else(|p| p.into_inner())
}

/// Any sampler, its last set kept in [`Shared::last`] for `Renderer.vpls()`.
pub struct Recorded {
    /// The sampler.
    pub inner: Box<dyn VplSampler>,
    /// Where its set is copied.
    pub hooks: Hooks,
}

impl VplSampler for Recorded {
    fn name(&self) -> &'static str {
        self.inner.name()
    }

    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        let set = self.inner.next_frame(frame);
        lock(&self.hooks).last.clone_from(set);
        set
    }

    fn stats(&self) -> Stats {
        self.inner.stats()
    }
}

/// What a Python sampler's `next_frame` receives.
#[pyclass(name = "FrameInfo", module = "vpl", frozen)]
pub struct FrameInfo {
    /// The frame index.
    #[pyo3(get)]
    index: u64,
    /// Seconds since the start of the animation.
    #[pyo3(get)]
    time: f32,
    /// The renderer's seed.
    #[pyo3(get)]
    seed: u64,
    /// The VPL budget I: at most this many VPLs, one per slot.
    #[pyo3(get)]
    vpls: usize,
    /// The scene at this frame (lights placed for it).
    #[pyo3(get)]
    scene: Option<Py<PyScene>>,
}

/// A sampler written in Python: an object whose `next_frame(frame)` returns
/// the frame's VPLs as `(positions, normals, fluxes)` or `(positions,
/// normals, fluxes, moved)`, arrays of shape (n, 3) with n at most the
/// budget and `moved` a bool array (n,), or a dict with the keys
/// `position`, `normal`, `flux` and optionally `moved`. Row i fills slot i;
/// slots past n are empty.
///
/// Without `moved`, a slot moves when its position or normal differs from
/// the last frame's, so a sampler that keeps its points and changes only
/// fluxes keeps every shadow map. With it, a slot marked moved holds a new
/// VPL (its shadow map is rebuilt even at the same place), and one marked
/// not moved must hold the same position and normal as in the last frame
/// (only its flux may change): a slot that moved unmarked is an error (a
/// slot that was empty holds a new VPL either way).
pub struct PythonSampler {
    obj: Py<PyAny>,
    set: VplSet,
    hooks: Hooks,
    /// Calls of `next_frame` so far.
    calls: u64,
}

impl PythonSampler {
    /// `obj` as a sampler for `vpls` slots; it must have `next_frame`.
    pub fn new(py: Python<'_>, obj: Py<PyAny>, vpls: usize, hooks: Hooks) -> PyResult<PythonSampler> {
        let callable = obj.bind(py).getattr("next_frame").map(|m| m.is_callable()).unwrap_or(false);
        if !callable {
            return Err(vpl_err("a Python sampler needs a method next_frame(frame) returning (positions, normals, fluxes)"));
        }
        Ok(PythonSampler { obj, set: VplSet::new(vpls), hooks, calls: 0 })
    }

    fn fill(&mut self, py: Python<'_>, frame: &Frame) -> PyResult<()> {
        let scene = lock(&self.hooks).scene.as_ref().map(|s| s.clone_ref(py));
        let info = FrameInfo { index: frame.index, time: frame.time, seed: frame.seed, vpls: self.set.len(), scene };
        let out = self.obj.bind(py).call_method1("next_frame", (info,))?;
        let (p, n, f, moved) = if let Ok(d) = out.cast::<PyDict>() {
            let get = |k: &str| d.get_item(k)?.ok_or_else(|| vpl_err(format!("next_frame's dict has no '{k}' (position, normal, flux)")));
            (get("position")?, get("normal")?, get("flux")?, d.get_item("moved")?)
        } else if let Ok(t) = out.cast::<PyTuple>()
            && (t.len() == 3 || t.len() == 4)
        {
            (t.get_item(0)?, t.get_item(1)?, t.get_item(2)?, if t.len() == 4 { Some(t.get_item(3)?) } else { None })
        } else {
            return Err(vpl_err(
                "next_frame must return (positions, normals, fluxes[, moved]) or a dict with position, normal, flux[, moved]",
            ));
        };
        let moved: Option<Vec<bool>> = match moved {
            Some(m) if !m.is_none() => {
                let np = m.py().import("numpy")?;
                let arr = np.call_method1("ascontiguousarray", (m, "bool"))?;
                let arr: numpy::PyReadonlyArray1<bool> = arr.extract().map_err(|_| vpl_err("moved must be a bool array of shape (n,)"))?;
                Some(arr.as_array().to_vec())
            }
            _ => None,
        };
        let (p, n, f) = (read_vectors(&p, "positions")?, read_vectors(&n, "normals")?, read_vectors(&f, "fluxes")?);
        if p.len() != n.len() || p.len() != f.len() {
            return Err(vpl_err(format!("next_frame returned {} positions, {} normals and {} fluxes", p.len(), n.len(), f.len())));
        }
        if p.len() > self.set.len() {
            return Err(vpl_err(format!("next_frame returned {} VPLs for a budget of {}", p.len(), self.set.len())));
        }
        if let Some(m) = &moved
            && m.len() != p.len()
        {
            return Err(vpl_err(format!("next_frame returned {} VPLs and {} moved flags", p.len(), m.len())));
        }
        let mut vpls = Vec::with_capacity(p.len());
        for (i, ((y, n), flux)) in p.iter().zip(&n).zip(&f).enumerate() {
            let unit = n.normalize_or_zero();
            if !(y.is_finite() && flux.is_finite()) || unit == vpl_render::vpl_core::glam::Vec3::ZERO {
                return Err(vpl_err(format!("VPL {i}: position {y}, normal {n} and flux {flux} must be finite, with a nonzero normal")));
            }
            let previous = self.set.get(i).copied();
            // A VPL's id names it: the slot's own while it stays, a fresh one
            // (from the call and the slot, above every slot number) when the
            // sampler says it moved.
            let id = match moved.as_ref().map(|m| m[i]) {
                None => i as u64,
                Some(true) => mix64(mix64(self.calls) ^ i as u64) | 1 << 63,
                Some(false) => match previous {
                    Some(v) if v.y == *y && v.n == unit => v.id,
                    // A slot that was empty holds a new VPL whatever it says.
                    None => i as u64,
                    Some(_) => return Err(vpl_err(format!("VPL {i} is marked not moved, but its slot held another position or normal"))),
                },
            };
            vpls.push(Vpl { y: *y, n: unit, flux: *flux, id, bounce: 0 });
        }
        for (i, v) in vpls.into_iter().enumerate() {
            self.set.set(i, Some(v));
        }
        for slot in p.len()..self.set.len() {
            self.set.set(slot, None);
        }
        Ok(())
    }
}

impl VplSampler for PythonSampler {
    fn name(&self) -> &'static str {
        "python"
    }

    fn next_frame(&mut self, frame: &Frame) -> &VplSet {
        self.set.begin_frame();
        self.calls += 1;
        let result = Python::attach(|py| self.fill(py, frame));
        if let Err(e) = result {
            // The frame goes on without VPLs; the renderer raises the error.
            for slot in 0..self.set.len() {
                self.set.set(slot, None);
            }
            let mut h = lock(&self.hooks);
            if h.error.is_none() {
                h.error = Some(e);
            }
        }
        &self.set
    }

    fn stats(&self) -> Stats {
        Stats::new().count("stored", self.set.stored()).count("moved", self.set.moved_count())
    }
}

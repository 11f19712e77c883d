//! `vpl.Renderer`: the VPL renderer of `vpl-render`, frame after frame.

use crate::arrays::{image as to_array, vectors};
use crate::error::vpl_err;
use crate::interrupt::interruptible;
use crate::sampler::{Hooks, PythonSampler, Recorded, lock};
use crate::scene::PyScene;
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::sync::{Arc, Mutex};
use vpl_render::vpl_core::{Budget, GeometryClamp, Params, Stat, VplSampler};
use vpl_render::{Backend, Backends, Clamp, FrameOutput, ReadBack, Registry, Renderer, ShadingSpec, VisibilitySpec};

/// What the last frame left besides its image.
struct Last {
    out: FrameOutput,
    frame: u64,
}

struct State {
    renderer: Renderer,
    last: Option<Last>,
}

/// A VPL renderer over one scene: a sampler (a registry name, or an object
/// with `next_frame` written in Python), a visibility structure and a
/// shader, on the CPU or the GPU backend. Each `frame(i)` renders frame i of
/// the scene's animation; the sampler, shadow maps and shader keep their
/// state from one frame to the next.
#[pyclass(name = "Renderer", module = "vpl", frozen)]
pub struct PyRenderer {
    scene: Py<PyScene>,
    size: Option<(u32, u32)>,
    state: Mutex<State>,
    hooks: Hooks,
    sampler: String,
    backend: String,
}

/// The clamp as vpl-render spells it (`auto`, `scene-area`, `off`), or
/// G_max as a number.
fn parse_clamp(value: &Bound<'_, PyAny>) -> PyResult<Clamp> {
    if let Ok(s) = value.cast::<PyString>() {
        return s.to_cow()?.parse::<Clamp>().map_err(vpl_err);
    }
    let g: f32 = value.extract().map_err(|_| vpl_err("clamp must be 'auto', 'scene-area', 'off' or G_max as a number"))?;
    if !(g.is_finite() && g > 0.0) {
        return Err(vpl_err(format!("the clamp's G_max must be positive and finite, not {g}")));
    }
    Ok(Clamp::Value(GeometryClamp::new(g)))
}

/// `image` as an array: its pixels where they are on the host, else the
/// frame's image read back from the device on request.
fn host_or_read<'py>(py: Python<'py>, renderer: &Renderer, image: &vpl_render::vpl_core::Image) -> Option<Bound<'py, PyArray3<f32>>> {
    if image.on_host() { Some(to_array(py, image)) } else { renderer.read_image().map(|i| to_array(py, &i)) }
}

fn backend_named(name: &str) -> PyResult<Box<dyn Backend>> {
    let mut backends = Backends::builtin();
    #[cfg(feature = "gpu")]
    vpl_gpu::register(&mut backends);
    #[cfg(not(feature = "gpu"))]
    backends.absent("gpu", "built without the `gpu` feature");
    backends.instantiate(name).map_err(vpl_err)
}

/// A sampler parameter's value as the toolkit's `key=value` text.
fn param_text(v: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(b) = v.extract::<bool>() {
        return Ok(b.to_string());
    }
    Ok(v.str()?.to_string())
}

#[pymethods]
impl PyRenderer {
    /// Builds a renderer; keyword arguments it does not name are the
    /// sampler's parameters (`m_max=16` or `**{"m-max": 16}`: underscores
    /// read as dashes), and one the sampler does not read is an error.
    /// `shading` is spelled as on the command line: `interleaved`,
    /// `exhaustive`, `lightcuts` or `lightcuts:N` (N VPLs a pixel through a
    /// light tree), `culled` or `culled:X` (stochastic light culling);
    /// `backend` is `cpu`, `gpu` (where built) or `auto`.
    #[new]
    #[pyo3(signature = (
        scene, sampler = None, vpls = 2048, visibility = "shadowmap", shadow_map = 128, shading = "interleaved",
        filter = true, backend = "cpu", mode = "full", max_depth = 5, clamp = None, compensation = 0,
        direct_samples = 16, seed = 0, size = None, **params
    ))]
    #[allow(clippy::too_many_arguments)] // the Python signature: keyword arguments with defaults
    fn new(
        py: Python<'_>,
        scene: Py<PyScene>,
        sampler: Option<&Bound<'_, PyAny>>,
        vpls: usize,
        visibility: &str,
        shadow_map: u32,
        shading: &str,
        filter: bool,
        backend: &str,
        mode: &str,
        max_depth: u32,
        clamp: Option<&Bound<'_, PyAny>>,
        compensation: u32,
        direct_samples: u32,
        seed: u64,
        size: Option<(u32, u32)>,
        params: Option<&Bound<'_, PyDict>>,
    ) -> PyResult<PyRenderer> {
        // Spelled as vpl-render spells them; `shadow_map` and `filter` set
        // what a bare `shadowmap` and `interleaved` leave to them.
        let visibility = match visibility.parse::<VisibilitySpec>().map_err(vpl_err)? {
            VisibilitySpec::ShadowMaps(_) if !visibility.contains(':') => {
                if shadow_map == 0 {
                    return Err(vpl_err("shadow_map must be at least 1 texel"));
                }
                VisibilitySpec::ShadowMaps(shadow_map)
            }
            v => v,
        };
        let shading = match shading.parse::<ShadingSpec>().map_err(vpl_err)? {
            ShadingSpec::Interleaved { filter: true } => ShadingSpec::Interleaved { filter },
            s => s,
        };
        let clamp = match clamp {
            Some(c) => parse_clamp(c)?,
            None => Clamp::Auto,
        };
        let mut p = Params::new();
        if let Some(d) = params {
            for (k, v) in d.iter() {
                let key: String = k.extract()?;
                p.insert(&key.replace('_', "-"), param_text(&v)?).map_err(vpl_err)?;
            }
        }
        let mode = crate::pathtrace::mode(mode)?;
        let budget = Budget { vpls, max_depth };
        if vpls == 0 {
            return Err(vpl_err("the VPL budget must be at least 1"));
        }
        let backend = backend_named(backend)?;
        let backend_name = backend.name().to_string();
        let hooks: Hooks = Arc::new(Mutex::new(Default::default()));
        let (inner, name): (Box<dyn VplSampler>, String) = match sampler {
            None => (Registry::builtin().build("smc", budget, &backend.services(), &p).map_err(vpl_err)?, "smc".into()),
            Some(s) if s.is_instance_of::<PyString>() => {
                let name: String = s.extract()?;
                (Registry::builtin().build(&name, budget, &backend.services(), &p).map_err(vpl_err)?, name)
            }
            Some(obj) => {
                if !p.unused().is_empty() {
                    let keys: Vec<&str> = p.unused();
                    return Err(vpl_err(format!("a Python sampler reads no parameters, got {}", keys.join(", "))));
                }
                let name = obj.get_type().name().map(|n| n.to_string()).unwrap_or_else(|_| "python".into());
                (Box::new(PythonSampler::new(py, obj.clone().unbind(), vpls, hooks.clone())?), name)
            }
        };
        let sc = scene.borrow(py);
        let renderer = Renderer::builder(&sc.scene)
            .budget(budget)
            .sampler(Box::new(Recorded { inner, hooks: hooks.clone() }) as Box<dyn VplSampler>)
            .visibility(visibility)
            .shader(shading)
            .clamp(clamp)
            .compensation(compensation)
            .mode(mode)
            .direct_samples(direct_samples)
            .seed(seed)
            .boxed_backend(backend)
            .build()
            .map_err(vpl_err)?;
        drop(sc);
        Ok(PyRenderer { scene, size, state: Mutex::new(State { renderer, last: None }), hooks, sampler: name, backend: backend_name })
    }

    /// Renders frame `index` (the scene's animation at that frame; a scene
    /// without one stays as it is, frames 1/30 s apart) and returns its
    /// image, float32 (height, width, 3). With `image=False` it returns
    /// None, and on the GPU backend an indirect frame stays on the device
    /// (neither its G-buffer nor its image is read back) until `image()` or
    /// `indirect()` asks for it. Releases the GIL; Ctrl-C stops
    /// the frame at its next stage boundary (before the sampler, after the
    /// visibility update, after shading) and raises KeyboardInterrupt. An
    /// interrupted frame may have advanced the sampler (and the visibility
    /// with it); the next frame renders on from there.
    #[pyo3(signature = (index, image = true))]
    fn frame<'py>(&self, py: Python<'py>, index: u32, image: bool) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        let base = self.scene.get();
        let count = base.setup.sequence.as_ref().map_or(1, |s| s.frame_count());
        let at = if base.setup.sequence.is_some() {
            if index >= count {
                return Err(vpl_err(format!("frame {index} is past the animation's last frame ({})", count - 1)));
            }
            Py::new(py, PyScene::at_frame(base.setup.clone(), index)?)?
        } else {
            self.scene.clone_ref(py)
        };
        let time = match &base.setup.sequence {
            Some(s) => s.time(index),
            None => index as f32 / 30.0,
        };
        let scene = at.get().scene.clone();
        let camera = at.get().camera_at(self.size)?;
        lock(&self.hooks).scene = Some(at);
        let mut state =
            self.state.try_lock().map_err(|_| vpl_err("the renderer is busy (next_frame may not render with its own renderer)"))?;
        let renderer = &mut state.renderer;
        // On the GPU the G-buffer stays on the device either way; the image
        // comes back only when asked for.
        renderer.set_read_back(if image { ReadBack::Image } else { ReadBack::Nothing });
        let result = interruptible(py, |cancel| renderer.render_cancellable(&scene, &camera, index as u64, time, cancel), |_| {})?;
        let raised = lock(&self.hooks).error.take();
        if let Some(e) = raised {
            return Err(e);
        }
        let out = result.map_err(vpl_err)?;
        let img = image.then(|| to_array(py, &out.image));
        state.last = Some(Last { out, frame: index as u64 });
        Ok(img)
    }

    /// The last frame's image, float32 (height, width, 3), read back from
    /// the device when the frame left it there (`frame(i, image=False)`);
    /// None before the first frame.
    fn image<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        let state = self.state.try_lock().map_err(|_| vpl_err("the renderer is busy"))?;
        Ok(state.last.as_ref().and_then(|l| host_or_read(py, &state.renderer, &l.out.image)))
    }

    /// The VPLs of the last frame as a NumPy structured array, one row per
    /// occupied slot: `position`, `normal`, `flux` (3 float32 each), `slot`
    /// (uint32), `moved` (bool: the slot holds another VPL than the frame
    /// before), `id` (uint64) and `bounce` (uint32).
    fn vpls<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let h = lock(&self.hooks);
        let set = &h.last;
        let rows: Vec<(usize, vpl_render::vpl_core::Vpl)> = set.iter().map(|(s, v)| (s, *v)).collect();
        let moved: Vec<bool> = rows.iter().map(|(s, _)| set.moved(*s)).collect();
        drop(h);
        let np = py.import("numpy")?;
        let dtype = [
            ("position", "<f4", 3usize),
            ("normal", "<f4", 3),
            ("flux", "<f4", 3),
            ("slot", "<u4", 1),
            ("moved", "?", 1),
            ("id", "<u8", 1),
            ("bounce", "<u4", 1),
        ];
        let fields: Vec<Bound<'_, PyAny>> =
            dtype
                .iter()
                .map(|(n, t, k)| {
                    if *k == 1 {
                        (n, t).into_pyobject(py).map(|o| o.into_any())
                    } else {
                        (n, t, *k).into_pyobject(py).map(|o| o.into_any())
                    }
                })
                .collect::<PyResult<_>>()?;
        let arr = np.call_method1("zeros", (rows.len(), fields))?;
        arr.set_item("position", vectors(py, rows.iter().map(|r| r.1.y)))?;
        arr.set_item("normal", vectors(py, rows.iter().map(|r| r.1.n)))?;
        arr.set_item("flux", vectors(py, rows.iter().map(|r| r.1.flux)))?;
        arr.set_item("slot", rows.iter().map(|r| r.0 as u32).collect::<Vec<_>>().into_pyarray(py))?;
        arr.set_item("moved", moved.into_pyarray(py))?;
        arr.set_item("id", rows.iter().map(|r| r.1.id).collect::<Vec<_>>().into_pyarray(py))?;
        arr.set_item("bounce", rows.iter().map(|r| r.1.bounce).collect::<Vec<_>>().into_pyarray(py))?;
        Ok(arr)
    }

    /// What the last frame measured: milliseconds per stage (`gbuffer_ms`,
    /// `sampling_ms`, `visibility_ms`, `shading_ms`, `compensation_ms`,
    /// `direct_ms`, `total_ms`), `frame`, `stored` and `moved` VPLs, shadow
    /// maps `rebuilt` and the visibility structure's `memory_bytes`, and
    /// `sampler`, a dict of the sampler's typed statistics. Empty before
    /// the first frame.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let state = self.state.try_lock().map_err(|_| vpl_err("the renderer is busy"))?;
        let Some(last) = &state.last else { return Ok(d) };
        let (o, t) = (&last.out, &last.out.timings);
        for (k, v) in [
            ("gbuffer_ms", t.gbuffer_ms),
            ("sampling_ms", t.sampling_ms),
            ("visibility_ms", t.visibility_ms),
            ("shading_ms", t.shading_ms),
            ("compensation_ms", t.compensation_ms),
            ("direct_ms", t.direct_ms),
            ("total_ms", t.total_ms),
        ] {
            d.set_item(k, v)?;
        }
        d.set_item("frame", last.frame)?;
        d.set_item("stored", o.stored)?;
        d.set_item("moved", o.moved)?;
        d.set_item("rebuilt", o.visibility.rebuilt)?;
        d.set_item("memory_bytes", o.visibility.memory_bytes)?;
        let s = PyDict::new(py);
        for (k, v) in o.sampler_stats.iter() {
            match v {
                Stat::Count(n) => s.set_item(k, n)?,
                Stat::Value(x) | Stat::Ms(x) => s.set_item(k, x)?,
            }
        }
        d.set_item("sampler", s)?;
        Ok(d)
    }

    /// The last frame's indirect light alone (what the VPLs gave), float32
    /// (height, width, 3), or None before a frame or in `direct` mode.
    fn indirect<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray3<f32>>>> {
        let state = self.state.try_lock().map_err(|_| vpl_err("the renderer is busy"))?;
        Ok(state.last.as_ref().and_then(|l| l.out.indirect.as_ref()).and_then(|i| match i.on_host() {
            true => Some(to_array(py, i)),
            // Left on the device: its indirect light alone is read back.
            false => state.renderer.read_indirect().map(|i| to_array(py, &i)),
        }))
    }

    /// The sampler's name (a registry name, or the Python sampler's class).
    #[getter]
    fn sampler(&self) -> String {
        self.sampler.clone()
    }

    /// The backend the stages run on (`cpu`, `gpu`; the one `auto` opened).
    #[getter]
    fn backend(&self) -> String {
        self.backend.clone()
    }

    /// The adapter of the GPU backend, None on the CPU.
    #[getter]
    fn device(&self) -> PyResult<Option<String>> {
        let state = self.state.try_lock().map_err(|_| vpl_err("the renderer is busy"))?;
        Ok(state.renderer.backend().device())
    }

    /// The VPL budget I.
    #[getter]
    fn vpls_budget(&self) -> PyResult<usize> {
        let state = self.state.try_lock().map_err(|_| vpl_err("the renderer is busy"))?;
        Ok(state.renderer.budget().vpls)
    }

    fn __repr__(&self) -> String {
        format!("Renderer(sampler='{}', backend='{}')", self.sampler, self.backend)
    }
}

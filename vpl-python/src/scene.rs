//! `vpl.Scene`: a scene as the toolkit loads it, at one frame of its
//! animation.

use crate::arrays::vectors;
use crate::error::vpl_err;
use crate::interrupt::interruptible;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray1, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use rayon::prelude::*;
use std::sync::Arc;
use vpl_pathtrace::PathRadiosity;
use vpl_render::vpl_core::distribution::Distribution1D;
use vpl_render::vpl_core::glam::Vec3;
use vpl_render::vpl_core::rng::mix64;
use vpl_render::vpl_core::sampling::uniform_triangle;
use vpl_render::vpl_core::{Camera, Light, Purpose, RadiosityEstimator, Scene, SceneSetup, SurfacePoint, stream};

/// The stream purpose of [`PyScene::sample_area`]'s points (index = point).
const AREA_SAMPLES: Purpose = Purpose(1100);

/// A scene at one frame: its geometry, materials, lights placed for the
/// frame, and camera.
///
/// `Scene.load(spec)` reads a built-in name (`"cornell"`, `"office"`, …), a
/// scene TOML, an OBJ, a glTF 2.0 (`.gltf`, `.glb`) or a Mitsuba 3 XML file;
/// `scene.at(frame)` is the same scene at another frame of its animation.
#[pyclass(name = "Scene", module = "vpl", frozen)]
pub struct PyScene {
    pub(crate) setup: Arc<SceneSetup>,
    pub(crate) frame: u32,
    pub(crate) scene: Arc<Scene>,
    pub(crate) camera: Camera,
}

impl PyScene {
    /// The scene of `setup` at `frame`.
    pub(crate) fn at_frame(setup: Arc<SceneSetup>, frame: u32) -> PyResult<PyScene> {
        let count = frame_count(&setup);
        if frame >= count {
            return Err(vpl_err(format!("frame {frame} is past the scene's last frame ({})", count - 1)));
        }
        let (scene, camera) = setup.frame(frame).map_err(vpl_err)?;
        Ok(PyScene { setup, frame, scene: Arc::new(scene), camera })
    }

    /// The camera at `size` (width, height), or the scene's own.
    pub(crate) fn camera_at(&self, size: Option<(u32, u32)>) -> PyResult<Camera> {
        match size {
            Some(s) => self.camera.with_resolution(s).map_err(vpl_err),
            None => Ok(self.camera.clone()),
        }
    }
}

fn frame_count(setup: &SceneSetup) -> u32 {
    setup.sequence.as_ref().map_or(1, |s| s.frame_count())
}

fn vec3(v: Vec3) -> [f32; 3] {
    v.to_array()
}

#[pymethods]
impl PyScene {
    /// Loads a built-in scene by name or a scene file (`.toml`, `.obj`,
    /// `.gltf`, `.glb`, `.xml`); raises `VplError` with the loader's message.
    /// The files a scene file names must lie in its folder, or under one of
    /// the folders in `allow_outside`.
    #[staticmethod]
    #[pyo3(signature = (spec, allow_outside = Vec::new()))]
    fn load(py: Python<'_>, spec: &str, allow_outside: Vec<std::path::PathBuf>) -> PyResult<PyScene> {
        let spec = spec.to_string();
        let options = vpl_scene_io::LoadOptions { allow_outside, memory_limit: None };
        let setup = py.detach(move || vpl_scene_io::load_with(&spec, &options)).map_err(vpl_err)?;
        PyScene::at_frame(Arc::new(setup), 0)
    }

    /// The names of the built-in scenes.
    #[staticmethod]
    fn builtins() -> Vec<&'static str> {
        vpl_render::vpl_core::builtin::NAMES.to_vec()
    }

    /// The same scene at frame `frame` of its animation (lights and camera
    /// moved; frame 0 is the scene as loaded).
    fn at(&self, frame: u32) -> PyResult<PyScene> {
        PyScene::at_frame(self.setup.clone(), frame)
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The frame this scene is at.
    #[getter]
    fn frame(&self) -> u32 {
        self.frame
    }

    /// Frames of the animation (1 without one).
    #[getter]
    fn frame_count(&self) -> u32 {
        frame_count(&self.setup)
    }

    /// Frames per second of the animation (`None` without one).
    #[getter]
    fn fps(&self) -> Option<f32> {
        self.setup.sequence.as_ref().map(|s| s.fps)
    }

    /// Seconds from the start of the animation to this frame.
    #[getter]
    fn time(&self) -> f32 {
        self.setup.sequence.as_ref().map_or(0.0, |s| s.time(self.frame))
    }

    /// Triangles of nonzero area.
    #[getter]
    fn triangles(&self) -> usize {
        self.scene.geometry.triangles.len()
    }

    /// Total surface area, m² (one side).
    #[getter]
    fn surface_area(&self) -> f32 {
        self.scene.surface_area()
    }

    /// Whether diffuse surfaces reflect on both sides.
    #[getter]
    fn two_sided(&self) -> bool {
        self.scene.two_sided
    }

    /// The bounding box, as ((x, y, z) min, (x, y, z) max).
    #[getter]
    fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let (lo, hi) = self.scene.geometry.bounds;
        (vec3(lo), vec3(hi))
    }

    /// What loading noticed (a missing material library, skipped triangles, …).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.setup.warnings.clone()
    }

    /// The lights, each a dict with its `type` (`area`, `point`, `spot`,
    /// `directional`, `environment`) and its values.
    #[getter]
    fn lights<'py>(&self, py: Python<'py>) -> PyResult<Vec<Bound<'py, PyDict>>> {
        self.scene
            .lights
            .iter()
            .map(|l| {
                let d = PyDict::new(py);
                match l {
                    Light::Area { triangle, radiance } => {
                        d.set_item("type", "area")?;
                        d.set_item("triangle", triangle)?;
                        d.set_item("radiance", vec3(*radiance))?;
                    }
                    Light::Point { position, intensity } => {
                        d.set_item("type", "point")?;
                        d.set_item("position", vec3(*position))?;
                        d.set_item("intensity", vec3(*intensity))?;
                    }
                    Light::Spot { position, direction, intensity, cos_falloff_start, cos_total } => {
                        d.set_item("type", "spot")?;
                        d.set_item("position", vec3(*position))?;
                        d.set_item("direction", vec3(*direction))?;
                        d.set_item("intensity", vec3(*intensity))?;
                        d.set_item("angle", cos_total.clamp(-1.0, 1.0).acos().to_degrees())?;
                        d.set_item("falloff_start", cos_falloff_start.clamp(-1.0, 1.0).acos().to_degrees())?;
                    }
                    Light::Directional { direction, irradiance } => {
                        d.set_item("type", "directional")?;
                        d.set_item("direction", vec3(*direction))?;
                        d.set_item("irradiance", vec3(*irradiance))?;
                    }
                    Light::Environment { sky } => {
                        d.set_item("type", "environment")?;
                        d.set_item("radiance", vec3(sky.zenith))?;
                        d.set_item("horizon", vec3(sky.horizon))?;
                        d.set_item("ground", vec3(sky.nadir))?;
                    }
                }
                Ok(d)
            })
            .collect()
    }

    /// The camera of this frame: a dict of `origin`, `target`, `up`, `fov`
    /// (degrees), `fov_axis`, `resolution` (width, height), `lens_radius`
    /// and `focus_distance`.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.camera;
        let d = PyDict::new(py);
        d.set_item("origin", vec3(c.origin))?;
        d.set_item("target", vec3(c.target))?;
        d.set_item("up", vec3(c.up))?;
        d.set_item("fov", c.fov_deg)?;
        d.set_item("fov_axis", format!("{:?}", c.fov_axis).to_lowercase())?;
        d.set_item("resolution", c.resolution)?;
        d.set_item("lens_radius", c.lens_radius)?;
        d.set_item("focus_distance", c.focus_distance)?;
        Ok(d)
    }

    /// The image size of the scene's camera, (width, height).
    #[getter]
    fn resolution(&self) -> (u32, u32) {
        self.camera.resolution
    }

    /// `n` points uniform by area over the surfaces (density 1/A, on a side
    /// drawn with probability 1/2 where surfaces are two-sided), from seeded
    /// streams (the same points for the same `seed`). Returns a dict of
    /// arrays: `position` and `normal` (n, 3) (the normal on the chosen
    /// side), `triangle` (n,), `barycentric` (n, 2) and `flipped` (n,) bool,
    /// and `pdf`, the density of each point per m² of one side
    /// (1/A, or 1/(2A) two-sided).
    #[pyo3(signature = (n, seed = 0))]
    fn sample_area<'py>(&self, py: Python<'py>, n: usize, seed: u64) -> PyResult<Bound<'py, PyDict>> {
        let tris = &self.scene.geometry.triangles;
        let areas: Vec<f32> = tris.iter().map(|t| t.area).collect();
        let by_area = Distribution1D::new(&areas).ok_or_else(|| vpl_err("the scene has no surface area to sample"))?;
        let two = self.scene.two_sided;
        let scene = &self.scene;
        let pts: Vec<(SurfacePoint, u32, f32, f32, bool)> = py.detach(|| {
            (0..n)
                .into_par_iter()
                .map(|i| {
                    let mut rng = stream(seed, 0, AREA_SAMPLES, i as u64);
                    let (tri, _) = by_area.sample(rng.next_f32());
                    let (b1, b2) = uniform_triangle(rng.next_f32(), rng.next_f32());
                    let y = scene.surface_point(tri as u32, b1, b2);
                    let flip = two && rng.next_f32() < 0.5;
                    (if flip { y.facing(-y.ng) } else { y }, tri as u32, b1, b2, flip)
                })
                .collect()
        });
        let d = PyDict::new(py);
        d.set_item("position", vectors(py, pts.iter().map(|p| p.0.p)))?;
        d.set_item("normal", vectors(py, pts.iter().map(|p| p.0.n)))?;
        d.set_item("triangle", pts.iter().map(|p| p.1).collect::<Vec<u32>>().into_pyarray(py))?;
        let bary: Vec<f32> = pts.iter().flat_map(|p| [p.2, p.3]).collect();
        d.set_item("barycentric", Array2::from_shape_vec((n, 2), bary).map_err(vpl_err)?.into_pyarray(py))?;
        d.set_item("flipped", pts.iter().map(|p| p.4).collect::<Vec<bool>>().into_pyarray(py))?;
        let area = self.scene.surface_area() * if two { 2.0 } else { 1.0 };
        d.set_item("pdf", 1.0 / area)?;
        Ok(d)
    }

    /// Exitant radiance L(y) of surface points toward their side (emission
    /// excluded), each estimated by `paths` path-traced paths of at most
    /// `max_bounces` bounces after y, seeded by (`seed`, point index): what
    /// the built-in samplers call radiosity. `points` is a dict as
    /// [`Scene.sample_area`] returns (its `triangle`, `barycentric` and
    /// `flipped`). Returns a float32 array (n, 3). Releases the GIL; Ctrl-C
    /// stops it.
    #[pyo3(signature = (points, paths = 16, max_bounces = 2, seed = 0))]
    fn radiosity<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyDict>,
        paths: u32,
        max_bounces: u32,
        seed: u64,
    ) -> PyResult<Bound<'py, numpy::PyArray2<f32>>> {
        if paths == 0 {
            return Err(vpl_err("radiosity needs at least 1 path per point"));
        }
        let get =
            |k: &str| points.get_item(k)?.ok_or_else(|| vpl_err(format!("points has no '{k}' (pass what Scene.sample_area returns)")));
        let tri: PyReadonlyArray1<u32> = get("triangle")?.extract().map_err(|_| vpl_err("points['triangle'] must be a uint32 array"))?;
        let bary: PyReadonlyArray2<f32> =
            get("barycentric")?.extract().map_err(|_| vpl_err("points['barycentric'] must be a float32 array of shape (n, 2)"))?;
        let flipped: PyReadonlyArray1<bool> = get("flipped")?.extract().map_err(|_| vpl_err("points['flipped'] must be a bool array"))?;
        let n = tri.len();
        if bary.shape() != [n, 2] || flipped.len() != n {
            return Err(vpl_err(format!(
                "points' arrays disagree: {n} triangles, barycentrics {:?}, {} flips",
                bary.shape(),
                flipped.len()
            )));
        }
        let count = self.scene.geometry.triangles.len();
        let (tri, bary, flipped) = (tri.as_array(), bary.as_array(), flipped.as_array());
        let mut ys = Vec::with_capacity(n);
        for i in 0..n {
            let t = tri[i];
            let (b1, b2) = (bary[[i, 0]], bary[[i, 1]]);
            if t as usize >= count {
                return Err(vpl_err(format!("point {i}: triangle {t} is past the scene's {count}")));
            }
            if !(b1 >= 0.0 && b2 >= 0.0 && b1 + b2 <= 1.0 + 1e-6) {
                return Err(vpl_err(format!("point {i}: barycentrics ({b1}, {b2}) lie outside the triangle")));
            }
            let y = self.scene.surface_point(t, b1, b2);
            ys.push((if flipped[i] { y.facing(-y.ng) } else { y }, i as u64));
        }
        let est = PathRadiosity { paths, max_bounces };
        let scene = self.scene.clone();
        let radiance = interruptible(
            py,
            |cancel| {
                ys.par_iter()
                    .map(|(y, i)| {
                        if cancel.load(std::sync::atomic::Ordering::Relaxed) {
                            return Vec3::ZERO;
                        }
                        est.radiosity(&scene, y, mix64(mix64(seed) ^ i))
                    })
                    .collect::<Vec<Vec3>>()
            },
            |_| {},
        )?;
        Ok(vectors(py, radiance.into_iter()))
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene('{}', frame {} of {}, {} triangles, {} lights, {}x{})",
            self.scene.name,
            self.frame,
            frame_count(&self.setup),
            self.scene.geometry.triangles.len(),
            self.scene.lights.len(),
            self.camera.resolution.0,
            self.camera.resolution.1
        )
    }
}

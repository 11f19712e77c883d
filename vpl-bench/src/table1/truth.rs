//! The ground truth of Table 1's tracked pixels: path-traced on the CPU
//! ([`vpl_pathtrace::track_with`]) or, with the GPU backend, on the device
//! ([`vpl_gpu::GpuTracker`], the same estimator over other streams).

use super::rows::Row;
use super::{Table1Error, Table1Spec, TruthUnit, UnitSettings};
use crate::pipeline::BackendKind;
use std::time::Instant;
use vpl_core::{Mode, SceneSetup};
use vpl_pathtrace::{Footprint, PathTracer, TrackRequest, TrackedPixel, track_with};

/// What a run's truth units share: the last sequence's scene (its frames
/// share one geometry, so a device keeps one upload) and, for the GPU,
/// the device, opened on the first unit.
#[derive(Default)]
pub struct Truth {
    setup: Option<(String, SceneSetup)>,
    #[cfg(feature = "gpu")]
    gpu: Option<vpl_gpu::GpuTracker>,
}

impl Truth {
    /// No scene loaded and no device open yet.
    pub fn new() -> Truth {
        Truth::default()
    }

    /// No scene loaded; units of the GPU backend run on `gpu`.
    #[cfg(feature = "gpu")]
    pub fn on(gpu: vpl_gpu::Gpu) -> Truth {
        Truth { gpu: Some(vpl_gpu::GpuTracker::new(gpu)), ..Truth::default() }
    }

    /// The truth unit of `row`'s frame `frame`: `spec.truth_spp` samples
    /// through each tracked pixel's centre, indirect light to the spec's
    /// depth, materials drawn as the VPL methods draw them. The unit
    /// records its wall time and, apart, what did not depend on the
    /// samples (loading the scene, the upload to a device).
    pub fn unit(&mut self, spec: &Table1Spec, row: &Row, frame: u32) -> Result<TruthUnit, Table1Error> {
        let start = Instant::now();
        if self.setup.as_ref().is_none_or(|(id, _)| id != row.id) {
            self.setup = Some((row.id.into(), row.setup()?));
        }
        let setup = &self.setup.as_ref().expect("loaded above").1;
        let (scene, camera) = setup.frame(frame)?;
        // The truth draws the materials as the VPL methods it judges do.
        let scene = scene.with_material_policy(vpl_core::MaterialPolicy::Diffuse);
        let camera = camera.with_resolution(spec.size)?;
        let pt = PathTracer::new(spec.max_depth, Mode::Indirect);
        let pixels = row.pixels(spec.size);
        // Rays through the pixel centres: the one point a G-buffer shades per
        // pixel, so edges inside a pixel do not count as VPL error.
        let request = TrackRequest {
            pixels: &pixels,
            spp: spec.truth_spp,
            seed: spec.seed ^ 0x0074_7275_7468,
            frame: frame as u64,
            footprint: Footprint::Centre,
        };
        let (tracked, setup_seconds, device) = match spec.backend {
            BackendKind::Cpu => {
                let setup_seconds = start.elapsed().as_secs_f64();
                (track_with(&scene, &camera, &pt, &request), setup_seconds, None)
            }
            BackendKind::Gpu => self.on_device(&scene, &camera, &pt, &request, start)?,
        };
        Ok(TruthUnit {
            settings: Some(UnitSettings::of(spec)),
            row: row.id.into(),
            frame,
            mean: tracked.iter().map(|p| p.mean.to_array()).collect(),
            stderr: tracked.iter().map(|p| p.stderr.to_array()).collect(),
            samples: spec.truth_spp as u64,
            seconds: start.elapsed().as_secs_f64(),
            setup_seconds,
            device,
        })
    }

    #[cfg(feature = "gpu")]
    fn on_device(
        &mut self,
        scene: &vpl_core::Scene,
        camera: &vpl_core::Camera,
        pt: &PathTracer,
        request: &TrackRequest,
        start: Instant,
    ) -> Result<(Vec<TrackedPixel>, f64, Option<String>), Table1Error> {
        let device = |e: vpl_gpu::GpuError| Table1Error::Invalid(format!("--backend gpu: ground truth: {e}"));
        if self.gpu.is_none() {
            self.gpu = Some(vpl_gpu::GpuTracker::new(vpl_gpu::Gpu::new().map_err(device)?));
        }
        let tracker = self.gpu.as_ref().expect("opened above");
        // The upload (kept while the geometry is the same) is set-up, not sampling.
        tracker.gpu().scene(scene).map_err(device)?;
        let setup_seconds = start.elapsed().as_secs_f64();
        let adapter = tracker.gpu().ctx().describe();
        Ok((tracker.track(scene, camera, pt, request).map_err(device)?, setup_seconds, Some(adapter)))
    }

    #[cfg(not(feature = "gpu"))]
    fn on_device(
        &mut self,
        _: &vpl_core::Scene,
        _: &vpl_core::Camera,
        _: &PathTracer,
        _: &TrackRequest,
        _: Instant,
    ) -> Result<(Vec<TrackedPixel>, f64, Option<String>), Table1Error> {
        Err(Table1Error::Invalid("--backend gpu: build vpl-bench with its default feature `gpu`".into()))
    }
}

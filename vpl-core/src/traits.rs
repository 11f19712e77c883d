//! Interfaces shared by the stages of the toolkit: samplers produce a
//! [`VplSet`], visibility answers V(x, y) for its slots, shaders turn the set
//! into indirect light, and radiosity estimators give L(y) to the samplers
//! that need it.

use crate::camera::{BounceRays, CameraRays};
use crate::frame::Frame;
use crate::gbuffer::{GBuffer, Receivers};
use crate::image::Image;
use crate::ray::Ray;
use crate::scene::Scene;
use crate::stats::Stats;
use crate::surface::Hit;
use crate::surface::SurfacePoint;
use crate::vpl::{Vpl, VplSet};
use glam::Vec3;

/// Estimates the exitant radiance L(y) of a diffuse surface point (its radiosity
/// divided by π), as the SMC sampler and Metropolis IR need for their VPLs.
///
/// `seed` selects the random paths, so a VPL that passes the same seed in
/// every frame gets the same estimate while the scene does not change.
pub trait RadiosityEstimator {
    /// Exitant radiance of `y` toward its front side (normal `y.n`), emission excluded.
    fn radiosity(&self, scene: &Scene, y: &SurfacePoint, seed: u64) -> Vec3;

    /// [`RadiosityEstimator::radiosity`] of many (point, seed) pairs, the
    /// same value each: what an estimator that runs in batches (on a GPU)
    /// implements. By default, the points in parallel (rayon).
    fn radiosity_many(&self, scene: &Scene, points: &[(SurfacePoint, u64)]) -> Vec<Vec3>
    where
        Self: Sync,
    {
        use rayon::prelude::*;
        points.par_iter().map(|(y, seed)| self.radiosity(scene, y, *seed)).collect()
    }
}

/// A VPL sampler (Instant Radiosity, Russian-roulette acceptance,
/// Metropolis IR, TCAS, SMC): produces each frame's VPLs in the flux
/// convention of [`crate::vpl`]. Samplers are stateful and may keep VPLs from
/// frame to frame; unchanged slots are what makes visibility updates cheap.
pub trait VplSampler: Send {
    /// Short name (`ir`, `smc`, …).
    fn name(&self) -> &'static str;
    /// Samples the VPLs of `frame`; slots that differ from the previous
    /// frame are marked changed.
    fn next_frame(&mut self, frame: &Frame) -> &VplSet;
    /// Statistics of the last frame as typed key–values (`stored`,
    /// `moved`, `acceptance`, milliseconds of each step, …): what a harness
    /// prints and writes to CSV or JSON.
    fn stats(&self) -> Stats {
        Stats::default()
    }
    /// Whether the sampler reads the previous frame's image
    /// ([`Frame::previous`]): a renderer that keeps its frames on a device
    /// then reads each image back for it. `false` by default.
    fn reads_previous_image(&self) -> bool {
        false
    }
}

/// A source of VPLs from light paths whose number is chosen per call, each
/// set an unbiased estimate of the light field on its own (Instant
/// Radiosity and the like). Samplers that thin or re-weight light-path VPLs
/// (Russian-roulette acceptance) wrap one.
pub trait LightPathGenerator: Send + Sync {
    /// Short name (`ir`, …).
    fn name(&self) -> &'static str;
    /// VPLs for a budget of `budget` slots (fewer when paths leave the
    /// scene), in the flux convention of [`crate::vpl`]: their sum over the
    /// set estimates the light field without bias. `seed` and `frame` key
    /// the random streams; `frame` is the caller's batch or frame number.
    fn generate(&self, scene: &Scene, budget: usize, seed: u64, frame: u64) -> Vec<Vpl>;
}

/// Batches of ray queries against a scene: the CPU BVH ([`CpuRays`]) or a
/// GPU twin. Samplers that cast many rays a frame (SMC's camera points,
/// candidate rays and indirect-visibility rays) cast them through one.
pub trait RayCaster: Send + Sync {
    /// Short name (`cpu`, `gpu`).
    fn name(&self) -> &'static str;
    /// The closest hit of each ray, as [`Scene::intersect`].
    fn intersect(&self, scene: &Scene, rays: &[Ray]) -> Vec<Option<Hit>>;
    /// Whether each ray is blocked before its `t_max`, as [`Scene::occluded`].
    fn occluded(&self, scene: &Scene, rays: &[Ray]) -> Vec<bool>;
    /// The closest hits of `batch`'s camera rays, as
    /// [`intersect`](RayCaster::intersect)`(scene, &batch.rays)`. A caster
    /// on a device may make the rays there from the camera and the key
    /// (moving a few bytes instead of 32 a ray); the hits are then completed
    /// with the host's rays, so they differ from the default's only where a
    /// ray grazes an edge.
    fn intersect_camera(&self, scene: &Scene, batch: &CameraRays) -> Vec<Option<Hit>> {
        self.intersect(scene, &batch.rays)
    }
    /// The closest hits of `batch`'s rays from the hits of a camera batch,
    /// as [`intersect`](RayCaster::intersect)`(scene, &batch.rays)`. A
    /// caster on a device that still holds the camera batch's hits may make
    /// the rays there (8 B a ray up instead of 24); the hits are then
    /// completed with the host's rays, as in
    /// [`intersect_camera`](RayCaster::intersect_camera).
    fn intersect_bounce(&self, scene: &Scene, batch: &BounceRays) -> Vec<Option<Hit>> {
        self.intersect(scene, &batch.rays)
    }
    /// Whether a batch costs far more than its rays, so that a caller
    /// trying candidates round by round (the first one a test passes wins)
    /// should rather cast every round's rays in one batch and take the first
    /// pass in round order: the same answers for more rays and one round
    /// trip. True for casters on a device across a bus; false (the default)
    /// where rays are cheap and batches free.
    fn speculates(&self) -> bool {
        false
    }
}

/// [`RayCaster`] on the scene's own BVH, in parallel (rayon).
#[derive(Clone, Copy, Debug, Default)]
pub struct CpuRays;

impl RayCaster for CpuRays {
    fn name(&self) -> &'static str {
        "cpu"
    }

    fn intersect(&self, scene: &Scene, rays: &[Ray]) -> Vec<Option<Hit>> {
        use rayon::prelude::*;
        rays.par_iter().map(|r| scene.intersect(r)).collect()
    }

    fn occluded(&self, scene: &Scene, rays: &[Ray]) -> Vec<bool> {
        use rayon::prelude::*;
        rays.par_iter().map(|r| scene.occluded(r)).collect()
    }
}

/// What a visibility update did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct VisibilityUpdate {
    /// Per-VPL structures (shadow maps) rebuilt.
    pub rebuilt: usize,
    /// Memory held after the update, in bytes.
    pub memory_bytes: usize,
}

/// Names the structures one visibility keeps on a device
/// ([`VplVisibility::device_key`]): unique among all keys made in the
/// process, so a shader on the device finds the structures of the
/// visibility it is handed and of no other.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DeviceKey(u64);

impl DeviceKey {
    /// A key no other call has returned.
    pub fn unique() -> DeviceKey {
        static NEXT: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        DeviceKey(NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed))
    }
}

/// Visibility V(x, y) between receivers and the VPLs of a set, by slot.
pub trait VplVisibility: Send + Sync {
    /// Short name (`raytrace`, `shadowmap`).
    fn name(&self) -> &'static str;
    /// Brings the structure up to date with `vpls`, rebuilding only what the
    /// slots that changed (or that were never built) need.
    fn update(&mut self, scene: &Scene, vpls: &VplSet) -> VisibilityUpdate;
    /// Visibility in [0, 1] between the VPL in `slot` and the surface point
    /// `x` with normal `n_x` (the normal lets the receiver step off its surface).
    fn visible(&self, slot: usize, x: Vec3, n_x: Vec3) -> f32;
    /// Multiplies each positive weight `w[i]` by the visibility of receiver
    /// `i` from the VPL in `slot`; zero weights are left alone (and need no
    /// query). The batch form lets shaders stream one VPL over many points.
    fn attenuate(&self, slot: usize, rx: &Receivers, w: &mut [f32]) {
        for (i, wi) in w.iter_mut().enumerate() {
            if *wi > 0.0 {
                *wi *= self.visible(slot, rx.p(i), rx.n(i));
            }
        }
    }
    /// Memory held, in bytes.
    fn memory_bytes(&self) -> usize;
    /// The key under which this visibility's structures on a device are
    /// found by shaders on that device, which then read them in place
    /// (with the same result as [`VplVisibility::attenuate`]). `None` (the
    /// default) for a visibility on the host.
    fn device_key(&self) -> Option<DeviceKey> {
        None
    }
    /// The shadow maps this visibility answers from, where every answer is
    /// its slot's map's (no map: not visible): shaders may read them
    /// directly, with the same result as [`VplVisibility::attenuate`].
    /// `None` (the default) for any other visibility.
    fn shadow_maps(&self) -> Option<&dyn crate::ShadowMapSource> {
        None
    }
}

/// Turns VPLs into the indirect radiance of every G-buffer pixel.
pub trait IndirectShader: Send {
    /// Short name (`interleaved`, `exhaustive`).
    fn name(&self) -> &'static str;
    /// Reflected radiance from `vpls` at each pixel of `gbuf` (zero where the
    /// camera sees nothing that reflects).
    fn shade(&mut self, gbuf: &GBuffer, vpls: &VplSet, vis: &dyn VplVisibility) -> Image;
    /// The geometry-term clamp of the frames after this call (`None`: off);
    /// a renderer whose clamp follows the view sets it when the camera moves.
    fn set_clamp(&mut self, clamp: Option<crate::clamp::GeometryClamp>);
    /// Whether this shader, with `vis`, shades on a device: it then takes a
    /// G-buffer whose samples stay there ([`GBuffer::on_device`]) and can
    /// leave its image there ([`IndirectShader::keep_on_device`]). `false`
    /// by default (the CPU shaders).
    fn on_device(&self, vis: &dyn VplVisibility) -> bool {
        let _ = vis;
        false
    }
    /// Where [`IndirectShader::on_device`]: with `keep`, the following
    /// shades leave their images on the device and return
    /// [`Image::on_device`]; [`IndirectShader::read_image`] reads the last
    /// one back. Ignored by shaders on the host.
    fn keep_on_device(&mut self, keep: bool) {
        let _ = keep;
    }
    /// The image the last shade left on the device, read back, with what
    /// [`IndirectShader::finish_on_device`] added; `None` when it left none
    /// there.
    fn read_image(&self) -> Option<Image> {
        None
    }
    /// The indirect light the last shade left on the device, read back:
    /// [`IndirectShader::read_image`] before anything was added to it.
    fn read_indirect(&self) -> Option<Image> {
        self.read_image()
    }
    /// Whether [`IndirectShader::finish_on_device`] can add the light paths
    /// a frame keeps besides the VPLs' to an image left on the device, so
    /// that a frame of every light path stays there. `false` by default.
    fn finishes_on_device(&self) -> bool {
        false
    }
    /// Adds to the image the last shade left on the device the G-buffer's
    /// emission (paths of k = 0: emitters and the environment seen
    /// directly) when `emission`, and the direct light (k = 1) when
    /// `direct` is `Some((samples, seed))`: `samples` light samples a pixel
    /// drawn from the streams the host's direct light draws from
    /// (`stream(seed, 0, Purpose::DIRECT, pixel)`). Answers whether it did;
    /// `false` where no image is on the device.
    fn finish_on_device(&mut self, scene: &crate::Scene, emission: bool, direct: Option<(u32, u64)>) -> bool {
        let _ = (scene, emission, direct);
        false
    }
}

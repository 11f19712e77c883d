//! # vpl-gpu
//!
//! The toolkit's hot loops as wgpu compute kernels (WGSL; Vulkan, Metal,
//! DX12, and GL as the fallback), each behind the trait or signature of its
//! CPU twin and tested against it:
//!
//! | kernel | twin | behind |
//! | --- | --- | --- |
//! | [`GpuRayCaster`]: closest hit and occlusion over [`GpuScene`] (binary BVH in storage buffers); camera rays made on the device | `Scene::intersect`, `Scene::occluded`, `CameraRays` | batch calls; [`GpuRays`] is a `RayCaster` (SMC's camera, candidate and visibility rays) |
//! | [`GpuGBufferRenderer`] / [`Gpu::render_gbuffer`] | `vpl_shading::render_gbuffer` | returns a `GBuffer` |
//! | [`GpuShadowMaps`]: paraboloid maps of moved slots, one ray per texel | `vpl_visibility::ShadowMaps` | `VplVisibility` |
//! | [`GpuRayTraced`]: shadow rays in the shading kernel | `vpl_visibility::RayTraced` | `VplVisibility` |
//! | [`GpuInterleavedShader`]: 4×4 interleaved (or exhaustive) gathering, clamp, filter, albedo | `InterleavedShader`, `ExhaustiveShader` | `IndirectShader` |
//! | [`GpuLightcutShader`]: stochastic lightcuts, the cut and walk of a host-built `vpl_lighttree` tree with the CPU's streams, shadow maps or rays | `vpl_shading::LightcutShader` | `IndirectShader` |
//! | [`GpuCrossBilateral`] | `vpl_shading::CrossBilateral` | `apply` |
//! | [`GpuRadiosity`]: path-traced L(y), NEE + MIS, the CPU's PCG32 streams | `vpl_pathtrace::PathRadiosity` | `RadiosityEstimator` |
//! | [`GpuTracker`]: tracked pixels' ground truth, a chunk of samples an invocation | `vpl_pathtrace::track_chunk` (`track_with`'s estimator) | batch call |
//! | [`Gpu::finish_frame`]: emission (the sky at misses) and direct light, the CPU's light samples and streams | `vpl_shading::direct_light` and the frame's emission | `IndirectShader::finish_on_device` |
//! | [`Gpu::neighbours`]: k nearest points over a grid built on the device (bounds, counting sort) | `vpl_density::KnnDensity` | batch call |
//! | [`GpuSmcSampler`]: Algorithm 1 of SMC, every line, with the paper's kNN flux | `vpl_smc::SmcSampler` (`flux = knn`) | `VplSampler`; the backend builds it for `smc-knn` |
//! | [`Gpu::temporal_change`]: Σ\|ΔL\|/ΣL of two frames | the viewer's host sum | batch call |
//!
//! The stages of one frame share a [`Gpu`] (the device, the scene upload and
//! the G-buffer left on the device). The kernels do the CPU twins'
//! arithmetic in the same order, so they differ only by rounding (fused
//! multiply-adds, `exp`, normalisation) and by ties: on lavapipe the
//! unfiltered shading is bit-equal to the CPU's.
//!
//! ## What crosses the bus
//!
//! The frame stays on the device: under `vpl_render::ReadBack::Nothing`
//! the G-buffer, the shadow maps, the gathered and filtered image stay
//! there, and only what the host asks for comes back. Every upload, read
//! and submission is counted ([`Gpu::traffic`], [`Traffic`]; `vpl
//! bench-gpu` prints them per frame). Sampling talks to the device in
//! batches, each one submission and one wait, and moves little in each:
//!
//! - camera rays are made on the device from the camera and one stream key
//!   ([`vpl_core::CameraRays`]), and rays that leave their hits from 8 B a
//!   ray ([`vpl_core::BounceRays`]: SMC's candidates); other rays go up as
//!   24 B (unbounded) or 28 B; hits come back as the triangle (4 B, the
//!   host completes the hit with its own ray and triangle test), occlusion
//!   as one bit;
//! - radiosity paths draw the CPU's streams from one key a point and are
//!   summed on the device (56 B up and 16 B back a point); the lights stay
//!   on the device until they change;
//! - rounds of visibility tests where the first pass wins are cast in one
//!   batch ([`vpl_core::RayCaster::speculates`]), with the same answers.
//!
//! A steady SMC frame at 1920×1080 with 2048 VPLs on office moves 1.3 MB in
//! 14 submissions (lavapipe; the counts do not depend on the device), where
//! reading the G-buffer and image back moved 199 MB. With the paper's kNN
//! flux SMC runs wholly on the device ([`GpuSmcSampler`]): its step is one
//! submission that writes 240 B of parameters and reads back the VPLs and
//! statistics (96 KiB), and the frame moves 321 KiB in 4 submissions.
//!
//! A frame left on the device is published, with its G-buffer, to the
//! backend's [`Frames`] ([`GpuBackend::frames`]): a window on the same
//! device ([`GpuContext::instance`], [`GpuContext::adapter`]) draws it from
//! there ([`DeviceFrame`]), and [`Gpu::temporal_change`] reduces the
//! frame-to-frame change Σ|ΔL|/ΣL on the device (2 KiB back). The
//! [`kernel`] helpers run a program's own kernels the same way, counted.
//!
//! ```no_run
//! use vpl_core::{GeometryClamp, IndirectShader, SceneSetup, Vpl, VplSet, VplVisibility};
//! use vpl_gpu::{Gpu, GpuInterleavedShader, GpuShadowMaps};
//!
//! let gpu = Gpu::new().expect("a GPU adapter (lavapipe will do)");
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let gbuf = gpu.render_gbuffer(&setup.scene, &setup.camera).unwrap();
//! // One VPL where the centre pixel's ray meets the scene (any sampler's set will do).
//! let ray = setup.camera.ray(128.0, 128.0, (0.5, 0.5));
//! let y = setup.scene.intersect(&ray).unwrap().point.facing(-ray.d);
//! let mut vpls = VplSet::new(1);
//! vpls.set(0, Some(Vpl { y: y.p + y.n * 1e-3, n: y.n, flux: vpl_core::glam::Vec3::ONE, id: 0, bounce: 1 }));
//! let mut maps = GpuShadowMaps::new(gpu.clone(), 128).unwrap();
//! maps.update(&setup.scene, &vpls);
//! let mut shader = GpuInterleavedShader::new(gpu.clone(), Some(GeometryClamp::new(50.0)), 0);
//! let indirect = shader.shade(&gbuf, &vpls, &maps);
//! assert_eq!(indirect.width, gbuf.width);
//! ```
//!
//! ## Build profile
//!
//! Debug builds of the toolkit's crates are 20–50× slower than optimised ones
//! (an SMC frame takes 9.7 s instead of 0.18 s). The toolkit's own workspace
//! optimises its dependencies, but a workspace's profile does not reach the
//! projects that depend on it. Add to your project's `Cargo.toml`:
//!
//! ```toml
//! [profile.dev.package."*"]
//! opt-level = 3
//! ```
//!
//! Your own crates stay quick to compile; every dependency, this one included,
//! is optimised.

#![warn(missing_docs)]

mod backend;
mod context;
mod device;
mod direct;
mod filter;
mod frame;
mod gbuffer;
mod interleaved;
pub mod kernel;
mod lightcuts;
mod neighbours;
mod radiosity;
mod raycast;
mod raytraced;
mod scene;
mod shadow_maps;
mod smc;
mod track;
mod visibility;

pub use backend::{GpuBackend, NAME, backend, register};
pub use context::{GpuContext, GpuError, Traffic};
pub use device::Gpu;
pub use filter::GpuCrossBilateral;
pub use frame::{DeviceFrame, Frames};
pub use gbuffer::{DeviceGBuffer, GpuGBufferRenderer};
pub use interleaved::{GpuInterleavedShader, GpuShadeTimings};
pub use lightcuts::{GpuLightcutShader, MAX_CUT};
pub use neighbours::{MAX_K, Neighbours};
pub use radiosity::GpuRadiosity;
pub use raycast::{GpuRayCaster, GpuRays};
pub use raytraced::GpuRayTraced;
pub use scene::GpuScene;
pub use shadow_maps::GpuShadowMaps;
pub use smc::GpuSmcSampler;
pub use track::GpuTracker;

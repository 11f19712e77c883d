//! # vpl-gpu
//!
//! The toolkit's hot loops as wgpu compute kernels (Vulkan, Metal, DX12, GL),
//! each behind the trait or signature of its CPU twin and tested against it.
//! This first step holds the device ([`GpuContext`]) and the cross-bilateral
//! filter ([`GpuCrossBilateral`], twin of [`vpl_shading::CrossBilateral`]).
//!
//! ```no_run
//! use vpl_gpu::{GpuContext, GpuCrossBilateral};
//! use vpl_core::{Image, SceneSetup};
//!
//! let ctx = GpuContext::new().expect("a GPU adapter (lavapipe will do)");
//! let setup = SceneSetup::load("cornell").unwrap();
//! let gbuf = vpl_shading::render_gbuffer(&setup.scene, &setup.camera);
//! let e = Image::new(gbuf.width, gbuf.height);
//! let f = GpuCrossBilateral::default().apply(&ctx, &gbuf, &e).unwrap();
//! assert_eq!(f.width, gbuf.width);
//! ```

#![warn(missing_docs)]

mod context;
mod device;
mod filter;
mod gbuffer;
mod interleaved;
mod kernel;
mod raycast;
mod raytraced;
mod scene;
mod shadow_maps;

pub use context::{GpuContext, GpuError};
pub use device::Gpu;
pub use filter::GpuCrossBilateral;
pub use gbuffer::{DeviceGBuffer, GpuGBufferRenderer};
pub use interleaved::{GpuInterleavedShader, GpuShadeTimings};
pub use raycast::GpuRayCaster;
pub use raytraced::GpuRayTraced;
pub use scene::GpuScene;
pub use shadow_maps::GpuShadowMaps;

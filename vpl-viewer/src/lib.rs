//! # vpl-viewer
//!
//! An interactive viewer of VPL renders: a window (winit, wgpu, egui) that
//! renders frames continuously with [`vpl_render::Renderer`], on the GPU
//! backend when there is an adapter and on the CPU at a reduced resolution
//! otherwise (stated on screen). Pick the sampler live from the registry
//! (a program's own samplers included), split the view between two
//! samplers on the same camera and lights, splat the VPLs over the image
//! (coloured by flux, those that moved this frame ringed), look at
//! G-buffer channels, and watch per-stage milliseconds, VPLs moved and the
//! frame-to-frame change Σ|ΔL|/ΣL (what the SMC paper's |E′| measures) in
//! live plots. While the camera stands still the path tracer accumulates a
//! reference, shown beside the frames or as their difference against it;
//! a clicked VPL shows its shadow map and, over the interleaving pattern,
//! the pixels it shades; the camera-and-light path of a session is
//! recorded as a scene file with an animation.
//!
//! On the GPU backend the window opens its surface on the renderer's
//! device, and frames whose every stage runs there stay there: the view
//! is composed by kernels from the device's images and G-buffer
//! ([`present`]), with no read-back. A click reads the G-buffer back once
//! (to test which VPLs the camera sees), a screenshot the frames, the
//! reference's comparison the image; the frame-to-frame change is reduced
//! on the device. [`Summary::device_frames`] counts the views composed
//! there.
//!
//! `vpl view --scene office` is this crate's [`run`]; a program with its
//! own samplers calls it with its registry:
//!
//! ```no_run
//! let registry = vpl_sampling::Registry::builtin();
//! let options = vpl_viewer::ViewerOptions::new("office");
//! vpl_viewer::run(options, &registry).unwrap();
//! ```
//!
//! What the window shows is built by pure functions, usable without a
//! window: here a frame of the Cornell box split against itself with the
//! VPLs splatted, and a scripted session parsed:
//!
//! ```
//! use vpl_core::SceneSetup;
//! use vpl_render::Renderer;
//! use vpl_viewer::view::{compose, Channel, Look, Overlay, SideFrame};
//!
//! let setup = SceneSetup::builtin("cornell").unwrap();
//! let camera = setup.camera.with_resolution((24, 24)).unwrap();
//! let mut r = Renderer::builder(&setup.scene).vpls(16).build().unwrap();
//! let out = r.render(&setup.scene, &camera, 0, 0.0).unwrap();
//! let side = SideFrame { image: &out.image, gbuffer: &out.gbuffer, vpls: &out.vpls, camera: &camera };
//! let view = compose(side, Some(side), &Look { channel: Channel::Image, overlay: Overlay::Vpls, ..Look::image() });
//! assert_eq!(view.split_x, Some(12));
//! assert_eq!(view.rgba.len(), 24 * 24 * 4);
//!
//! let script = vpl_viewer::Script::parse("sampler smc\nframes 2\nscreenshot shot").unwrap();
//! assert_eq!(script.steps.len(), 3);
//! ```
//!
//! ## Input
//!
//! Drag with the left button to orbit around the point looked at, with the
//! right button to look around; W A S D fly, Q E down and up (Shift: faster);
//! the wheel dollies toward the point looked at; Ctrl + left drag moves the
//! scene's first point or spot light in the view plane (a directional light
//! turns). A click picks the VPL nearest to it. A scene with an animation
//! plays, pauses and scrubs on the panel.

#![warn(missing_docs)]

mod app;
pub mod camera;
mod display;
mod error;
pub mod inspect;
#[cfg(feature = "gpu")]
pub mod present;
pub mod record;
pub mod script;
pub mod view;
pub mod worker;

pub use error::ViewerError;
pub use script::{Script, ScriptError, Step};

use vpl_core::{Budget, Mode};
use vpl_render::PipelineSpec;
use vpl_sampling::Registry;

/// How the viewer starts.
#[derive(Clone, Debug)]
pub struct ViewerOptions {
    /// Scene: a built-in name or a scene file (as `vpl render --scene`).
    pub scene: String,
    /// Window size in pixels.
    pub window: (u32, u32),
    /// The pipeline of the left (or only) side: sampler, its parameters,
    /// VPL budget, visibility, shading, clamp, light paths, seed, and where
    /// it runs (`backend`: `auto`, the GPU when there is an adapter, else
    /// the CPU; `cpu`; `gpu`). The panel changes the sampler, the budget
    /// and the light paths; the parameters go to the pipeline's own sampler
    /// (one chosen in the panel starts from its defaults).
    pub pipeline: PipelineSpec,
    /// Render resolution over the view's size (default ½ on the GPU, ¼ on
    /// the CPU).
    pub scale: Option<f32>,
    /// Sampler of the right side of a split view.
    pub split: Option<String>,
    /// Exposure of the tone mapping.
    pub exposure: f32,
    /// Accumulate the path tracer's reference while the camera stands still
    /// from the start (the panel turns it on and off).
    pub reference: bool,
    /// A scripted session: the viewer runs it and closes (see [`script`]).
    pub script: Option<Script>,
    /// Where the scene's files may be read from besides its folder (see
    /// `vpl_scene_io::sandbox`).
    pub load: vpl_scene_io::LoadOptions,
}

impl ViewerOptions {
    /// The defaults for `scene`: a 1280×720 window, IR with 256 VPLs, full
    /// light, on the GPU when there is one.
    pub fn new(scene: impl Into<String>) -> ViewerOptions {
        ViewerOptions {
            scene: scene.into(),
            window: (1280, 720),
            pipeline: PipelineSpec {
                sampler: "ir".into(),
                budget: Budget { vpls: 256, ..PipelineSpec::default().budget },
                mode: Mode::Full,
                seed: 0,
                backend: vpl_render::AUTO.into(),
                ..PipelineSpec::default()
            },
            scale: None,
            split: None,
            exposure: 1.0,
            reference: false,
            script: None,
            load: Default::default(),
        }
    }
}

/// What a session did.
#[derive(Clone, Debug, PartialEq)]
pub struct Summary {
    /// Frames shown (every side rendered).
    pub frames: u64,
    /// Frames shown per second over the session, the first frame excluded
    /// (it builds the samplers' state).
    pub fps: f64,
    /// Where the renderer ran, in words.
    pub renderer: String,
    /// Render resolution at the end.
    pub resolution: (u32, u32),
    /// Views composed on the renderer's device from frames that stayed
    /// there (no read-back): the GPU backend with a window on the same
    /// device, and frames whose every stage runs there (indirect light).
    pub device_frames: u64,
}

/// Opens the viewer's window and runs until it is closed (or the script ends).
pub fn run(options: ViewerOptions, registry: &Registry) -> Result<Summary, ViewerError> {
    for name in std::iter::once(&options.pipeline.sampler).chain(options.split.as_ref()) {
        if !registry.contains(name) {
            return Err(ViewerError::UnknownSampler { name: name.clone(), known: registry.names().join(", ") });
        }
    }
    // The pipeline's sampler takes its parameters (a key it does not read
    // is an error), checked before any window opens.
    let p = &options.pipeline;
    registry
        .build(&p.sampler, p.budget, &vpl_core::Services::cpu(), &p.params)
        .map_err(|e| ViewerError::Sampler { name: p.sampler.clone(), source: Box::new(e) })?;
    if options.pipeline.backend != vpl_render::AUTO {
        app::backends().entry(&options.pipeline.backend).map_err(|e| ViewerError::Backend(e.to_string()))?;
    }
    if options.pipeline.budget.vpls == 0 {
        return Err(ViewerError::Invalid("the VPL budget must be positive".into()));
    }
    if let Some(s) = options.scale.filter(|s| !(s.is_finite() && *s > 0.0 && *s <= 1.0)) {
        return Err(ViewerError::Invalid(format!("the render scale must be in (0, 1], got {s}")));
    }
    app::run(options, registry)
}

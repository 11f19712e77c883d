//! The stateful VPL renderer: a sampler, a visibility structure and a
//! shader on a backend, keeping their state (VPLs, shadow maps, the last
//! indirect image) from frame to frame.

use crate::backend::{Backend, CpuBackend};
use crate::compensation::Compensation;
use crate::error::RenderError;
use crate::frame::{FrameOutput, FrameRequest, FrameSettings, FrameStages, render_frame};
use crate::spec::{Clamp, ReadBack, ShadingSpec, VisibilitySpec};
use std::sync::atomic::AtomicBool;
use std::time::Instant;
use vpl_core::{Budget, Camera, GeometryClamp, Image, IndirectShader, Mode, Params, Scene, VplSampler, VplVisibility};
use vpl_sampling::Registry;

/// The sampler a [`RendererBuilder`] is given.
pub enum SamplerChoice {
    /// A registry name, built with the renderer's budget and the backend's
    /// services, its settings read from the builder's parameters.
    Named(String),
    /// A sampler built by the caller (for the renderer's budget: the
    /// caller's responsibility).
    Built(Box<dyn VplSampler>),
}

impl From<&str> for SamplerChoice {
    fn from(name: &str) -> SamplerChoice {
        SamplerChoice::Named(name.into())
    }
}

impl From<String> for SamplerChoice {
    fn from(name: String) -> SamplerChoice {
        SamplerChoice::Named(name)
    }
}

impl From<Box<dyn VplSampler>> for SamplerChoice {
    fn from(s: Box<dyn VplSampler>) -> SamplerChoice {
        SamplerChoice::Built(s)
    }
}

/// Builds a [`Renderer`]; every setting has the SMC paper's default.
pub struct RendererBuilder<'a> {
    scene: &'a Scene,
    budget: Budget,
    sampler: SamplerChoice,
    params: Params,
    registry: Option<&'a Registry>,
    visibility: VisibilitySpec,
    shading: ShadingSpec,
    clamp: Clamp,
    compensation: u32,
    mode: Mode,
    direct_samples: u32,
    seed: u64,
    backend: Option<Box<dyn Backend>>,
    read_back: ReadBack,
}

impl<'a> RendererBuilder<'a> {
    /// The VPL budget I (2048 by default).
    pub fn vpls(mut self, vpls: usize) -> Self {
        self.budget.vpls = vpls;
        self
    }

    /// The longest path in segments (5 by default: three indirect bounces).
    pub fn max_depth(mut self, max_depth: u32) -> Self {
        self.budget.max_depth = max_depth;
        self
    }

    /// Budget and depth at once.
    pub fn budget(mut self, budget: Budget) -> Self {
        self.budget = budget;
        self
    }

    /// The sampler: a registry name (`"smc"`) or a built sampler (`ir` by default).
    pub fn sampler(mut self, sampler: impl Into<SamplerChoice>) -> Self {
        self.sampler = sampler.into();
        self
    }

    /// Settings of a named sampler (`m-max=8`, …); a key it does not read is
    /// an error when the renderer is built.
    pub fn params(mut self, params: Params) -> Self {
        self.params = params;
        self
    }

    /// The registry named samplers come from ([`Registry::builtin`] by default).
    pub fn registry(mut self, registry: &'a Registry) -> Self {
        self.registry = Some(registry);
        self
    }

    /// VPL-to-pixel visibility (128² shadow maps by default).
    pub fn visibility(mut self, visibility: VisibilitySpec) -> Self {
        self.visibility = visibility;
        self
    }

    /// Indirect shading (interleaved and filtered by default).
    pub fn shader(mut self, shading: ShadingSpec) -> Self {
        self.shading = shading;
        self
    }

    /// The geometry-term clamp ([`Clamp::Auto`] by default).
    pub fn clamp(mut self, clamp: Clamp) -> Self {
        self.clamp = clamp;
        self
    }

    /// Bias compensation of the clamp with `gather_rays` rays per pixel
    /// (0, the default: none); see [`crate::compensation`].
    pub fn compensation(mut self, gather_rays: u32) -> Self {
        self.compensation = gather_rays;
        self
    }

    /// Which paths frames include (all by default).
    pub fn mode(mut self, mode: Mode) -> Self {
        self.mode = mode;
        self
    }

    /// Light samples per pixel of the direct light (16 by default).
    pub fn direct_samples(mut self, n: u32) -> Self {
        self.direct_samples = n;
        self
    }

    /// Seed of every random stream (0 by default).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// What frames on a device bring to the host ([`ReadBack::All`] by
    /// default).
    pub fn read_back(mut self, read_back: ReadBack) -> Self {
        self.read_back = read_back;
        self
    }

    /// Where the stages run ([`CpuBackend`] by default).
    pub fn backend(mut self, backend: impl Backend + 'static) -> Self {
        self.backend = Some(Box::new(backend));
        self
    }

    /// [`RendererBuilder::backend`] from a box.
    pub fn boxed_backend(mut self, backend: Box<dyn Backend>) -> Self {
        self.backend = Some(backend);
        self
    }

    /// Builds the renderer, or says what is wrong.
    pub fn build(self) -> Result<Renderer, RenderError> {
        if self.budget.vpls == 0 {
            return Err(RenderError::Invalid("the VPL budget must be at least 1".into()));
        }
        if self.budget.max_depth == 0 {
            return Err(RenderError::Invalid("the max depth must be at least 1".into()));
        }
        if self.direct_samples == 0 {
            return Err(RenderError::Invalid("direct light needs at least 1 sample per pixel".into()));
        }
        let backend = self.backend.unwrap_or_else(|| Box::new(CpuBackend));
        let sampler = match self.sampler {
            SamplerChoice::Built(s) => {
                let keys = self.params.unused();
                if !keys.is_empty() {
                    let keys = keys.into_iter().map(String::from).collect();
                    return Err(vpl_sampling::SamplingError::Unread { name: s.name().into(), keys, reads: Vec::new() }.into());
                }
                s
            }
            SamplerChoice::Named(name) => {
                let builtin;
                let registry = match self.registry {
                    Some(r) => r,
                    None => {
                        builtin = Registry::builtin();
                        &builtin
                    }
                };
                registry.build(&name, self.budget, &backend.services(), &self.params)?
            }
        };
        let visibility = backend.visibility(self.visibility, &self.budget)?;
        // A rule that needs no view is resolved now, and the shader built with
        // it; the view rule waits for the first frame's camera.
        let (clamp, shader) = match self.clamp.without_view(self.budget.vpls, self.scene) {
            Some(c) => (c, Some(backend.shader(self.shading, c, self.seed)?)),
            None => (None, None),
        };
        Ok(Renderer {
            budget: self.budget,
            mode: self.mode,
            direct_samples: self.direct_samples,
            seed: self.seed,
            clamp_rule: self.clamp,
            clamp,
            clamp_view: None,
            compensation: self.compensation,
            shading: self.shading,
            backend,
            sampler,
            visibility,
            shader,
            previous: None,
            read_back: self.read_back,
            last_on_device: false,
        })
    }
}

/// A VPL renderer: the sampler, visibility and shader keep their state
/// from frame to frame (unchanged VPLs keep their shadow maps; adaptive
/// samplers read the last frame's indirect image).
pub struct Renderer {
    budget: Budget,
    mode: Mode,
    direct_samples: u32,
    seed: u64,
    clamp_rule: Clamp,
    clamp: Option<GeometryClamp>,
    /// The camera the view rule's clamp was resolved for.
    clamp_view: Option<Camera>,
    compensation: u32,
    shading: ShadingSpec,
    backend: Box<dyn Backend>,
    sampler: Box<dyn VplSampler>,
    visibility: Box<dyn VplVisibility>,
    /// Built with the resolved clamp: at build time, or at the first frame
    /// under the view rule.
    shader: Option<Box<dyn IndirectShader>>,
    previous: Option<Image>,
    read_back: ReadBack,
    /// Whether the last frame left its image on the device.
    last_on_device: bool,
}

impl Renderer {
    /// A builder for frames of `scene` (the `auto` clamp reads its area).
    pub fn builder(scene: &Scene) -> RendererBuilder<'_> {
        // The settings a pipeline description leaves out; the backend is
        // the CPU unless one is given.
        let d = crate::PipelineSpec::default();
        RendererBuilder {
            scene,
            budget: d.budget,
            sampler: SamplerChoice::Named(d.sampler),
            params: d.params,
            registry: None,
            visibility: d.visibility,
            shading: d.shading,
            clamp: d.clamp,
            compensation: d.compensation,
            mode: d.mode,
            direct_samples: d.direct_samples,
            seed: d.seed,
            backend: None,
            read_back: ReadBack::All,
        }
    }

    /// Renders frame `index` (at `time` seconds) of `scene` seen by `camera`.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, index: u64, time: f32) -> Result<FrameOutput, RenderError> {
        self.render_cancellable(scene, camera, index, time, &AtomicBool::new(false))
    }

    /// [`Renderer::render`] that stops at the next stage boundary once
    /// `cancel` is set (from another thread) and answers
    /// [`RenderError::Cancelled`]; see [`FrameRequest::cancel`]
    /// for the boundaries. A cancelled frame may have advanced the sampler
    /// (and with it the visibility, which always matches the sampler's set)
    /// but leaves the previous frame's image, which adaptive samplers read,
    /// as it was. A frame that is not cancelled is [`Renderer::render`]'s.
    pub fn render_cancellable(
        &mut self,
        scene: &Scene,
        camera: &Camera,
        index: u64,
        time: f32,
        cancel: &AtomicBool,
    ) -> Result<FrameOutput, RenderError> {
        // The view rule follows the camera: resolved at the first frame and
        // again whenever the camera has moved.
        let view_rule = self.clamp_rule == Clamp::Auto;
        let moved = view_rule && self.clamp_view.as_ref() != Some(camera);
        if moved {
            self.clamp = self.clamp_rule.resolve(self.budget.vpls, scene, camera);
            self.clamp_view = Some(camera.clone());
        }
        let shader = match &mut self.shader {
            Some(shader) => {
                if moved {
                    shader.set_clamp(self.clamp);
                }
                shader
            }
            unbuilt => unbuilt.insert(self.backend.shader(self.shading, self.clamp, self.seed)?),
        };
        let compensation = match self.clamp {
            Some(clamp) if self.compensation > 0 => Some(Compensation { clamp, gather_rays: self.compensation }),
            _ => None,
        };
        let settings = FrameSettings {
            mode: self.mode,
            max_depth: self.budget.max_depth,
            direct_samples: self.direct_samples,
            seed: self.seed,
            index,
            time,
            compensation,
        };
        // The frame stays on the device where every stage runs there (see
        // ReadBack): the G-buffer is not read back, nor, under
        // ReadBack::Nothing, the image.
        // Emission and direct light are added on the device where the
        // shader can; else only an indirect frame stays there.
        let finishes = self.mode == Mode::Indirect || (self.mode != Mode::Direct && shader.finishes_on_device());
        let resident = self.read_back != ReadBack::All
            && finishes
            && compensation.is_none()
            && !self.sampler.reads_previous_image()
            && shader.on_device(self.visibility.as_ref());
        // A frame finished on the device (emission, direct light) is kept
        // there to be finished, and read back after under ReadBack::Image.
        let keep = resident && (self.read_back == ReadBack::Nothing || self.mode != Mode::Indirect);
        shader.keep_on_device(keep);
        let t0 = Instant::now();
        let gbuffer = match resident {
            true => self.backend.device_gbuffer(scene, camera)?,
            false => None,
        };
        let gbuffer = match gbuffer {
            Some(g) => g,
            None => self.backend.gbuffer(scene, camera)?,
        };
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut out = render_frame(
            FrameRequest::new(scene, camera, settings).previous(self.previous.as_ref()).gbuffer(gbuffer, ms).cancel(cancel),
            FrameStages { sampler: self.sampler.as_mut(), visibility: self.visibility.as_mut(), shader: shader.as_mut() },
        );
        if out.cancelled {
            return Err(RenderError::Cancelled { frame: index });
        }
        if let Some((stage, count)) = out.non_finite {
            return Err(RenderError::NonFinite { stage, count, frame: index });
        }
        self.last_on_device = !out.image.on_host();
        if self.last_on_device && self.read_back == ReadBack::Image {
            out.image = shader.read_image().unwrap_or(out.image);
        }
        self.previous = out.indirect.clone().filter(|i| i.on_host());
        Ok(out)
    }

    /// The last frame's image on the host, every light path of its mode:
    /// read back from the device when the frame was kept there
    /// ([`ReadBack::Nothing`], or a frame finished there), else a copy of
    /// [`FrameOutput::image`]'s indirect light; `None` before the first
    /// frame. Under [`ReadBack::Nothing`] this is the one read a caller
    /// pays for, when it wants the pixels (to write a file).
    pub fn read_image(&self) -> Option<Image> {
        if self.last_on_device { self.shader.as_ref()?.read_image() } else { self.previous.clone() }
    }

    /// The last frame's indirect light alone on the host
    /// ([`FrameOutput::indirect`]): read back from the device when the
    /// frame was kept there, else a copy; `None` before the first frame and
    /// for frames without one.
    pub fn read_indirect(&self) -> Option<Image> {
        if self.last_on_device { self.shader.as_ref()?.read_indirect() } else { self.previous.clone() }
    }

    /// What the next frames on a device bring to the host (see
    /// [`RendererBuilder::read_back`]); frames on the host are unchanged.
    pub fn set_read_back(&mut self, read_back: ReadBack) {
        self.read_back = read_back;
    }

    /// What frames on a device bring to the host.
    pub fn read_back(&self) -> ReadBack {
        self.read_back
    }

    /// The budget and depth every stage reads.
    pub fn budget(&self) -> Budget {
        self.budget
    }

    /// The geometry clamp of the shader: `None` when off, and under
    /// [`Clamp::Auto`] until the first frame; then the last frame's view's.
    pub fn clamp(&self) -> Option<GeometryClamp> {
        self.clamp
    }

    /// The rule the clamp follows.
    pub fn clamp_rule(&self) -> Clamp {
        self.clamp_rule
    }

    /// Gather rays per pixel of the clamp's bias compensation (0: none).
    pub fn compensation(&self) -> u32 {
        self.compensation
    }

    /// Which paths frames include.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The seed of every stream.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The backend.
    pub fn backend(&self) -> &dyn Backend {
        self.backend.as_ref()
    }

    /// The sampler.
    pub fn sampler(&self) -> &dyn VplSampler {
        self.sampler.as_ref()
    }

    /// The sampler, to change it between frames.
    pub fn sampler_mut(&mut self) -> &mut dyn VplSampler {
        self.sampler.as_mut()
    }

    /// The visibility structure.
    pub fn visibility(&self) -> &dyn VplVisibility {
        self.visibility.as_ref()
    }

    /// The indirect shader (`None` under [`Clamp::Auto`] before the first
    /// frame, which builds it with the clamp of its view).
    pub fn shader(&self) -> Option<&dyn IndirectShader> {
        self.shader.as_deref()
    }

    /// The last frame's indirect image.
    pub fn previous(&self) -> Option<&Image> {
        self.previous.as_ref()
    }
}

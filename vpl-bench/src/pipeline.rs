//! A VPL renderer assembled from names and settings: sampler, visibility,
//! shader. What `vpl render --method vpl` and `vpl sequence` run.

use vpl_core::{Camera, GeometryClamp, Image, IndirectShader, Mode, Scene, VplSampler, VplVisibility};
use vpl_sampling::SamplerConfig;
use vpl_shading::{ExhaustiveShader, FrameOutput, FrameSettings, InterleavedShader};
use vpl_visibility::{RayTraced, ShadowMaps};

/// VPL-to-pixel visibility.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VisibilitySpec {
    /// Exact BVH shadow rays.
    RayTraced,
    /// Paraboloid shadow maps of this side in texels.
    ShadowMaps(u32),
}

/// Indirect shading.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadingSpec {
    /// 4×4 interleaved subsets, with or without the cross-bilateral filter.
    Interleaved {
        /// Whether to filter.
        filter: bool,
    },
    /// Every VPL at every pixel.
    Exhaustive,
}

/// Everything that names a VPL renderer.
#[derive(Clone, Debug, PartialEq)]
pub struct PipelineSpec {
    /// Sampler name in the `vpl-sampling` registry.
    pub sampler: String,
    /// Its settings (budget, depth, …).
    pub config: SamplerConfig,
    /// Visibility.
    pub visibility: VisibilitySpec,
    /// Shading.
    pub shading: ShadingSpec,
    /// Geometry-term clamp.
    pub clamp: Option<GeometryClamp>,
    /// Which paths the frames include.
    pub mode: Mode,
    /// Light samples per pixel of direct light.
    pub direct_samples: u32,
    /// Seed of all streams.
    pub seed: u64,
}

/// A built VPL renderer; samplers and shadow maps keep their state from
/// frame to frame.
pub struct Pipeline {
    /// What it was built from.
    pub spec: PipelineSpec,
    /// The sampler.
    pub sampler: Box<dyn VplSampler>,
    /// The visibility structure.
    pub visibility: Box<dyn VplVisibility>,
    /// The shader.
    pub shader: Box<dyn IndirectShader>,
    /// The indirect image of the last frame, which the next frame's sampler reads.
    pub previous: Option<Image>,
}

impl Pipeline {
    /// Builds the pipeline, or says in one line what is wrong with the spec.
    pub fn new(spec: PipelineSpec) -> Result<Pipeline, String> {
        if spec.direct_samples == 0 {
            return Err("direct light needs at least 1 sample per pixel".into());
        }
        let sampler = vpl_sampling::build(&spec.sampler, &spec.config).map_err(|e| e.to_string())?;
        let visibility: Box<dyn VplVisibility> = match spec.visibility {
            VisibilitySpec::RayTraced => Box::new(RayTraced::default()),
            VisibilitySpec::ShadowMaps(res) => Box::new(ShadowMaps::new(res).map_err(|e| format!("shadow maps: {e}"))?),
        };
        let shader: Box<dyn IndirectShader> = match spec.shading {
            ShadingSpec::Exhaustive => Box::new(ExhaustiveShader { clamp: spec.clamp }),
            ShadingSpec::Interleaved { filter } => {
                let mut s = InterleavedShader::new(spec.clamp, spec.seed);
                if !filter {
                    s.filter = None;
                }
                Box::new(s)
            }
        };
        Ok(Pipeline { spec, sampler, visibility, shader, previous: None })
    }

    /// Renders frame `index` (at `time` seconds) of `scene` seen by `camera`.
    pub fn render(&mut self, scene: &Scene, camera: &Camera, index: u64, time: f32) -> FrameOutput {
        let settings = FrameSettings {
            mode: self.spec.mode,
            max_depth: self.spec.config.max_depth,
            direct_samples: self.spec.direct_samples,
            seed: self.spec.seed,
            index,
            time,
        };
        let out = vpl_shading::render_frame(scene, camera, settings, self.previous.as_ref(), self.sampler.as_mut(), self.visibility.as_mut(), self.shader.as_mut());
        self.previous = out.indirect.clone();
        out
    }
}

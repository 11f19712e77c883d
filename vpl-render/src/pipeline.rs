//! One description of a VPL pipeline: the sampler by name and its
//! parameters, the budget, visibility, shading, clamp, compensation, mode,
//! seed and the backend by name. The command line, Python and the
//! experiments describe renderers with it, store it and compare it; one
//! line of text is its written form (`Display` prints it, `FromStr` reads
//! it, serde goes through it):
//!
//! ```text
//! sampler=smc vpls=2048 max-depth=5 visibility=shadowmap:128 shading=interleaved clamp=auto
//! compensation=0 mode=full direct-samples=16 seed=0 backend=cpu m-max=8
//! ```
//!
//! Keys the pipeline does not read are the sampler's parameters, given
//! (an error when the sampler does not read them); `?key=value` offers a
//! value the sampler may ignore ([`Params::offer`]), and `param:key=value`
//! passes a parameter whose key the pipeline itself uses. A key left out
//! takes the default ([`PipelineSpec::default`]).
//!
//! ```
//! use vpl_render::{Backends, PipelineSpec, Registry, ShadingSpec};
//!
//! let spec: PipelineSpec = "sampler=ir vpls=64 shading=exhaustive mode=indirect fresh-paths=false".parse().unwrap();
//! assert_eq!(spec.shading, ShadingSpec::Exhaustive);
//! assert_eq!(spec.to_string().parse::<PipelineSpec>().unwrap().to_string(), spec.to_string());
//! let setup = vpl_core::SceneSetup::builtin("cornell").unwrap();
//! let renderer = spec.build(&Registry::builtin(), &Backends::builtin(), &setup.scene).unwrap();
//! assert_eq!(renderer.budget().vpls, 64);
//! ```

use crate::backends::Backends;
use crate::error::RenderError;
use crate::renderer::{Renderer, RendererBuilder};
use crate::spec::{Clamp, ShadingSpec, VisibilitySpec};
use std::fmt;
use std::str::FromStr;
use vpl_core::{Budget, Mode, Params, Scene};
use vpl_sampling::Registry;

/// Everything that names a VPL renderer.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct PipelineSpec {
    /// Sampler name in the registry.
    pub sampler: String,
    /// Its parameters (keys given must be read; offered ones may not be).
    pub params: Params,
    /// VPL slots and path depth.
    pub budget: Budget,
    /// Visibility.
    pub visibility: VisibilitySpec,
    /// Shading.
    pub shading: ShadingSpec,
    /// Geometry-term clamp: a value, or a rule the renderer resolves (the
    /// view rule follows the camera).
    pub clamp: Clamp,
    /// Gather rays per pixel of the clamp's bias compensation (0: none).
    pub compensation: u32,
    /// Which paths the frames include.
    pub mode: Mode,
    /// Light samples per pixel of direct light.
    pub direct_samples: u32,
    /// Seed of all streams.
    pub seed: u64,
    /// Where the stages run: a name in [`Backends`] (`cpu`, `gpu`).
    pub backend: String,
}

impl Default for PipelineSpec {
    /// IR with the papers' budget (2048 VPLs, max depth 5), 128² shadow
    /// maps, interleaved and filtered shading, the view's clamp, full light
    /// with 16 direct samples, seed 0, on the CPU: what
    /// [`Renderer::builder`] starts from too.
    fn default() -> Self {
        PipelineSpec {
            sampler: "ir".into(),
            params: Params::new(),
            budget: Budget::default(),
            visibility: VisibilitySpec::default(),
            shading: ShadingSpec::default(),
            clamp: Clamp::Auto,
            compensation: 0,
            mode: Mode::Full,
            direct_samples: 16,
            seed: 0,
            backend: "cpu".into(),
        }
    }
}

impl PipelineSpec {
    /// The renderer of this spec for frames of `scene`: its sampler from
    /// `registry`, its backend from `backends`.
    pub fn build(&self, registry: &Registry, backends: &Backends, scene: &Scene) -> Result<Renderer, RenderError> {
        self.builder(registry, scene).boxed_backend(backends.instantiate(&self.backend)?).build()
    }

    /// A builder with every setting of this spec but the backend, for a
    /// caller that holds its backend itself (the viewer, whose GPU backend
    /// shares the window's device).
    pub fn builder<'a>(&self, registry: &'a Registry, scene: &'a Scene) -> RendererBuilder<'a> {
        Renderer::builder(scene)
            .registry(registry)
            .budget(self.budget)
            .sampler(self.sampler.as_str())
            .params(self.params.clone())
            .visibility(self.visibility)
            .shader(self.shading)
            .clamp(self.clamp)
            .compensation(self.compensation)
            .mode(self.mode)
            .direct_samples(self.direct_samples)
            .seed(self.seed)
    }
}

/// The keys the pipeline reads itself, in the order they are written.
const KEYS: [&str; 11] =
    ["sampler", "vpls", "max-depth", "visibility", "shading", "clamp", "compensation", "mode", "direct-samples", "seed", "backend"];

impl fmt::Display for PipelineSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "sampler={} vpls={} max-depth={} visibility={} shading={} clamp={} compensation={} mode={} direct-samples={} seed={} backend={}",
            self.sampler,
            self.budget.vpls,
            self.budget.max_depth,
            self.visibility,
            self.shading,
            self.clamp,
            self.compensation,
            self.mode,
            self.direct_samples,
            self.seed,
            self.backend
        )?;
        for (k, v) in self.params.iter() {
            let prefix = if !self.params.is_given(k) {
                "?"
            } else if KEYS.contains(&k) {
                "param:"
            } else {
                ""
            };
            write!(f, " {prefix}{k}={v}")?;
        }
        Ok(())
    }
}

impl FromStr for PipelineSpec {
    type Err = String;
    fn from_str(text: &str) -> Result<Self, String> {
        let mut spec = PipelineSpec::default();
        let mut seen: Vec<&str> = Vec::new();
        for token in text.split_whitespace() {
            let (key, value) = token.split_once('=').ok_or_else(|| format!("pipeline: '{token}' is not key=value"))?;
            if let Some(k) = key.strip_prefix('?') {
                spec.params.offer(k, value);
                continue;
            }
            if let Some(k) = key.strip_prefix("param:") {
                spec.params.insert(k, value).map_err(|e| format!("pipeline: {e}"))?;
                continue;
            }
            if !KEYS.contains(&key) {
                spec.params.insert(key, value).map_err(|e| format!("pipeline: {e}"))?;
                continue;
            }
            if seen.contains(&key) {
                return Err(format!("pipeline: {key} is given twice"));
            }
            seen.push(key);
            let number = |what: &str| format!("pipeline: {key}={value}: {what}");
            match key {
                "sampler" => spec.sampler = value.to_string(),
                "vpls" => spec.budget.vpls = value.parse().map_err(|_| number("not a whole number"))?,
                "max-depth" => spec.budget.max_depth = value.parse().map_err(|_| number("not a whole number"))?,
                "visibility" => spec.visibility = value.parse().map_err(|e| format!("pipeline: {e}"))?,
                "shading" => spec.shading = value.parse().map_err(|e| format!("pipeline: {e}"))?,
                "clamp" => spec.clamp = value.parse().map_err(|e| format!("pipeline: {e}"))?,
                "compensation" => spec.compensation = value.parse().map_err(|_| number("not a whole number"))?,
                "mode" => spec.mode = value.parse().map_err(|e| format!("pipeline: {e}"))?,
                "direct-samples" => spec.direct_samples = value.parse().map_err(|_| number("not a whole number"))?,
                "seed" => spec.seed = value.parse().map_err(|_| number("not a whole number"))?,
                _ => spec.backend = value.to_string(),
            }
        }
        Ok(spec)
    }
}

impl TryFrom<String> for PipelineSpec {
    type Error = String;
    fn try_from(s: String) -> Result<Self, String> {
        s.parse()
    }
}

impl From<PipelineSpec> for String {
    fn from(spec: PipelineSpec) -> String {
        spec.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_written_form_keeps_every_field_and_parameter() {
        let mut spec = PipelineSpec {
            sampler: "tcas".into(),
            budget: Budget::new(512, 4),
            visibility: VisibilitySpec::RayTraced,
            shading: ShadingSpec::Interleaved { filter: false },
            clamp: Clamp::Value(vpl_core::GeometryClamp::new(2.5)),
            compensation: 2,
            mode: Mode::Indirect,
            direct_samples: 3,
            seed: 7,
            backend: "gpu".into(),
            ..PipelineSpec::default()
        };
        spec.params.insert("m-max", 8).unwrap();
        spec.params.insert("seed", 3).unwrap();
        spec.params.offer("fresh-paths", true);
        let text = spec.to_string();
        assert_eq!(
            text,
            "sampler=tcas vpls=512 max-depth=4 visibility=raytrace shading=interleaved-unfiltered clamp=2.5 compensation=2 \
             mode=indirect direct-samples=3 seed=7 backend=gpu m-max=8 param:seed=3 ?fresh-paths=true"
        );
        let back: PipelineSpec = text.parse().unwrap();
        assert_eq!(back.to_string(), text);
        assert!(back.params.is_given("seed") && !back.params.is_given("fresh-paths"));
        // Through serde: the same line.
        let json = serde_json::to_string(&spec).unwrap();
        assert_eq!(json, format!("\"{text}\""));
        let again: PipelineSpec = serde_json::from_str(&json).unwrap();
        assert_eq!(again.to_string(), text);
    }

    #[test]
    fn left_out_keys_take_the_defaults_and_bad_ones_are_named() {
        assert_eq!("".parse::<PipelineSpec>().unwrap().to_string(), PipelineSpec::default().to_string());
        for (bad, says) in [
            ("vpls=many", "vpls=many"),
            ("seed=1 seed=2", "twice"),
            ("clamp=areas", "clamp 'areas'"),
            ("visibility=shadowmap:0", "positive"),
            ("m-max", "key=value"),
            ("m-max=1 m-max=2", "m-max"),
            ("mode=both", "both"),
        ] {
            let e = bad.parse::<PipelineSpec>().unwrap_err();
            assert!(e.contains(says), "{bad}: {e}");
        }
        let e = serde_json::from_str::<PipelineSpec>("\"shading=fancy\"").unwrap_err().to_string();
        assert!(e.contains("fancy"), "{e}");
    }

    #[test]
    fn a_backend_not_in_the_build_is_named_when_built() {
        let setup = vpl_core::SceneSetup::builtin("cornell").unwrap();
        let spec: PipelineSpec = "sampler=ir vpls=8 backend=abacus".parse().unwrap();
        let e = spec.build(&Registry::builtin(), &Backends::builtin(), &setup.scene).err().unwrap().to_string();
        assert!(e.contains("abacus") && e.contains("cpu"), "{e}");
    }
}

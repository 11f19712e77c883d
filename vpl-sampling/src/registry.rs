//! The registry of samplers: a value users extend with their own.

use std::sync::Arc;
use vpl_core::{Budget, ParamError, ParamKey, Params, Services, SharedEstimator, VplSampler};

/// Errors of building a sampler from the registry.
#[derive(Debug, thiserror::Error)]
pub enum SamplingError {
    /// No sampler has this name.
    #[error("unknown sampler '{0}' (available: {1})")]
    Unknown(String, String),
    /// A sampler of this name is already registered.
    #[error("a sampler called '{0}' is already registered")]
    Duplicate(String),
    /// A parameter is malformed, out of range, or read by nobody.
    #[error("sampler '{name}': {source}")]
    Param {
        /// The sampler.
        name: String,
        /// What is wrong, naming the key.
        #[source]
        source: ParamError,
    },
    /// Keys were given that the sampler does not read.
    #[error("sampler '{name}' does not read {} (it reads: {})", keys.join(", "), if reads.is_empty() { "no keys".to_string() } else { reads.join(", ") })]
    Unread {
        /// The sampler.
        name: String,
        /// The keys it did not read.
        keys: Vec<String>,
        /// The keys its entry documents.
        reads: Vec<String>,
    },
    /// The budget does not suit the sampler (too shallow for VPLs, say).
    #[error("sampler '{0}': {1}")]
    Budget(String, String),
    /// The sampler's own constructor refused its settings.
    #[error("sampler '{name}': {source}")]
    Sampler {
        /// The sampler.
        name: String,
        /// Its error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl SamplingError {
    /// Wraps a sampler constructor's error.
    pub fn sampler(name: &str, source: impl std::error::Error + Send + Sync + 'static) -> SamplingError {
        SamplingError::Sampler { name: name.into(), source: Box::new(source) }
    }
}

/// What a sampler is built with: the renderer's budget and depth, the
/// backend's services, and the registry itself (for samplers that wrap
/// another one, as RR wraps its candidate source).
#[derive(Clone, Copy)]
pub struct SamplerContext<'a> {
    /// VPL slots and path depth, set once for the whole renderer.
    pub budget: Budget,
    /// Ray caster and radiosity estimators of the backend.
    pub services: &'a Services,
    /// The registry the sampler is being built from.
    pub registry: &'a Registry,
}

impl SamplerContext<'_> {
    /// An error when the depth leaves no indirect light for VPLs to carry.
    pub fn needs_indirect(&self, name: &str) -> Result<(), SamplingError> {
        if !self.budget.has_indirect() {
            return Err(SamplingError::Budget(
                name.into(),
                format!("max depth {} has no indirect light for VPLs to carry (at least 3)", self.budget.max_depth),
            ));
        }
        Ok(())
    }

    /// An error when the budget holds no VPL.
    pub fn needs_vpls(&self, name: &str) -> Result<(), SamplingError> {
        if self.budget.vpls == 0 {
            return Err(SamplingError::Budget(name.into(), "the VPL budget must be at least 1".into()));
        }
        Ok(())
    }

    /// A radiosity estimator of `paths` paths per estimate and at most
    /// `max_bounces` scattering vertices after the point: the backend's
    /// when it offers one, otherwise the CPU path tracer's.
    pub fn radiosity(&self, paths: u32, max_bounces: u32) -> SharedEstimator {
        match &self.services.radiosity {
            Some(make) => make.estimator(paths, max_bounces),
            None => Box::new(vpl_pathtrace::PathRadiosity { paths, max_bounces }),
        }
    }

    /// Builds the sampler `name` with these settings, reading from `params`
    /// (without checking that every key was read: the outer build does).
    pub fn build(&self, name: &str, params: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
        let entry = self.registry.entry(name)?;
        (entry.build)(self, params)
    }
}

/// The constructor of a registered sampler.
pub type BuildFn = dyn Fn(&SamplerContext, &Params) -> Result<Box<dyn VplSampler>, SamplingError> + Send + Sync;

/// The working memory a sampler's settings need beyond its VPLs, in parts
/// ([`SamplerEntry::with_memory`]): budget, parameters → parts.
pub type MemoryFn = dyn Fn(&Budget, &Params) -> Vec<MemoryPart> + Send + Sync;

/// One part of a sampler's working memory, for the estimate a tool checks
/// before it runs (`vpl --memory`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MemoryPart {
    /// What it is, in words (`SMC area probes: 2048 VPLs × 16 hits × 16 iterations`).
    pub what: String,
    /// Its bytes.
    pub bytes: u64,
    /// The settings that make it smaller (`vpls`, `resample-ratio`).
    pub keys: &'static [&'static str],
}

/// A sampler the registry can build by name.
#[derive(Clone)]
pub struct SamplerEntry {
    /// Name used on the command line and in experiment specs.
    pub name: String,
    /// One line about it.
    pub about: String,
    /// The parameters it reads: help texts, and the command line's flags.
    pub keys: Vec<ParamKey>,
    /// Its constructor.
    pub build: Arc<BuildFn>,
    /// Its working memory beyond the VPLs, where it is large enough to say.
    pub memory: Option<Arc<MemoryFn>>,
}

impl std::fmt::Debug for SamplerEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SamplerEntry").field("name", &self.name).field("about", &self.about).field("keys", &self.keys).finish()
    }
}

impl SamplerEntry {
    /// An entry called `name` that `build` constructs.
    pub fn new(
        name: impl Into<String>,
        about: impl Into<String>,
        build: impl Fn(&SamplerContext, &Params) -> Result<Box<dyn VplSampler>, SamplingError> + Send + Sync + 'static,
    ) -> SamplerEntry {
        SamplerEntry { name: name.into(), about: about.into(), keys: Vec::new(), build: Arc::new(build), memory: None }
    }

    /// The same entry, saying how much working memory its settings need
    /// (parts a tool adds to its estimate before it runs). Settings the
    /// sampler would refuse give no parts: building it says what is wrong.
    pub fn with_memory(mut self, memory: impl Fn(&Budget, &Params) -> Vec<MemoryPart> + Send + Sync + 'static) -> SamplerEntry {
        self.memory = Some(Arc::new(memory));
        self
    }

    /// The parts of [`SamplerEntry::with_memory`] for `budget` and `params`
    /// (none when the entry says nothing). Reading `params` here marks no
    /// key read.
    pub fn memory(&self, budget: &Budget, params: &Params) -> Vec<MemoryPart> {
        self.memory.as_ref().map_or_else(Vec::new, |m| m(budget, &params.clone()))
    }

    /// The same entry, documenting the keys it reads.
    pub fn with_keys(mut self, keys: &[ParamKey]) -> SamplerEntry {
        self.keys.extend_from_slice(keys);
        self
    }
}

/// Samplers by name: [`Registry::builtin`] holds the toolkit's, and
/// [`Registry::register`] adds a user's own, which every tool that takes a
/// registry (the renderer, `vpl`, Table 1, the benches) can then run.
#[derive(Clone, Debug, Default)]
pub struct Registry {
    entries: Vec<SamplerEntry>,
}

impl Registry {
    /// A registry with no samplers.
    pub fn empty() -> Registry {
        Registry::default()
    }

    /// The toolkit's samplers: `ir`, `rr`, `mir`, `mir-resample`, `tcas`, `smc`.
    pub fn builtin() -> Registry {
        let mut r = Registry::empty();
        for e in crate::builtin::entries() {
            r.register(e).expect("built-in names are distinct");
        }
        r
    }

    /// Adds `entry`; a name already taken is an error.
    pub fn register(&mut self, entry: SamplerEntry) -> Result<&mut Registry, SamplingError> {
        if self.entries.iter().any(|e| e.name == entry.name) {
            return Err(SamplingError::Duplicate(entry.name));
        }
        self.entries.push(entry);
        Ok(self)
    }

    /// [`Registry::register`] by value, for chaining.
    pub fn with(mut self, entry: SamplerEntry) -> Result<Registry, SamplingError> {
        self.register(entry)?;
        Ok(self)
    }

    /// Every entry, in the order registered.
    pub fn entries(&self) -> &[SamplerEntry] {
        &self.entries
    }

    /// The names, in the order registered.
    pub fn names(&self) -> Vec<&str> {
        self.entries.iter().map(|e| e.name.as_str()).collect()
    }

    /// Whether a sampler called `name` is registered.
    pub fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e.name == name)
    }

    /// The entry called `name`.
    pub fn entry(&self, name: &str) -> Result<&SamplerEntry, SamplingError> {
        self.entries.iter().find(|e| e.name == name).ok_or_else(|| SamplingError::Unknown(name.into(), self.names().join(", ")))
    }

    /// Builds the sampler `name` for `budget` with `services`, its settings
    /// read from `params`; a key of `params` that it does not read is an error.
    pub fn build(&self, name: &str, budget: Budget, services: &Services, params: &Params) -> Result<Box<dyn VplSampler>, SamplingError> {
        let cx = SamplerContext { budget, services, registry: self };
        let sampler = cx.build(name, params)?;
        let keys = params.unused();
        if !keys.is_empty() {
            let reads = self.entry(name)?.keys.iter().map(|k| k.key.to_string()).collect();
            return Err(SamplingError::Unread { name: name.into(), keys: keys.into_iter().map(String::from).collect(), reads });
        }
        Ok(sampler)
    }

    /// [`Registry::build`] on the CPU with default settings.
    pub fn build_default(&self, name: &str, budget: Budget) -> Result<Box<dyn VplSampler>, SamplingError> {
        self.build(name, budget, &Services::cpu(), &Params::new())
    }
}

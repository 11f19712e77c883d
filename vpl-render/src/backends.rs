//! Backends by name: what a pipeline description ([`crate::PipelineSpec`])
//! names in its `backend` field, and what the command line, Python and the
//! viewer offer. [`Backends::builtin`] holds the CPU; a crate with another
//! backend registers it (`vpl_gpu::register(&mut backends)` adds `gpu`),
//! so that no application matches on backend names itself. Every interface
//! also takes [`AUTO`]: the first device that opens, else the CPU.
//!
//! ```
//! use vpl_render::{Backends, CpuBackend};
//!
//! let mut backends = Backends::builtin();
//! backends.register("cpu-again", "the CPU under another name", || Ok(Box::new(CpuBackend)));
//! assert_eq!(backends.names(), ["cpu", "cpu-again"]);
//! assert_eq!(backends.instantiate("cpu-again").unwrap().name(), "cpu");
//! let e = backends.instantiate("tpu").err().unwrap().to_string();
//! assert!(e.contains("tpu") && e.contains("cpu, cpu-again"), "{e}");
//! ```

use crate::backend::{Backend, CpuBackend};
use crate::error::RenderError;

/// The name every interface accepts beside the registered ones: the first
/// backend that opens of [`Backends::auto_order`] (a device's when there is
/// one, else the CPU's).
pub const AUTO: &str = "auto";

/// Makes a backend (on a device: opens it).
pub type BackendFactory = fn() -> Result<Box<dyn Backend>, RenderError>;

/// One registered backend.
#[derive(Clone, Copy, Debug)]
pub struct BackendEntry {
    /// Its name (`cpu`, `gpu`): the one spelling every interface uses.
    pub name: &'static str,
    /// One line on what runs where.
    pub about: &'static str,
    /// Makes it.
    pub factory: BackendFactory,
}

/// The backends an application offers, by name, in the order registered.
#[derive(Clone, Debug, Default)]
pub struct Backends {
    entries: Vec<BackendEntry>,
    /// Known names this build lacks, with why (a backend compiled out).
    absent: Vec<(&'static str, String)>,
}

impl Backends {
    /// The CPU backend alone (`cpu`).
    pub fn builtin() -> Backends {
        let mut b = Backends::default();
        b.register("cpu", "the CPU stages of vpl-shading and vpl-visibility (rayon)", || Ok(Box::new(CpuBackend)));
        b
    }

    /// Adds (or replaces) the backend `name`.
    pub fn register(&mut self, name: &'static str, about: &'static str, factory: BackendFactory) -> &mut Backends {
        self.absent.retain(|(n, _)| *n != name);
        let entry = BackendEntry { name, about, factory };
        match self.entries.iter_mut().find(|e| e.name == name) {
            Some(e) => *e = entry,
            None => self.entries.push(entry),
        }
        self
    }

    /// Says that this build has no backend `name`, and why (e.g. "built
    /// without the `gpu` feature"): asking for it gives that reason
    /// rather than "unknown backend".
    pub fn absent(&mut self, name: &'static str, why: impl Into<String>) -> &mut Backends {
        if !self.entries.iter().any(|e| e.name == name) {
            self.absent.push((name, why.into()));
        }
        self
    }

    /// The registered names, in order.
    pub fn names(&self) -> Vec<&'static str> {
        self.entries.iter().map(|e| e.name).collect()
    }

    /// The entries, in order.
    pub fn entries(&self) -> &[BackendEntry] {
        &self.entries
    }

    /// What [`AUTO`] tries, in order: every registered backend but the
    /// CPU's (`cpu`), in the order registered (a device when there is
    /// one), then the CPU's.
    pub fn auto_order(&self) -> Vec<&BackendEntry> {
        let (cpu, devices): (Vec<&BackendEntry>, Vec<&BackendEntry>) = self.entries.iter().partition(|e| e.name == "cpu");
        devices.into_iter().chain(cpu).collect()
    }

    /// Whether `name` is registered.
    pub fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e.name == name)
    }

    /// The backend `name`, made anew; an unknown or absent name, or a
    /// device that cannot be opened, is a [`RenderError::Backend`] naming it.
    /// [`AUTO`] makes the first of [`Backends::auto_order`] that opens.
    pub fn instantiate(&self, name: &str) -> Result<Box<dyn Backend>, RenderError> {
        if name == AUTO {
            let mut why = Vec::new();
            for e in self.auto_order() {
                match (e.factory)() {
                    Ok(b) => return Ok(b),
                    Err(err) => why.push(format!("{}: {err}", e.name)),
                }
            }
            let message = format!("no backend opened ({})", why.join("; "));
            return Err(RenderError::Backend { backend: AUTO.to_string(), message });
        }
        self.entry(name).and_then(|e| (e.factory)())
    }

    /// The entry `name`; an unknown or absent name is a
    /// [`RenderError::Backend`] naming it ([`AUTO`] names no entry).
    pub fn entry(&self, name: &str) -> Result<&BackendEntry, RenderError> {
        if let Some(e) = self.entries.iter().find(|e| e.name == name) {
            return Ok(e);
        }
        let message = match self.absent.iter().find(|(n, _)| *n == name) {
            Some((_, why)) => format!("this build has no {name} backend ({why})"),
            None => format!("unknown backend (this build has: {AUTO}, {})", self.names().join(", ")),
        };
        Err(RenderError::Backend { backend: name.to_string(), message })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_absent_backend_says_why_and_a_registered_one_replaces_the_reason() {
        let mut b = Backends::builtin();
        b.absent("gpu", "built without the `gpu` feature");
        let e = b.instantiate("gpu").err().unwrap().to_string();
        assert!(e.contains("no gpu backend") && e.contains("`gpu` feature"), "{e}");
        b.register("gpu", "a stand-in", || Ok(Box::new(CpuBackend)));
        assert!(b.instantiate("gpu").is_ok());
        assert_eq!(b.names(), ["cpu", "gpu"]);
        // Registering a name again replaces it in place.
        b.register("cpu", "again", || Err(RenderError::Invalid("no".into())));
        assert_eq!(b.names(), ["cpu", "gpu"]);
        assert!(b.instantiate("cpu").is_err());
    }

    /// `auto` tries the devices in the order registered, then the CPU, and
    /// takes the first that opens.
    #[test]
    fn auto_takes_the_first_backend_that_opens_devices_first() {
        let mut b = Backends::builtin();
        assert_eq!(b.instantiate(AUTO).unwrap().name(), "cpu", "the CPU alone");
        b.register("dead", "a device that is not there", || Err(RenderError::Invalid("no adapter".into())));
        b.register("gpu", "a stand-in device", || Ok(Box::new(Named("gpu"))));
        assert_eq!(b.auto_order().iter().map(|e| e.name).collect::<Vec<_>>(), ["dead", "gpu", "cpu"]);
        assert_eq!(b.instantiate(AUTO).unwrap().name(), "gpu");
        b.register("gpu", "gone too", || Err(RenderError::Invalid("no adapter".into())));
        assert_eq!(b.instantiate(AUTO).unwrap().name(), "cpu");
        b.register("cpu", "gone as well", || Err(RenderError::Invalid("no threads".into())));
        let e = b.instantiate(AUTO).err().unwrap().to_string();
        assert!(e.contains("auto") && e.contains("dead: ") && e.contains("no threads"), "{e}");
    }

    /// The CPU backend under another name.
    struct Named(&'static str);

    impl Backend for Named {
        fn name(&self) -> &str {
            self.0
        }
        fn gbuffer(&self, scene: &vpl_core::Scene, camera: &vpl_core::Camera) -> Result<vpl_core::GBuffer, RenderError> {
            CpuBackend.gbuffer(scene, camera)
        }
        fn visibility(
            &self,
            spec: crate::VisibilitySpec,
            budget: &vpl_core::Budget,
        ) -> Result<Box<dyn vpl_core::VplVisibility>, RenderError> {
            CpuBackend.visibility(spec, budget)
        }
        fn shader(
            &self,
            spec: crate::ShadingSpec,
            clamp: Option<vpl_core::GeometryClamp>,
            seed: u64,
        ) -> Result<Box<dyn vpl_core::IndirectShader>, RenderError> {
            CpuBackend.shader(spec, clamp, seed)
        }
    }
}

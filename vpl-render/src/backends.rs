//! Backends by name: what a pipeline description ([`crate::PipelineSpec`])
//! names in its `backend` field, and what the command line, Python and the
//! viewer offer. [`Backends::builtin`] holds the CPU; a crate with another
//! backend registers it (`vpl_gpu::register(&mut backends)` adds `gpu`),
//! so that no application matches on backend names itself.
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

    /// Whether `name` is registered.
    pub fn contains(&self, name: &str) -> bool {
        self.entries.iter().any(|e| e.name == name)
    }

    /// The backend `name`, made anew; an unknown or absent name, or a
    /// device that cannot be opened, is a [`RenderError::Backend`] naming it.
    pub fn instantiate(&self, name: &str) -> Result<Box<dyn Backend>, RenderError> {
        if let Some(e) = self.entries.iter().find(|e| e.name == name) {
            return (e.factory)();
        }
        let message = match self.absent.iter().find(|(n, _)| *n == name) {
            Some((_, why)) => format!("this build has no {name} backend ({why})"),
            None => format!("unknown backend (this build has: {})", self.names().join(", ")),
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
}

//! A scene's folder is its sandbox: the files a scene file names (a TOML's
//! model, an OBJ's material libraries, glTF buffers and images, Mitsuba
//! includes, meshes and bitmaps) must lie inside the folder of the file the
//! user named, or inside a root the user allowed ([`LoadOptions::allow_outside`],
//! `--allow-outside` on the command line).
//!
//! A reference is resolved against the folder of the file that holds it,
//! then made canonical (`..` and symbolic links resolved), and refused unless
//! the canonical path lies under one of the canonical roots. So `../x`,
//! `/etc/passwd`, `file:///etc/passwd` and a link inside the folder that
//! points out of it are all refused, naming the reference as written. The
//! check is made on the path that is then read; a file system that another
//! process changes between the check and the read is outside what this
//! guards.

use crate::error::{Result, SceneIoError};
use std::path::{Path, PathBuf};
use vpl_core::CoreError;

/// How a scene is loaded: which folders besides its own its files may read,
/// and how much memory loading may take.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// Folders (with everything under them) that a scene's files may name
    /// besides the scene's own folder.
    pub allow_outside: Vec<PathBuf>,
    /// The most bytes one decoded image or one mesh buffer may take while
    /// loading (`--memory-limit`); `None` leaves only the input limits of
    /// [`crate::input`].
    pub memory_limit: Option<u64>,
}

impl LoadOptions {
    /// Options that allow references under `root` besides the scene's folder.
    pub fn allowing(root: impl Into<PathBuf>) -> LoadOptions {
        LoadOptions { allow_outside: vec![root.into()], memory_limit: None }
    }
}

/// The folders a scene's references may reach, made canonical once.
#[derive(Clone, Debug)]
pub struct Sandbox {
    roots: Vec<PathBuf>,
    memory_limit: Option<u64>,
}

impl Sandbox {
    /// The sandbox of the scene file `scene` (which the user named: it may
    /// lie anywhere): its folder and the options' allowed roots.
    pub fn for_scene(scene: &Path, options: &LoadOptions) -> Result<Sandbox> {
        Sandbox::for_folder(&crate::input::folder_of(scene), options)
    }

    /// The sandbox of a scene whose own folder is `folder`.
    pub fn for_folder(folder: &Path, options: &LoadOptions) -> Result<Sandbox> {
        let mut roots = vec![canonical(folder)?];
        for root in &options.allow_outside {
            let c = canonical(root).map_err(|e| CoreError::Invalid(format!("--allow-outside {}: {e}", root.display())))?;
            roots.push(c);
        }
        Ok(Sandbox { roots, memory_limit: options.memory_limit })
    }

    /// The memory limit of [`LoadOptions::memory_limit`].
    pub fn memory_limit(&self) -> Option<u64> {
        self.memory_limit
    }

    /// The path of `reference` (as written in a scene file: a path relative
    /// to `from`, the folder of the file that holds it, or an absolute one)
    /// joined to `from`, if its canonical form lies inside the sandbox.
    ///
    /// Refuses a reference that leaves every root ([`SceneIoError::OutsideScene`])
    /// and one that names nothing ([`SceneIoError::Read`], naming the path).
    pub fn resolve(&self, from: &Path, reference: &str) -> Result<PathBuf> {
        if reference.is_empty() {
            return Err(CoreError::Invalid("an empty file name".into()).into());
        }
        if reference.contains('\0') {
            return Err(CoreError::Invalid(format!("the file name {reference:?} holds a NUL byte")).into());
        }
        let joined = from.join(reference);
        let outside = || SceneIoError::OutsideScene { reference: reference.to_string(), root: self.roots[0].clone() };
        // First by the names alone, so that whether a file outside exists
        // is never looked at (an error could tell it); then with links
        // resolved.
        let lexical = lexically_normal(&canonical(from)?.join(reference));
        if !self.roots.iter().any(|r| lexical.starts_with(r)) {
            return Err(outside());
        }
        let path = canonical(&joined)?;
        if self.roots.iter().any(|r| path.starts_with(r)) { Ok(joined) } else { Err(outside()) }
    }
}

/// `path` with `.` and `..` taken away by name (a `..` at the root stays
/// at the root).
fn lexically_normal(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir => {}
            c => out.push(c),
        }
    }
    out
}

/// `path` with `..` and links resolved; an error naming `path` when it does
/// not exist.
fn canonical(path: &Path) -> Result<PathBuf> {
    let p = if path.as_os_str().is_empty() { Path::new(".") } else { path };
    std::fs::canonicalize(p).map_err(|source| SceneIoError::Read { path: path.into(), source })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn references_stay_in_the_scene_folder_unless_a_root_allows_them() {
        let dir = tempfile::tempdir().unwrap();
        let scene = dir.path().join("scene");
        std::fs::create_dir_all(scene.join("sub")).unwrap();
        std::fs::write(scene.join("sub/mesh.bin"), b"x").unwrap();
        std::fs::write(dir.path().join("secret"), b"s").unwrap();
        let file = scene.join("a.gltf");
        let sandbox = Sandbox::for_scene(&file, &LoadOptions::default()).unwrap();
        let inside = sandbox.resolve(&scene, "sub/mesh.bin").unwrap();
        assert!(inside.ends_with("sub/mesh.bin"));
        // `..` that stays inside is fine.
        assert!(sandbox.resolve(&scene.join("sub"), "../sub/mesh.bin").is_ok());
        let secret = dir.path().join("secret");
        for reference in ["../secret", secret.to_str().unwrap()] {
            let e = sandbox.resolve(&scene, reference).unwrap_err();
            assert!(matches!(e, SceneIoError::OutsideScene { .. }), "{e}");
            assert!(e.to_string().contains(reference) && e.to_string().contains("--allow-outside"), "{e}");
        }
        // A link inside the folder that points out of it.
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(&secret, scene.join("link")).unwrap();
            assert!(matches!(sandbox.resolve(&scene, "link").unwrap_err(), SceneIoError::OutsideScene { .. }));
        }
        let allowed = Sandbox::for_scene(&file, &LoadOptions::allowing(dir.path())).unwrap();
        assert!(allowed.resolve(&scene, "../secret").is_ok());
        // Outside and missing: refused as outside, so an error never tells
        // whether a file outside exists.
        let e = sandbox.resolve(&scene, "../no/such/file").unwrap_err();
        assert!(matches!(e, SceneIoError::OutsideScene { .. }), "{e}");
        // A missing file is named; a missing root is refused as a bad option.
        let e = sandbox.resolve(&scene, "nothing.bin").unwrap_err();
        assert!(e.to_string().contains("nothing.bin"), "{e}");
        let e = Sandbox::for_scene(&file, &LoadOptions::allowing(dir.path().join("nope"))).unwrap_err();
        assert!(e.to_string().contains("--allow-outside"), "{e}");
    }
}

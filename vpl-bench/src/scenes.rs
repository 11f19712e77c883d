//! Where the scene files of the real-scene rows are found, at run time.
//!
//! Table 1's rows on real geometry (and `bench-rays`' Sponza) read scene
//! files such as `sponza-dabrovic.toml`, which the repository keeps in
//! `scenes/` and which name their models by paths relative to themselves.
//! A `vpl` binary may run far from the folder it was built in (installed
//! with `cargo install`, copied to a cluster), so the folder is looked up
//! when a file is asked for, in this order:
//!
//! 1. the folder given to [`set_dir`] (the command line's `--scenes-dir DIR`);
//! 2. the folder named by the environment variable `VPL_SCENES`;
//! 3. `scenes/` in the working folder or the nearest folder above it that
//!    has one holding the file (a checkout of the repository, from any of
//!    its subfolders);
//! 4. `scenes/` in the folder of the executable or one above it (a release
//!    folder with `bin/` and `scenes/` side by side, or `target/release/`
//!    inside a checkout).
//!
//! A folder given by 1 or 2 is the only one tried: a wrong one is an error,
//! never a silent fallback. When no folder holds the file the error names
//! what was tried and how to point at the right one.

use std::path::{Path, PathBuf};
use std::sync::RwLock;

/// The environment variable naming the folder of scene files.
pub const ENV: &str = "VPL_SCENES";

/// The folder set by [`set_dir`].
static DIR: RwLock<Option<PathBuf>> = RwLock::new(None);

/// Makes `dir` the folder of scene files (`None`: look them up as the module
/// says). The command line sets it from `--scenes-dir` on every run.
pub fn set_dir(dir: Option<PathBuf>) {
    // A poisoned lock only means a panic elsewhere while it was held; the
    // value is a plain path either way.
    *DIR.write().unwrap_or_else(|e| e.into_inner()) = dir;
}

/// The folder set by [`set_dir`], if any.
fn given_dir() -> Option<PathBuf> {
    DIR.read().unwrap_or_else(|e| e.into_inner()).clone()
}

/// The path of scene file `file` (e.g. `sponza-dabrovic.toml`), or why it
/// cannot be found (one line).
pub fn locate(file: &str) -> Result<PathBuf, String> {
    let named = given_dir()
        .map(|d| (d, "--scenes-dir"))
        .or_else(|| std::env::var_os(ENV).filter(|v| !v.is_empty()).map(|v| (PathBuf::from(v), ENV)));
    let starts = [std::env::current_dir().ok(), std::env::current_exe().ok().and_then(|e| e.parent().map(Path::to_path_buf))];
    lookup(file, named, &starts.into_iter().flatten().collect::<Vec<_>>())
}

/// [`locate`] with the named folder (and what named it) and the folders
/// whose ancestors are searched given.
fn lookup(file: &str, named: Option<(PathBuf, &str)>, starts: &[PathBuf]) -> Result<PathBuf, String> {
    if let Some((dir, by)) = named {
        let path = dir.join(file);
        return if path.is_file() {
            Ok(path)
        } else {
            Err(format!("{file} is not in {} (the folder of scene files {by} names)", dir.display()))
        };
    }
    let mut tried = Vec::new();
    for start in starts {
        for dir in start.ancestors() {
            let path = dir.join("scenes").join(file);
            if path.is_file() {
                return Ok(path);
            }
        }
        tried.push(start.display().to_string());
    }
    Err(format!(
        "{file} is in no scenes/ folder at or above {}: name the folder of scene files with --scenes-dir DIR or {ENV}",
        if tried.is_empty() { "the working folder or the executable".to_string() } else { tried.join(" or ") }
    ))
}

/// Why the scene file at `path` cannot be loaded here: it cannot be read,
/// or the model it names is not where it says; `None` when it can.
pub fn model_missing(path: &Path) -> Option<String> {
    let described = match vpl_scene_io::read_scene_file(path) {
        Ok(f) => f,
        Err(e) => return Some(format!("{}: {e}", path.display())),
    };
    let model = described.geometry.obj.or(described.geometry.gltf).or(described.geometry.mitsuba)?;
    let model = path.parent().unwrap_or(Path::new(".")).join(model);
    (!model.is_file()).then(|| format!("its model {} is not there", model.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_named_folder_is_the_only_one_tried_else_the_nearest_scenes_folder_above() {
        let root = std::env::temp_dir().join(format!("vpl-scenes-{}", std::process::id()));
        let (named, deep, other) = (root.join("named"), root.join("a/b/c"), root.join("other"));
        for d in [&named, &deep, &other, &root.join("a/scenes")] {
            std::fs::create_dir_all(d).unwrap();
        }
        std::fs::write(named.join("x.toml"), "").unwrap();
        std::fs::write(root.join("a/scenes/y.toml"), "").unwrap();
        let by = |d: &PathBuf| Some((d.clone(), "--scenes-dir"));
        assert_eq!(lookup("x.toml", by(&named), std::slice::from_ref(&deep)), Ok(named.join("x.toml")));
        // A named folder without the file is an error, though a scenes/
        // above the working folder holds it.
        let e = lookup("y.toml", by(&named), std::slice::from_ref(&deep)).unwrap_err();
        assert!(e.contains("--scenes-dir") && e.contains(&named.display().to_string()), "{e}");
        assert_eq!(lookup("y.toml", None, &[other.clone(), deep.clone()]), Ok(root.join("a/scenes/y.toml")));
        let e = lookup("z.toml", None, &[other.clone(), deep.clone()]).unwrap_err();
        assert!(e.contains("--scenes-dir DIR") && e.contains(ENV) && e.contains(&other.display().to_string()), "{e}");
        std::fs::remove_dir_all(&root).unwrap();
    }

    #[test]
    fn a_scene_file_whose_model_is_elsewhere_says_so() {
        let root = std::env::temp_dir().join(format!("vpl-scenes-model-{}", std::process::id()));
        std::fs::create_dir_all(&root).unwrap();
        let file = root.join("s.toml");
        std::fs::write(&file, "[geometry]\nobj = \"models/m.obj\"\n").unwrap();
        let why = model_missing(&file).expect("no model");
        assert!(why.contains("models/m.obj"), "{why}");
        std::fs::create_dir_all(root.join("models")).unwrap();
        std::fs::write(root.join("models/m.obj"), "v 0 0 0\n").unwrap();
        assert_eq!(model_missing(&file), None);
        assert!(model_missing(&root.join("absent.toml")).is_some());
        std::fs::remove_dir_all(&root).unwrap();
    }
}

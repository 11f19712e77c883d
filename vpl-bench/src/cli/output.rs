//! What every subcommand promises about its outputs:
//!
//! - an image's format follows its extension: `.exr` writes the EXR and a
//!   PNG preview beside it (same stem), `.png` writes the PNG only, anything
//!   else is an error before any work;
//! - `--out`, `--stderr` and the previews are distinct files;
//! - no image with a NaN or infinite pixel is written: the command fails
//!   naming the stage that produced it;
//! - a command that fails leaves none of its outputs behind: files it wrote
//!   are removed ([`Written`]), and a folder it created is removed with its
//!   contents ([`OutDir`]); in a folder that existed, the files it added.

use super::Res;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use vpl_core::Image;
use vpl_core::image::preview_path;

/// An image output and, for `.exr`, its PNG preview.
#[derive(Clone, Debug)]
pub(super) struct ImageOut {
    /// The file named on the command line.
    pub path: PathBuf,
    /// The preview written beside an EXR.
    pub preview: Option<PathBuf>,
}

impl ImageOut {
    /// The output `flag` names; `preview`: whether an EXR gets a PNG beside it.
    pub fn new(flag: &str, path: &Path, preview: bool) -> Res<ImageOut> {
        super::check_writable(path)?;
        let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        let out = match ext.as_deref() {
            Some("exr") => ImageOut { path: path.into(), preview: preview.then(|| preview_path(path)) },
            Some("png") => ImageOut { path: path.into(), preview: None },
            _ => return Err(format!("{flag} {}: the name must end in .exr (EXR and a PNG preview) or .png (PNG only)", path.display())),
        };
        if let Some(p) = &out.preview {
            super::check_writable(p)?;
        }
        Ok(out)
    }
}

/// The path `p` resolves to, for comparing outputs: its folder made
/// absolute and free of `..` and links where the folder exists.
fn resolved(p: &Path) -> PathBuf {
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let dir = dir.canonicalize().unwrap_or_else(|_| dir.to_path_buf());
    match p.file_name() {
        Some(name) => dir.join(name),
        None => dir,
    }
}

/// Fails when two of the named outputs are one file.
pub(super) fn distinct(outputs: &[(&str, &Path)]) -> Res<()> {
    for (i, (fa, a)) in outputs.iter().enumerate() {
        for (fb, b) in &outputs[i + 1..] {
            if resolved(a) == resolved(b) {
                return Err(format!("{fa} and {fb} name the same file {}: each output needs its own name", a.display()));
            }
        }
    }
    Ok(())
}

/// Fails when `img` holds NaN or infinite pixels, naming `stage` and the first one.
pub(super) fn check_finite(img: &Image, stage: &str) -> Res<()> {
    match img.data.iter().position(|p| !p.is_finite()) {
        None => Ok(()),
        Some(i) => {
            let w = img.width.max(1) as usize;
            let bad = vpl_render::count_non_finite(img);
            Err(format!("{stage} produced {bad} non-finite pixel(s) (first at {}, {}); nothing written", i % w, i / w))
        }
    }
}

/// Outputs of commands in progress, removed if the process is interrupted
/// (see [`interrupted`]).
static IN_PROGRESS: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

fn track(p: &Path) {
    IN_PROGRESS.lock().unwrap_or_else(|e| e.into_inner()).push(p.into());
}

fn untrack(p: &Path) {
    IN_PROGRESS.lock().unwrap_or_else(|e| e.into_inner()).retain(|q| q != p);
}

/// On SIGINT or SIGTERM: removes the temporary files of writes in progress
/// and the outputs of the command that did not finish.
pub(super) fn interrupted() {
    vpl_core::image::remove_temporaries();
    for p in IN_PROGRESS.lock().unwrap_or_else(|e| e.into_inner()).iter() {
        if p.is_dir() {
            let _ = std::fs::remove_dir_all(p);
        } else {
            let _ = std::fs::remove_file(p);
        }
    }
}

/// The files a command wrote; unless [`Written::keep`] is called, dropping it
/// (a failure returned with `?`, or a panic) removes them.
#[derive(Default)]
pub(super) struct Written {
    files: Vec<PathBuf>,
    kept: bool,
}

impl Written {
    /// Writes `img` to `out` (and its preview at `exposure`) after checking
    /// that every pixel is finite.
    pub fn image(&mut self, img: &Image, out: &ImageOut, exposure: f32, stage: &str) -> Res<()> {
        check_finite(img, stage)?;
        let exr = out.path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        if exr {
            img.write_exr(&out.path).map_err(|e| e.to_string())?;
        } else {
            img.write_png(&out.path, exposure).map_err(|e| e.to_string())?;
        }
        self.files.push(out.path.clone());
        track(&out.path);
        if let Some(p) = &out.preview {
            img.write_png(p, exposure).map_err(|e| e.to_string())?;
            self.files.push(p.clone());
            track(p);
        }
        Ok(())
    }

    /// The command succeeded: keep the files.
    pub fn keep(mut self) {
        self.kept = true;
    }
}

impl Drop for Written {
    fn drop(&mut self) {
        for f in &self.files {
            untrack(f);
            if !self.kept {
                let _ = std::fs::remove_file(f);
            }
        }
    }
}

/// An output folder. Unless [`OutDir::keep`] is called, dropping it removes
/// the folder when the command created it, and otherwise the files the
/// command added to it.
pub(super) struct OutDir {
    path: PathBuf,
    created: bool,
    before: BTreeSet<PathBuf>,
    kept: bool,
}

impl OutDir {
    /// Creates `path` (with its parents) unless it is a folder already.
    pub fn create(flag: &str, path: &Path) -> Res<OutDir> {
        if path.exists() && !path.is_dir() {
            return Err(format!("{flag} {} is not a directory", path.display()));
        }
        let created = !path.exists();
        let before = listing(path);
        std::fs::create_dir_all(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        if created {
            track(path);
        }
        Ok(OutDir { path: path.into(), created, before, kept: false })
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The command succeeded: keep what it wrote.
    pub fn keep(mut self) {
        self.kept = true;
    }
}

fn listing(dir: &Path) -> BTreeSet<PathBuf> {
    std::fs::read_dir(dir).map(|r| r.flatten().map(|e| e.path()).collect()).unwrap_or_default()
}

impl Drop for OutDir {
    fn drop(&mut self) {
        untrack(&self.path);
        if self.kept {
            return;
        }
        if self.created {
            let _ = std::fs::remove_dir_all(&self.path);
        } else {
            for p in listing(&self.path).difference(&self.before) {
                if p.is_dir() {
                    let _ = std::fs::remove_dir_all(p);
                } else {
                    let _ = std::fs::remove_file(p);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extensions_decide_the_format_and_outputs_must_differ() {
        assert!(ImageOut::new("--out", Path::new("r.exr"), true).unwrap().preview.is_some());
        assert!(ImageOut::new("--out", Path::new("r.PNG"), true).unwrap().preview.is_none());
        let e = ImageOut::new("--out", Path::new("r.tif"), true).unwrap_err();
        assert!(e.contains(".exr") && e.contains(".png"), "{e}");
        assert!(ImageOut::new("--out", Path::new("r"), true).is_err());
        assert!(ImageOut::new("--out", Path::new("/"), true).unwrap_err().contains("cannot write"));
        assert!(distinct(&[("--out", Path::new("a.exr")), ("--stderr", Path::new("./a.exr"))]).is_err());
        assert!(distinct(&[("--out", Path::new("a.exr")), ("--stderr", Path::new("b.exr"))]).is_ok());
    }

    #[test]
    fn failed_commands_leave_nothing() {
        let root = std::env::temp_dir().join(format!("vpl-out-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        {
            let d = OutDir::create("--out", &root.join("new")).unwrap();
            std::fs::write(d.path().join("x.csv"), "1").unwrap();
        }
        assert!(!root.join("new").exists());
        std::fs::create_dir_all(root.join("old")).unwrap();
        std::fs::write(root.join("old/mine.txt"), "keep").unwrap();
        {
            let d = OutDir::create("--out", &root.join("old")).unwrap();
            std::fs::write(d.path().join("x.csv"), "1").unwrap();
        }
        assert!(root.join("old/mine.txt").exists() && !root.join("old/x.csv").exists());
        let out = ImageOut::new("--out", &root.join("old/r.exr"), true).unwrap();
        let mut img = Image::new(2, 1);
        {
            let mut w = Written::default();
            w.image(&img, &out, 1.0, "test").unwrap();
            assert!(root.join("old/r.exr").exists() && root.join("old/r.png").exists());
        }
        assert!(!root.join("old/r.exr").exists() && !root.join("old/r.png").exists());
        img.data[1].y = f32::NAN;
        let e = Written::default().image(&img, &out, 1.0, "indirect shading").unwrap_err();
        assert!(e.starts_with("indirect shading produced 1 non-finite pixel(s) (first at 1, 0)"), "{e}");
        assert!(!root.join("old/r.exr").exists());
        std::fs::remove_dir_all(&root).unwrap();
    }
}

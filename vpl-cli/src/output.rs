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
use std::path::{Path, PathBuf};
use vpl_core::Image;
use vpl_core::image::preview_path;
use vpl_scene_io::ImageFile;

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

/// The files a command writes, staged beside their names
/// ([`vpl_core::image::Staging`]): [`Written::keep`] renames all of them
/// into place at once; dropping it (a failure returned with `?`, or a
/// panic) removes the staged files and leaves the earlier files as they
/// were. A re-render whose `--stderr` cannot be written keeps the earlier
/// `--out`.
#[derive(Default)]
pub(super) struct Written {
    staging: vpl_core::image::Staging,
}

impl Written {
    /// Stages `img` for `out` (and its preview at `exposure`) after checking
    /// that every pixel is finite.
    pub fn image(&mut self, img: &Image, out: &ImageOut, exposure: f32, stage: &str) -> Res<()> {
        check_finite(img, stage)?;
        let exr = out.path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
        let bytes = if exr { img.encode_exr()? } else { img.encode_png(exposure)? };
        self.staging.stage(&out.path, &bytes).map_err(|e| e.to_string())?;
        if let Some(p) = &out.preview {
            self.staging.stage(p, &img.encode_png(exposure)?).map_err(|e| e.to_string())?;
        }
        Ok(())
    }

    /// The command succeeded: every staged file takes its place.
    pub fn keep(self) -> Res<()> {
        self.staging.commit().map_err(|e| e.to_string())
    }
}

/// An output folder. A new folder is made and written directly; dropping
/// it without [`OutDir::keep`] removes it. Into a folder that exists, the
/// command writes a staging folder inside it (`.vpl-staging.PID`), and
/// [`OutDir::keep`] moves what it holds into place, all or none (a file it
/// replaces is restored if a later move fails); dropping it without
/// `keep` removes the staging folder, so a failed or interrupted command
/// leaves the folder as it was, its earlier frames included.
pub(super) struct OutDir {
    /// The folder the user named.
    target: PathBuf,
    /// Where the command writes: `target` when the command made it, else
    /// the staging folder inside it.
    path: PathBuf,
    created: bool,
    kept: bool,
}

impl OutDir {
    /// Creates `path` (with its parents) unless it is a folder already, and
    /// a staging folder inside it when it was.
    pub fn create(flag: &str, path: &Path) -> Res<OutDir> {
        if path.exists() && !path.is_dir() {
            return Err(format!("{flag} {} is not a directory", path.display()));
        }
        let created = !path.exists();
        std::fs::create_dir_all(path).map_err(|e| format!("cannot create {}: {e}", path.display()))?;
        let write_to = if created { path.to_path_buf() } else { path.join(format!("{STAGING}{}", std::process::id())) };
        if !created {
            remove_stale_staging(path);
            let _ = std::fs::remove_dir_all(&write_to);
            std::fs::create_dir(&write_to).map_err(|e| format!("cannot write into {}: {e}", path.display()))?;
        }
        track(&write_to);
        Ok(OutDir { target: path.into(), path: write_to, created, kept: false })
    }

    /// The folder the command writes into (the staging folder when the
    /// named folder existed before).
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The command succeeded: what it wrote takes its place.
    pub fn keep(mut self) -> Res<()> {
        self.kept = true;
        if self.created {
            untrack(&self.path);
            return Ok(());
        }
        let result = commit_tree(&self.path, &self.target);
        // Tracked until here: an interrupt before the commit removes it.
        untrack(&self.path);
        let _ = std::fs::remove_dir_all(&self.path);
        result
    }
}

impl Drop for OutDir {
    fn drop(&mut self) {
        if !self.kept {
            untrack(&self.path);
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// The name of a staging folder, before its process id.
const STAGING: &str = ".vpl-staging.";

/// Removes the staging folders in `dir` of processes that no longer run
/// (killed with SIGKILL, or a machine that went down). Where the process
/// table cannot be read (no `/proc`), nothing is removed.
fn remove_stale_staging(dir: &Path) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = name.strip_prefix(STAGING).and_then(|p| p.parse::<u32>().ok()) else { continue };
        if pid != std::process::id() && !Path::new("/proc").join(pid.to_string()).exists() && e.path().is_dir() {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// Moves every file under `from` to the same place under `to`, all or
/// none, through [`vpl_core::image::Staging`]: folders are made as needed,
/// a file in the way is kept under a backup name until every move
/// succeeded, and on a failure the moved files go back, the backups are
/// restored and the made folders removed.
fn commit_tree(from: &Path, to: &Path) -> Res<()> {
    let mut moves = Vec::new();
    collect_files(from, to, &mut moves).map_err(|e| format!("cannot read {}: {e}", from.display()))?;
    let mut staging = vpl_core::image::Staging::new();
    for (src, dst) in moves {
        staging.adopt(&dst, src).map_err(|e| e.to_string())?;
    }
    staging.commit().map_err(|e| e.to_string())
}

/// The files under `from` (recursively) with their places under `to`.
fn collect_files(from: &Path, to: &Path, out: &mut Vec<(PathBuf, PathBuf)>) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(from)?.collect::<std::io::Result<_>>()?;
    entries.sort_by_key(|e| e.file_name());
    for e in entries {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if e.file_type()?.is_dir() {
            collect_files(&src, &dst, out)?;
        } else {
            out.push((src, dst));
        }
    }
    Ok(())
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
        let listing = |d: &Path| {
            let mut v: Vec<String> = std::fs::read_dir(d).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
            v.sort();
            v
        };
        // Into an existing folder: an earlier file of the same name survives a failure.
        std::fs::create_dir_all(root.join("old")).unwrap();
        std::fs::write(root.join("old/mine.txt"), "keep").unwrap();
        std::fs::write(root.join("old/x.csv"), "earlier").unwrap();
        {
            let d = OutDir::create("--out", &root.join("old")).unwrap();
            std::fs::write(d.path().join("x.csv"), "1").unwrap();
            std::fs::create_dir(d.path().join("sub")).unwrap();
            std::fs::write(d.path().join("sub/y.csv"), "2").unwrap();
        }
        assert_eq!(listing(&root.join("old")), ["mine.txt", "x.csv"]);
        assert_eq!(std::fs::read_to_string(root.join("old/x.csv")).unwrap(), "earlier");
        // The staging folder of a process killed outright (no such process:
        // pid 4194304 is past Linux's largest) goes with the next command.
        std::fs::create_dir_all(root.join("old/.vpl-staging.4194304/sub")).unwrap();
        drop(OutDir::create("--out", &root.join("old")).unwrap());
        assert_eq!(listing(&root.join("old")), ["mine.txt", "x.csv"]);
        // Kept, what it wrote takes its place, subfolders included.
        let d = OutDir::create("--out", &root.join("old")).unwrap();
        std::fs::write(d.path().join("x.csv"), "1").unwrap();
        std::fs::create_dir(d.path().join("sub")).unwrap();
        std::fs::write(d.path().join("sub/y.csv"), "2").unwrap();
        d.keep().unwrap();
        assert_eq!(listing(&root.join("old")), ["mine.txt", "sub", "x.csv"]);
        assert_eq!(std::fs::read_to_string(root.join("old/x.csv")).unwrap(), "1");
        // A move that fails (a folder took a file's place) moves nothing.
        let d = OutDir::create("--out", &root.join("old")).unwrap();
        std::fs::write(d.path().join("a.csv"), "new a").unwrap();
        std::fs::write(d.path().join("x.csv"), "new x").unwrap();
        std::fs::remove_file(root.join("old/x.csv")).unwrap();
        std::fs::create_dir(root.join("old/x.csv")).unwrap();
        assert!(d.keep().unwrap_err().contains("x.csv"));
        assert_eq!(listing(&root.join("old")), ["mine.txt", "sub", "x.csv"]);
        std::fs::remove_dir(root.join("old/x.csv")).unwrap();
        // Images: nothing replaced until every output is staged.
        let out = ImageOut::new("--out", &root.join("old/r.exr"), true).unwrap();
        let mut img = Image::new(2, 1);
        let mut w = Written::default();
        w.image(&img, &out, 1.0, "test").unwrap();
        w.keep().unwrap();
        let earlier = std::fs::read(root.join("old/r.exr")).unwrap();
        img.data[0].x = 5.0;
        {
            let mut w = Written::default();
            w.image(&img, &out, 1.0, "test").unwrap();
            // The --stderr cannot be staged: the new --out is not kept.
            let stderr = ImageOut { path: root.join("missing/s.exr"), preview: None };
            assert!(w.image(&img, &stderr, 1.0, "test").is_err());
        }
        assert_eq!(std::fs::read(root.join("old/r.exr")).unwrap(), earlier);
        assert_eq!(listing(&root.join("old")), ["mine.txt", "r.exr", "r.png", "sub"]);
        img.data[1].y = f32::NAN;
        let e = Written::default().image(&img, &out, 1.0, "indirect shading").unwrap_err();
        assert!(e.starts_with("indirect shading produced 1 non-finite pixel(s) (first at 1, 0)"), "{e}");
        std::fs::remove_dir_all(&root).unwrap();
    }
}

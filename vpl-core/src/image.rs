//! Linear RGB f32 images: EXR read/write, PNG previews (Reinhard + sRGB), atomic writes.

use crate::error::{CoreError, Result};
use glam::Vec3;
use std::io::Write;
use std::path::{Path, PathBuf};

/// A linear-RGB image, row-major, pixel (0,0) top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// `width·height` pixels, row by row from the top.
    pub data: Vec<Vec3>,
}

impl Image {
    /// A black image.
    pub fn new(width: u32, height: u32) -> Image {
        Image { width, height, data: vec![Vec3::ZERO; width as usize * height as usize] }
    }

    /// An image left on a device: its size, and no pixels on the host
    /// (`data` is empty). The stage that made it reads it back on request
    /// (`IndirectShader::read_image`).
    pub fn on_device(width: u32, height: u32) -> Image {
        Image { width, height, data: Vec::new() }
    }

    /// Whether the pixels are on the host: one per pixel (false for
    /// [`Image::on_device`] of a non-empty size).
    pub fn on_host(&self) -> bool {
        self.data.len() == self.width as usize * self.height as usize
    }

    /// Pixel (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.data[(y * self.width + x) as usize]
    }

    /// Sets pixel (x, y).
    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        self.data[(y * self.width + x) as usize] = v;
    }

    /// Mean over all pixels, per channel (f64 accumulation).
    pub fn mean(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.data {
            s[0] += p.x as f64;
            s[1] += p.y as f64;
            s[2] += p.z as f64;
        }
        let n = self.data.len().max(1) as f64;
        [s[0] / n, s[1] / n, s[2] / n]
    }
}

/// Luminance (Rec. 709 / sRGB primaries).
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Reinhard's global operator on luminance, L/(1+L), applied by scaling the
/// colour (Reinhard et al. 2002, eq. 3 with L_white = ∞).
#[inline]
pub fn reinhard(c: Vec3) -> Vec3 {
    let l = luminance(c);
    if l <= 0.0 { Vec3::ZERO } else { c / (1.0 + l) }
}

/// The sRGB transfer function (IEC 61966-2-1), per channel.
#[inline]
pub fn linear_to_srgb(c: Vec3) -> Vec3 {
    let f = |v: f32| {
        let v = v.max(0.0);
        if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
    };
    Vec3::new(f(c.x), f(c.y), f(c.z))
}

/// The sRGB transfer function decoded (IEC 61966-2-1): an encoded channel
/// value in [0, 1] to linear light.
#[inline]
pub fn srgb_to_linear(c: f32) -> f32 {
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

/// The path of the PNG preview written beside `path` (same stem, `.png`).
pub fn preview_path(path: &Path) -> PathBuf {
    path.with_extension("png")
}

/// Temporary files being written now (removed by [`remove_temporaries`]).
static IN_FLIGHT: std::sync::Mutex<Vec<PathBuf>> = std::sync::Mutex::new(Vec::new());

/// Held by every write of this module while it runs (a temporary being
/// written, a staging commit renaming files), and by [`stop_writes`] for
/// good: an interrupt waits for the write in progress and no write starts
/// after it.
static WRITING: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// Holds off an interrupt's clean-up ([`stop_writes`]) until the guard is
/// dropped: for a caller that moves several files into place as one step.
/// The writes of this module take it themselves; do not call them while
/// holding it.
pub fn begin_write() -> std::sync::MutexGuard<'static, ()> {
    WRITING.lock().unwrap_or_else(|e| e.into_inner())
}

/// For a SIGINT/SIGTERM handler: waits until the write in progress (if
/// any) is complete, removes the temporaries of every staged or unfinished
/// output, and returns a guard that keeps any later write from starting.
/// The handler cleans up what else it must and exits while holding it, so
/// the writing thread never sees its temporary vanish (no "cannot write"
/// error in place of the interrupt) and never leaves one behind.
pub fn stop_writes() -> std::sync::MutexGuard<'static, ()> {
    let guard = begin_write();
    remove_temporaries();
    guard
}

/// Removes the temporary files of writes in progress. A program calls it
/// from its SIGINT/SIGTERM handler before exiting (through [`stop_writes`],
/// which first waits for the write in progress), so an interrupted command
/// leaves neither a partial output nor a temporary file.
pub fn remove_temporaries() {
    let list = IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner());
    for p in list.iter() {
        let _ = std::fs::remove_file(p);
    }
}

/// The longest file name the temporaries are given, in bytes: the limit of
/// every common file system (ext4, XFS, btrfs, tmpfs, APFS, NTFS).
const MAX_NAME_BYTES: usize = 255;

/// The temporary name of a write of `name` by process `pid`:
/// [`temporary_stem`]`PID.tmp`.
fn temporary_name(name: &str, pid: u32) -> String {
    format!("{}{pid}.tmp", temporary_stem(name))
}

/// What every temporary of `name` starts with: `.NAME.`, or, where a
/// temporary of that form could pass [`MAX_NAME_BYTES`] (a legal name of
/// 246 bytes and more), `NAME` cut at a character boundary and followed by
/// `~` and a 64-bit FNV-1a hash of the whole name, so that two long names
/// with the same beginning keep apart.
fn temporary_stem(name: &str) -> String {
    // '.' + name + '.' + a PID of at most 10 digits + ".tmp"
    const SPARE: usize = 1 + 1 + 10 + 4;
    if name.len() + SPARE <= MAX_NAME_BYTES {
        return format!(".{name}.");
    }
    let hash = name.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3));
    // '~' and 16 hex digits take 17 bytes more.
    let mut keep = MAX_NAME_BYTES - SPARE - 17;
    while !name.is_char_boundary(keep) {
        keep -= 1;
    }
    format!(".{}~{hash:016x}.", &name[..keep])
}

/// Removes `.NAME.PID.tmp` files beside `NAME` left by writes of processes
/// that no longer run (killed with SIGKILL, or a machine that went down).
/// Where the process table cannot be read (no `/proc`), nothing is removed.
fn remove_stale_temporaries(dir: &Path, name: &str) {
    let proc = Path::new("/proc/self");
    if !proc.exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let prefix = temporary_stem(name);
    for e in entries.flatten() {
        let file = e.file_name().to_string_lossy().into_owned();
        let Some(pid) = file.strip_prefix(&prefix).and_then(|r| r.strip_suffix(".tmp")).and_then(|p| p.parse::<u32>().ok()) else {
            continue;
        };
        if pid != std::process::id() && !Path::new("/proc").join(pid.to_string()).exists() {
            let _ = std::fs::remove_file(e.path());
        }
    }
}

/// Writes `bytes` to `path` atomically: a temporary file in the same
/// directory, flushed, then renamed over `path`. On failure nothing is left
/// behind; the temporary is registered for [`remove_temporaries`] while it
/// exists, and stale temporaries of the same output are removed first.
///
/// `path` must be a new name or a regular file: a device, a FIFO, a
/// socket, a directory or a symbolic link is refused before anything is
/// written, since the rename would put a regular file in its place (an
/// output named `/dev/null`, run as root, would replace the system's).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let _writing = begin_write();
    let tmp = write_temporary(path, bytes)?;
    let renamed = std::fs::rename(&tmp, path);
    forget_temporary(&tmp, renamed.is_err());
    renamed.map_err(|e| CoreError::Write { path: path.into(), reason: e.to_string() })
}

/// The checks of an output and its temporary: `bytes` written and flushed
/// to `.NAME.PID.tmp` beside `path` (registered for
/// [`remove_temporaries`]; stale temporaries of the same output removed
/// first). `path`'s folder must exist and `path` must be a new name or a
/// regular file. On failure nothing is left. The caller holds
/// [`begin_write`]'s guard.
fn write_temporary(path: &Path, bytes: &[u8]) -> Result<PathBuf> {
    let err = |reason: String| CoreError::Write { path: path.into(), reason };
    let dir = folder_of(path);
    if !dir.is_dir() {
        return Err(err(format!("directory {} does not exist", dir.display())));
    }
    check_replaceable(path)?;
    let name = path.file_name().ok_or_else(|| err("no file name".into()))?.to_string_lossy().into_owned();
    remove_stale_temporaries(&dir, &name);
    let tmp = dir.join(temporary_name(&name, std::process::id()));
    IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner()).push(tmp.clone());
    let written = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    match written {
        Ok(()) => Ok(tmp),
        Err(e) => {
            forget_temporary(&tmp, true);
            Err(err(e.to_string()))
        }
    }
}

/// Takes `tmp` off the temporaries in flight, removing the file when
/// `remove`.
fn forget_temporary(tmp: &Path, remove: bool) {
    if remove {
        let _ = std::fs::remove_file(tmp);
    }
    IN_FLIGHT.lock().unwrap_or_else(|e| e.into_inner()).retain(|p| p != tmp);
}

/// The outputs of one command, written together: each is staged to a
/// temporary beside its final name ([`Staging::stage`]), or is a file the
/// command wrote into a staging folder of its own ([`Staging::adopt`]), and
/// only when all are staged are they renamed into place ([`Staging::commit`]). A command
/// that fails before the commit, or is interrupted, leaves every earlier
/// file as it was: the staged temporaries are removed (on drop, and by
/// [`remove_temporaries`] from a signal handler). During the commit, a file
/// that is replaced is first kept under a backup name; if a rename fails,
/// the files already replaced are restored from their backups and the new
/// ones removed, so the folder is as before the command.
#[derive(Debug, Default)]
pub struct Staging {
    /// (final path, staged temporary) in staging order.
    staged: Vec<(PathBuf, PathBuf)>,
}

impl Staging {
    /// No outputs yet.
    pub fn new() -> Staging {
        Staging::default()
    }

    /// Stages `bytes` as the future content of `path` (checked as
    /// [`write_atomic`] checks it). Staging the same path twice is an error.
    pub fn stage(&mut self, path: &Path, bytes: &[u8]) -> Result<()> {
        self.check_new(path)?;
        let _writing = begin_write();
        let tmp = write_temporary(path, bytes)?;
        self.staged.push((path.to_path_buf(), tmp));
        Ok(())
    }

    /// Stages `file`, already written on the same file system (in a staging
    /// folder of the caller's), as the future content of `path`. `path`
    /// must be a new name or a regular file; its folder is made at the
    /// commit if it is missing (and removed again if the commit fails).
    /// An adopted file that is not committed is removed on drop.
    pub fn adopt(&mut self, path: &Path, file: PathBuf) -> Result<()> {
        self.check_new(path)?;
        check_replaceable(path)?;
        self.staged.push((path.to_path_buf(), file));
        Ok(())
    }

    /// Refuses a path staged already.
    fn check_new(&self, path: &Path) -> Result<()> {
        if self.staged.iter().any(|(p, _)| p == path) {
            return Err(CoreError::Write { path: path.into(), reason: "the command writes it twice".into() });
        }
        Ok(())
    }

    /// Renames every staged output into place, all or none (see the type).
    pub fn commit(mut self) -> Result<()> {
        let _writing = begin_write();
        let staged = std::mem::take(&mut self.staged);
        // (final path, its backup if it existed), and the folders made.
        let mut done: Vec<(PathBuf, Option<PathBuf>)> = Vec::new();
        let mut made: Vec<PathBuf> = Vec::new();
        let mut failure = None;
        for (path, tmp) in &staged {
            if let Err(e) = make_folder(&folder_of(path), &mut made) {
                failure = Some(CoreError::Write { path: path.clone(), reason: e.to_string() });
                break;
            }
            let backup = path.with_file_name(format!(
                "{}{}.bak",
                temporary_stem(&path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default()),
                std::process::id()
            ));
            // What took the output's place since it was staged is checked again.
            if let Err(e) = check_replaceable(path) {
                failure = Some(e);
                break;
            }
            let kept = match std::fs::symlink_metadata(path) {
                Ok(_) => match std::fs::rename(path, &backup) {
                    Ok(()) => Some(backup),
                    Err(e) => {
                        failure = Some(CoreError::Write { path: path.clone(), reason: e.to_string() });
                        break;
                    }
                },
                Err(_) => None,
            };
            if let Err(e) = std::fs::rename(tmp, path) {
                if let Some(b) = &kept {
                    let _ = std::fs::rename(b, path);
                }
                failure = Some(CoreError::Write { path: path.clone(), reason: e.to_string() });
                break;
            }
            done.push((path.clone(), kept));
        }
        for (_, tmp) in &staged {
            forget_temporary(tmp, true);
        }
        match failure {
            None => {
                for (_, backup) in done {
                    if let Some(b) = backup {
                        let _ = std::fs::remove_file(b);
                    }
                }
                Ok(())
            }
            Some(e) => {
                // Back to the folder as it was: new files removed, replaced ones restored.
                for (path, backup) in done.into_iter().rev() {
                    match backup {
                        Some(b) => {
                            let _ = std::fs::rename(b, &path);
                        }
                        None => {
                            let _ = std::fs::remove_file(&path);
                        }
                    }
                }
                for dir in made.into_iter().rev() {
                    let _ = std::fs::remove_dir(dir);
                }
                Err(e)
            }
        }
    }
}

/// Makes `dir` and the folders above it that are missing, recording each
/// made in `made` (outermost first).
fn make_folder(dir: &Path, made: &mut Vec<PathBuf>) -> std::io::Result<()> {
    let mut missing = Vec::new();
    let mut p = dir;
    while !p.as_os_str().is_empty() && !p.exists() {
        missing.push(p.to_path_buf());
        p = p.parent().unwrap_or(Path::new(""));
    }
    for m in missing.into_iter().rev() {
        std::fs::create_dir(&m)?;
        made.push(m);
    }
    Ok(())
}

impl Drop for Staging {
    /// Outputs never committed are removed.
    fn drop(&mut self) {
        for (_, tmp) in self.staged.drain(..) {
            forget_temporary(&tmp, true);
        }
    }
}

/// Refuses an output path that exists and is no regular file (see
/// [`write_atomic`]). A symbolic link is refused whatever it points to: the
/// rename would replace the link, not write where it points.
pub fn check_replaceable(path: &Path) -> Result<()> {
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(CoreError::Write { path: path.into(), reason: e.to_string() }),
        Ok(meta) if meta.is_file() => Ok(()),
        Ok(meta) => {
            let t = meta.file_type();
            let kind = if t.is_symlink() { "a symbolic link" } else { kind_of(&meta) };
            Err(CoreError::Write {
                path: path.into(),
                reason: format!("it is {kind}; an output replaces only a regular file or takes a new name"),
            })
        }
    }
}

/// The folder of `path`: its parent, or `.` for a bare name.
pub fn folder_of(path: &Path) -> std::path::PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => std::path::PathBuf::from("."),
    }
}

/// What a path that is no regular file is, in words ("a directory", "a
/// device", "a pipe", "a socket").
pub fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_fifo() {
            return "a pipe";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A command whose last output fails leaves the folder as it was: the
    /// earlier outputs are not written (a failed stage) or are restored (a
    /// failed commit), and no temporary stays.
    #[test]
    fn staged_outputs_are_written_all_or_none() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (dir.path().join("a.txt"), dir.path().join("b.txt"));
        std::fs::write(&a, "old a").unwrap();
        // A stage that fails (its folder is missing): nothing is touched.
        let mut s = Staging::new();
        s.stage(&a, b"new a").unwrap();
        assert!(s.stage(&dir.path().join("missing/c.txt"), b"c").is_err());
        drop(s);
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        let names = || {
            let mut v: Vec<String> =
                std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
            v.sort();
            v
        };
        assert_eq!(names(), ["a.txt"]);
        // A commit that fails on its second rename (a folder took b's place
        // after staging): a is restored, b never appears.
        let mut s = Staging::new();
        s.stage(&a, b"new a").unwrap();
        s.stage(&b, b"new b").unwrap();
        std::fs::create_dir(&b).unwrap();
        std::fs::write(b.join("x"), "x").unwrap();
        assert!(s.commit().is_err());
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "old a");
        std::fs::remove_dir_all(&b).unwrap();
        assert_eq!(names(), ["a.txt"]);
        // Both staged, both committed.
        let mut s = Staging::new();
        s.stage(&a, b"new a").unwrap();
        s.stage(&b, b"new b").unwrap();
        assert!(s.stage(&b, b"again").is_err());
        s.commit().unwrap();
        assert_eq!(std::fs::read_to_string(&a).unwrap(), "new a");
        assert_eq!(std::fs::read_to_string(&b).unwrap(), "new b");
        assert_eq!(names(), ["a.txt", "b.txt"]);
    }

    #[test]
    #[cfg(unix)]
    fn stale_temporaries_of_dead_writers_are_removed() {
        let dir = std::env::temp_dir().join(format!("vpl-core-tmp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // PID 4194304 is above Linux's largest (2^22), so it never runs.
        let dead = dir.join(temporary_name("a.exr", 4_194_304));
        let alive = dir.join(temporary_name("a.exr", 1));
        let other = dir.join(temporary_name("b.exr", 4_194_304));
        for p in [&dead, &alive, &other] {
            std::fs::write(p, b"partial").unwrap();
        }
        write_atomic(&dir.join("a.exr"), b"whole").unwrap();
        assert!(!dead.exists(), "the dead writer's temporary stays");
        assert_eq!(alive.exists(), Path::new("/proc/1").exists());
        assert!(other.exists(), "another output's temporary was removed");
        assert_eq!(std::fs::read(dir.join("a.exr")).unwrap(), b"whole");
        let mine = dir.join(temporary_name("a.exr", std::process::id()));
        assert!(!mine.exists() && !IN_FLIGHT.lock().unwrap().contains(&mine));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A legal name of 250 bytes (the limit is 255) is written, its
    /// temporary kept within the limit, and a stale temporary of it found.
    #[test]
    fn long_names_are_written_and_their_temporaries_fit() {
        let dir = tempfile::tempdir().unwrap();
        for len in [240, 246, 250, 255] {
            let name = format!("{}.exr", "é".repeat((len - 4) / 2) + &"a".repeat((len - 4) % 2));
            assert_eq!(name.len(), len);
            for pid in [1, u32::MAX] {
                assert!(temporary_name(&name, pid).len() <= MAX_NAME_BYTES, "{len}");
            }
            write_atomic(&dir.path().join(&name), b"whole").unwrap();
            assert_eq!(std::fs::read(dir.path().join(&name)).unwrap(), b"whole");
        }
        // Two long names alike up to the cut keep apart.
        let (a, b) = ("x".repeat(250) + "1", "x".repeat(250) + "2");
        assert_ne!(temporary_stem(&a), temporary_stem(&b));
        #[cfg(unix)]
        {
            let name = "y".repeat(250);
            let dead = dir.path().join(temporary_name(&name, 4_194_304));
            std::fs::write(&dead, b"partial").unwrap();
            write_atomic(&dir.path().join(&name), b"whole").unwrap();
            assert!(!dead.exists(), "the dead writer's temporary of a long name stays");
        }
        let names: Vec<String> =
            std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
    }

    /// A FIFO, a directory and a symbolic link named as the output are
    /// refused and left as they were.
    #[cfg(unix)]
    #[test]
    fn outputs_replace_only_regular_files() {
        use std::os::unix::fs::FileTypeExt;
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("out.exr");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
        let e = write_atomic(&fifo, b"x").unwrap_err().to_string();
        assert!(e.contains("a pipe") && e.contains("regular file"), "{e}");
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
        let sub = dir.path().join("sub.exr");
        std::fs::create_dir(&sub).unwrap();
        assert!(write_atomic(&sub, b"x").unwrap_err().to_string().contains("a directory"));
        let target = dir.path().join("target.exr");
        std::fs::write(&target, b"kept").unwrap();
        let link = dir.path().join("link.exr");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        assert!(write_atomic(&link, b"x").unwrap_err().to_string().contains("a symbolic link"));
        assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
        assert_eq!(std::fs::read(&target).unwrap(), b"kept");
        // A regular file is replaced.
        write_atomic(&target, b"new").unwrap();
        assert_eq!(std::fs::read(&target).unwrap(), b"new");
    }

    #[test]
    fn reinhard_maps_into_unit_range() {
        let c = reinhard(Vec3::splat(1.0));
        assert!((c.x - 0.5).abs() < 1e-6);
        assert_eq!(reinhard(Vec3::ZERO), Vec3::ZERO);
        assert!((linear_to_srgb(Vec3::ONE).x - 1.0).abs() < 1e-6);
    }
}

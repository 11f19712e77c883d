//! Reading input files with limits decided before the work: only regular
//! files are read (never a device, a FIFO or a directory), and never more
//! than a stated number of bytes, so `obj = "/dev/zero"` or a 40 GB file named
//! by mistake ends in one line instead of an allocation failure.
//!
//! Every file the toolkit reads goes through [`read_bytes`] or [`read_text`]
//! with one of the limits below.

use crate::error::{Result, SceneIoError};
use std::io::Read;
use std::path::Path;

/// The most bytes an OBJ file may have (4 GiB: about 40 M triangles).
pub const MAX_MESH_BYTES: u64 = 4 << 30;
/// The most bytes a small text input may have: an MTL library, a scene TOML,
/// a Table 1 unit or spec (64 MiB).
pub const MAX_TEXT_BYTES: u64 = 64 << 20;
/// The most bytes an image input (a reference EXR) may have (2 GiB).
pub const MAX_IMAGE_BYTES: u64 = 2 << 30;
/// The most pixels an image input may declare (2²⁸ ≈ 268 M, 16384² ≈ 2²⁸).
pub const MAX_IMAGE_PIXELS: u64 = 1 << 28;

/// The bytes of the regular file `path`, at most `limit` of them.
///
/// Refuses a path that is no regular file ([`SceneIoError::NotAFile`]) and a file
/// longer than `limit` ([`SceneIoError::TooLarge`]); both the size the file system
/// reports and the bytes actually read are checked, so a file that grows
/// while it is read is refused too.
///
/// The path's type is looked at before it is opened (opening a FIFO for
/// reading waits for a writer), and the file is opened without blocking
/// and looked at again, so a path swapped for a FIFO in between is refused
/// too instead of hanging the read.
pub fn read_bytes(path: &Path, limit: u64) -> Result<Vec<u8>> {
    let read_err = |source| SceneIoError::Read { path: path.into(), source };
    check_regular_file(path)?;
    let file = open_without_blocking(path).map_err(read_err)?;
    let meta = file.metadata().map_err(read_err)?;
    if !meta.is_file() {
        return Err(SceneIoError::NotAFile { path: path.into(), kind: kind_of(&meta) });
    }
    if meta.len() > limit {
        return Err(SceneIoError::TooLarge { path: path.into(), size: meta.len(), limit });
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(read_err)?;
    if bytes.len() as u64 > limit {
        return Err(SceneIoError::TooLarge { path: path.into(), size: bytes.len() as u64, limit });
    }
    Ok(bytes)
}

/// The UTF-8 text of the regular file `path` (at most `limit` bytes), without
/// a leading byte-order mark.
pub fn read_text(path: &Path, limit: u64) -> Result<String> {
    let bytes = read_bytes(path, limit)?;
    let text = String::from_utf8(bytes).map_err(|e| SceneIoError::Encoding { path: path.into(), offset: e.utf8_error().valid_up_to() })?;
    Ok(match text.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => text,
    })
}

/// Checks that `path` names an existing regular file without reading it.
pub fn check_regular_file(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|source| SceneIoError::Read { path: path.into(), source })?;
    if meta.is_file() { Ok(()) } else { Err(SceneIoError::NotAFile { path: path.into(), kind: kind_of(&meta) }) }
}

/// `path` opened for reading; on Unix with `O_NONBLOCK`, which a regular
/// file ignores and which keeps a FIFO's open from waiting for a writer.
fn open_without_blocking(path: &Path) -> std::io::Result<std::fs::File> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        options.custom_flags(libc::O_NONBLOCK);
    }
    options.open(path)
}

pub use vpl_core::image::{folder_of, kind_of};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn devices_directories_and_long_files_are_refused() {
        let dir = std::env::temp_dir().join(format!("vpl-core-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = read_bytes(&dir, 10).unwrap_err();
        assert!(matches!(e, SceneIoError::NotAFile { .. }) && e.to_string().contains("directory"), "{e}");
        #[cfg(unix)]
        {
            let e = read_bytes(Path::new("/dev/zero"), 10).unwrap_err();
            assert!(e.to_string().contains("a device"), "{e}");
        }
        let f = dir.join("a.txt");
        std::fs::write(&f, "\u{feff}hello").unwrap();
        assert_eq!(read_text(&f, 100).unwrap(), "hello");
        let e = read_bytes(&f, 4).unwrap_err();
        assert!(matches!(e, SceneIoError::TooLarge { size: 8, limit: 4, .. }), "{e}");
        std::fs::write(&f, [b'a', 0xff, b'b']).unwrap();
        assert!(read_text(&f, 100).unwrap_err().to_string().contains("offset 1"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A FIFO with no writer: opening it for reading the plain way waits
    /// forever. The read must answer at once, refusing it as a pipe.
    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_waiting_for_a_writer() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("scene.toml");
        let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo (coreutils) runs");
        assert!(made.success(), "mkfifo failed");
        let (tx, rx) = std::sync::mpsc::channel();
        let path = fifo.clone();
        std::thread::spawn(move || {
            let _ = tx.send((
                read_bytes(&path, 100).map(|_| ()).map_err(|e| e.to_string()),
                read_text(&path, 100).map(|_| ()).map_err(|e| e.to_string()),
            ));
        });
        let (bytes, text) = rx.recv_timeout(std::time::Duration::from_secs(20)).expect("reading a FIFO hung");
        for e in [bytes, text] {
            let e = e.unwrap_err();
            assert!(e.contains("a pipe, not a regular file"), "{e}");
        }
        // The no-blocking open itself: a FIFO opened without a writer.
        let f = open_without_blocking(&fifo).unwrap();
        assert!(!f.metadata().unwrap().is_file());
    }
}

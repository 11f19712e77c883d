//! # vpl-tests
//!
//! Workspace-level tests of the VPL toolkit: statistical image tests against
//! Mitsuba 3 references, furnace tests with closed forms, loader and
//! determinism tests. This library holds the helpers they share.
//!
//! ```
//! assert!(vpl_tests::data_dir().join("cornell-box/cbox.obj").exists());
//! ```

#![warn(missing_docs)]

use std::path::PathBuf;

/// The folder of test data shipped with the repository (`tests/data`).
pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// A scratch folder for files a test writes (difference images of failed
/// comparisons, malformed inputs); kept under `target/` so CI can collect it.
pub fn scratch_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/test-output").join(name);
    std::fs::create_dir_all(&d).expect("create scratch dir");
    d
}

//! The `vpl` binary away from the folder it was built in: copied into a
//! `bin/` of its own and run from another folder (as `cargo install` or a
//! copy to another machine leaves it), it finds the scene files of Table 1's
//! real-scene rows through `--scenes-dir` or `VPL_SCENES`, and says how to
//! name them when it cannot. (`.ci/run` does the same with a real
//! `cargo install --path vpl-bench --root`.)

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A fresh folder outside the repository (so that no `scenes/` lies above it).
fn temp_root(name: &str) -> PathBuf {
    let root = std::env::temp_dir().join(format!("vpl-relocatable-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(root.join("bin")).unwrap();
    std::fs::create_dir_all(root.join("work")).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_vpl"), root.join("bin/vpl")).unwrap();
    root
}

/// The smallest Table 1 run of the Sponza row, from `root/work`.
fn table1(root: &Path, scenes: Option<&Path>, env: Option<&Path>, out: &str) -> Output {
    let mut c = Command::new(root.join("bin/vpl"));
    c.current_dir(root.join("work")).env_remove("VPL_SCENES");
    if let Some(e) = env {
        c.env("VPL_SCENES", e);
    }
    if let Some(s) = scenes {
        c.arg("--scenes-dir").arg(s);
    }
    c.args(["table1", "--scene", "sponza", "--methods", "ir", "--frames", "0..1", "--size", "16x12"])
        .args(["--truth-spp", "4", "--seeds", "1", "--quiet", "--out", out])
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn an_installed_binary_finds_the_scene_files_it_is_told_of_and_says_how_otherwise() {
    let root = temp_root("table1");
    // No folder named, none above the working folder or the binary.
    let o = table1(&root, None, None, "lost");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("sponza-dabrovic.toml") && e.contains("--scenes-dir DIR") && e.contains("VPL_SCENES"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(!root.join("work/lost").exists(), "a failed run leaves its output folder behind");
    // A folder that is not one.
    let o = table1(&root, Some(&root.join("absent")), None, "absent");
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not a folder"), "{}", stderr(&o));

    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let model = vpl_bench::scenes::model_missing(&scenes.join("sponza-dabrovic.toml"));
    for (flag, env, out) in [(Some(scenes.as_path()), None, "by-flag"), (None, Some(scenes.as_path()), "by-env")] {
        let o = table1(&root, flag, env, out);
        match &model {
            None => {
                assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
                let md = std::fs::read_to_string(root.join("work").join(out).join("table1.md")).unwrap();
                assert!(md.contains("sponza"), "{md}");
            }
            // Without the model (kept outside the repository) the row says which file it lacks.
            Some(why) => {
                eprintln!("skipped the Sponza run ({out}): {why}");
                assert_eq!(o.status.code(), Some(2));
                assert!(stderr(&o).contains("is not there"), "{}", stderr(&o));
            }
        }
    }
    std::fs::remove_dir_all(&root).unwrap();
}

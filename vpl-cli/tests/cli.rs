//! The `vpl` binary on bad input: one line naming the problem, exit code 2,
//! no panic, no output file. And on good input: an EXR, its PNG preview and
//! the standard-error EXR.

use std::path::{Path, PathBuf};
use std::process::Command;
use vpl_scene_io::ImageFile;

fn vpl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vpl"))
}

/// A fresh folder under the system's temporary folder, removed when the
/// test that made it ends (passing or failing).
struct Scratch(PathBuf);

impl std::ops::Deref for Scratch {
    type Target = PathBuf;
    fn deref(&self) -> &PathBuf {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<std::ffi::OsStr> for Scratch {
    fn as_ref(&self) -> &std::ffi::OsStr {
        self.0.as_os_str()
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn scratch(name: &str) -> Scratch {
    let d = std::env::temp_dir().join(format!("vpl-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    Scratch(d)
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

/// Runs `vpl render` with `args`, expects exit 2, one stderr line containing `needle`, and no output file.
fn fails(dir: &Path, args: &[&str], needle: &str) {
    let out = dir.join("out.exr");
    let o = vpl().arg("render").args(args).arg("--out").arg(&out).arg("--spp").arg("1").arg("--size").arg("8x8").output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("vpl: warning:")).collect();
    assert_eq!(o.status.code(), Some(2), "{args:?}: status {:?}, stderr {err}", o.status);
    assert_eq!(lines.len(), 1, "{args:?}: expected one line, got {err:?}");
    assert!(lines[0].starts_with("vpl: error: ") && lines[0].contains(needle), "{args:?}: {:?} lacks {needle:?}", lines[0]);
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(!out.exists() && !dir.join("out.png").exists(), "{args:?}: output written");
    let leftovers: Vec<_> =
        std::fs::read_dir(dir).unwrap().filter_map(|e| e.ok()).filter(|e| e.file_name().to_string_lossy().contains(".tmp")).collect();
    assert!(leftovers.is_empty(), "{args:?}: temporary files left");
}

#[test]
fn bad_input_is_one_line_and_exit_code_2() {
    let d = scratch("bad");
    let malformed = write(&d, "malformed.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nf 1 2 3\n");
    let nan = write(&d, "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    let zero = write(&d, "zero.obj", "mtllib z.mtl\nusemtl e\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n");
    write(&d, "z.mtl", "newmtl e\nKd 0.5 0.5 0.5\nKe 1 1 1\n");
    let empty = write(&d, "empty.obj", "# no faces\nv 0 0 0\n");
    let dark = write(&d, "dark.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let nomtl = write(&d, "nomtl.obj", "mtllib missing.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let fov0 = write(&d, "fov0.toml", "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0,0,3]\ntarget = [0,0,0]\nfov = 0\n");
    let fovneg = write(&d, "fovneg.toml", "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0,0,3]\ntarget = [0,0,0]\nfov = -10\n");
    let missing = d.join("missing.obj").to_string_lossy().into_owned();
    fails(&d, &["--scene", &malformed], "malformed OBJ");
    fails(&d, &["--scene", &missing], "cannot read");
    fails(&d, &["--scene", &nomtl], "no lights");
    fails(&d, &["--scene", &nan], "non-finite vertex");
    fails(&d, &["--scene", &zero], "is empty");
    fails(&d, &["--scene", &empty], "is empty");
    fails(&d, &["--scene", &dark], "no lights");
    fails(&d, &["--scene", &fov0], "field of view");
    fails(&d, &["--scene", &fovneg], "field of view");
    fails(&d, &["--scene", "cornell", "--size", "0x8"], "size");
    fails(&d, &["--scene", "cornell", "--spp", "0"], "spp");
    fails(&d, &["--scene", "cornell", "--frame", "100000"], "past the end");
    fails(&d, &["--scene", "nowhere"], "unknown built-in");
    fails(&d, &["--scene", "cornell", "--mode", "sideways"], "sideways");
    fails(&d, &["--scene", "cornell", "--clamp", "-3"], "clamp");
    fails(&d, &["--scene", "cornell", "--threads", "0"], "threads");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "rr", "--rr-epsilon", "0"], "--rr-epsilon");
    // A flag the chosen sampler does not read is refused, not ignored; so is an unknown `--set` key.
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "ir", "--m-max", "4"], "--sampler ir does not read --m-max");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "smc", "--set", "no-such-key=1"], "does not read --no-such-key");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "smc", "--set", "knn-k"], "--set knn-k: expected KEY=VALUE");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "smc", "--set", "knn-k=x"], "--knn-k x: expected");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "tcas", "--rsm-res", "0"], "--rsm-res");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "mir", "--mh-iterations", "0"], "--mh-iterations");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "smc", "--resample-ratio", "0"], "resample-ratio");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "smc", "--knn-k", "0"], "knn-k");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "smc", "--max-depth", "2"], "max depth");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--sampler", "xyz"], "unknown sampler");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--shadowmap-res", "0"], "shadowmap-res");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--vpls", "0"], "vpls");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--visibility", "magic"], "magic");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--direct-samples", "0"], "direct-samples");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--clamp", "off", "--compensate", "2"], "--compensate");
    fails(&d, &["--scene", "cornell", "--method", "vpl", "--clamp", "areas"], "'auto', 'scene-area', 'off'");
    // A missing MTL is named in a warning line before the error.
    let o = vpl().args(["render", "--scene", &nomtl, "--out"]).arg(d.join("x.exr")).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing.mtl"));
}

#[test]
fn unwritable_output_is_an_error_before_rendering() {
    let d = scratch("unwritable");
    for out in [d.join("no/such/dir/a.exr"), d.clone()] {
        let o = vpl().args(["render", "--scene", "cornell", "--spp", "1", "--size", "8x8", "--out"]).arg(&out).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("cannot write"), "{err}");
    }
    let o = vpl()
        .args(["render", "--scene", "cornell", "--spp", "1", "--size", "8x8", "--out"])
        .arg(d.join("a.exr"))
        .arg("--stderr")
        .arg(d.join("none/se.exr"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(!d.join("a.exr").exists(), "nothing written when any output is unwritable");
    // A FIFO in the output's place is refused in one line and stays a FIFO.
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let fifo = d.join("f.exr");
        assert!(std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs").success());
        let o = vpl().args(["render", "--scene", "cornell", "--spp", "1", "--size", "8x8", "--out"]).arg(&fifo).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.contains("a pipe"), "{err}");
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    }
}

#[test]
fn render_writes_exr_png_and_stderr() {
    let d = scratch("good");
    let out = d.join("c.exr");
    let se = d.join("c_se.exr");
    let o = vpl()
        .args(["render", "--scene", "cornell", "--spp", "4", "--size", "32x32", "--mode", "indirect", "--threads", "2", "--out"])
        .arg(&out)
        .arg("--stderr")
        .arg(&se)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let img = vpl_core::Image::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (32, 32));
    assert!(img.mean()[0] > 0.0);
    assert!(d.join("c.png").exists());
    assert!(vpl_core::Image::read_exr(&se).unwrap().mean()[0] > 0.0);
}

#[test]
fn export_scene_round_trips_through_render() {
    let d = scratch("export");
    for name in ["cornell", "maze", "glass"] {
        let o = vpl().args(["export-scene", name]).output().unwrap();
        assert!(o.status.success());
        let text = String::from_utf8(o.stdout).unwrap();
        assert!(text.contains(&format!("builtin = \"{name}\"")), "{text}");
        let toml = write(&d, &format!("{name}.toml"), &text);
        let r = vpl()
            .args(["render", "--scene", &toml, "--spp", "1", "--size", "8x8", "--quiet", "--out"])
            .arg(d.join(format!("{name}.exr")))
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
}

#[test]
fn track_prints_csv_with_standard_errors() {
    let o = vpl().args(["track", "--scene", "cornell", "--pixel", "128,128", "--pixel", "10,250", "--spp", "256"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3);
    assert!(lines[0].starts_with("x,y,r,g,b,stderr_r"));
    let f: Vec<f64> = lines[1].split(',').map(|v| v.parse().unwrap()).collect();
    assert_eq!((f[0], f[1], f[8]), (128.0, 128.0, 256.0));
    assert!(f[2] > 0.0 && f[5] > 0.0);
    let o = vpl().args(["track", "--scene", "cornell", "--pixel", "999,1"]).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("outside"));
}

#[test]
fn vpl_method_renders_with_both_visibilities_and_shadings() {
    let d = scratch("vplmethod");
    for (vis, shading, compensate) in [("shadowmap", "interleaved", "0"), ("raytrace", "exhaustive", "2")] {
        let out = d.join(format!("{vis}.exr"));
        let o = vpl()
            .args([
                "render",
                "--scene",
                "cornell",
                "--method",
                "vpl",
                "--vpls",
                "256",
                "--size",
                "32x32",
                "--visibility",
                vis,
                "--shading",
                shading,
                "--shadowmap-res",
                "32",
                "--compensate",
                compensate,
                "--out",
            ])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{vis}: {err}");
        assert!(err.contains("VPLs stored") && err.contains("mean RGB"), "{err}");
        assert_eq!(err.contains("compensated (2 gather rays"), compensate == "2", "{err}");
        let img = vpl_core::Image::read_exr(&out).unwrap();
        assert!(img.mean()[0] > 0.05, "{vis}: {:?}", img.mean());
        assert!(d.join(format!("{vis}.png")).exists());
    }
}

/// `--shading lightcuts --cut 64` renders through a light tree, near the
/// exhaustive image (unbiased: within 3 % on the image mean at 64 VPLs a
/// pixel of 256), and a cut of 0 is refused in one line; `--shading culled`
/// likewise.
#[test]
fn lightcuts_render_near_the_exhaustive_image() {
    let d = scratch("lightcuts");
    let render = |shading: &str, cut: &str| {
        let out = d.join(format!("{shading}-{cut}.exr"));
        let o = vpl()
            .args(["render", "--scene", "cornell", "--method", "vpl", "--vpls", "256", "--size", "32x32", "--mode", "indirect"])
            .args(["--visibility", "raytrace", "--clamp", "off", "--shading", shading, "--cut", cut, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        (o.status.code(), err, out)
    };
    let (code, err, out) = render("exhaustive", "32");
    assert_eq!(code, Some(0), "{err}");
    let all = vpl_core::Image::read_exr(&out).unwrap().mean();
    let (code, err, out) = render("lightcuts", "64");
    assert_eq!(code, Some(0), "{err}");
    assert!(err.contains("lightcuts"), "the summary names the shader: {err}");
    let cut = vpl_core::Image::read_exr(&out).unwrap().mean();
    assert!((cut[0] / all[0] - 1.0).abs() < 0.03, "lightcuts {cut:?} against exhaustive {all:?}");
    let (code, err, _) = render("lightcuts", "0");
    assert_eq!(code, Some(2));
    assert!(err.contains("--cut") && err.trim_end().lines().count() == 1, "{err}");
    // Stochastic light culling, unbiased too: near the exhaustive image at a
    // bound that skips some terms; a bound of 0 is refused in one line.
    let culled = |bound: &str| {
        let out = d.join(format!("culled-{bound}.exr"));
        let o = vpl()
            .args(["render", "--scene", "cornell", "--method", "vpl", "--vpls", "256", "--size", "32x32", "--mode", "indirect"])
            .args(["--visibility", "raytrace", "--clamp", "off", "--shading", "culled", "--culling-bound", bound, "--out"])
            .arg(&out)
            .output()
            .unwrap();
        (o.status.code(), String::from_utf8_lossy(&o.stderr).to_string(), out)
    };
    let (code, err, out) = culled("1");
    assert_eq!(code, Some(0), "{err}");
    let m = vpl_core::Image::read_exr(&out).unwrap().mean();
    assert!((m[0] / all[0] - 1.0).abs() < 0.03, "culled {m:?} against exhaustive {all:?}");
    let (code, err, _) = culled("0");
    assert_eq!(code, Some(2));
    assert!(err.contains("--culling-bound") && err.trim_end().lines().count() == 1, "{err}");
}

/// `vpl sequence` with SMC: one EXR and PNG per frame, tracked.csv with 8
/// pixels per frame, frames.csv with at most M_max VPLs moved after the
/// first frame; bad frame ranges are one line and exit 2.
#[test]
fn sequence_writes_frames_and_csvs() {
    let d = scratch("sequence");
    let out = d.join("run");
    let o = vpl()
        .args([
            "sequence",
            "--scene",
            "office",
            "--sampler",
            "smc",
            "--vpls",
            "128",
            "--warmup",
            "3",
            "--m-max",
            "5",
            "--frames",
            "10..13",
            "--size",
            "32x18",
            "--shadowmap-res",
            "16",
            "--quiet",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in 10..13 {
        assert!(out.join(format!("frame_{f:04}.exr")).exists() && out.join(format!("frame_{f:04}.png")).exists());
    }
    let tracked = std::fs::read_to_string(out.join("tracked.csv")).unwrap();
    assert_eq!(tracked.lines().count(), 1 + 3 * 8);
    let frames = std::fs::read_to_string(out.join("frames.csv")).unwrap();
    let moved: Vec<usize> = frames.lines().skip(1).map(|l| l.split(',').nth(8).unwrap().parse().unwrap()).collect();
    assert_eq!(moved.len(), 3);
    assert!(moved[1..].iter().all(|&m| m <= 5), "{moved:?}");
    for (args, needle) in
        [(vec!["--frames", "9000.."], "does not fit"), (vec!["--frames", "5..2"], "frames"), (vec!["--frame", "3"], "--frames")]
    {
        let o = vpl().args(["sequence", "--scene", "office", "--size", "8x8", "--out"]).arg(d.join("bad")).args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.lines().count() == 1 && err.contains(needle), "{args:?}: {err}");
    }
}

/// `vpl table1`, `vpl merge`, `vpl table2` and `vpl figures` on bad input:
/// one line, exit code 2, nothing written.
#[test]
fn experiment_commands_refuse_bad_input_in_one_line() {
    let dir = scratch("experiments");
    let out = dir.join("t1");
    let out_s = out.to_string_lossy().into_owned();
    for (args, needle) in [
        (vec!["table1", "--scene", "sponza-crytek", "--out", &out_s], "unknown sequence 'sponza-crytek'"),
        (vec!["table1", "--methods", "nope", "--out", &out_s], "unknown method 'nope'"),
        (vec!["table1", "--frames", "5000..5001", "--out", &out_s], "do not fit"),
        (vec!["table1", "--shard", "2/2", "--out", &out_s], "index must be below"),
        (vec!["merge", &out_s], "no Table 1 run"),
        (vec!["table2", "--frames", "0", "--out", &out_s], "--frames must be at least 1"),
        (vec!["table2", "--smc", "device", "--out", &out_s], "--smc device needs --backend gpu"),
        (vec!["table2", "--smc", "gpu", "--out", &out_s], "--smc: 'gpu': host or device"),
        (vec!["figures", "--only", "9", "--out", &out_s], "no figure 9"),
        (vec!["figures", "--scenes", "nowhere", "--out", &out_s], "nowhere"),
        (vec!["progressive-figures", "--only", "9", "--out", &out_s], "no figure 9"),
        (vec!["progressive-figures", "--fig8-scenes", "nowhere", "--out", &out_s], "nowhere"),
        (vec!["progressive-figures", "--seconds", "0", "--out", &out_s], "--seconds must be positive"),
        (vec!["bench-rays", "--copies", "0"], "--copies and --size must be at least 1"),
        (vec!["bench-rays", "--scene", "nowhere.toml"], "nowhere.toml"),
    ] {
        let o = vpl().args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("vpl: error: ") && err.contains(needle), "{args:?}: {err:?} lacks {needle:?}");
        assert!(!out.exists(), "{args:?}: wrote {}", out.display());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `vpl bench-rays` prints one row per scene and one for the copies of the
/// last, with a positive rate in every column.
#[test]
fn bench_rays_prints_a_row_per_scene_and_copies() {
    let o = vpl().args(["bench-rays", "--scene", "cornell,office", "--copies", "3", "--size", "16x16", "--seconds", "0"]).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("| ") && !l.starts_with("| scene") && !l.starts_with("| ---")).collect();
    assert_eq!(rows.len(), 3, "{text}");
    assert!(rows[0].starts_with("| cornell | 36 |") && rows[2].starts_with("| office ×3 |"), "{text}");
    for r in rows {
        let rates: Vec<f64> = r.split('|').map(str::trim).filter(|c| !c.is_empty()).skip(5).map(|c| c.parse().unwrap()).collect();
        assert!(rates.len() == 4 && rates.iter().all(|&v| v > 0.0), "{r}");
    }
}

/// `--backend gpu` where no adapter of the allowed backends exists (Metal
/// on a machine without it): one line naming the option, exit code 2.
#[cfg(all(feature = "gpu", not(target_os = "macos")))]
#[test]
fn gpu_backend_without_an_adapter_is_one_line() {
    let dir = scratch("no-adapter");
    let out = dir.join("out.exr");
    let o = vpl()
        .env("WGPU_BACKEND", "metal")
        .args(["render", "--scene", "cornell", "--method", "vpl", "--backend", "gpu", "--size", "8x8", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(o.status.code(), Some(2), "status {:?}, stderr {err}", o.status);
    assert_eq!(lines.len(), 1, "expected one line, got {err:?}");
    assert!(lines[0].starts_with("vpl: error: ") && lines[0].contains("--backend gpu"), "{:?}", lines[0]);
    assert!(!out.exists());
}

/// `--backend gpu` with an image whose per-pixel buffers exceed any
/// adapter's storage-buffer limit (16384² × 16 bytes = 4 GiB): one line and
/// exit code 2 (or, without an adapter, the line that says so).
#[cfg(feature = "gpu")]
#[test]
fn gpu_backend_with_too_large_an_image_is_one_line() {
    let dir = scratch("too-large");
    let out = dir.join("out.exr");
    let o = vpl()
        .env("XDG_RUNTIME_DIR", &dir)
        .args([
            "render",
            "--scene",
            "cornell",
            "--method",
            "vpl",
            "--backend",
            "gpu",
            "--size",
            "16384x16384",
            "--memory-limit",
            "1T",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().collect();
    assert_eq!(o.status.code(), Some(2), "status {:?}, stderr {err}", o.status);
    assert_eq!(lines.len(), 1, "expected one line, got {err:?}");
    assert!(lines[0].starts_with("vpl: error: --backend gpu:"), "{:?}", lines[0]);
    assert!(!out.exists());
}

/// `--method progressive`: bad settings give one line and exit code 2.
#[test]
fn progressive_refuses_bad_input_in_one_line() {
    let dir = scratch("progressive-bad");
    let snaps = dir.join("snaps").to_string_lossy().into_owned();
    for (args, needle) in [
        (vec!["--scene", "cornell", "--method", "progressive", "--passes", "0"], "--passes must be at least 1"),
        (vec!["--scene", "cornell", "--method", "progressive", "--seconds", "-1"], "--seconds must be positive"),
        (vec!["--scene", "cornell", "--method", "progressive", "--techniques", "photons"], "unknown technique 'photons'"),
        (vec!["--scene", "cornell", "--method", "progressive", "--cull-accept", "0"], "--cull-accept"),
        (vec!["--scene", "cornell", "--method", "progressive", "--lens-radius", "-0.1"], "--lens-radius"),
        (vec!["--scene", "cornell", "--method", "progressive", "--snapshot-every", "4"], "go together"),
        (
            vec!["--scene", "cornell", "--method", "progressive", "--snapshot-every", "0", "--snapshots", &snaps],
            "--snapshot-every must be at least 1",
        ),
        (vec!["--scene", "cornell", "--method", "progressive", "--mode", "indirect"], "--techniques"),
        (vec!["--scene", "cornell", "--method", "progressive", "--max-depth", "0"], "--max-depth"),
    ] {
        fails(&dir, &args, needle);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--method progressive` writes the image, its preview, the standard
/// error and the snapshots, and says how many passes it rendered.
#[test]
fn progressive_renders_passes_and_snapshots() {
    let dir = scratch("progressive");
    let out = dir.join("g.exr");
    let se = dir.join("g_se.exr");
    let snaps = dir.join("snaps");
    let o = vpl()
        .args([
            "render",
            "--scene",
            "glass",
            "--method",
            "progressive",
            "--passes",
            "4",
            "--caustic-paths",
            "2000",
            "--size",
            "24x18",
            "--snapshot-every",
            "2",
            "--threads",
            "2",
            "--out",
        ])
        .arg(&out)
        .arg("--stderr")
        .arg(&se)
        .arg("--snapshots")
        .arg(&snaps)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("4 passes"), "{err}");
    let img = vpl_core::Image::read_exr(&out).unwrap();
    assert_eq!((img.width, img.height), (24, 18));
    assert!(img.mean()[0] > 0.0);
    assert!(dir.join("g.png").exists());
    assert!(vpl_core::Image::read_exr(&se).unwrap().mean()[0] > 0.0);
    for k in [2, 4] {
        assert!(snaps.join(format!("pass_{k:06}.exr")).exists(), "snapshot {k}");
    }
    // A time budget alone: at least one pass.
    let o = vpl()
        .args(["render", "--scene", "cornell", "--method", "progressive", "--seconds", "0.2", "--size", "16x16", "--quiet", "--out"])
        .arg(dir.join("c.exr"))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(vpl_core::Image::read_exr(dir.join("c.exr")).unwrap().mean()[0] > 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The loader's traps say what they are, one line each: a camera that sees
/// nothing, a camera behind one-sided walls, and layered materials that the
/// VPL pipeline (and the path tracer with `--materials diffuse`) draw by
/// their diffuse part. A clean render says none of it.
#[test]
fn views_of_nothing_and_dropped_layers_are_warned_in_one_line() {
    let d = scratch("warnings");
    let out = d.join("r.exr");
    let run = |args: &[&str]| {
        let o = vpl().arg("render").args(args).args(["--size", "16x12", "--quiet", "--out"]).arg(&out).output().unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stderr).lines().filter(|l| l.starts_with("vpl: warning:")).map(str::to_string).collect::<Vec<_>>()
    };
    // Cornell's camera turned around, and moved behind the box (a sequence
    // of its own, without camera keys, keeps the camera where it is put).
    let away = write(
        &d,
        "away.toml",
        "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0.0, 0.0, 3.9]\ntarget = [0.0, 0.0, 8.0]\nfov = 40.0\n[sequence]\nduration = 1.0\n",
    );
    let w = run(&["--scene", &away, "--spp", "1"]);
    assert!(w.len() == 1 && w[0].contains("the camera sees no surface"), "{w:?}");
    let behind = write(
        &d,
        "behind.toml",
        "[geometry]\nbuiltin = \"cornell\"\n[camera]\norigin = [0.2, 0.1, -6.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 40.0\n[sequence]\nduration = 1.0\n",
    );
    let w = run(&["--scene", &behind, "--spp", "1"]);
    assert!(w.len() == 1 && w[0].contains("only the back of one-sided surfaces"), "{w:?}");
    // The glass scene's sphere is layered.
    let w = run(&["--scene", "glass", "--method", "vpl", "--vpls", "64"]);
    assert!(w.iter().any(|l| l.contains("the VPL pipeline") && l.contains("glass")), "{w:?}");
    let w = run(&["--scene", "glass", "--spp", "1", "--materials", "diffuse"]);
    assert!(w.iter().any(|l| l.contains("the path tracer") && l.contains("glass")), "{w:?}");
    assert!(run(&["--scene", "glass", "--spp", "1"]).is_empty());
    assert!(run(&["--scene", "cornell", "--method", "vpl", "--vpls", "64"]).is_empty());
}

/// `--tev`: for each method, a server in the test receives the packets of
/// tev's IPC protocol, decoded independently of the client
/// (`vpl_cli::tev_ipc::decode_stream`); replayed, they give the image the
/// render wrote to its EXR, exactly. The path tracer sends tiles (several
/// packets), the progressive renderer passes. A tev that cannot be
/// reached is one line and exit 2, before rendering.
#[test]
fn render_streams_to_tev() {
    use std::io::Read;
    use std::net::TcpListener;
    use vpl_cli::tev_ipc::{Decoded, decode_stream, replay};
    let d = scratch("tev");
    let methods: [&[&str]; 3] = [
        &["--method", "path", "--spp", "2"],
        &["--method", "vpl", "--sampler", "ir", "--vpls", "64"],
        &["--method", "progressive", "--passes", "3", "--caustic-paths", "500"],
    ];
    for args in methods {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = l.local_addr().unwrap().to_string();
        let server = std::thread::spawn(move || {
            let (mut s, _) = l.accept().unwrap();
            let mut buf = Vec::new();
            s.read_to_end(&mut buf).unwrap();
            buf
        });
        let out = d.join("t.exr");
        let o = vpl()
            .args(["render", "--scene", "cornell", "--size", "40x24", "--threads", "2", "--tev", &addr, "--out"])
            .arg(&out)
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
        let packets = decode_stream(&server.join().unwrap()).unwrap_or_else(|e| panic!("{args:?}: {e}"));
        let name = match &packets[0] {
            Decoded::Create(name, 40, 24, ch) if ch == &["R", "G", "B"] => name.clone(),
            other => panic!("{args:?}: first packet {other:?}"),
        };
        let updates = packets.iter().filter(|p| matches!(p, Decoded::Update(..))).count();
        assert!(updates >= if args[1] == "vpl" { 1 } else { 2 }, "{args:?}: {updates} updates");
        let shown = replay(&packets, &name).unwrap();
        let written = vpl_core::Image::read_exr(&out).unwrap();
        assert!(shown == written, "{args:?}: tev's image differs from the EXR");
        assert!(written.mean()[0] > 0.0);
    }
    let free = TcpListener::bind("127.0.0.1:0").unwrap().local_addr().unwrap().to_string();
    fails(&d, &["--scene", "cornell", "--tev", &free], "--tev: cannot reach tev");
}

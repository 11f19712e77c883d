//! The `vpl` command as a careless or hostile user runs it: every case ends
//! in exit 0 with a finite image or exit 2 with one line naming the problem;
//! no panic, no runaway memory, no lost or left-over outputs.
//! `docs/robustness.md` lists the promises these tests hold the tool to.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use vpl_scene_io::ImageFile;

fn vpl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vpl"))
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vpl-robust-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data").join(rel)
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.to_string_lossy().into_owned()
}

fn files(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir).unwrap().flatten().map(|e| e.file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// Exit 2, one `vpl: error:` line containing `needle`, no panic.
fn refused(o: &Output, needle: &str, what: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("vpl: warning:")).collect();
    assert_eq!(o.status.code(), Some(2), "{what}: status {:?}, stderr {err}", o.status);
    assert_eq!(lines.len(), 1, "{what}: expected one line, got {err:?}");
    assert!(lines[0].starts_with("vpl: error: ") && lines[0].contains(needle), "{what}: {:?} lacks {needle:?}", lines[0]);
}

/// Exit 0 and a finite EXR at `out`.
fn rendered(o: &Output, out: &Path, what: &str) {
    assert_eq!(o.status.code(), Some(0), "{what}: {}", String::from_utf8_lossy(&o.stderr));
    let img = vpl_core::Image::read_exr(out).unwrap_or_else(|e| panic!("{what}: {e}"));
    assert!(img.data.iter().all(|p| p.is_finite()), "{what}: non-finite pixel");
}

fn render(args: &[&str], out: &Path) -> Output {
    vpl().arg("render").args(args).arg("--out").arg(out).args(["--size", "12x9", "--quiet"]).output().unwrap()
}

/// The Cornell box with its MTL replaced by `mtl`, and the OBJ edited by `edit`.
fn cornell(dir: &Path, mtl: Option<&str>, edit: impl Fn(String) -> String) -> String {
    let obj = std::fs::read_to_string(data("cornell-box/cbox.obj")).unwrap();
    let lib = std::fs::read_to_string(data("cornell-box/cbox.mtl")).unwrap();
    write(dir, "cbox.mtl", mtl.unwrap_or(&lib));
    write(dir, "cbox.obj", &edit(obj))
}

const METHODS: [&[&str]; 3] = [
    &["--method", "path", "--spp", "2"],
    &["--method", "vpl", "--vpls", "32", "--direct-samples", "2"],
    &["--method", "progressive", "--passes", "2", "--caustic-paths", "256"],
];

#[test]
fn a_long_thin_triangle_renders_with_every_method() {
    let d = scratch("sliver");
    // One top corner of the tall block moved to y = 4000.
    let scene = cornell(&d, None, |o| o.replacen("v 0.048859 0.21 -0.089039", "v 0.048859 4000 -0.089039", 1));
    for m in METHODS {
        let out = d.join("r.exr");
        let mut args = vec!["--scene", &scene];
        args.extend_from_slice(m);
        rendered(&render(&args, &out), &out, &format!("sliver {m:?}"));
    }
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn material_libraries_are_parsed_or_refused_by_line() {
    let d = scratch("mtl");
    let lib = std::fs::read_to_string(data("cornell-box/cbox.mtl")).unwrap();
    let out = d.join("r.exr");
    // One number is all three channels (the MTL specification).
    let scene = cornell(&d, Some(&lib.replace("Kd 0.885809 0.698859 0.666422", "Kd 0.8")), |o| o);
    rendered(&render(&["--scene", &scene, "--spp", "1"], &out), &out, "Kd 0.8");
    std::fs::remove_file(&out).unwrap();
    // Two numbers, a non-finite and a non-number: errors naming file:line and the value.
    for (from, to, needle) in [
        ("Ke 18.387 13.9873 6.75357", "Ke 10 10", "cbox.mtl:"),
        ("Ke 18.387 13.9873 6.75357", "Ke inf 1 1", "'inf' is not finite"),
        ("Ke 18.387 13.9873 6.75357", "Ke ten", "'ten' is not a number"),
        ("Ke 18.387 13.9873 6.75357", "Ke 3e38", "is above"),
    ] {
        let edited = lib.replace(from, to);
        assert_ne!(edited, lib, "{from} not in cbox.mtl");
        let scene = cornell(&d, Some(&edited), |o| o);
        refused(&render(&["--scene", &scene, "--spp", "1"], &out), needle, to);
        assert!(!out.exists());
    }
    // A byte-order mark before mtllib.
    let scene = cornell(&d, None, |o| format!("\u{feff}{o}"));
    rendered(&render(&["--scene", &scene, "--spp", "1"], &out), &out, "BOM");
    // An mtllib naming the OBJ itself; a usemtl naming nothing (the light's): the problem is named.
    let scene = cornell(&d, None, |o| o.replace("mtllib cbox.mtl", "mtllib cbox.obj"));
    refused(&render(&["--scene", &scene, "--spp", "1"], &out), "no material library", "mtllib self");
    let scene = cornell(&d, None, |o| o.replace("usemtl light", "usemtl lamp"));
    refused(&render(&["--scene", &scene, "--spp", "1"], &out), "usemtl 'lamp' names no material", "unknown usemtl");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn devices_and_absurd_values_are_refused_at_load() {
    let d = scratch("load");
    let out = d.join("r.exr");
    let zero = write(&d, "zero.toml", "[geometry]\nobj = \"/dev/zero\"\n");
    // Outside the scene's folder: refused by the sandbox; allowed, still no file.
    refused(&render(&["--scene", &zero], &out), "'/dev/zero' leaves the scene's folder", "obj = /dev/zero");
    refused(&render(&["--scene", &zero, "--allow-outside", "/dev"], &out), "/dev/zero is a device", "obj = /dev/zero, allowed");
    let scene = cornell(&d, None, |o| o.replace("mtllib cbox.mtl", "mtllib /dev/zero"));
    refused(&render(&["--scene", &scene], &out), "'/dev/zero' leaves the scene's folder", "mtllib /dev/zero");
    refused(&render(&["--scene", &scene, "--allow-outside", "/dev"], &out), "/dev/zero is a device", "mtllib /dev/zero, allowed");
    let huge = write(&d, "e.toml", "[geometry]\nbuiltin = \"cornell\"\n[[materials]]\nname = \"light\"\nemission = [3e38, 3e38, 3e38]\n");
    refused(&render(&["--scene", &huge], &out), "material 'light' emission", "emission 3e38");
    let bright = write(&d, "a.toml", "[geometry]\nbuiltin = \"cornell\"\n[[materials]]\nname = \"white\"\nalbedo = [1.5, 0.5, 0.5]\n");
    refused(&render(&["--scene", &bright], &out), "reflects more light than it receives", "albedo 1.5");
    let far = write(
        &d,
        "p.toml",
        "[geometry]\nbuiltin = \"cornell\"\n[[lights]]\ntype = \"point\"\nposition = [0, 1e30, 0]\nintensity = [1, 1, 1]\n",
    );
    refused(&render(&["--scene", &far], &out), "light 0 position", "light at 1e30");
    assert!(files(&d).iter().all(|f| !f.starts_with("r.")), "{:?}", files(&d));
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn memory_and_threads_are_decided_before_the_work() {
    let d = scratch("limits");
    let out = d.join("r.exr");
    let vpl_args = ["--scene", "cornell", "--method", "vpl", "--memory-limit", "8G"];
    let o = render(&[&vpl_args[..], &["--vpls", "10000000"]].concat(), &out);
    refused(&o, "(--vpls", "10 M VPLs");
    assert!(String::from_utf8_lossy(&o.stderr).contains("8.0 GiB"));
    let o = render(&[&vpl_args[..], &["--vpls", "2048", "--shadowmap-res", "4096"]].concat(), &out);
    refused(&o, "--shadowmap-res)", "4096² maps");
    assert!(String::from_utf8_lossy(&o.stderr).contains("128."), "{}", String::from_utf8_lossy(&o.stderr));
    // Camera samples: weighed in the estimate, and past 2²⁴ refused as a
    // parameter (a "capacity overflow" abort before).
    let tcas = ["--scene", "cornell", "--method", "vpl", "--sampler", "tcas"];
    let o = render(&[&tcas[..], &["--camera-samples", "100000000", "--memory-limit", "1G"]].concat(), &out);
    refused(&o, "(--camera-samples)", "10^8 camera samples");
    for sampler in ["tcas", "mir", "rr"] {
        let o = render(
            &["--scene", "cornell", "--method", "vpl", "--sampler", sampler, "--camera-samples", "4294967296", "--memory-limit", "1000T"],
            &out,
        );
        refused(&o, "camera-samples", "2^32 camera samples");
    }
    // A bitmap texture is decoded within --memory-limit (it peaked at 1.8 GiB
    // under 256M): a 512² RGB texture (768 KiB decoded) under 512K is refused
    // naming the limit, and renders under 256M.
    let rgb = vec![200u8; 512 * 512 * 3];
    std::fs::write(d.join("t.png"), vpl_scene_io::encode_png_rgb8(512, 512, &rgb).unwrap()).unwrap();
    let textured = write(
        &d,
        "t.xml",
        "<scene version=\"3.0.0\"><bsdf type=\"diffuse\" id=\"b\"><texture type=\"bitmap\" name=\"reflectance\">\
         <string name=\"filename\" value=\"t.png\"/></texture></bsdf><shape type=\"cube\"><ref id=\"b\"/></shape>\
         <emitter type=\"point\"><point name=\"position\" x=\"0\" y=\"3\" z=\"3\"/><rgb name=\"intensity\" value=\"5\"/></emitter>\
         <sensor type=\"perspective\"><transform name=\"to_world\"><lookat origin=\"0, 2, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform></sensor></scene>",
    );
    refused(
        &render(&["--scene", &textured, "--spp", "1", "--memory-limit", "512K"], &out),
        "decoding its 512×512 pixels takes more than the memory limit",
        "bitmap under 512K",
    );
    let o = render(&["--scene", &textured, "--spp", "1", "--memory-limit", "256M"], &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    refused(&render(&["--scene", "cornell", "--threads", "100000"], &out), "--threads 100000", "threads");
    refused(&render(&["--scene", "cornell", "--memory-limit", "lots"], &out), "memory limit 'lots'", "limit syntax");
    // The summary reports the estimate beside the peak.
    let o = vpl().args(["render", "--scene", "cornell", "--size", "8x8", "--spp", "1", "--out"]).arg(&out).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && err.contains("memory: estimated") && err.contains("peak"), "{err}");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn outputs_follow_their_extension_and_never_collide() {
    let d = scratch("outputs");
    // .png: a PNG, nothing else.
    let png = d.join("r.png");
    assert!(render(&["--scene", "cornell", "--spp", "1"], &png).status.success());
    assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    assert_eq!(files(&d), ["r.png"]);
    // .exr: the EXR and its preview.
    let exr = d.join("r.exr");
    assert!(render(&["--scene", "cornell", "--spp", "1"], &exr).status.success());
    assert_eq!(files(&d), ["r.exr", "r.png"]);
    std::fs::remove_file(&exr).unwrap();
    std::fs::remove_file(&png).unwrap();
    refused(&render(&["--scene", "cornell"], &d.join("r.tif")), "must end in .exr", ".tif");
    let same = d.join("s.exr").to_string_lossy().into_owned();
    refused(&render(&["--scene", "cornell", "--stderr", &same], &d.join("s.exr")), "name the same file", "--stderr = --out");
    let preview = d.join("s.png").to_string_lossy().into_owned();
    refused(&render(&["--scene", "cornell", "--stderr", &preview], &d.join("s.exr")), "name the same file", "--stderr = preview");
    // A preview that cannot be written: the EXR is not left behind.
    std::fs::create_dir(d.join("t.png")).unwrap();
    refused(&render(&["--scene", "cornell", "--spp", "1"], &d.join("t.exr")), "t.png", "preview is a folder");
    assert_eq!(files(&d), ["t.png"]);
    // A stale temporary of a killed writer is removed by the next write.
    let stale = d.join(".u.exr.4194304.tmp");
    std::fs::write(&stale, b"partial").unwrap();
    assert!(render(&["--scene", "cornell", "--spp", "1"], &d.join("u.exr")).status.success());
    assert!(!stale.exists());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn failed_commands_create_no_folder() {
    let d = scratch("folders");
    let out = d.join("out");
    let o = vpl()
        .args(["sequence", "--scene", "cornell", "--size", "8x8", "--pixel", "99,99", "--frames", "0..1", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    refused(&o, "99", "sequence --pixel");
    assert!(!out.exists(), "sequence left its folder");
    let o = vpl().args(["validate-cornell", "--spp", "1", "--data"]).arg(d.join("nothing")).arg("--out").arg(&out).output().unwrap();
    refused(&o, "cannot read", "validate-cornell --data");
    assert!(!out.exists(), "validate-cornell left its folder");
    let o = vpl().args(["georgiev", "--sweep", "7", "--out"]).arg(&out).output().unwrap();
    refused(&o, "--sweep", "georgiev --sweep");
    assert!(!out.exists(), "georgiev left its folder");
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
fn hostile_references_are_refused_before_rendering() {
    let d = scratch("refs");
    for f in std::fs::read_dir(data("cornell-box")).unwrap().flatten() {
        std::fs::copy(f.path(), d.join(f.file_name())).unwrap();
    }
    // A header claiming a 10⁹ × 10⁹ data window.
    let path = d.join("reference_indirect.exr");
    let mut bytes = std::fs::read(&path).unwrap();
    let tag = b"dataWindow\0box2i\0";
    let at = bytes.windows(tag.len()).position(|w| w == tag).unwrap() + tag.len() + 4;
    for (k, v) in [0i32, 0, 1_000_000_000, 1_000_000_000].into_iter().enumerate() {
        bytes[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
    }
    std::fs::write(&path, &bytes).unwrap();
    let out = d.join("out");
    let o = vpl().args(["validate-cornell", "--spp", "1", "--data"]).arg(&d).arg("--out").arg(&out).output().unwrap();
    refused(&o, "reference_indirect.exr", "huge data window");
    // A NaN pixel.
    let mut img = vpl_core::Image::read_exr(data("cornell-box/reference_indirect.exr")).unwrap();
    img.data[5].x = f32::NAN;
    img.write_exr(&path).unwrap();
    let o = vpl().args(["validate-cornell", "--spp", "1", "--data"]).arg(&d).arg("--out").arg(&out).output().unwrap();
    refused(&o, "reference_indirect.exr pixel (5, 0)", "NaN reference pixel");
    assert!(!out.exists());
    std::fs::remove_dir_all(&d).unwrap();
}

#[test]
#[cfg(unix)]
fn an_interrupted_render_leaves_nothing() {
    let d = scratch("sigint");
    let out = d.join("r.exr");
    let mut child = vpl()
        .args(["render", "--scene", "cornell", "--size", "256x256", "--spp", "100000", "--threads", "1", "--quiet", "--out"])
        .arg(&out)
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let _ = Command::new("kill").args(["-INT", &child.id().to_string()]).status();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{status:?}");
    assert!(files(&d).is_empty(), "{:?}", files(&d));
    std::fs::remove_dir_all(&d).unwrap();
}

/// Every file under `dir` with its bytes, for comparing a folder before
/// and after a command.
#[cfg(unix)]
fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            for (n, b) in snapshot(&p) {
                out.push((format!("{}/{n}", e.file_name().to_string_lossy()), b));
            }
        } else {
            out.push((e.file_name().to_string_lossy().into_owned(), std::fs::read(&p).unwrap()));
        }
    }
    out.sort();
    out
}

/// A sequence into a folder that holds an earlier run, stopped by SIGTERM
/// at several moments: the exit code is 130 and the folder holds exactly
/// the earlier run's files, byte for byte (before, the new frames replaced
/// the old ones as they were rendered and stayed; a signal during a write
/// ended in "cannot write" with exit 2, or left a temporary).
#[test]
#[cfg(unix)]
fn an_interrupted_sequence_leaves_the_earlier_run_as_it_was() {
    let d = scratch("sigterm-sequence");
    let out = d.join("run");
    let first = vpl()
        .args(["sequence", "--scene", "cornell", "--size", "16x12", "--vpls", "64", "--frames", "0..2", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(first.status.success(), "{}", String::from_utf8_lossy(&first.stderr));
    let before = snapshot(&out);
    assert!(before.len() >= 3, "{:?}", before.iter().map(|f| &f.0).collect::<Vec<_>>());
    for delay_ms in [700, 1500, 2600] {
        let child = vpl()
            .args([
                "sequence",
                "--scene",
                "cornell",
                "--size",
                "96x72",
                "--vpls",
                "256",
                "--frames",
                "0..400",
                "--threads",
                "1",
                "--quiet",
                "--out",
            ])
            .arg(&out)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(delay_ms));
        let _ = Command::new("kill").args(["-TERM", &child.id().to_string()]).status();
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "after {delay_ms} ms: {err}");
        assert!(err.contains("interrupted") && !err.contains("cannot write"), "{err}");
        let after = snapshot(&out);
        assert!(after == before, "after {delay_ms} ms the folder changed: {:?}", after.iter().map(|f| &f.0).collect::<Vec<_>>());
    }
    std::fs::remove_dir_all(&d).unwrap();
}

//! `vpl view` on a display (Xvfb and lavapipe in CI): a scripted session
//! switches to a split view and turns the VPL overlay on, and its
//! screenshots must show the scene, the panel, the split line, the overlay,
//! and a right half that changed with the sampler; a second picks a VPL
//! (its shadow map and interleaving class shown), accumulates the path
//! tracer's reference and its difference, and records a camera path as a
//! scene file that loads with the animation flown. Without a display the
//! session test says it skipped, unless `VPL_REQUIRE_DISPLAY=1` (CI) makes
//! that a failure; without one the command must say so in one line, exit 2.

use std::path::Path;
use std::process::Command;

fn vpl() -> Command {
    Command::new(env!("CARGO_BIN_EXE_vpl"))
}

fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"].iter().any(|v| std::env::var(v).is_ok_and(|s| !s.is_empty()))
}

struct Png {
    w: usize,
    h: usize,
    rgb: Vec<u8>,
}

impl Png {
    fn read(path: &Path) -> Png {
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!(info.color_type, png::ColorType::Rgb, "{}", path.display());
        buf.truncate(info.buffer_size());
        Png { w: info.width as usize, h: info.height as usize, rgb: buf }
    }

    fn px(&self, x: usize, y: usize) -> [u8; 3] {
        let i = (y * self.w + x) * 3;
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }
}

/// The numbers of a screenshot's JSON that the checks read.
struct Layout {
    view: [usize; 4],
    split_x: Option<usize>,
    overlay: String,
    sides: usize,
    reference_passes: u32,
    picked: bool,
    shadow_map: Option<[usize; 4]>,
}

fn layout(path: &Path) -> Layout {
    let text = std::fs::read_to_string(path).unwrap();
    let field = |key: &str| -> String {
        let start = text.find(&format!("\"{key}\": ")).unwrap_or_else(|| panic!("{key} in {text}")) + key.len() + 4;
        let rest = &text[start..];
        rest[..rest.find('\n').unwrap()].trim_end_matches(',').to_string()
    };
    let nums = |s: String| -> Vec<f64> { s.trim_matches(['[', ']']).split(',').map(|v| v.trim().parse().unwrap()).collect() };
    let v = nums(field("view"));
    let split = field("split_x");
    Layout {
        view: [v[0].ceil() as usize, v[1].ceil() as usize, v[2].floor() as usize, v[3].floor() as usize],
        split_x: (split != "null").then(|| split.parse::<f64>().unwrap().round() as usize),
        overlay: field("overlay").trim_matches('"').to_string(),
        sides: field("sides").matches('"').count() / 2,
        reference_passes: field("reference_passes").parse().unwrap(),
        picked: field("picked") != "null",
        shadow_map: Some(field("shadow_map")).filter(|m| m != "null").map(|m| {
            let v = nums(m);
            [v[0].ceil() as usize, v[1].ceil() as usize, v[2].floor() as usize, v[3].floor() as usize]
        }),
    }
}

/// Mean absolute difference (0–255) of two screenshots over columns `x0..x1`
/// of rows `y0..y1`, and the share of pixels that differ by more than 8.
fn difference(a: &Png, b: &Png, x0: usize, x1: usize, y0: usize, y1: usize) -> (f64, f64) {
    let (mut sum, mut differ, mut n) = (0.0, 0usize, 0usize);
    for y in y0..y1 {
        for x in x0..x1 {
            let (p, q) = (a.px(x, y), b.px(x, y));
            let d: i32 = (0..3).map(|c| (p[c] as i32 - q[c] as i32).abs()).sum();
            sum += d as f64 / 3.0;
            differ += (d > 8 * 3) as usize;
            n += 1;
        }
    }
    (sum / n.max(1) as f64, differ as f64 / n.max(1) as f64)
}

#[test]
fn a_scripted_session_shows_the_scene_the_split_and_the_overlay() {
    if !has_display() {
        assert!(std::env::var("VPL_REQUIRE_DISPLAY").is_err(), "VPL_REQUIRE_DISPLAY is set and there is no display");
        eprintln!("skipped: no display (DISPLAY or WAYLAND_DISPLAY); CI runs this under Xvfb");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = |name: &str| dir.path().join(name);
    let script = format!(
        "frames 2\nscreenshot {}\nsplit smc\nframes 3\nscreenshot {}\noverlay vpls\nframes 1\nscreenshot {}\nquit\n",
        shot("alone").display(),
        shot("split").display(),
        shot("overlay").display()
    );
    let script_path = dir.path().join("session.txt");
    std::fs::write(&script_path, script).unwrap();
    let out = vpl()
        .args(["view", "--scene", "office", "--window", "800x450", "--vpls", "64"])
        .arg("--script")
        .arg(&script_path)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "vpl view failed: {stderr}");
    assert!(stderr.contains("frames shown"), "{stderr}");
    eprintln!("{stderr}");

    for name in ["alone", "split", "overlay"] {
        for ext in ["png", "exr", "json"] {
            assert!(shot(&format!("{name}.{ext}")).exists(), "{name}.{ext} written");
        }
    }
    let alone = Png::read(&shot("alone.png"));
    let split = Png::read(&shot("split.png"));
    let overlay = Png::read(&shot("overlay.png"));
    assert_eq!((alone.w, alone.h), (800, 450));
    let la = layout(&shot("alone.json"));
    let ls = layout(&shot("split.json"));
    let lo = layout(&shot("overlay.json"));
    let [x0, y0, x1, y1] = la.view;
    assert!(x0 > 100 && x1 <= 800 && y1 <= 450 && x1 > x0 + 100, "the view beside the panel: {:?}", la.view);

    // The scene: the view is not black (office is lit: a mean of 8 of 255 is very dim).
    let mean = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .map(|(x, y)| alone.px(x, y).iter().map(|v| *v as f64).sum::<f64>() / 3.0)
        .sum::<f64>()
        / ((x1 - x0) * (y1 - y0)) as f64;
    assert!(mean > 8.0, "the view shows the scene: mean {mean:.1} of 255");
    // The UI: the panel holds text and widgets, many distinct colours, not one fill.
    let mut colours: Vec<[u8; 3]> = (0..y1).flat_map(|y| (0..x0 - 5).map(move |x| (x, y))).map(|(x, y)| alone.px(x, y)).collect();
    colours.sort();
    colours.dedup();
    assert!(colours.len() > 20, "the panel shows the UI: {} colours", colours.len());

    // The split: no split alone; a white line at split_x over the view's height.
    assert_eq!((la.split_x, la.sides), (None, 1));
    assert_eq!(ls.sides, 2);
    let sx = ls.split_x.expect("split_x of a split view");
    assert!(sx > x0 + 20 && sx + 20 < x1, "split at {sx} inside {:?}", ls.view);
    let white = (y0..y1).filter(|y| (sx.saturating_sub(2)..=sx + 2).any(|x| split.px(x, *y).iter().all(|v| *v >= 250))).count();
    assert!(white as f64 > 0.95 * (y1 - y0) as f64, "the split line: {white} of {} rows", y1 - y0);
    // The right half shows another sampler (smc instead of ir): it changed.
    let (right_mad, right_share) = difference(&alone, &split, sx + 4, x1, y0, y1);
    assert!(
        right_mad > 1.0 && right_share > 0.05,
        "the right half changed with the sampler: mean |Δ| {right_mad:.2}, {:.1} % of pixels",
        100.0 * right_share
    );

    // The overlay: splats in saturated colours of the flux ramp over a grey
    // office (its walls, floor and light are grey), none before.
    assert_eq!((ls.overlay.as_str(), lo.overlay.as_str()), ("off", "vpls"));
    let saturated = |p: &Png| {
        (y0..y1)
            .flat_map(|y| (x0..x1).map(move |x| (x, y)))
            .filter(|&(x, y)| {
                let c = p.px(x, y);
                c.iter().max().unwrap() - c.iter().min().unwrap() > 120
            })
            .count()
    };
    let (before, after) = (saturated(&split), saturated(&overlay));
    eprintln!(
        "view mean {mean:.1}/255, panel colours {}, split line {white}/{} rows, right half mean |Δ| {right_mad:.2} ({:.1} % of pixels), saturated {before} -> {after}",
        colours.len(),
        y1 - y0,
        100.0 * right_share
    );
    assert!(after > before + 90, "the overlay splats the VPLs (3×3 each): {before} saturated pixels before, {after} after");
}

/// Mean of the channels over the view's pixels outside `hole`.
fn view_mean(p: &Png, view: [usize; 4], hole: Option<[usize; 4]>) -> f64 {
    let [x0, y0, x1, y1] = view;
    let inside = |x: usize, y: usize| hole.is_some_and(|[a, b, c, d]| x >= a && x < c && y >= b && y < d);
    let (mut sum, mut n) = (0.0, 0usize);
    for y in y0..y1 {
        for x in x0..x1 {
            if !inside(x, y) {
                sum += p.px(x, y).iter().map(|v| *v as f64).sum::<f64>() / 3.0;
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

/// Counts in `vpl view`'s closing line: frames shown, and views composed
/// on the device.
fn counts(stderr: &str) -> (u64, u64) {
    let before = |marker: &str| {
        stderr
            .split(marker)
            .next()
            .and_then(|head| head.rsplit(' ').next())
            .and_then(|n| n.parse::<u64>().ok())
            .unwrap_or_else(|| panic!("a count before `{marker}` in {stderr}"))
    };
    (before(" frames shown"), before(" of them composed on the device"))
}

/// On the GPU the window opens on the renderer's device and every frame
/// (all light paths) stays there: the view is composed on the device, and
/// the pick, the reference and the difference read back only what they
/// need. On the CPU (no adapter) nothing is composed on a device, and
/// VPL_REQUIRE_GPU=1 makes that a failure.
#[test]
fn a_session_picks_a_vpl_accumulates_a_reference_and_records_a_path() {
    let Some(stderr) = picks_references_and_records(&[]) else { return };
    let (shown, composed) = counts(&stderr);
    if !stderr.contains("renderer: GPU") {
        assert!(std::env::var("VPL_REQUIRE_GPU").is_err(), "VPL_REQUIRE_GPU=1 and the viewer ran on the CPU: {stderr}");
        assert_eq!(composed, 0, "{stderr}");
        return;
    }
    // Every frame composes on the device (some twice: a change of overlay
    // or channel recomposes the frame shown).
    assert!(composed >= shown, "{composed} views composed on the device for {shown} frames: {stderr}");
}

/// The same session on the CPU backend: the frames are on the host and the
/// view is composed there.
#[test]
fn the_same_session_on_the_cpu_composes_on_the_host() {
    let Some(stderr) = picks_references_and_records(&["--backend", "cpu"]) else { return };
    assert!(stderr.contains("renderer: CPU"), "{stderr}");
    let (shown, composed) = counts(&stderr);
    assert!(shown > 0 && composed == 0, "{stderr}");
}

/// Runs the picking session with `extra` arguments and checks what it
/// shows; answers its stderr (`None`: skipped, no display).
fn picks_references_and_records(extra: &[&str]) -> Option<String> {
    if !has_display() {
        assert!(std::env::var("VPL_REQUIRE_DISPLAY").is_err(), "VPL_REQUIRE_DISPLAY is set and there is no display");
        eprintln!("skipped: no display (DISPLAY or WAYLAND_DISPLAY); CI runs this under Xvfb");
        return None;
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = |name: &str| dir.path().join(name);
    let path_file = dir.path().join("flown").join("office-path.toml");
    let script = format!(
        "overlay vpls\nframes 2\nscreenshot {plain}\npick 0.5 0.6\nframes 1\nscreenshot {picked}\n\
         overlay interleave\nframes 1\nscreenshot {interleave}\noverlay off\npick off\nreference on\nframes 4\n\
         screenshot {reference}\nshow difference\nframes 1\nscreenshot {difference}\nshow image\nrecord start\n\
         orbit 25 0\nframes 1\norbit 25 5\nframes 1\nrecord stop {path}\nquit\n",
        plain = shot("plain").display(),
        picked = shot("picked").display(),
        interleave = shot("interleave").display(),
        reference = shot("reference").display(),
        difference = shot("difference").display(),
        path = path_file.display(),
    );
    let script_path = dir.path().join("session.txt");
    std::fs::write(&script_path, script).unwrap();
    let out = vpl()
        .args(["view", "--scene", "office", "--window", "800x450", "--vpls", "64"])
        .args(extra)
        .arg("--script")
        .arg(&script_path)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "vpl view failed: {stderr}");
    eprintln!("{stderr}");
    let png = |n: &str| Png::read(&shot(&format!("{n}.png")));
    let json = |n: &str| layout(&shot(&format!("{n}.json")));
    let (plain, picked, interleave, diff_shot) = (png("plain"), png("picked"), png("interleave"), png("difference"));
    let (lp, lk, li, lr) = (json("plain"), json("picked"), json("interleave"), json("reference"));

    // A picked VPL: ringed, its shadow map inset in the view's corner.
    assert!(!lp.picked && lp.shadow_map.is_none());
    assert!(lk.picked, "pick 0.5 0.6 picks the VPL nearest the point");
    let map = lk.shadow_map.expect("the shadow map is shown");
    let [mx0, my0, mx1, my1] = map;
    assert!(mx1 > mx0 + 40 && my1 > my0 + 40 && mx1 <= lk.view[2] && my1 <= lk.view[3], "the map inside the view: {map:?}");
    let (map_change, _) = difference(&plain, &picked, mx0, mx1, my0, my1);
    assert!(map_change > 5.0, "the map covers the view's corner: mean |Δ| {map_change:.1}");
    // The map's corners lie outside the paraboloid's disk: grey (60, 60, 60).
    let corner = picked.px(mx0 + 3, my0 + 3);
    assert!(corner.iter().all(|v| (*v as i32 - 60).abs() <= 8), "the map's corner is grey: {corner:?}");
    let magenta = |p: &Png| (0..p.h).flat_map(|y| (0..p.w).map(move |x| (x, y))).filter(|&(x, y)| p.px(x, y) == [255, 0, 255]).count();
    assert!(magenta(&picked) > magenta(&plain) + 100, "the pick's ring and the map's frame are drawn");

    // The interleaving pattern with a VPL picked: only its class (1 pixel of
    // 16) keeps its brightness, the rest is dimmed to a quarter.
    assert_eq!(li.overlay, "interleave");
    let (m_plain, m_inter) = (view_mean(&plain, lp.view, Some(map)), view_mean(&interleave, li.view, Some(map)));
    assert!(m_inter < 0.6 * m_plain, "the pattern dims the other classes: mean {m_inter:.1} against {m_plain:.1}");

    // The reference: one pass at least for each of the 4 frames waited for.
    assert!(lr.reference_passes >= 4, "{} reference passes", lr.reference_passes);
    // The difference: red and blue where the frame is brighter or darker.
    let [x0, y0, x1, y1] = lr.view;
    let coloured = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| (x, y)))
        .filter(|&(x, y)| {
            let c = diff_shot.px(x, y);
            (c[0] as i32).max(c[2] as i32) > 2 * c[1] as i32 + 20
        })
        .count();
    let share = coloured as f64 / ((x1 - x0) * (y1 - y0)) as f64;
    assert!(share > 0.1, "the difference shows red and blue: {:.1} % of the view", 100.0 * share);

    // The recorded path: a scene file of office whose animation ends where the orbits left the camera.
    let text = std::fs::read_to_string(&path_file).unwrap();
    assert!(text.contains("builtin = \"office\""), "{text}");
    let setup = vpl_scene_io::load(path_file.to_str().unwrap()).unwrap();
    let seq = setup.sequence.as_ref().expect("the file has the animation");
    assert!(seq.camera.len() >= 2, "{} camera keys", seq.camera.len());
    let (first, last) = (seq.camera[0], *seq.camera.last().unwrap());
    let office = vpl_core::SceneSetup::builtin("office").unwrap();
    assert!((first.origin - office.camera.origin).length() < 1e-3, "the path starts at the scene's camera");
    assert!((last.origin - first.origin).length() > 0.05 * setup.scene.radius(), "the orbits moved the camera");
    eprintln!(
        "map change {map_change:.1}, pattern mean {m_inter:.1} of {m_plain:.1}, {} reference passes, difference coloured {:.1} %, {} camera keys over {:.2} s",
        lr.reference_passes,
        100.0 * share,
        seq.camera.len(),
        seq.duration
    );
    Some(stderr)
}

/// `vpl view` with `display` as `DISPLAY` (none: unset; then on the
/// default backend, whose GPU libraries must not load first), no Wayland and,
/// as a new user's shell may be, no XDG_RUNTIME_DIR (where
/// libwayland-client, once loaded, prints lines of its own): it must end
/// with exit 2 and one line that says "no display" and quotes no source
/// location.
fn assert_no_display_in_one_line(display: Option<&str>) {
    let mut c = vpl();
    c.args(["view", "--scene", "cornell"]);
    for var in ["DISPLAY", "WAYLAND_DISPLAY", "WAYLAND_SOCKET", "XDG_RUNTIME_DIR"] {
        c.env_remove(var);
    }
    if let Some(d) = display {
        // On the CPU: no GPU library loads beside the failed connection.
        c.args(["--backend", "cpu"]).env("DISPLAY", d);
    }
    let out = c.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no display"), "{stderr}");
    assert!(!stderr.contains(".rs:"), "a source location in the line: {stderr}");
}

#[test]
fn without_a_display_view_says_so_in_one_line() {
    assert_no_display_in_one_line(None);
}

/// A `DISPLAY` that names no server: winit's error comes back in one
/// line, without the location inside winit's sources.
#[test]
fn an_unreachable_display_is_one_line_without_source_paths() {
    assert_no_display_in_one_line(Some(":4711"));
}

#[test]
fn a_bad_script_or_sampler_is_one_line_before_any_window() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.txt");
    std::fs::write(&bad, "frames 1\nfly away\n").unwrap();
    let out = vpl().arg("view").arg("--script").arg(&bad).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("line 2") && stderr.trim_end().lines().count() == 1, "{stderr}");
    let out = vpl().args(["view", "--sampler", "nonesuch"]).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("unknown sampler `nonesuch`"), "{stderr}");
    // The pipeline's flags are read before any window too: a backend is
    // one of the build's names, a flag one the sampler reads.
    for (args, says) in [
        (&["view", "--backend", "abacus"][..], "unknown backend (this build has: auto, cpu"),
        (&["view", "--sampler", "ir", "--m-max", "3"][..], "--sampler ir does not read --m-max"),
        (&["view", "--shadowmap-res", "0"][..], "--shadowmap-res"),
    ] {
        let out = vpl().args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says) && stderr.trim_end().lines().count() == 1, "{args:?}: {stderr}");
    }
}

/// The pipeline's flags reach the viewer's renderers: the sampler's own
/// flags and `--set` keys go to the left side's sampler (the split side, a
/// sampler of the panel, starts from its defaults), and visibility, shading
/// and backend to both, as the screenshot's layout reports them.
#[test]
fn the_pipeline_flags_reach_both_sides() {
    if !has_display() {
        assert!(std::env::var("VPL_REQUIRE_DISPLAY").is_err(), "VPL_REQUIRE_DISPLAY is set and there is no display");
        eprintln!("skipped: no display (DISPLAY or WAYLAND_DISPLAY); CI runs this under Xvfb");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot");
    let script = dir.path().join("session.txt");
    std::fs::write(&script, format!("frames 1\nscreenshot {}\nquit\n", shot.display())).unwrap();
    let out = vpl()
        .args(["view", "--scene", "cornell", "--window", "320x240", "--vpls", "32", "--backend", "cpu"])
        .args(["--sampler", "smc", "--m-max", "2", "--set", "resample-ratio=4", "--split", "ir"])
        .args(["--visibility", "raytrace", "--shading", "exhaustive", "--direct-samples", "2", "--script"])
        .arg(&script)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "vpl view failed: {stderr}");
    let text = std::fs::read_to_string(dir.path().join("shot.json")).unwrap();
    let line = text.lines().find(|l| l.contains("\"pipelines\"")).unwrap_or_else(|| panic!("{text}"));
    let sides: Vec<&str> = line.split('"').filter(|p| p.contains("sampler=")).collect();
    assert_eq!(sides.len(), 2, "{line}");
    for (side, sampler) in sides.iter().zip(["smc", "ir"]) {
        for want in
            [&format!("sampler={sampler} "), "vpls=32 ", "visibility=raytrace", "shading=exhaustive", "direct-samples=2", "backend=cpu"]
        {
            assert!(side.contains(want), "{want} in {side}");
        }
    }
    assert!(sides[0].contains("m-max=2") && sides[0].contains("resample-ratio=4"), "{}", sides[0]);
    assert!(!sides[1].contains("m-max"), "the split side's sampler starts from its defaults: {}", sides[1]);
}

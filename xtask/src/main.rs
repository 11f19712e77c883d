//! `cargo xtask …`: the toolkit's jobs.
//!
//! - `cargo xtask reproduce [--quick | --full] [--only LIST]`: the scene
//!   gallery (`results/scenes/`), path-traced references of every built-in
//!   scene (`results/references/`), the path tracer's validation against
//!   Mitsuba 3 (`results/validation/`), and `results/README.md`.
//! - `cargo xtask test`: the whole test suite, as CI runs it.
//! - `cargo xtask bench-pt`: path-tracing throughput on `cornell`.
//! - `cargo xtask bench-vpl`: milliseconds per VPL stage at 640×360, 2048 VPLs, `cornell` and
//!   `office`, and the SMC sampler's steps (the SMC paper's Table 2) on `office` and `maze`.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

const SCENES: [&str; 7] = ["cornell", "maze", "office", "courtyard", "atrium", "corner", "glass"];
const JOBS: [&str; 4] = ["scenes", "references", "validation", "georgiev"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).parent().unwrap().to_path_buf()
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

fn run(mut c: Command, what: &str) -> Result<(), String> {
    let status = c.status().map_err(|e| format!("{what}: {e}"))?;
    if status.success() { Ok(()) } else { Err(format!("{what} failed ({status})")) }
}

fn usage() -> &'static str {
    "usage: cargo xtask <reproduce [--quick | --full] [--only scenes,references,validation,georgiev] | test | bench-pt [--spp N] | bench-vpl [--repeat N]>"
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("reproduce") => reproduce(&args[1..]),
        Some("test") => test(&args[1..]),
        Some("bench-pt") => bench_pt(&args[1..]),
        Some("bench-vpl") => bench_vpl(&args[1..]),
        _ => Err(usage().to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: error: {e}");
            ExitCode::from(2)
        }
    }
}

/// Builds the `vpl` binary in release mode and returns its path.
fn build_vpl() -> Result<PathBuf, String> {
    let mut c = cargo();
    c.args(["build", "--release", "--quiet", "-p", "vpl-bench", "--bin", "vpl"]);
    run(c, "building vpl")?;
    Ok(root().join("target/release/vpl"))
}

fn test(args: &[String]) -> Result<(), String> {
    let mut c = cargo();
    c.args(["test", "--workspace", "--no-fail-fast"]).args(args);
    run(c, "cargo test")
}

fn bench_pt(args: &[String]) -> Result<(), String> {
    let vpl = build_vpl()?;
    let mut c = Command::new(vpl);
    c.arg("bench-pt").args(args);
    run(c, "vpl bench-pt")
}

fn bench_vpl(args: &[String]) -> Result<(), String> {
    let vpl = build_vpl()?;
    let mut c = Command::new(vpl);
    c.arg("bench-vpl").args(args);
    run(c, "vpl bench-vpl")
}

struct Profile {
    name: &'static str,
    gallery_spp: u32,
    reference_spp: u32,
    validation_spp: u32,
    georgiev_spp: u32,
    georgiev_frames: u32,
}

fn reproduce(args: &[String]) -> Result<(), String> {
    let mut profile = Profile { name: "quick", gallery_spp: 64, reference_spp: 64, validation_spp: 1024, georgiev_spp: 2048, georgiev_frames: 8 };
    let mut only: Vec<String> = JOBS.iter().map(|s| s.to_string()).collect();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => {}
            "--full" => profile = Profile { name: "full", gallery_spp: 1024, reference_spp: 4096, validation_spp: 32768, georgiev_spp: 16384, georgiev_frames: 32 },
            "--only" => {
                let list = it.next().ok_or("--only needs a list")?;
                only = list.split(',').map(|s| s.trim().to_string()).collect();
                if let Some(bad) = only.iter().find(|j| !JOBS.contains(&j.as_str())) {
                    return Err(format!("unknown job '{bad}' (jobs: {})", JOBS.join(", ")));
                }
            }
            other => return Err(format!("unknown argument '{other}'\n{}", usage())),
        }
    }
    let start = Instant::now();
    let vpl = build_vpl()?;
    let results = root().join("results");
    let mut readme = String::from("# Results\n\nWritten by `cargo xtask reproduce`");
    readme.push_str(&format!(" (profile `{}`).\n\n", profile.name));
    let mut timings = Vec::new();

    if only.iter().any(|j| j == "scenes") {
        let t = Instant::now();
        let dir = results.join("scenes");
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        readme.push_str(&format!("## Scene gallery (`scenes/`)\n\nEvery built-in scene at frame 0, path traced (full, max-depth 5, {} spp).\n\n", profile.gallery_spp));
        for (i, s) in SCENES.iter().enumerate() {
            eprintln!("xtask: [scenes {}/{}] {s}", i + 1, SCENES.len());
            render(&vpl, s, "full", profile.gallery_spp, &dir.join(format!("{s}.exr")), None)?;
            readme.push_str(&format!("![{s}](scenes/{s}.png) "));
        }
        readme.push_str("\n\n");
        timings.push(("scenes", t.elapsed().as_secs_f64()));
    }
    if only.iter().any(|j| j == "references") {
        let t = Instant::now();
        let dir = results.join("references");
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        readme.push_str(&format!(
            "## Path-traced references (`references/`)\n\nFrame 0 of every built-in scene, max-depth 5, {} spp, in `full` and `indirect` mode (what VPL methods render), \
             each with its per-pixel standard-error EXR.\n\n| scene | full | indirect |\n| --- | --- | --- |\n",
            profile.reference_spp
        ));
        for (i, s) in SCENES.iter().enumerate() {
            for mode in ["full", "indirect"] {
                eprintln!("xtask: [references {}/{}] {s} {mode}", i + 1, SCENES.len());
                let out = dir.join(format!("{s}_{mode}.exr"));
                render(&vpl, s, mode, profile.reference_spp, &out, Some(&dir.join(format!("{s}_{mode}_stderr.exr"))))?;
            }
            readme.push_str(&format!("| {s} | [exr]({0}_full.exr) ![]({0}_full.png) | [exr]({0}_indirect.exr) ![]({0}_indirect.png) |\n", format!("references/{s}")));
        }
        readme.push('\n');
        timings.push(("references", t.elapsed().as_secs_f64()));
    }
    if only.iter().any(|j| j == "validation") {
        let t = Instant::now();
        eprintln!("xtask: [validation] cornell vs Mitsuba 3.9.1 at {} spp", profile.validation_spp);
        let dir = results.join("validation");
        let mut c = Command::new(&vpl);
        c.current_dir(root()).args(["validate-cornell", "--spp", &profile.validation_spp.to_string(), "--out"]).arg(&dir);
        c.stdout(std::process::Stdio::null());
        run(c, "vpl validate-cornell")?;
        readme.push_str("## Validation against Mitsuba 3 (`validation/`)\n\n");
        let md = std::fs::read_to_string(dir.join("cornell_validation.md")).map_err(|e| e.to_string())?;
        readme.push_str(md.trim_start_matches("# Path tracer vs Mitsuba 3.9.1 on `cornell`\n\n"));
        readme.push_str("\nDifference (ours − Mitsuba) and |z| images: `validation/cornell_<mode>_difference.exr`, `validation/cornell_<mode>_z.exr`; \
         failing pixels in red: ![full](validation/cornell_full_z.png) ![direct](validation/cornell_direct_z.png) ![indirect](validation/cornell_indirect_z.png)\n\n");
        timings.push(("validation", t.elapsed().as_secs_f64()));
    }
    readme.push_str("## Run\n\n| job | wall time (s) |\n| --- | --- |\n");
    for (j, s) in &timings {
        readme.push_str(&format!("| {j} | {s:.0} |\n"));
    }
    readme.push_str(&format!("| total | {:.0} |\n", start.elapsed().as_secs_f64()));
    let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    if only.iter().any(|j| j == "georgiev") {
        let t = Instant::now();
        eprintln!("xtask: [georgiev] RR against IR on corner, reference {} spp, {} frames", profile.georgiev_spp, profile.georgiev_frames);
        let dir = results.join("georgiev");
        let mut c = Command::new(&vpl);
        c.current_dir(root())
            .args(["georgiev", "--spp", &profile.georgiev_spp.to_string(), "--frames", &profile.georgiev_frames.to_string(), "--out"])
            .arg(&dir)
            .stdout(std::process::Stdio::null());
        run(c, "vpl georgiev")?;
        let md = std::fs::read_to_string(dir.join("georgiev.md")).map_err(|e| e.to_string())?;
        readme.push_str("## Russian-roulette acceptance (`georgiev/`)\n\n");
        let body = md.trim_start_matches("# Georgiev & Slusallek (EG 2010): Russian-roulette VPL acceptance\n\n");
        readme.push_str(&body.replace("](corner_", "](georgiev/corner_"));
        readme.push_str("\nData: `georgiev/georgiev.csv`.\n\n");
        timings.push(("georgiev", t.elapsed().as_secs_f64()));
    }
    readme.push_str(&format!("\nMachine: {threads} hardware threads. Command: `cargo xtask reproduce {}`.\n", args.join(" ")));
    write_atomic(&results.join("README.md"), &readme)?;
    eprintln!("xtask: done in {:.0} s; see results/README.md", start.elapsed().as_secs_f64());
    Ok(())
}

fn render(vpl: &Path, scene: &str, mode: &str, spp: u32, out: &Path, stderr: Option<&Path>) -> Result<(), String> {
    let mut c = Command::new(vpl);
    c.current_dir(root()).args(["render", "--scene", scene, "--mode", mode, "--spp", &spp.to_string(), "--out"]).arg(out);
    if let Some(s) = stderr {
        c.arg("--stderr").arg(s);
    }
    run(c, &format!("vpl render {scene}"))
}

fn write_atomic(path: &Path, text: &str) -> Result<(), String> {
    let tmp = path.with_extension("md.tmp");
    std::fs::write(&tmp, text).and_then(|_| std::fs::rename(&tmp, path)).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

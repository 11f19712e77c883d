//! `cargo xtask …`: the toolkit's jobs.
//!
//! - `cargo xtask reproduce [--quick | --full] [--only LIST] [--scene S,..] [--methods M,..]
//!   [--frames A..B] [--seeds N] [--size WxH] [--truth-spp N] [--shard I/N] [--docs]`: the SMC paper's Table 1 with Fig. 7 (`results/table1/`),
//!   Table 2 (`results/table2/`), Figs. 8, 9 and 10 (`results/figures/`), Figs. 6-8 of the
//!   progressive renderer (Dammertz et al. 2010, `results/progressive/`), Georgiev's RR experiment,
//!   the scene gallery, path-traced references, the path tracer's validation against Mitsuba 3,
//!   the many-light study (`results/manylights/`: SMC 2K, IR 64K and IR 1M gathered
//!   interleaved, exhaustively and by stochastic lightcuts, error over wall time),
//!   and `results/README.md` linking all of it. `--shard I/N` runs shard I of Table 1's units
//!   (shard 0 also runs the other jobs); `cargo xtask merge` then writes the tables.
//!   `--backend gpu` runs the VPL stages of Table 1 and Table 2 and Table 1's ground truth on the
//!   GPU (`vpl-gpu`); the figures and Georgiev's experiment stay on the CPU.
//!   `--docs` then writes `docs/reproduction.md` and its plots from `results/` (module `docs`).
//!   `--slurm [--shards N] [--partition P] [--time T] [--cpus-per-task C] [--gpus G] [--dry-run]`
//!   submits Table 1 as a Slurm job array and a merge job after it instead (module `slurm`);
//!   `--slurm --status` reports the units done per shard.
//! - `cargo xtask docs`: writes `docs/reproduction.md` from `results/` as it is (after a merge).
//! - `cargo xtask merge [DIR]`: merges the shards of a Table 1 run (default `results/table1`).
//! - `cargo xtask test [--cargo-test] [ARGS]`: the whole test suite, as CI runs it: under
//!   cargo-nextest when it is installed, with the 15 slowest tests and their times, then the
//!   doctests; `cargo test --workspace` otherwise (module `test`).
//! - `cargo xtask bench-pt`: path-tracing throughput on `cornell`.
//! - `cargo xtask bench-rays`: BVH build time and memory, and rays per second (primary and diffuse
//!   closest hits, shadow occlusion) on `cornell`, Dabrovic's Sponza and five Sponzas side by side.
//! - `cargo xtask bench-vpl`: milliseconds per VPL stage at 640×360, 2048 VPLs, `cornell` and
//!   `office`, and the SMC sampler's steps (the SMC paper's Table 2) on `office` and `maze`.
//! - `cargo xtask bench-gpu`: milliseconds per GPU kernel and per indirect frame at 1920×1080,
//!   2048 SMC VPLs, `office` and `atrium`, and the adapter they ran on.
//! - `cargo xtask fuzz [--seconds N] [--target obj|mtl|toml|exr|mitsuba|ply|gltf|glb|sequence|table1|all] [--seed S]`: the loader
//!   fuzz targets (`tests/src/fuzz.rs`) for N seconds (default 600) in the `fuzz` profile (release
//!   speed with debug assertions and overflow checks); prints the
//!   executions and findings, writes findings to `target/fuzz-findings/`.

mod docs;
mod slurm;
mod test;

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};
use std::time::Instant;

const SCENES: [&str; 9] = ["cornell", "maze", "office", "courtyard", "atrium", "corner", "glass", "building", "colonnade"];

/// The real scenes of the gallery: (name, what it is, scene path from the
/// repository root). Sponza and Munich name models kept outside the
/// repository (`../shared/scenes`); the others are the test data's copies.
const REAL_SCENES: [(&str, &str, &str); 10] = [
    ("sponza", "Dabrovic Sponza (OBJ), a point light", "scenes/sponza-dabrovic.toml"),
    ("munich", "Munich city blocks (OBJ, Z up), the sun", "scenes/city-munich.toml"),
    ("munich-sky", "Munich city blocks, the sun and a sky", "scenes/city-munich-sky.toml"),
    ("cornell-xml", "Mitsuba's Cornell box written as Mitsuba XML (analytic shapes)", "tests/data/cornell-box/cornell.xml"),
    ("mcguire", "McGuire's Cornell box (OBJ + MTL)", "tests/data/mcguire/CornellBox-Original.obj"),
    ("sundial", "Sundial (glTF binary, KHR_lights_punctual sun)", "vpl-scene-io/tests/data/gltf/Sundial-KHR_lights_punctual/Sundial.glb"),
    ("mitsuba-cbox", "Mitsuba's cbox.xml (spectral reflectances and light)", "vpl-scene-io/tests/data/mitsuba/cbox-mitsuba-data/cbox.xml"),
    ("mitsuba-tutorials", "Mitsuba tutorials' box: a mirror and a glass sphere", "vpl-scene-io/tests/data/mitsuba/cbox-tutorials/cbox.xml"),
    ("veach-mis", "Veach's MIS scene (Mitsuba data)", "vpl-scene-io/tests/data/mitsuba/veach-mis-mitsuba-data/veach_mis.xml"),
    ("veach-mis-bitterli", "Veach's MIS scene (Bitterli's resources)", "vpl-scene-io/tests/data/mitsuba/veach-mis-bitterli/scene.xml"),
];

/// Renders each of [`REAL_SCENES`] by the path tracer and by SMC into
/// `dir`, and returns the Markdown table that sets them side by side.
/// The path tracer draws the materials as SMC does (`--materials diffuse`);
/// where that drops layers, the scene as the file gives it is shown too.
/// A scene whose model is not there is listed as skipped.
fn real_scene_gallery(vpl: &Path, dir: &Path, profile: &Profile) -> Result<String, String> {
    let mut md = format!(
        "### Real scenes\n\nThe scenes of `../shared/scenes` (through the test data's copies, or the scene files of `scenes/`), at their own \
         cameras and sizes: the path tracer (full light, max-depth 5, {} spp) and SMC (2048 VPLs, one frame, ray-traced \
         visibility), side by side. Both draw each material by its albedo (the VPL pipeline can draw nothing else; the path tracer \
         with `--materials diffuse`); where that drops a glossy or transparent layer, a third picture is the path tracer on the \
         materials as the file gives them.\n\n| scene | path tracer | SMC | path tracer, materials as given |\n| --- | --- | --- | --- |\n",
        profile.gallery_spp
    );
    for (i, (name, what, path)) in REAL_SCENES.iter().enumerate() {
        eprintln!("xtask: [scenes, real {}/{}] {name}", i + 1, REAL_SCENES.len());
        let spp = profile.gallery_spp.to_string();
        let pt = dir.join(format!("{name}_path.exr"));
        let o = Command::new(vpl)
            .current_dir(root())
            .args(["render", "--scene", path, "--mode", "full", "--spp", &spp, "--materials", "diffuse", "--quiet", "--out"])
            .arg(&pt)
            .output()
            .map_err(|e| format!("vpl render {name}: {e}"))?;
        let err = String::from_utf8_lossy(&o.stderr);
        if !o.status.success() {
            let why = err.lines().find(|l| l.starts_with("vpl: error:")).unwrap_or("failed").trim_start_matches("vpl: error: ");
            if why.contains("cannot read") || why.contains("is not there") || why.contains("No such file") {
                md.push_str(&format!("| {what} (`{path}`) | skipped: {why} | | |\n"));
                continue;
            }
            return Err(format!("vpl render {name}: {why}"));
        }
        let layered = err.contains("layered material");
        let smc = dir.join(format!("{name}_smc.exr"));
        let mut c = Command::new(vpl);
        c.current_dir(root())
            .args([
                "render",
                "--scene",
                path,
                "--method",
                "vpl",
                "--sampler",
                "smc",
                "--vpls",
                "2048",
                "--visibility",
                "raytrace",
                "--quiet",
                "--out",
            ])
            .arg(&smc)
            .stderr(std::process::Stdio::null());
        run(c, &format!("vpl render {name} (SMC)"))?;
        let as_given = if layered {
            let out = dir.join(format!("{name}_path_as_given.exr"));
            let mut c = Command::new(vpl);
            c.current_dir(root())
                .args(["render", "--scene", path, "--mode", "full", "--spp", &spp, "--quiet", "--out"])
                .arg(&out)
                .stderr(std::process::Stdio::null());
            run(c, &format!("vpl render {name} (materials as given)"))?;
            format!("![{name} as given](scenes/{name}_path_as_given.png)")
        } else {
            "(no layered materials)".to_string()
        };
        md.push_str(&format!(
            "| {what} (`{path}`) | ![{name}](scenes/{name}_path.png) | ![{name} SMC](scenes/{name}_smc.png) | {as_given} |\n"
        ));
    }
    md.push('\n');
    Ok(md)
}
const JOBS: [&str; 11] =
    ["scenes", "references", "validation", "georgiev", "table1", "table2", "energy", "fig8", "fig10", "progressive", "manylights"];

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
    "usage: cargo xtask <reproduce [--quick | --full] [--only scenes,references,validation,georgiev,table1,fig7,table2,energy,fig8,fig9,fig10,progressive,manylights] \
     [--scene S,..] [--methods M,..] [--frames A..B] [--shard I/N] [--backend cpu|gpu] [--docs] [--slurm [--shards N] [--partition P] [--time T] [--cpus-per-task C] [--gpus G] [--dry-run] | --slurm --status] | docs | merge [DIR] | test [--cargo-test] | bench-pt [--spp N] | bench-rays [--scene S,..] [--size WxH] | bench-vpl [--repeat N] \
     | bench-gpu [--scene S,..] [--size WxH] [--vpls N] [--frames N] [--out DIR] | fuzz [--seconds N] [--target T] [--seed S]>"
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some("reproduce") => reproduce(&args[1..]),
        Some("merge") => merge(&args[1..]),
        Some("docs") if args.len() == 1 => docs::write(&root(), &docs::results(&root())),
        Some("test") => test::test(&args[1..]),
        Some("bench-pt") => bench_pt(&args[1..]),
        Some("bench-vpl") => bench_vpl(&args[1..]),
        Some("bench-rays") => bench_rays(&args[1..]),
        Some("bench-gpu") => bench_gpu(&args[1..]),
        Some("fuzz") => fuzz(&args[1..]),
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

/// Builds the `vpl` binary in release mode and returns its path; where
/// `VPL_BIN` names a binary, that one, unbuilt (one built elsewhere: a
/// cluster's login node, or the test suite's debug build in CI).
fn build_vpl() -> Result<PathBuf, String> {
    if let Some(bin) = std::env::var_os("VPL_BIN").filter(|v| !v.is_empty()) {
        let bin = PathBuf::from(bin);
        return if bin.is_file() { Ok(bin) } else { Err(format!("VPL_BIN: {} is not a file", bin.display())) };
    }
    let mut c = cargo();
    c.args(["build", "--release", "--quiet", "-p", "vpl-cli", "--bin", "vpl"]);
    run(c, "building vpl")?;
    Ok(target_dir()?.join("release").join(format!("vpl{}", std::env::consts::EXE_SUFFIX)))
}

/// Cargo's target directory as cargo itself resolves it (`CARGO_TARGET_DIR`,
/// `build.target-dir` in a config file, or `target/`), from `cargo metadata`.
fn target_dir() -> Result<PathBuf, String> {
    let out = cargo().args(["metadata", "--format-version", "1", "--no-deps"]).output().map_err(|e| format!("cargo metadata: {e}"))?;
    if !out.status.success() {
        return Err(format!("cargo metadata: {}", String::from_utf8_lossy(&out.stderr).trim()));
    }
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).map_err(|e| format!("cargo metadata: {e}"))?;
    meta["target_directory"].as_str().map(PathBuf::from).ok_or_else(|| "cargo metadata: no target_directory".to_string())
}

fn fuzz(args: &[String]) -> Result<(), String> {
    let mut c = cargo();
    c.args(["run", "--profile", "fuzz", "--quiet", "-p", "vpl-tests", "--bin", "vpl-fuzz", "--"]);
    if !args.iter().any(|a| a == "--seconds") {
        c.args(["--seconds", "600"]);
    }
    c.args(args);
    run(c, "vpl-fuzz")
}

fn bench_pt(args: &[String]) -> Result<(), String> {
    let vpl = build_vpl()?;
    let mut c = Command::new(vpl);
    c.arg("bench-pt").args(args);
    run(c, "vpl bench-pt")
}

fn bench_gpu(args: &[String]) -> Result<(), String> {
    let vpl = build_vpl()?;
    let mut c = Command::new(vpl);
    c.arg("bench-gpu").args(args);
    run(c, "vpl bench-gpu")
}

fn bench_rays(args: &[String]) -> Result<(), String> {
    let vpl = build_vpl()?;
    let mut c = Command::new(vpl);
    c.arg("bench-rays").args(args);
    run(c, "vpl bench-rays")
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
    table2: (&'static str, u32),
    /// `vpl energy`: checkpoints a sequence and the stride of the sampler's steps.
    energy: (u32, u32),
    figures: &'static [&'static str],
    progressive: &'static [&'static str],
    /// `vpl manylights`: image size, seconds a configuration, reference and truth samples.
    manylights: &'static [&'static str],
}

const QUICK: Profile = Profile {
    name: "quick",
    gallery_spp: 64,
    reference_spp: 64,
    validation_spp: 1024,
    georgiev_spp: 2048,
    georgiev_frames: 8,
    table2: ("640x360", 10),
    energy: (3, 8),
    figures: &[
        "--scenes",
        "office",
        "--fig10-scenes",
        "atrium",
        "--spp",
        "256",
        "--fig10-spp",
        "1024",
        "--shadow-maps",
        "128,256",
        "--fig10-size",
        "160x120",
        "--fig10-warmup",
        "20",
    ],
    progressive: &[
        "--fig7-size",
        "160x120",
        "--passes",
        "512",
        "--converged",
        "2048",
        "--reference-spp",
        "1024",
        "--fig8-scenes",
        "cornell,office,maze",
        "--fig8-size",
        "160x120",
        "--seconds",
        "10",
    ],
    manylights: &["--size", "128x96", "--seconds", "8", "--spp", "4096", "--truth-spp", "16384"],
};

const FULL: Profile = Profile {
    name: "full",
    gallery_spp: 1024,
    reference_spp: 4096,
    validation_spp: 32768,
    georgiev_spp: 16384,
    georgiev_frames: 32,
    table2: ("1920x1080", 30),
    energy: (8, 1),
    figures: &[
        "--scenes",
        "office,atrium",
        "--fig10-scenes",
        "atrium,courtyard,office",
        "--spp",
        "32768",
        "--fig10-spp",
        "8192",
        "--shadow-maps",
        "128,256,512,1024",
        "--fig10-size",
        "320x240",
        "--fig10-warmup",
        "100",
    ],
    progressive: &[
        "--fig7-size",
        "320x240",
        "--passes",
        "2048",
        "--converged",
        "11456",
        "--reference-spp",
        "16384",
        "--fig8-scenes",
        "cornell,office,maze,atrium,corner,courtyard",
        "--fig8-size",
        "320x240",
        "--seconds",
        "180",
    ],
    manylights: &["--size", "320x240", "--seconds", "120", "--spp", "32768", "--truth-spp", "262144"],
};

/// Folder of the README sections each job leaves (so `cargo xtask merge` can rebuild the README).
fn sections() -> PathBuf {
    root().join("results/.sections")
}

fn save_section(job: &str, text: &str, seconds: Option<f64>) -> Result<(), String> {
    let dir = sections();
    std::fs::create_dir_all(&dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    write_atomic(&dir.join(format!("{job}.md")), text)?;
    if let Some(s) = seconds {
        write_atomic(&dir.join(format!("{job}.seconds")), &format!("{s:.0}"))?;
    }
    Ok(())
}

/// `results/README.md` from the sections of every job run so far, in job order.
fn write_readme(header: &str) -> Result<(), String> {
    let mut readme = String::from(header);
    let mut timings = String::from("## Wall time\n\n| job | seconds |\n| --- | ---: |\n");
    let mut total = 0.0;
    for job in JOBS {
        if let Ok(text) = std::fs::read_to_string(sections().join(format!("{job}.md"))) {
            readme.push_str(&text);
        }
        if let Ok(t) = std::fs::read_to_string(sections().join(format!("{job}.seconds"))) {
            timings.push_str(&format!("| {job} | {} |\n", t.trim()));
            total += t.trim().parse::<f64>().unwrap_or(0.0);
        }
    }
    timings.push_str(&format!("| all | {total:.0} |\n\n"));
    readme.push_str(&timings);
    if let Ok(run) = std::fs::read_to_string(sections().join("run.md")) {
        readme.push_str(&run);
    }
    write_atomic(&root().join("results/README.md"), &readme)
}

const README_HEADER: &str = "# Results\n\nWritten by `cargo xtask reproduce` (and `cargo xtask merge` after a sharded run). \
Each section comes from the newest run of its job; the wall times below are of those runs.\n\n\
- [Table 1](table1/table1.md): |E| and |E′| of IR, RR, MIR, TCAS, SMC and SMC with the paper's kNN flux on five stand-in sequences and two on real geometry (Sponza, Munich; where their models are present), three seeds each with 95 % confidence intervals, with Fig. 7 ([`table1/`](table1/))\n\
- [Table 2](table2/table2.md): milliseconds per stage of an SMC frame\n\
- [Figs. 8 and 9](figures/fig8.md): one frame by path tracing and by VPLs; shadow-map resolutions\n\
- [Fig. 10](figures/fig10.md): error against the VPL budget\n\
- [Progressive](progressive/progressive.md): Figs. 6-8 of Dammertz et al., error against passes and equal time against path tracing\n\
- [Many lights](manylights/manylights.md): SMC 2K against IR 64K and 1M, gathered interleaved, exhaustively and by stochastic lightcuts, error over wall time\n\
- [Georgiev](georgiev/georgiev.md), [validation](validation/cornell_validation.md), path-traced references, the scene gallery\n\n";

fn reproduce(args: &[String]) -> Result<(), String> {
    let mut profile = &QUICK;
    let mut only: Vec<String> = JOBS.iter().map(|s| s.to_string()).collect();
    let mut table1_args: Vec<String> = Vec::new();
    let mut shard: Option<String> = None;
    let mut backend = String::from("cpu");
    let mut write_docs = false;
    let mut slurm: Option<slurm::SlurmSettings> = None;
    let mut status = false;
    let mut slurm_flags: Vec<String> = Vec::new();
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => profile = &QUICK,
            "--full" => profile = &FULL,
            "--only" => {
                let list = it.next().ok_or("--only needs a list")?;
                only = Vec::new();
                for j in list.split(',').map(|s| s.trim()) {
                    let j = match j {
                        "fig7" => "table1",
                        "fig9" => "fig8",
                        j => j,
                    };
                    if !JOBS.contains(&j) {
                        return Err(format!("unknown job '{j}' (jobs: {}, fig7, fig9)", JOBS.join(", ")));
                    }
                    if !only.iter().any(|o| o == j) {
                        only.push(j.to_string());
                    }
                }
            }
            "--scene" | "--methods" | "--frames" | "--seeds" | "--size" | "--truth-spp" => {
                let v = it.next().ok_or_else(|| format!("{a} needs a value"))?;
                table1_args.push(a.clone());
                table1_args.push(v.clone());
            }
            "--shard" => shard = Some(it.next().ok_or("--shard needs I/N")?.clone()),
            "--docs" => write_docs = true,
            "--slurm" => slurm = Some(slurm::SlurmSettings { shards: 16, cpus_per_task: 16, ..Default::default() }),
            "--status" => status = true,
            "--dry-run" => slurm_flags.push(a.clone()),
            "--partition" | "--time" | "--cpus-per-task" | "--gpus" | "--shards" => {
                let v = it.next().ok_or_else(|| format!("{a} needs a value"))?;
                slurm_flags.push(a.clone());
                slurm_flags.push(v.clone());
            }
            "--backend" => {
                let b = it.next().ok_or("--backend needs cpu or gpu")?;
                if b != "cpu" && b != "gpu" {
                    return Err(format!("--backend: '{b}' is not cpu or gpu"));
                }
                backend = b.clone();
            }
            other => return Err(format!("unknown argument '{other}'\n{}", usage())),
        }
    }
    if let Some(mut settings) = slurm {
        let mut f = slurm_flags.iter();
        while let Some(flag) = f.next() {
            let mut value = || f.next().cloned().ok_or_else(|| format!("{flag} needs a value"));
            let count = |v: String| v.parse::<u32>().map_err(|_| format!("{flag}: '{v}' is not a count"));
            match flag.as_str() {
                "--dry-run" => settings.dry_run = true,
                "--partition" => settings.partition = Some(value()?),
                "--time" => settings.time = Some(value()?),
                "--cpus-per-task" => settings.cpus_per_task = count(value()?)?.max(1),
                "--gpus" => settings.gpus = count(value()?)?,
                "--shards" => settings.shards = count(value()?)?,
                _ => {}
            }
        }
        let dir = root().join("results/slurm");
        if status {
            return slurm_status(&dir);
        }
        if shard.is_some() {
            return Err("--slurm makes the shards itself: leave out --shard".into());
        }
        if settings.gpus > 0 && backend != "gpu" {
            return Err("--gpus gives each task a GPU that only --backend gpu uses (the VPL stages and the ground truth): add it".into());
        }
        let vpl = build_vpl()?;
        let mut t1 = vec!["--profile".to_string(), profile.name.to_string(), "--backend".into(), backend.clone()];
        t1.extend(table1_args.iter().cloned());
        return slurm::submit(&root(), &vpl, &t1, &root().join("results/table1"), &dir, &settings);
    }
    if status || !slurm_flags.is_empty() {
        return Err("--status, --dry-run, --partition, --time, --cpus-per-task, --gpus and --shards go with --slurm".into());
    }
    // Sharded: shard i runs its share of Table 1; shard 0 also runs every other job.
    let first_shard = shard.as_deref().is_none_or(|s| s.trim().starts_with("0/"));
    if !first_shard {
        only.retain(|j| j == "table1");
    }
    let start = Instant::now();
    let vpl = build_vpl()?;
    let results = root().join("results");
    let job = |name: &str| only.iter().any(|j| j == name);

    if job("scenes") {
        let t = Instant::now();
        let dir = results.join("scenes");
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let mut md = format!(
            "## Scene gallery (`scenes/`)\n\nEvery built-in scene at frame 0, path traced (full, max-depth 5, {} spp).\n\n",
            profile.gallery_spp
        );
        for (i, s) in SCENES.iter().enumerate() {
            eprintln!("xtask: [scenes {}/{}] {s}", i + 1, SCENES.len());
            render(&vpl, s, "full", profile.gallery_spp, &dir.join(format!("{s}.exr")), None)?;
            md.push_str(&format!("![{s}](scenes/{s}.png) "));
        }
        md.push_str("\n\n");
        md.push_str(&real_scene_gallery(&vpl, &dir, profile)?);
        save_section("scenes", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("references") {
        let t = Instant::now();
        let dir = results.join("references");
        std::fs::create_dir_all(&dir).map_err(|e| e.to_string())?;
        let mut md = format!(
            "## Path-traced references (`references/`)\n\nFrame 0 of every built-in scene, max-depth 5, {} spp, in `full` and `indirect` mode (what VPL methods render), \
             each with its per-pixel standard-error EXR.\n\n| scene | full | indirect |\n| --- | --- | --- |\n",
            profile.reference_spp
        );
        for (i, s) in SCENES.iter().enumerate() {
            for mode in ["full", "indirect"] {
                eprintln!("xtask: [references {}/{}] {s} {mode}", i + 1, SCENES.len());
                let out = dir.join(format!("{s}_{mode}.exr"));
                render(&vpl, s, mode, profile.reference_spp, &out, Some(&dir.join(format!("{s}_{mode}_stderr.exr"))))?;
            }
            md.push_str(&format!(
                "| {s} | [exr]({0}_full.exr) ![]({0}_full.png) | [exr]({0}_indirect.exr) ![]({0}_indirect.png) |\n",
                format!("references/{s}")
            ));
        }
        md.push('\n');
        save_section("references", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("validation") {
        let t = Instant::now();
        eprintln!("xtask: [validation] cornell vs Mitsuba 3.9.1 at {} spp", profile.validation_spp);
        let dir = results.join("validation");
        let mut c = Command::new(&vpl);
        c.current_dir(root()).args(["validate-cornell", "--spp", &profile.validation_spp.to_string(), "--out"]).arg(&dir);
        c.stdout(std::process::Stdio::null());
        run(c, "vpl validate-cornell")?;
        let mut md = String::from("## Validation against Mitsuba 3 (`validation/`)\n\n");
        let text = std::fs::read_to_string(dir.join("cornell_validation.md")).map_err(|e| e.to_string())?;
        md.push_str(text.trim_start_matches("# Path tracer vs Mitsuba 3.9.1 on `cornell`\n\n"));
        md.push_str("\nDifference (ours − Mitsuba) and |z| images: `validation/cornell_<mode>_difference.exr`, `validation/cornell_<mode>_z.exr`; \
         failing pixels in red: ![full](validation/cornell_full_z.png) ![direct](validation/cornell_direct_z.png) ![indirect](validation/cornell_indirect_z.png)\n\n");
        save_section("validation", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("georgiev") {
        let t = Instant::now();
        eprintln!("xtask: [georgiev] RR against IR on corner, reference {} spp, {} frames", profile.georgiev_spp, profile.georgiev_frames);
        let dir = results.join("georgiev");
        let mut c = Command::new(&vpl);
        c.current_dir(root())
            .args(["georgiev", "--spp", &profile.georgiev_spp.to_string(), "--frames", &profile.georgiev_frames.to_string(), "--out"])
            .arg(&dir)
            .stdout(std::process::Stdio::null());
        run(c, "vpl georgiev")?;
        let text = std::fs::read_to_string(dir.join("georgiev.md")).map_err(|e| e.to_string())?;
        let mut md = String::from("## Russian-roulette acceptance (`georgiev/`)\n\n");
        let body = text.trim_start_matches("# Georgiev & Slusallek (EG 2010): Russian-roulette VPL acceptance\n\n");
        md.push_str(&body.replace("](corner_", "](georgiev/corner_"));
        md.push_str("\nData: `georgiev/georgiev.csv`.\n\n");
        save_section("georgiev", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("table1") {
        let t = Instant::now();
        let dir = results.join("table1");
        // An unsharded run starts afresh (units of an older build or other settings would be
        // kept or refused); the shards of a sharded run share the folder and resume in it.
        if shard.is_none() && dir.exists() {
            std::fs::remove_dir_all(&dir).map_err(|e| format!("cannot clear {}: {e}", dir.display()))?;
        }
        eprintln!(
            "xtask: [table1] seven sequences (five where the real scenes are absent) x six samplers x three seeds and their ground truth ({} profile{})",
            profile.name,
            shard.as_deref().map_or(String::new(), |s| format!(", shard {s}"))
        );
        let mut c = Command::new(&vpl);
        c.current_dir(root()).args(["table1", "--profile", profile.name, "--backend", &backend]).args(&table1_args).arg("--out").arg(&dir);
        if let Some(s) = &shard {
            c.args(["--shard", s]);
        }
        run(c, "vpl table1")?;
        if shard.is_none() {
            table1_section(Some(t.elapsed().as_secs_f64()))?;
        } else {
            save_section(
                "table1",
                &format!(
                    "## Table 1 (`table1/`)\n\nShard {} of a sharded run is done; when every shard is, `cargo xtask merge` writes the tables here.\n\n",
                    shard.as_deref().unwrap_or("")
                ),
                None,
            )?;
        }
    }
    if job("table2") {
        let t = Instant::now();
        eprintln!("xtask: [table2] SMC stage timings at {}", profile.table2.0);
        let dir = results.join("table2");
        let mut c = Command::new(&vpl);
        c.current_dir(root())
            .args(["table2", "--backend", &backend, "--size", profile.table2.0, "--frames", &profile.table2.1.to_string(), "--out"])
            .arg(&dir);
        run(c, "vpl table2")?;
        let text = std::fs::read_to_string(dir.join("table2.md")).map_err(|e| e.to_string())?;
        let md = format!(
            "## Table 2 (`table2/`)\n\n{}\n",
            text.trim_start_matches("# Table 2: milliseconds per stage of an SMC frame\n\n").replace("## ", "### ")
        );
        save_section("table2", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("energy") {
        let t = Instant::now();
        let (checkpoints, stride) = profile.energy;
        // Every built-in, Table 1's moving sun, and its real scenes (skipped where absent).
        let mut scenes: Vec<String> = SCENES.iter().map(|s| s.to_string()).collect();
        scenes.extend(["courtyard-sun", "sponza", "munich"].map(String::from));
        eprintln!(
            "xtask: [energy] SMC's image mean against path tracing on {} scenes, 3 seeds along the sequences, 16 at frame 0",
            scenes.len()
        );
        let dir = results.join("energy");
        let mut c = Command::new(&vpl);
        c.current_dir(root())
            .args(["energy", "--scene", &scenes.join(","), "--checkpoints", &checkpoints.to_string(), "--stride", &stride.to_string()])
            .arg("--out")
            .arg(&dir);
        run(c, "vpl energy")?;
        let text = std::fs::read_to_string(dir.join("energy.md")).map_err(|e| e.to_string())?;
        let md = format!(
            "## SMC's energy along the sequences (`energy/`)\n\nThe default SMC's unclamped indirect image mean over the path tracer's, at frame 0 and over \
             checkpoints of each sequence (the sampler stepped along it from frame 0), and the share of its light the default clamp \
             (G_max = I / A_view of each view) removes; means over seeds ± their standard errors.\n\n{text}\n"
        );
        save_section("energy", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    for (name, fig) in [("fig8", "8"), ("fig10", "10")] {
        if !job(name) {
            continue;
        }
        let t = Instant::now();
        eprintln!("xtask: [{name}] Fig. {fig}{}", if fig == "8" { " and Fig. 9" } else { "" });
        let dir = results.join("figures");
        let mut c = Command::new(&vpl);
        c.current_dir(root()).args(["figures", "--only", fig]).args(profile.figures).arg("--out").arg(&dir);
        run(c, &format!("vpl figures --only {fig}"))?;
        let text = std::fs::read_to_string(dir.join(format!("{name}.md"))).map_err(|e| e.to_string())?;
        let body = text.split_once("\n\n").map_or(text.as_str(), |(_, b)| b);
        let title = if fig == "8" { "Figs. 8 and 9" } else { "Fig. 10" };
        let md = format!("## {title} (`figures/{name}.md`)\n\n{}\n", fix_links(&body.replace("## ", "### "), "figures/"));
        save_section(name, &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("progressive") {
        let t = Instant::now();
        eprintln!("xtask: [progressive] Figs. 6-8 of Dammertz et al. 2010");
        let dir = results.join("progressive");
        let mut c = Command::new(&vpl);
        c.current_dir(root()).arg("progressive-figures").args(profile.progressive).arg("--out").arg(&dir);
        run(c, "vpl progressive-figures")?;
        let text = std::fs::read_to_string(dir.join("progressive.md")).map_err(|e| e.to_string())?;
        let body = text.split_once("\n\n").map_or(text.as_str(), |(_, b)| b);
        let md = format!(
            "## Progressive point-light rendering, Figs. 6-8 of Dammertz et al. (`progressive/`)\n\n{}\n",
            fix_links(body, "progressive/")
        );
        save_section("progressive", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    if job("manylights") {
        let t = Instant::now();
        eprintln!("xtask: [manylights] SMC 2K, IR 64K and IR 1M gathered interleaved, exhaustively and by lightcuts, at equal time");
        let dir = results.join("manylights");
        let mut c = Command::new(&vpl);
        c.current_dir(root()).arg("manylights").args(profile.manylights).args(["--backend", &backend]).arg("--out").arg(&dir);
        c.stdout(std::process::Stdio::null());
        run(c, "vpl manylights")?;
        let text = std::fs::read_to_string(dir.join("manylights.md")).map_err(|e| e.to_string())?;
        let md = format!("## Many lights at equal time (`manylights/`)\n\n{}\n", fix_links(&text.replace("### ", "#### "), "manylights/"));
        save_section("manylights", &md, Some(t.elapsed().as_secs_f64()))?;
    }
    let threads = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    save_section(
        "run",
        &format!(
            "Last run: `cargo xtask reproduce {}` (profile `{}`) on {threads} hardware threads, {:.0} s.\n",
            args.join(" "),
            profile.name,
            start.elapsed().as_secs_f64()
        ),
        None,
    )?;
    write_readme(README_HEADER)?;
    eprintln!("xtask: done in {:.0} s; see results/README.md", start.elapsed().as_secs_f64());
    if write_docs {
        if shard.is_some() {
            eprintln!("xtask: --docs: a sharded run writes docs/reproduction.md with `cargo xtask docs` after `cargo xtask merge`");
        } else {
            docs::write(&root(), &results)?;
        }
    }
    Ok(())
}

/// `cargo xtask reproduce --slurm --status`: the units done per shard of the
/// submitted run, what the queue says of its jobs, and the README's Table 1
/// section once the merge job has written the tables.
fn slurm_status(dir: &Path) -> Result<(), String> {
    let (array, merge_id, shards, out) = slurm::jobs(dir)?;
    let vpl = build_vpl()?;
    let mut c = Command::new(&vpl);
    c.current_dir(root()).arg("merge").arg(&out).args(["--status", "--shards", &shards.to_string()]);
    run(c, "vpl merge --status")?;
    let q = slurm::queue(&[&array, &merge_id]);
    if q.trim().is_empty() {
        println!(
            "jobs {array} (array) and {merge_id} (merge): not in the queue (done, failed or cancelled; see {})",
            dir.join("logs").display()
        );
    } else {
        print!("{q}");
    }
    if out.join("table1.md").is_file() && out == root().join("results/table1") {
        table1_section(None)?;
        write_readme(README_HEADER)?;
        println!("merged: {} (results/README.md updated)", out.join("table1.md").display());
    }
    Ok(())
}

/// Image links of a job's Markdown made relative to `results/`.
fn fix_links(md: &str, prefix: &str) -> String {
    md.replace("](", &format!("]({prefix}"))
}

/// The README section of Table 1 from `results/table1/table1.md`.
fn table1_section(seconds: Option<f64>) -> Result<(), String> {
    let dir = root().join("results/table1");
    let text = std::fs::read_to_string(dir.join("table1.md")).map_err(|e| format!("{}: {e}", dir.join("table1.md").display()))?;
    let body = text.trim_start_matches("# Table 1: error and temporal instability of the VPL samplers\n\n").replace("## ", "### ");
    let mut md = format!("## Table 1 and Fig. 7 (`table1/`)\n\n{body}\n");
    for id in ["courtyard-sun", "office", "maze"] {
        if dir.join(format!("fig7_{id}.png")).exists() {
            md.push_str(&format!("![Fig. 7, {id}](table1/fig7_{id}.png)\n"));
        }
    }
    md.push_str("\nData: `table1/table1.csv`, `table1/table1.json`, `table1/fig7.csv`; timings per run: `table1/runs.csv`.\n\n");
    save_section("table1", &md, seconds)
}

fn merge(args: &[String]) -> Result<(), String> {
    let dir = args.first().map(PathBuf::from).unwrap_or_else(|| root().join("results/table1"));
    let vpl = build_vpl()?;
    let mut c = Command::new(vpl);
    c.current_dir(root()).arg("merge").arg(&dir);
    run(c, "vpl merge")?;
    if dir == root().join("results/table1") {
        table1_section(None)?;
        write_readme(README_HEADER)?;
    }
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
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, text).and_then(|_| std::fs::rename(&tmp, path)).map_err(|e| format!("cannot write {}: {e}", path.display()))
}

//! `vpl`: render scenes, export built-ins, validate and benchmark the path tracer.
//!
//! Errors are one line on stderr and exit code 2.

use clap::{Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;
use vpl_bench::cli::{ClampArg, PixelArg, Size};
use vpl_core::image::{preview_path, write_atomic};
use vpl_core::{GeometryClamp, SceneSetup};
use vpl_pathtrace::{render, track, Mode, PathTracer, RenderSettings};

#[derive(Parser)]
#[command(name = "vpl", version, about = "Virtual-point-light global illumination toolkit")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum Method {
    /// Path tracing (the reference).
    Path,
    /// Virtual point lights.
    Vpl,
    /// The progressive point-light renderer.
    Progressive,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
enum ModeArg {
    Full,
    Direct,
    Indirect,
}

/// What to render: scene, frame, path tracer settings, threads.
#[derive(clap::Args)]
struct SceneArgs {
    /// A built-in name (cornell, maze, office, courtyard, atrium, corner, glass), a .toml scene file or an .obj file.
    #[arg(long)]
    scene: String,
    /// Frame of the scene's sequence.
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Longest path in segments (Mitsuba 3's convention: 5 = direct + 3 indirect bounces).
    #[arg(long, default_value_t = 5)]
    max_depth: u32,
    /// Geometry-term clamp of the segment leaving the primary hit (§5.4 of the SMC paper), or off.
    #[arg(long, default_value = "off", allow_hyphen_values = true)]
    clamp: ClampArg,
    /// Image size WxH (default: the scene camera's).
    #[arg(long)]
    size: Option<Size>,
    /// Seed of all random streams.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

#[derive(Subcommand)]
enum Command {
    /// Render one frame of a scene.
    Render {
        #[command(flatten)]
        s: SceneArgs,
        /// Rendering method.
        #[arg(long, value_enum, default_value_t = Method::Path)]
        method: Method,
        /// Which light paths to include.
        #[arg(long, value_enum, default_value_t = ModeArg::Full)]
        mode: ModeArg,
        /// Samples per pixel (path).
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Output EXR; a PNG preview is written beside it.
        #[arg(long, default_value = "render.exr")]
        out: PathBuf,
        /// Also write the per-pixel standard error of the mean to this EXR.
        #[arg(long)]
        stderr: Option<PathBuf>,
        /// Exposure applied to the PNG preview.
        #[arg(long, default_value_t = 1.0)]
        exposure: f32,
        /// No progress bar or summary.
        #[arg(long)]
        quiet: bool,
    },
    /// Many path-traced samples at a few pixels: ground truth with standard errors, as CSV.
    Track {
        #[command(flatten)]
        s: SceneArgs,
        /// Which light paths to include.
        #[arg(long, value_enum, default_value_t = ModeArg::Indirect)]
        mode: ModeArg,
        /// A pixel X,Y (repeat for more).
        #[arg(long = "pixel", required = true)]
        pixels: Vec<PixelArg>,
        /// Samples per pixel.
        #[arg(long, default_value_t = 65536)]
        spp: u32,
        /// Write the CSV here instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Print a built-in scene (or any scene) as a TOML scene file.
    ExportScene {
        /// Built-in name or scene file.
        name: String,
        /// Write to this file instead of standard output.
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Path-tracing throughput on `cornell` 256×256, max-depth 5, all cores.
    BenchPt {
        /// Samples per pixel of each timed render.
        #[arg(long, default_value_t = 64)]
        spp: u32,
        /// Timed renders (the best and the median are reported).
        #[arg(long, default_value_t = 5)]
        repeat: u32,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Compare the path tracer with the Mitsuba 3 references of `cornell`; write a Markdown report.
    ValidateCornell {
        /// Samples per pixel.
        #[arg(long, default_value_t = 1024)]
        spp: u32,
        /// Folder holding the reference EXRs.
        #[arg(long, default_value = "tests/data/cornell-box")]
        data: PathBuf,
        /// Folder for the report and difference images.
        #[arg(long, default_value = "results")]
        out: PathBuf,
        /// Seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand) {
                let _ = e.print();
                std::process::exit(if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand { 2 } else { 0 });
            }
            let text = e.to_string();
            let line = text.lines().next().unwrap_or("bad arguments").trim_start_matches("error: ");
            eprintln!("vpl: error: {line}");
            std::process::exit(2);
        }
    };
    if let Err(e) = run(cli) {
        eprintln!("vpl: error: {e}");
        std::process::exit(2);
    }
}

type Res<T> = Result<T, String>;

fn pool(threads: Option<usize>) -> Res<rayon::ThreadPool> {
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        if n == 0 {
            return Err("--threads must be at least 1".into());
        }
        b = b.num_threads(n);
    }
    b.build().map_err(|e| format!("cannot start threads: {e}"))
}

/// Fails early, before any work, if `path` cannot be written.
fn check_writable(path: &Path) -> Res<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!("cannot write {}: directory {} does not exist", path.display(), dir.display()));
    }
    let md = std::fs::metadata(dir).map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    if md.permissions().readonly() {
        return Err(format!("cannot write {}: directory {} is read-only", path.display(), dir.display()));
    }
    if path.is_dir() {
        return Err(format!("cannot write {}: it is a directory", path.display()));
    }
    Ok(())
}

/// Loads a scene, checks the frame against its sequence, and applies `--size`.
fn load_frame(scene: &str, frame: u32, size: Option<Size>) -> Res<(vpl_core::Scene, vpl_core::Camera)> {
    let setup = SceneSetup::load(scene).map_err(|e| e.to_string())?;
    for w in &setup.warnings {
        eprintln!("vpl: warning: {w}");
    }
    if let Some(seq) = &setup.sequence {
        if frame >= seq.frame_count() {
            return Err(format!("--frame {frame} is past the end of the sequence ({} frames)", seq.frame_count()));
        }
    } else if frame > 0 {
        return Err(format!("--frame {frame}: the scene has no sequence"));
    }
    let (sc, mut camera) = setup.frame(frame).map_err(|e| e.to_string())?;
    if let Some(Size(w, h)) = size {
        camera = camera.with_resolution((w, h)).map_err(|e| e.to_string())?;
    }
    Ok((sc, camera))
}

/// The path tracer that `--max-depth`, `--mode` and `--clamp` describe.
fn tracer(max_depth: u32, mode: ModeArg, clamp: ClampArg) -> Res<PathTracer> {
    if max_depth == 0 {
        return Err("--max-depth must be at least 1".into());
    }
    let mut pt = PathTracer::new(
        max_depth,
        match mode {
            ModeArg::Full => Mode::Full,
            ModeArg::Direct => Mode::Direct,
            ModeArg::Indirect => Mode::Indirect,
        },
    );
    if let ClampArg::Value(v) = clamp {
        pt.clamp = Some(GeometryClamp::new(v));
    }
    Ok(pt)
}

/// Writes `text` atomically to `out`, or to standard output when there is none.
fn emit(out: Option<&Path>, text: &str) -> Res<()> {
    match out {
        Some(p) => write_atomic(p, text.as_bytes()).map_err(|e| e.to_string()),
        None => {
            print!("{text}");
            Ok(())
        }
    }
}

fn run(cli: Cli) -> Res<()> {
    match cli.command {
        Command::Render { s: SceneArgs { scene, frame, max_depth, clamp, size, seed, threads }, method, mode, spp, out, stderr, exposure, quiet } => {
            if method != Method::Path {
                return Err(format!("--method {} is not available yet: this build renders with --method path", format!("{method:?}").to_lowercase()));
            }
            if spp == 0 {
                return Err("--spp must be at least 1".into());
            }
            let pt = tracer(max_depth, mode, clamp)?;
            if !(exposure.is_finite() && exposure > 0.0) {
                return Err("--exposure must be positive".into());
            }
            check_writable(&out)?;
            if let Some(s) = &stderr {
                check_writable(s)?;
            }
            let pool = pool(threads)?;
            let (sc, camera) = load_frame(&scene, frame, size)?;
            let bar = ProgressBar::with_draw_target(Some(camera.resolution.0 as u64 * camera.resolution.1 as u64), ProgressDrawTarget::hidden());
            bar.set_style(ProgressStyle::with_template("{spinner} {elapsed_precise} [{bar:40}] {percent}% pixels, eta {eta}").unwrap().progress_chars("=> "));
            let start = Instant::now();
            let shown = AtomicBool::new(false);
            let progress = |done: u64, _total: u64| {
                if !quiet && !shown.load(Ordering::Relaxed) && start.elapsed().as_secs_f32() > 1.0 {
                    shown.store(true, Ordering::Relaxed);
                    bar.set_draw_target(ProgressDrawTarget::stderr());
                }
                bar.set_position(done);
            };
            let r = pool
                .install(|| render(&sc, &camera, &pt, RenderSettings { spp, seed, frame: frame as u64 }, &progress))
                .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            r.image.write_exr(&out).map_err(|e| e.to_string())?;
            r.image.write_png(preview_path(&out), exposure).map_err(|e| e.to_string())?;
            if let Some(s) = &stderr {
                r.stderr.write_exr(s).map_err(|e| e.to_string())?;
            }
            if !quiet {
                let m = r.image.mean();
                eprintln!(
                    "vpl: {} {}x{} {spp} spp in {:.2} s ({:.2} M paths/s), mean RGB {:.5} {:.5} {:.5} -> {}",
                    sc.name, camera.resolution.0, camera.resolution.1, r.seconds, r.paths as f64 / r.seconds / 1e6, m[0], m[1], m[2], out.display()
                );
            }
            Ok(())
        }
        Command::Track { s: SceneArgs { scene, frame, max_depth, clamp, size, seed, threads }, mode, pixels, spp, out } => {
            if spp == 0 {
                return Err("--spp must be at least 1".into());
            }
            let pt = tracer(max_depth, mode, clamp)?;
            if let Some(p) = &out {
                check_writable(p)?;
            }
            let pool = pool(threads)?;
            let (sc, camera) = load_frame(&scene, frame, size)?;
            let (w, h) = camera.resolution;
            if let Some(p) = pixels.iter().find(|p| p.0 >= w || p.1 >= h) {
                return Err(format!("--pixel {},{} is outside the {w}x{h} image", p.0, p.1));
            }
            let px: Vec<(u32, u32)> = pixels.iter().map(|p| (p.0, p.1)).collect();
            let ts = pool.install(|| track(&sc, &camera, &pt, &px, spp, seed, frame as u64));
            let mut csv = String::from("x,y,r,g,b,stderr_r,stderr_g,stderr_b,samples\n");
            for t in ts {
                csv.push_str(&format!(
                    "{},{},{},{},{},{},{},{},{}\n",
                    t.pixel.0, t.pixel.1, t.mean.x, t.mean.y, t.mean.z, t.stderr.x, t.stderr.y, t.stderr.z, t.samples
                ));
            }
            emit(out.as_deref(), &csv)
        }
        Command::ExportScene { name, out } => {
            let setup = SceneSetup::load(&name).map_err(|e| e.to_string())?;
            emit(out.as_deref(), &setup.to_toml())
        }
        Command::BenchPt { spp, repeat, threads } => {
            if spp == 0 || repeat == 0 {
                return Err("--spp and --repeat must be at least 1".into());
            }
            let pool = pool(threads)?;
            let setup = SceneSetup::load("cornell").map_err(|e| e.to_string())?;
            let pt = PathTracer::new(5, Mode::Full);
            let mut rates = Vec::new();
            // One warm-up render, then the timed ones.
            for i in 0..=repeat {
                let r = pool
                    .install(|| render(&setup.scene, &setup.camera, &pt, RenderSettings { spp, seed: i as u64, frame: 0 }, &|_, _| {}))
                    .map_err(|e| e.to_string())?;
                if i > 0 {
                    rates.push(r.paths as f64 / r.seconds);
                }
            }
            rates.sort_by(f64::total_cmp);
            println!(
                "bench-pt: cornell 256x256, max-depth 5, {spp} spp, {} threads: best {:.3} M paths/s, median {:.3} M paths/s over {repeat} renders",
                pool.current_num_threads(),
                rates[rates.len() - 1] / 1e6,
                rates[rates.len() / 2] / 1e6
            );
            Ok(())
        }
        Command::ValidateCornell { spp, data, out, seed } => {
            if spp == 0 {
                return Err("--spp must be at least 1".into());
            }
            std::fs::create_dir_all(&out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
            let bar = ProgressBar::new(3 * 256 * 256);
            bar.set_style(ProgressStyle::with_template("{msg:>9} {elapsed_precise} [{bar:40}] {percent}%, eta {eta}").unwrap().progress_chars("=> "));
            let vs = vpl_bench::validation::validate_cornell(&data, spp, seed, &|m, d, t| {
                let k = vpl_bench::validation::MODES.iter().position(|x| x.0 == m).unwrap_or(0) as u64;
                bar.set_message(m.to_string());
                bar.set_position(k * t + d);
            })
            .map_err(|e| e.to_string())?;
            bar.finish_and_clear();
            for v in &vs {
                vpl_bench::validation::write_difference(v, &out).map_err(|e| e.to_string())?;
                v.ours.0.write_png(out.join(format!("cornell_{}_ours.png", v.mode)), 1.0).map_err(|e| e.to_string())?;
                v.theirs.0.write_png(out.join(format!("cornell_{}_mitsuba.png", v.mode)), 1.0).map_err(|e| e.to_string())?;
            }
            let md = vpl_bench::validation::report_markdown(&vs, spp);
            write_atomic(&out.join("cornell_validation.md"), md.as_bytes()).map_err(|e| e.to_string())?;
            print!("{md}");
            Ok(())
        }
    }
}
